#!/usr/bin/env python3
"""Writes the San Miguel bench scene: DIR/san-miguel.pbrt and its geometry files, from a copy of
pbrt-v3-scenes' San Miguel (Guillermo M. Leal Llaguno's model; the copy in the public git
repository AndiMiko/pbrt-scenes, folder sanmiguel/, holds it in pbrt-v3's format).

The scene is the full model less a fixed list of files (the tree trunks, four of the seven leaf
sets, the wall ivy, nine plant and building PLY meshes and the sky's image map: the largest
files, which the snapshot this table was measured on lacks; a full clone has them, but they are
left out whatever the source holds, so that every table renders the same scene). A constant sky
of the image map's scale lights it. The camera, materials and textures are the original's; the
integrator is `path` (maxdepth 5) at 4 spp, as the other interiors of bench/versus.py.

The original closes every object definition with `AttributeEnd` then `ObjectEnd` inside an outer
`AttributeBegin`, which pbrt-v3 accepts (one stack) and acr accepts with a warning, but which
pbrt-v4 rejects; the copies here close them in order, which means the same in pbrt-v3.
Two "scale" textures that nothing uses, and two emitters' references to a material that is
never defined, are dropped, for pbrt-v4 (pbrt-v3 ignores that reference). The leaves' alpha
cut-outs and the alpha of two light meshes are dropped too: acr does not read alpha, and the
speed comparison wants both renderers to do the same work.
PLY meshes and textures are linked, not copied. Python 3 standard library only.
usage: python3 bench/tools/make_san_miguel.py SANMIGUEL_DIR DIR"""

import os
import re
import sys

LEFT_OUT_INCLUDES = [
    "troncoA-geom", "troncoB-geom", "hojas_a1-geom", "hojas_a3-geom", "hojas_a4-geom",
    "hojas_b2-geom", "hojas_b4-geom", "enredadera-geom",
]
LEFT_OUT_PLYS = [
    "sanmiguel_00236", "plantas_00002", "plantas_00086", "plantas_00087", "plantas_00102",
    "plantas_00103", "plantas_00210", "plantas_00216", "plantas_00221",
]
CROSSED = re.compile(r"(\n[ \t]*)AttributeEnd([ \t]*\n[ \t]*)ObjectEnd")
# Two lights define a "scale" texture of one constant colour that nothing uses, which pbrt-v4's
# upgrade refuses; they are dropped.
# Two emitters (the sun, a fill light) name a material that is never defined: pbrt-v3 reports it and keeps the
# material in effect, pbrt-v4 stops; dropping the line is pbrt-v3's reading.
# acr has no alpha cut-outs (docs/pbrt-v3-compatibility.md): both renderers get the meshes
# without them, so that they do the same work.
ALPHA = re.compile(r'[ \t]*"(texture|float) (shadow)?alpha"[ \t]*(\[[^\]]*\]|"[^"]*"|[-0-9.e]+)[ \t]*(?=\n)')
UNDEFINED_MATERIAL = re.compile(r'\n[ \t]*NamedMaterial "(Sun_Light|Fill_Light_Patio)"[ \t]*(?=\n)')
SCALE_OF_ONE = re.compile(r'Texture "(SunLight_Mat01|Fill Light_Patio06_Mat01)" "color" "scale"\s*"rgb tex1"\s*\[[^\]]*\]\s*(?!\s*"[a-z]+ tex2")')


def fix_geometry(text):
    """Drops the left-out PLY meshes and closes object definitions in order."""
    for ply in LEFT_OUT_PLYS:
        text = re.sub(r'Shape "plymesh" "string filename" "geometry/' + ply + r'\.ply"[ \t]*\n',
                      "", text)
    text = SCALE_OF_ONE.sub("", text)
    text = UNDEFINED_MATERIAL.sub("", text)
    text = ALPHA.sub("", text)
    return CROSSED.sub(r"\1ObjectEnd\2AttributeEnd", text)


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__.rsplit("\n", 1)[-1])
    src, out = sys.argv[1], sys.argv[2]
    main_file = os.path.join(src, "sanmiguel.pbrt")
    if not os.path.exists(main_file):
        sys.exit(f"{main_file} not found: SANMIGUEL_DIR is the sanmiguel/ folder of the scenes")
    os.makedirs(os.path.join(out, "geometry"), exist_ok=True)
    textures = os.path.join(out, "textures")
    if not os.path.lexists(textures):
        os.symlink(os.path.abspath(os.path.join(src, "textures")), textures)
    for name in sorted(os.listdir(os.path.join(src, "geometry"))):
        source = os.path.abspath(os.path.join(src, "geometry", name))
        target = os.path.join(out, "geometry", name)
        if name.endswith(".pbrt"):
            with open(source) as f:
                text = f.read()
            with open(target, "w") as f:
                f.write(fix_geometry(text))
        elif not os.path.lexists(target):
            os.symlink(source, target)
    with open(main_file) as f:
        scene = f.read()
    scene = re.sub(r'Sampler "sobol"\s+"integer pixelsamples" \d+\s*\nIntegrator "bdpt"',
                   'Sampler "sobol" "integer pixelsamples" 4\n'
                   'Integrator "path" "integer maxdepth" 5', scene)
    scene = re.sub(r'LightSource "infinite"\s*\n"integer nsamples" \[32\]\s*\n'
                   r'"color scale" \[13.0 13.0 13.0\]\s*\n\s*"string mapname" \[[^\]]*\]',
                   'LightSource "infinite" "rgb L" [13 13 13]', scene)
    for name in LEFT_OUT_INCLUDES:
        scene = scene.replace(f'Include "geometry/{name}.pbrt"',
                              f'# left out (see bench/tools/make_san_miguel.py): {name}.pbrt')
    scene = scene.replace('"sanmiguel.exr"', '"san-miguel.exr"')
    if '"integer pixelsamples" 4' not in scene or '"rgb L" [13 13 13]' not in scene:
        sys.exit("sanmiguel.pbrt is not the expected file (its sampler or sky line differs)")
    with open(os.path.join(out, "san-miguel.pbrt"), "w") as f:
        f.write("# pbrt-v3-scenes' San Miguel (Guillermo M. Leal Llaguno), less the files "
                "bench/tools/make_san_miguel.py names.\n" + scene)


if __name__ == "__main__":
    main()
