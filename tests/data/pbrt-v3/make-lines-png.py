#!/usr/bin/env python3
"""Writes scenes/pbrt-v3/textures/lines.png for scenes/pbrt-v3/texture-filtering.pbrt: a 96 x 80
(not powers of two, so that pbrt-v3 resamples it) grey image of thin dark lines on white, one
every 8 texels in each direction, and a red diagonal. Written for acr (CC0). Run from the
repository root."""
import struct
import zlib

W, H = 96, 80
rows = []
for y in range(H):
    row = bytearray([0])  # filter type: none
    for x in range(W):
        if x == y:
            rgb = (200, 30, 30)
        elif x % 8 == 0 or y % 8 == 0:
            rgb = (20, 20, 20)
        else:
            rgb = (235, 235, 235)
        row += bytes(rgb)
    rows.append(bytes(row))


def chunk(kind, data):
    c = struct.pack(">I", len(data)) + kind + data
    return c + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


png = b"\x89PNG\r\n\x1a\n"
png += chunk(b"IHDR", struct.pack(">IIBBBBB", W, H, 8, 2, 0, 0, 0))
png += chunk(b"IDAT", zlib.compress(b"".join(rows), 9))
png += chunk(b"IEND", b"")
with open("scenes/pbrt-v3/textures/lines.png", "wb") as f:
    f.write(png)
