#!/usr/bin/env python3
"""Writes the example meshes in scenes/meshes/ deterministically (standard library only).

- icosphere.ply: binary little-endian, an icosahedron subdivided once (80 triangles), unit
  radius, with per-vertex normals and (u, v) from longitude and latitude.
- cube.ply: ascii, a unit cube with six quad faces (exercises quad splitting).

Licence: CC0, written for the acr project.
"""
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "..", "meshes")


def icosphere():
    t = (1.0 + 5.0 ** 0.5) / 2.0
    verts = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
             (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    verts = [tuple(c / math.sqrt(sum(x * x for x in v)) for c in v) for v in verts]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
             (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
             (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    cache = {}

    def midpoint(a, b):
        key = (min(a, b), max(a, b))
        if key not in cache:
            m = [(verts[a][i] + verts[b][i]) / 2 for i in range(3)]
            n = math.sqrt(sum(x * x for x in m))
            verts.append(tuple(x / n for x in m))
            cache[key] = len(verts) - 1
        return cache[key]

    sub = []
    for a, b, c in faces:
        ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
        sub += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
    return verts, sub


def write_icosphere(path):
    verts, faces = icosphere()
    header = ("ply\nformat binary_little_endian 1.0\ncomment acr example mesh (CC0)\n"
              f"element vertex {len(verts)}\nproperty float x\nproperty float y\nproperty float z\n"
              "property float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\n"
              f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        for x, y, z in verts:
            u = (math.atan2(y, x) / (2 * math.pi)) % 1.0
            v = math.acos(max(-1.0, min(1.0, z))) / math.pi
            f.write(struct.pack("<8f", x, y, z, x, y, z, u, v))
        for a, b, c in faces:
            f.write(struct.pack("<B3i", 3, a, b, c))


def write_cube(path):
    verts = [(x, y, z) for z in (0, 1) for y in (0, 1) for x in (0, 1)]
    # Counter-clockwise seen from outside, so normals point out.
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    with open(path, "w", newline="\n") as f:
        f.write("ply\nformat ascii 1.0\ncomment acr example mesh (CC0)\n")
        f.write(f"element vertex {len(verts)}\nproperty float x\nproperty float y\nproperty float z\n")
        f.write(f"element face {len(quads)}\nproperty list uchar int vertex_indices\nend_header\n")
        for v in verts:
            f.write("%g %g %g\n" % v)
        for q in quads:
            f.write("4 %d %d %d %d\n" % q)


if __name__ == "__main__":
    os.makedirs(OUT, exist_ok=True)
    write_icosphere(os.path.join(OUT, "icosphere.ply"))
    write_cube(os.path.join(OUT, "cube.ply"))
