#!/usr/bin/env python3
"""Figures for docs/reconstruction.md: per scene, side by side, a 256-spp sobol+box render (the
reference's stand-in), stratified+gaussian at 8 spp, cluster+polynomial (defaults) at 8 spp, and
the clusters that fit used (--aov fitclusters: colours, borders dark), written to
OUT/figure-SCENE.png.

usage: python3 bench/tools/features_figures.py [OUT_DIR]   (default docs/bench/features)
Needs target/release/acr. Python 3 standard library only (reads and writes 8-bit RGB PNGs)."""

import os
import struct
import subprocess
import sys
import tempfile
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCENES = ["motion-blur", "depth-of-field", "motion-dof", "cornell-box"]


def read_png(path):
    """(width, height, rows of RGB bytes) of a non-interlaced 8-bit RGB or RGBA PNG."""
    data = open(path, "rb").read()
    pos, idat, width = 8, b"", None
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour = struct.unpack(">IIBB", body[:10])
            if depth != 8 or colour not in (2, 6):
                sys.exit(f"{path}: only 8-bit RGB or RGBA PNGs are read")
            channels = 3 if colour == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw = zlib.decompress(idat)
    stride = width * channels
    rows, prev = [], bytearray(stride)
    for y in range(height):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b = prev[i]
            c = prev[i - channels] if i >= channels else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                line[i] = (line[i] + pred) & 255
        prev = line
        rgb = line if channels == 3 else bytearray(
            v for k, v in enumerate(line) if k % 4 != 3)
        rows.append(bytes(rgb))
    return width, height, rows


def write_png(path, width, height, rows):
    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(
            ">I", zlib.crc32(kind + body) & 0xFFFFFFFF)
    raw = b"".join(b"\0" + r for r in rows)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(raw, 9)))
        f.write(chunk(b"IEND", b""))


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "docs", "bench", "features")
    os.makedirs(out, exist_ok=True)
    acr = os.path.join(ROOT, "target", "release", "acr")
    with tempfile.TemporaryDirectory() as tmp:
        for scene in SCENES:
            s = os.path.join(ROOT, "scenes", f"{scene}.pbrt")
            p = {k: os.path.join(tmp, f"{k}.png") for k in ["ref", "sg", "cp", "clusters"]}
            run = lambda *a: subprocess.run([acr, "render", s, "-q", "--seed", "1", *a], check=True)
            run("--spp", "256", "--sampler", "sobol", "--filter", "box", "-o", p["ref"])
            run("--spp", "8", "--sampler", "stratified", "--filter", "gaussian", "-o", p["sg"])
            run("--spp", "8", "--sampler", "cluster", "--filter", "polynomial", "-o", p["cp"],
                "--aov", f"fitclusters={p['clusters']}")
            images = [read_png(p[k]) for k in ["ref", "sg", "cp", "clusters"]]
            w, h = images[0][0], images[0][1]
            gap = b"\xff\xff\xff" * 4
            rows = [gap.join(img[2][y] for img in images) for y in range(h)]
            path = os.path.join(out, f"figure-{scene}.png")
            write_png(path, 4 * w + 12, h, rows)
            print(path)


if __name__ == "__main__":
    main()
