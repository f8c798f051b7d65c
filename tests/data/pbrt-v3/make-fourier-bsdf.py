#!/usr/bin/env python3
"""Writes scenes/pbrt-v3/textures/tabulated.bsdf, a small pbrt-v3 .bsdf file (the SCATFUN
format of layerlab, read by pbrt-v3's FourierBSDFTable::Read) for acr's fourier tests: a
coloured glossy reflection (a cos(phi) term peaking at the mirror direction) and a diffuse
transmission through a boundary of relative index 1.33, on 25 zenith-cosine nodes, 3 channels
(luminance, red, blue). Written for acr (CC0). Run from the repository root."""
import math
import struct

N_MU = 25
ETA = 1.33
REFLECT = {"Y": 0.5, "R": 0.7, "B": 0.2}
TRANSMIT = {"Y": 0.3, "R": 0.2, "B": 0.4}
GLOSS = 0.8

mu = [-math.cos(math.pi * j / (N_MU - 1)) for j in range(N_MU)]
mu[N_MU // 2] = 0.0


def series(mu_i, mu_o):
    """Per channel (Y, R, B), the coefficients of f * |mu_i| over cos(k phi)."""
    if mu_i * mu_o < 0:
        s = math.sqrt(max(0.0, 1 - mu_i * mu_i)) * math.sqrt(max(0.0, 1 - mu_o * mu_o))
        return [[REFLECT[c] * abs(mu_i) / math.pi * k for k in (1.0, GLOSS * s)] for c in "YRB"]
    if mu_i * mu_o > 0:
        return [[TRANSMIT[c] * abs(mu_i) / math.pi] for c in "YRB"]
    # On the horizon: the mean of the two.
    return [[(REFLECT[c] + TRANSMIT[c]) / 2 * abs(mu_i) / math.pi] for c in "YRB"]


def integrate_catmull_rom(x, values):
    """pbrt-v3's IntegrateCatmullRom: the running integral of the spline through values."""
    n, total, cdf = len(x), 0.0, [0.0]
    for i in range(n - 1):
        x0, x1, f0, f1 = x[i], x[i + 1], values[i], values[i + 1]
        width = x1 - x0
        d0 = width * (f1 - values[i - 1]) / (x1 - x[i - 1]) if i > 0 else f1 - f0
        d1 = width * (values[i + 2] - f0) / (x[i + 2] - x0) if i + 2 < n else f1 - f0
        total += ((d0 - d1) * (1.0 / 12.0) + (f0 + f1) * 0.5) * width
        cdf.append(total)
    return cdf


coeffs, offsets, cdf = [], [], []
for o in range(N_MU):
    a0_row = []
    for i in range(N_MU):
        s = series(mu[i], mu[o])
        m = len(s[0])
        offsets += [len(coeffs), m]
        for channel in s:
            coeffs += channel
        a0_row.append(s[0][0])
    cdf += integrate_catmull_rom(mu, a0_row)

m_max = 2
header = b"SCATFUN\x01" + struct.pack(
    "<9i", 1, N_MU, len(coeffs), m_max, 3, 1, 0, 0, 0
) + struct.pack("<f", ETA) + struct.pack("<4i", 0, 0, 0, 0)
assert len(header) == 64
with open("scenes/pbrt-v3/textures/tabulated.bsdf", "wb") as f:
    f.write(header)
    f.write(struct.pack(f"<{N_MU}f", *mu))
    f.write(struct.pack(f"<{len(cdf)}f", *cdf))
    f.write(struct.pack(f"<{len(offsets)}i", *offsets))
    f.write(struct.pack(f"<{len(coeffs)}f", *coeffs))
