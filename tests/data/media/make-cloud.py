#!/usr/bin/env python3
"""Writes scenes/pbrt-v3/geometry/cloud-density.pbrt: a 16^3 density grid (a lumpy blob, values
in [0, 1] with three decimals) included by scenes/pbrt-v3/media-cloud.pbrt. Deterministic."""
import math
import sys

N = 16
values = []
for z in range(N):
    for y in range(N):
        for x in range(N):
            p = [(c + 0.5) / N - 0.5 for c in (x, y, z)]
            r = math.sqrt(p[0] ** 2 + (1.3 * p[1]) ** 2 + p[2] ** 2)
            lumps = 0.5 + 0.5 * math.sin(9 * p[0] + 2) * math.sin(11 * p[1] + 1) * math.sin(7 * p[2])
            d = max(0.0, 1 - r / 0.48) * (0.55 + 0.45 * lumps)
            values.append(round(min(1.0, 1.6 * d), 3))
out = sys.argv[1] if len(sys.argv) > 1 else "scenes/pbrt-v3/geometry/cloud-density.pbrt"
with open(out, "w") as f:
    f.write("# A 16^3 density grid made by tests/data/media/make-cloud.py. CC0.\n")
    f.write('MakeNamedMedium "cloud" "string type" "heterogeneous"\n')
    f.write('    "integer nx" [16] "integer ny" [16] "integer nz" [16]\n')
    f.write('    "point p0" [-1 0.2 -1] "point p1" [1 1.8 1]\n')
    f.write('    "rgb sigma_a" [0.4 0.4 0.4] "rgb sigma_s" [3.6 3.6 3.6] "float g" [0.5]\n')
    f.write('    "float density" [\n')
    for i in range(0, len(values), 16):
        f.write("      " + " ".join(f"{v:g}" for v in values[i:i + 16]) + "\n")
    f.write("    ]\n")
