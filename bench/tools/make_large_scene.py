#!/usr/bin/env python3
"""Writes a large triangle scene for speed and memory comparisons: DIR/large-mesh.pbrt and
DIR/large-mesh.ply, a rippled terrain of 2 x N x N triangles (binary little-endian PLY with
per-vertex normals; N = 720 gives 1,036,800 triangles), a sphere, and a quad area light.
Deterministic; Python 3 standard library only.
usage: python3 bench/tools/make_large_scene.py DIR [N]"""

import math
import os
import struct
import sys


def main():
    out = sys.argv[1]
    n = int(sys.argv[2]) if len(sys.argv) > 2 else 720
    os.makedirs(out, exist_ok=True)
    verts = (n + 1) * (n + 1)
    with open(os.path.join(out, "large-mesh.ply"), "wb") as f:
        f.write((
            "ply\nformat binary_little_endian 1.0\n"
            "comment rippled terrain, written by bench/tools/make_large_scene.py\n"
            f"element vertex {verts}\nproperty float x\nproperty float y\nproperty float z\n"
            "property float nx\nproperty float ny\nproperty float nz\n"
            f"element face {2 * n * n}\nproperty list uchar int vertex_indices\nend_header\n"
        ).encode())
        rows = []
        for j in range(n + 1):
            z = -4.0 + 8.0 * j / n
            row = bytearray()
            for i in range(n + 1):
                x = -4.0 + 8.0 * i / n
                y = 0.15 * math.sin(3.1 * x) * math.cos(2.3 * z) + 0.05 * math.sin(11.0 * x + 7.0 * z)
                dx = 0.15 * 3.1 * math.cos(3.1 * x) * math.cos(2.3 * z) + 0.05 * 11.0 * math.cos(11.0 * x + 7.0 * z)
                dz = -0.15 * 2.3 * math.sin(3.1 * x) * math.sin(2.3 * z) + 0.05 * 7.0 * math.cos(11.0 * x + 7.0 * z)
                inv = 1.0 / math.sqrt(dx * dx + 1.0 + dz * dz)
                row += struct.pack("<6f", x, y, z, -dx * inv, inv, -dz * inv)
            rows.append(bytes(row))
        f.write(b"".join(rows))
        tri = struct.Struct("<B3i")
        for j in range(n):
            faces = bytearray()
            for i in range(n):
                a = j * (n + 1) + i
                b, c, d = a + 1, a + n + 2, a + n + 1
                # Counter-clockwise seen from above (+y): normals up.
                faces += tri.pack(3, a, d, c) + tri.pack(3, a, c, b)
            f.write(bytes(faces))
    with open(os.path.join(out, "large-mesh.pbrt"), "w") as f:
        f.write(f"""# A rippled terrain of {2 * n * n} triangles (large-mesh.ply), a sphere and a quad light.
# Written by bench/tools/make_large_scene.py. Licence: CC0, written for the acr project.
LookAt 0 3.5 6   0 0 0   0 1 0
Camera "perspective" "float fov" [50]
Film "image" "integer xresolution" [400] "integer yresolution" [300] "string filename" "large-mesh.exr"
Sampler "halton" "integer pixelsamples" [8]
Integrator "path" "integer maxdepth" [5]
WorldBegin
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [30 28 24]
  Material "matte" "rgb Kd" [0 0 0]
  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
      "point3 P" [-1 4 -1   1 4 -1   1 4 1   -1 4 1]
AttributeEnd
AttributeBegin
  Material "plastic" "rgb Kd" [0.4 0.5 0.7] "float roughness" [0.05]
  Translate 0.5 0.8 0
  Shape "sphere" "float radius" [0.6]
AttributeEnd
Material "matte" "rgb Kd" [0.6 0.55 0.45]
Shape "plymesh" "string filename" "large-mesh.ply"
WorldEnd
""")


if __name__ == "__main__":
    main()
