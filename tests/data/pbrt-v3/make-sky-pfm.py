#!/usr/bin/env python3
"""Writes scenes/pbrt-v3/textures/sky.pfm, the environment map of environment-map.pbrt: 40 x 20
(not powers of two, so that pbrt-v3 resamples it for its MIP map), latitude-longitude with
theta = 0 at the top row: a blue sky brightening to the horizon, a dim brown ground, and a small
sun of radiance 60. Run from the repository root. Python 3 standard library only."""

import math
import struct

W, H = 40, 20
rows = []
for v in range(H):
    theta = math.pi * (v + 0.5) / H
    row = []
    for u in range(W):
        phi = 2 * math.pi * (u + 0.5) / W
        if theta < math.pi / 2:
            t = theta / (math.pi / 2)
            rgb = (0.15 + 0.5 * t, 0.25 + 0.45 * t, 0.6 + 0.3 * t)
        else:
            rgb = (0.12, 0.09, 0.06)
        # The sun: two texels high and wide, a third of the way round, 35 degrees up.
        if u in (13, 14) and v in (5, 6):
            rgb = (60.0, 55.0, 45.0)
        # A faint variation around phi, so that the map is not symmetric.
        k = 1.0 + 0.2 * math.sin(phi)
        row.append(tuple(c * k for c in rgb))
    rows.append(row)

with open("scenes/pbrt-v3/textures/sky.pfm", "wb") as f:
    f.write(b"PF\n%d %d\n-1.0\n" % (W, H))
    # PFM stores the bottom row first.
    for row in reversed(rows):
        for rgb in row:
            f.write(struct.pack("<3f", *rgb))
