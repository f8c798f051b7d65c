#!/usr/bin/env python3
"""Writes scenes/many-lights.pbrt: a closed room whose ceiling holds 4,608 small emitting
triangles (a 48 x 48 grid of quads in four coloured quadrants, one-sided, facing down), with
two spheres and a box on the floor. Deterministic; Python 3 standard library only.
Run from the repository root: python3 scenes/tools/make_many_lights.py"""

N = 48          # quads per side of the ceiling grid
SIDE = 1.6      # the grid spans x, z in [-SIDE, SIDE]
GAP = 0.35      # fraction of each grid cell left dark between emitters
Y = 2.98        # emitters just below the ceiling (y = 3)
COLOURS = [(6, 5, 4), (2, 3, 8), (8, 2, 1.5), (3, 7, 3)]


def fmt(v):
    return ("%.5f" % v).rstrip("0").rstrip(".")


def quadrant_mesh(qx, qz):
    """The emitters of one quadrant as one trianglemesh: P and indices."""
    pts, idx = [], []
    half = N // 2
    cell = 2 * SIDE / N
    size = cell * (1 - GAP)
    for i in range(qx * half, (qx + 1) * half):
        for k in range(qz * half, (qz + 1) * half):
            x0 = -SIDE + i * cell + cell * GAP / 2
            z0 = -SIDE + k * cell + cell * GAP / 2
            base = len(pts)
            # Wound so that n = cross(p1 - p0, p2 - p0) points down (-y).
            pts += [(x0, Y, z0), (x0 + size, Y, z0), (x0 + size, Y, z0 + size), (x0, Y, z0 + size)]
            idx += [base, base + 1, base + 2, base, base + 2, base + 3]
    return pts, idx


def main():
    out = []
    w = out.append
    w("# Many lights: a closed room (x -2..2, y 0..3, z -2..2) whose ceiling holds 4,608 small")
    w("# one-sided emitting triangles (48 x 48 quads in four coloured quadrants, facing down), two")
    w("# spheres and a box. Exercises many-light sampling (lightsamplestrategy bvh, spatial, power,")
    w("# uniform) and path tracing. Rendering space: x y.")
    w("# Written by scenes/tools/make_many_lights.py. Licence: CC0, written for the acr project.")
    w("")
    w("Scale -1 1 1")
    w("LookAt 0 1.4 1.95   0 1.2 0   0 1 0")
    w('Camera "perspective" "float fov" [80]')
    w('Film "image" "integer xresolution" [256] "integer yresolution" [256]')
    w('    "string filename" "many-lights.png"')
    w('Sampler "halton" "integer pixelsamples" [4]')
    w('PixelFilter "gaussian"')
    w('Integrator "path" "integer maxdepth" [5]')
    w("")
    w("WorldBegin")
    w("")
    for q, (qx, qz) in enumerate([(0, 0), (1, 0), (0, 1), (1, 1)]):
        r, g, b = COLOURS[q]
        pts, idx = quadrant_mesh(qx, qz)
        w("AttributeBegin")
        w('  AreaLightSource "diffuse" "rgb L" [%s %s %s]' % (fmt(r), fmt(g), fmt(b)))
        w('  Material "matte" "rgb Kd" [0 0 0]')
        w('  Shape "trianglemesh" "integer indices" [')
        for j in range(0, len(idx), 24):
            w("    " + " ".join(str(v) for v in idx[j:j + 24]))
        w('  ] "point3 P" [')
        for j in range(0, len(pts), 4):
            w("    " + "   ".join(" ".join(fmt(c) for c in p) for p in pts[j:j + 4]))
        w("  ]")
        w("AttributeEnd")
    w("")
    w('Material "matte" "rgb Kd" [0.7 0.7 0.7]')
    w("# Floor (normal +y), ceiling (-y), back (+z), front (-z), left (+x), right (-x).")
    walls = [
        "-2 0 -2   -2 0 2   2 0 2   2 0 -2",
        "-2 3 -2   2 3 -2   2 3 2   -2 3 2",
        "-2 0 -2   2 0 -2   2 3 -2   -2 3 -2",
        "-2 0 2   -2 3 2   2 3 2   2 0 2",
    ]
    for p in walls:
        w('Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [%s]' % p)
    w('Material "matte" "rgb Kd" [0.6 0.2 0.2]')
    w('Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-2 0 -2   -2 3 -2   -2 3 2   -2 0 2]')
    w('Material "matte" "rgb Kd" [0.2 0.5 0.25]')
    w('Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [2 0 -2   2 0 2   2 3 2   2 3 -2]')
    w("")
    w("AttributeBegin")
    w('  Material "plastic" "rgb Kd" [0.5 0.5 0.7] "rgb Ks" [0.3 0.3 0.3] "float roughness" [0.05]')
    w("  Translate -0.7 0.5 -0.6")
    w('  Shape "sphere" "float radius" [0.5]')
    w("AttributeEnd")
    w("AttributeBegin")
    w('  Material "metal" "float roughness" [0.1]')
    w("  Translate 0.8 0.4 -0.2")
    w('  Shape "sphere" "float radius" [0.4]')
    w("AttributeEnd")
    w("AttributeBegin")
    w('  Material "matte" "rgb Kd" [0.75 0.7 0.5]')
    w("  Translate 0.1 0 -1.2")
    w("  Rotate 25 0 1 0")
    w('  Shape "trianglemesh" "integer indices" [0 2 1 0 3 2  4 5 6 4 6 7  0 1 5 0 5 4  1 2 6 1 6 5  2 3 7 2 7 6  3 0 4 3 4 7]')
    w('      "point3 P" [-0.4 0 -0.4   0.4 0 -0.4   0.4 0 0.4   -0.4 0 0.4   -0.4 1.1 -0.4   0.4 1.1 -0.4   0.4 1.1 0.4   -0.4 1.1 0.4]')
    w("AttributeEnd")
    w("")
    w("WorldEnd")
    with open("scenes/many-lights.pbrt", "w") as f:
        f.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
