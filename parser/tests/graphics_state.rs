//! The graphics state's semantics, checked on small inline scenes.

use acr_parser::{parse_str, ParamType, SceneDescription};
use glam::{DMat4, DVec3};
use std::path::Path;

fn parse(text: &str) -> SceneDescription {
    parse_str(text, Path::new("test.pbrt")).unwrap_or_else(|e| panic!("{e}"))
}

fn err(text: &str) -> String {
    match parse_str(text, Path::new("test.pbrt")) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e.to_string(),
    }
}

fn close(a: DVec3, b: DVec3) -> bool {
    (a - b).length() < 1e-9
}

fn point(m: &DMat4, p: [f64; 3]) -> DVec3 {
    m.transform_point3(DVec3::from(p))
}

#[test]
fn transforms_compose_on_the_right_as_in_pbrt() {
    let d = parse(
        "WorldBegin\nTranslate 1 0 0\nScale 2 2 2\nRotate 90 0 0 1\nShape \"sphere\"\nWorldEnd\n",
    );
    let m = d.shapes[0].world_from_object.start;
    // Rotate first (innermost), then scale, then translate.
    assert!(close(point(&m, [1.0, 0.0, 0.0]), DVec3::new(1.0, 2.0, 0.0)));
    assert!(!d.shapes[0].world_from_object.is_animated());
}

#[test]
fn transform_and_concat_transform_are_column_major_like_pbrt() {
    let d = parse(
        "WorldBegin\nTransform [1 0 0 0  0 1 0 0  0 0 1 0  5 6 7 1]\n\
         ConcatTransform [2 0 0 0  0 2 0 0  0 0 2 0  0 0 0 1]\nShape \"sphere\"\nWorldEnd",
    );
    let m = d.shapes[0].world_from_object.start;
    assert!(close(point(&m, [1.0, 1.0, 1.0]), DVec3::new(7.0, 8.0, 9.0)));
}

#[test]
fn attribute_blocks_restore_transform_material_and_orientation() {
    let d = parse(
        "WorldBegin\nMaterial \"plastic\"\nAttributeBegin\nTranslate 0 5 0\nMaterial \"mirror\"\n\
         ReverseOrientation\nShape \"sphere\"\nAttributeEnd\nShape \"sphere\"\n\
         TransformBegin\nTranslate 1 0 0\nMaterial \"glass\"\nTransformEnd\nShape \"disk\"\nWorldEnd",
    );
    let [a, b, c] = &d.shapes[..] else { panic!() };
    assert_eq!(d.materials[a.material.unwrap()].plugin.kind, "mirror");
    assert!(a.reverse_orientation);
    assert!(close(
        point(&a.world_from_object.start, [0.0; 3]),
        DVec3::new(0.0, 5.0, 0.0)
    ));
    assert_eq!(d.materials[b.material.unwrap()].plugin.kind, "plastic");
    assert!(!b.reverse_orientation);
    assert_eq!(b.world_from_object.start, DMat4::IDENTITY);
    // TransformEnd restores the transform but not the material.
    assert_eq!(c.world_from_object.start, DMat4::IDENTITY);
    assert_eq!(d.materials[c.material.unwrap()].plugin.kind, "glass");
}

#[test]
fn default_material_and_none() {
    let d = parse("WorldBegin\nShape \"sphere\"\nMaterial \"\"\nShape \"sphere\"\nWorldEnd");
    assert_eq!(d.shapes[0].material, Some(0));
    assert_eq!(d.materials[0].plugin.kind, "matte");
    assert_eq!(d.shapes[1].material, None);
}

#[test]
fn motion_uses_active_transform_and_transform_times() {
    let d = parse(
        "TransformTimes 0.25 0.75\nWorldBegin\nTranslate 1 0 0\nActiveTransform EndTime\n\
         Translate 0 2 0\nActiveTransform StartTime\nScale 3 3 3\nActiveTransform All\n\
         Shape \"sphere\"\nShape \"disk\"\nWorldEnd",
    );
    let t = d.shapes[0].world_from_object;
    assert!(t.is_animated());
    assert_eq!((t.start_time, t.end_time), (0.25, 0.75));
    assert!(close(
        point(&t.start, [1.0, 0.0, 0.0]),
        DVec3::new(4.0, 0.0, 0.0)
    ));
    assert!(close(
        point(&t.end, [1.0, 0.0, 0.0]),
        DVec3::new(2.0, 2.0, 0.0)
    ));
}

#[test]
fn camera_transform_and_named_camera_space() {
    let d = parse(
        "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\nWorldBegin\n\
         AttributeBegin\nCoordSysTransform \"camera\"\nLightSource \"point\"\nAttributeEnd\nWorldEnd",
    );
    let cam = d.camera.as_ref().unwrap();
    assert_eq!(cam.plugin.params.float("fov").unwrap(), Some(45.0));
    // The camera's origin in world space is its position.
    let world_from_camera = cam.camera_from_world.start.inverse();
    assert!(close(
        point(&world_from_camera, [0.0; 3]),
        DVec3::new(0.0, 0.0, 5.0)
    ));
    // A light placed in camera space sits at the camera.
    let l = d.lights[0].world_from_light;
    assert!(close(point(&l, [0.0; 3]), DVec3::new(0.0, 0.0, 5.0)));
}

#[test]
fn named_materials_are_scoped_and_mix_resolves() {
    let d = parse(
        "WorldBegin\nMakeNamedMaterial \"red\" \"string type\" \"matte\" \"rgb Kd\" [1 0 0]\n\
         AttributeBegin\nMakeNamedMaterial \"blue\" \"string type\" \"matte\" \"rgb Kd\" [0 0 1]\n\
         MakeNamedMaterial \"both\" \"string type\" \"mix\" \"string namedmaterial1\" \"red\"\n\
         \"string namedmaterial2\" \"blue\"\nNamedMaterial \"both\"\nShape \"sphere\"\nAttributeEnd\n\
         NamedMaterial \"red\"\nShape \"sphere\"\nWorldEnd",
    );
    let mix = &d.materials[d.shapes[0].material.unwrap()];
    assert_eq!(mix.plugin.kind, "mix");
    let [a, b] = mix.mix.unwrap();
    assert_eq!(d.materials[a].name.as_deref(), Some("red"));
    assert_eq!(d.materials[b].name.as_deref(), Some("blue"));
    assert_eq!(
        d.materials[d.shapes[1].material.unwrap()].name.as_deref(),
        Some("red")
    );
    // "blue" went out of scope with its attribute block: as pbrt-v3, naming it is a located
    // warning and the current material ("red") is kept.
    let d = parse(
        "WorldBegin\nMakeNamedMaterial \"red\" \"string type\" \"matte\"\nNamedMaterial \"red\"\n\
         AttributeBegin\nMakeNamedMaterial \"blue\" \"string type\" \"matte\"\n\
         AttributeEnd\nNamedMaterial \"blue\"\nShape \"sphere\"\nWorldEnd",
    );
    let warnings: Vec<String> = d.warnings.iter().map(ToString::to_string).collect();
    assert!(
        warnings.iter().any(|w| w
            .starts_with("test.pbrt:7:1: warning: no material named \"blue\"")
            && w.contains("the current material is kept")),
        "{warnings:?}"
    );
    assert_eq!(
        d.materials[d.shapes[0].material.unwrap()].name.as_deref(),
        Some("red")
    );
}

#[test]
fn textures_resolve_by_kind_and_scope() {
    let d = parse(
        "WorldBegin\nTexture \"c\" \"color\" \"checkerboard\" \"float uscale\" 4\n\
         Texture \"f\" \"float\" \"constant\" \"float value\" 0.5\n\
         Texture \"s\" \"color\" \"scale\" \"texture tex1\" \"c\" \"texture tex2\" \"f\"\n\
         Material \"matte\" \"texture Kd\" \"s\" \"texture sigma\" \"f\"\nShape \"sphere\"\nWorldEnd",
    );
    let m = &d.materials[1];
    let kd = m.plugin.params.texture("Kd").unwrap();
    assert_eq!((kd.spectrum, kd.float), (Some(2), None));
    let sigma = m.plugin.params.texture("sigma").unwrap();
    assert_eq!((sigma.spectrum, sigma.float), (None, Some(1)));
    let scale = &d.textures[2].plugin.params;
    assert_eq!(scale.texture("tex1").unwrap().spectrum, Some(0));
    let e = err("WorldBegin\nMaterial \"matte\" \"texture Kd\" \"nope\"\nWorldEnd");
    assert!(
        e.contains("test.pbrt:2:18: no texture named \"nope\""),
        "{e}"
    );
}

#[test]
fn object_instances_share_one_definition() {
    let d = parse(
        "WorldBegin\nObjectBegin \"tri\"\nTranslate 0 0 1\nShape \"trianglemesh\" \
         \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\nObjectEnd\n\
         Translate 5 0 0\nObjectInstance \"tri\"\nTranslate 5 0 0\nObjectInstance \"tri\"\nWorldEnd",
    );
    assert!(d.shapes.is_empty());
    assert_eq!(d.objects.len(), 1);
    assert_eq!(d.objects["tri"].shapes.len(), 1);
    assert_eq!(d.instances.len(), 2);
    let inst = &d.instances[1];
    assert!(close(
        point(&inst.world_from_instance.start, [0.0; 3]),
        DVec3::new(10.0, 0.0, 0.0)
    ));
    // The transform inside the definition stays on the shape; ObjectEnd restored the outer one.
    let s = &d.objects["tri"].shapes[0];
    assert!(close(
        point(&s.world_from_object.start, [0.0; 3]),
        DVec3::new(0.0, 0.0, 1.0)
    ));
    assert!(close(
        point(&d.instances[0].world_from_instance.start, [0.0; 3]),
        DVec3::new(5.0, 0.0, 0.0)
    ));
}

/// San Miguel (pbrt-v3-scenes) closes its object definitions as `AttributeEnd` then
/// `ObjectEnd` inside an outer `AttributeBegin`: pbrt-v3 keeps both blocks on one stack.
#[test]
fn crossed_attribute_and_object_blocks_parse_as_in_pbrt_v3() {
    let d = parse(
        "WorldBegin\nAttributeBegin\nObjectBegin \"tri\"\nAttributeBegin\nTranslate 0 0 1\n\
         Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\n\
         AttributeEnd\nAttributeEnd\nObjectEnd\n\
         AttributeBegin\nTranslate 5 0 0\nObjectInstance \"tri\"\nAttributeEnd\n\
         Translate 7 0 0\nObjectInstance \"tri\"\nWorldEnd",
    );
    assert_eq!(d.objects["tri"].shapes.len(), 1);
    assert_eq!(d.instances.len(), 2);
    // Every block was closed: the last instance sees only the Translate after them.
    assert!(close(
        point(&d.instances[1].world_from_instance.start, [0.0; 3]),
        DVec3::new(7.0, 0.0, 0.0)
    ));
    let crossed: Vec<_> = d
        .warnings
        .iter()
        .filter(|w| w.to_string().contains("one stack"))
        .collect();
    assert_eq!(crossed.len(), 1, "{:?}", d.warnings);
    assert!(
        crossed[0].to_string().contains("test.pbrt:8:1"),
        "{}",
        crossed[0]
    );
    // A stray ObjectEnd is still an error, and so is a TransformEnd crossing either block.
    assert!(err("WorldBegin\nAttributeBegin\nObjectEnd")
        .contains("ObjectEnd without a matching ObjectBegin"));
    assert!(err("WorldBegin\nObjectBegin \"a\"\nTransformEnd")
        .contains("TransformEnd closes the ObjectBegin"));
}

#[test]
fn area_lights_attach_to_shapes_in_scope() {
    let d = parse(
        "WorldBegin\nAttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 2 3]\n\
         Shape \"sphere\"\nShape \"disk\"\nAttributeEnd\nShape \"sphere\"\nWorldEnd",
    );
    assert!(d.shapes[0].area_light.is_some());
    assert!(d.shapes[1].area_light.is_some());
    assert!(d.shapes[2].area_light.is_none());
    let l = d.shapes[0].area_light.as_ref().unwrap();
    assert_eq!(
        l.params.vec3("L", ParamType::Rgb).unwrap(),
        Some([1.0, 2.0, 3.0])
    );
}

#[test]
fn parameter_types_and_single_values() {
    let d = parse(
        "Film \"image\" \"integer xresolution\" 64 \"string filename\" \"a \\\"b\\\".exr\"\n\
         Sampler \"halton\" \"bool flag\" \"true\" \"bool other\" false\nWorldBegin\n\
         LightSource \"distant\" \"point from\" [0 1 0] \"color L\" [1 1 1] \
         \"blackbody I\" [6500 1] \"spectrum s\" [300 1 800 1]\nWorldEnd",
    );
    let film = d.film.as_ref().unwrap();
    assert_eq!(film.params.int("xresolution").unwrap(), Some(64));
    assert_eq!(film.params.string("filename").unwrap(), Some("a \"b\".exr"));
    let s = d.sampler.as_ref().unwrap();
    assert_eq!(s.params.bool("flag").unwrap(), Some(true));
    assert_eq!(s.params.bool("other").unwrap(), Some(false));
    let l = &d.lights[0].plugin.params;
    assert_eq!(
        l.vec3("from", ParamType::Point3).unwrap(),
        Some([0.0, 1.0, 0.0])
    );
    assert_eq!(
        l.numbers("I", ParamType::Blackbody).unwrap().unwrap().len(),
        2
    );
    // Asking for the wrong type is an error that names the declared type.
    let e = film.params.float("xresolution").unwrap_err().to_string();
    assert!(e.contains("declared integer"), "{e}");
}

#[test]
fn unused_parameters_are_reported_with_their_location() {
    let d = parse("Camera \"perspective\" \"float fvo\" 45 \"float fov\" 30\nWorldBegin\nWorldEnd");
    let cam = &d.camera.as_ref().unwrap().plugin.params;
    assert_eq!(cam.float("fov").unwrap(), Some(30.0));
    let w = d.unused_parameter_warnings();
    assert_eq!(w.len(), 1);
    assert_eq!(
        w[0].to_string(),
        "test.pbrt:1:22: warning: parameter \"float fvo\" of perspective was not used"
    );
}

#[test]
fn hundred_thousand_nested_attribute_blocks() {
    let n = 100_000;
    let mut text = String::from("WorldBegin\n");
    text.push_str(&"AttributeBegin\n".repeat(n));
    text.push_str("Translate 1 0 0\nShape \"sphere\"\n");
    text.push_str(&"AttributeEnd\n".repeat(n));
    text.push_str("Shape \"sphere\"\nWorldEnd\n");
    let d = parse(&text);
    assert_eq!(d.shapes.len(), 2);
    assert_eq!(d.shapes[1].world_from_object.start, DMat4::IDENTITY);
    assert!(d.warnings.is_empty(), "{:?}", d.warnings);
}

#[test]
fn long_one_line_mesh_parses() {
    // About 12 MB on a single line: pbrt exporters write meshes this way.
    let n = 400_000;
    let mut text = String::from("WorldBegin Shape \"trianglemesh\" \"point3 P\" [");
    for i in 0..n {
        let x = i as f64 * 0.001;
        text.push_str(&format!("{x:.4} 0.1234 {:.4} ", 1.0 - x));
    }
    text.push_str("] \"integer indices\" [");
    for i in 0..n - 2 {
        text.push_str(&format!("{} {} {} ", i, i + 1, i + 2));
    }
    text.push_str("] WorldEnd");
    assert!(text.len() > 12_000_000, "{}", text.len());
    let d = parse(&text);
    let mesh = d.shapes[0].mesh.as_ref().unwrap();
    assert_eq!(mesh.positions.len(), n);
    assert_eq!(mesh.triangle_count(), n - 2);
}

#[test]
fn structural_errors() {
    for (text, want) in [
        ("Shape \"sphere\"", "test.pbrt:1:1: Shape is only allowed between WorldBegin and WorldEnd"),
        ("WorldBegin\nCamera \"perspective\"", "test.pbrt:2:1: Camera must come before WorldBegin"),
        ("WorldBegin\nAttributeEnd", "AttributeEnd without a matching AttributeBegin"),
        ("WorldBegin\nAttributeBegin\nTransformEnd", "TransformEnd closes the AttributeBegin at test.pbrt:2:1"),
        ("WorldBegin\nWorldEnd\nShape \"sphere\"", "Shape after WorldEnd"),
        ("WorldBegin\nObjectInstance \"x\"", "no object named \"x\""),
        ("WorldBegin\nObjectBegin \"a\"\nObjectBegin \"b\"", "inside the definition of \"a\""),
        ("Rotate 10 0 0 0", "zero-length axis"),
        ("LookAt 0 0 0 0 0 0 0 1 0", "LookAt"),
        ("Translate 1 2", "Translate expects 3 numbers, found the end of the file after 2"),
        ("CoordSysTransform \"camra\"", "no coordinate system named \"camra\""),
        ("ActiveTransform Sometimes", "not 'Sometimes'"),
        ("WorldBegin\nWorldBegin", "WorldBegin appears twice"),
        ("WorldBegin\nMakeNamedMaterial \"m\" \"rgb Kd\" [1 1 1]", "needs a \"string type\""),
        ("WorldBegin\nMaterial \"mix\" \"string namedmaterial1\" \"a\"", "no material named \"a\""),
        ("\"float fov\" 3", "expected a directive, found string \"float fov\""),
        ("Camera \"perspective\" \"float fov\" [ 1 2", "'[' is never closed"),
        ("Camera \"perspective\" \"flaot fov\" 1", "unknown parameter type 'flaot' (did you mean float?)"),
        ("Camera \"perspective\" \"float\" 1", "expected a parameter declaration"),
        ("Camera \"perspective\" \"integer n\" 1.5", "1.5 is not a 32-bit integer"),
        ("Camera \"perspective\" \"float fov\" \"wide\"", "declared float but has string values"),
        ("Camera \"perspective\" \"point3 p\" [1 2]", "not a multiple of 3"),
        ("Camera \"perspective\" \"bool b\" \"yes\"", "\"yes\" is not \"true\" or \"false\""),
        ("Camera \"perspective\" \"float fov\" [1 \"a\"]", "mixes strings"),
        ("Camera \"perspective\" \"float fov\" Shape", "has no value"),
        ("Shpae \"sphere\"", "unknown directive 'Shpae' (did you mean Shape?)"),
        ("WorldBegin\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 3]",
         "test.pbrt:2:53: trianglemesh: vertex index 3 (index #2) is out of range: the mesh has 3 vertices"),
        ("WorldBegin\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0 1 1 1] \"integer indices\" [0 1 2 3]",
         "not a multiple of 3"),
        ("WorldBegin\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0 1 1 1]", "needs an \"integer indices\""),
        ("WorldBegin\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"float uv\" [0 0 1 1]", "4 \"uv\" values for 3 vertices"),
        ("WorldBegin\nShape \"plymesh\" \"string filename\" \"missing.ply\"", "cannot read PLY file \"missing.ply\": no such file"),
        ("Include \"missing.pbrt\"", "test.pbrt:1:1: cannot read included file \"missing.pbrt\": no such file"),
    ] {
        let e = err(text);
        assert!(e.contains(want), "for {text:?}\n got: {e}\nwant: {want}");
    }
}

#[test]
fn error_shows_line_and_caret() {
    let e = err("WorldBegin\n  Shape \"sphere\" \"float radius\" [ 1 ] \"flot r\" 2\nWorldEnd");
    assert_eq!(
        e,
        "test.pbrt:2:39: unknown parameter type 'flot' (did you mean float?)\n  \
         Shape \"sphere\" \"float radius\" [ 1 ] \"flot r\" 2\n                                      ^"
    );
}

/// Parses `text` and asserts that it gives a description or an error at a place in it: the
/// error names `t.pbrt`, a line the text has and a column from 1, in that order at its start.
/// Gives whether it was an error.
fn ok_or_located_error(text: &str) -> bool {
    match parse_str(text, Path::new("t.pbrt")) {
        Ok(_) => false,
        Err(e @ acr_parser::Error::At { .. }) => {
            let acr_parser::Error::At { loc, .. } = &e else {
                unreachable!()
            };
            let (line, col) = loc.line_col();
            let lines = text.split('\n').count();
            assert!(
                (1..=lines).contains(&line) && col >= 1,
                "{text:?}: {line}:{col} is not in the text: {e}"
            );
            let shown = e.to_string();
            assert!(
                shown.starts_with(&format!("t.pbrt:{line}:{col}: ")),
                "{text:?}: {shown}"
            );
            true
        }
        Err(e) => panic!("{text:?}: an error with no place in the text: {e}"),
    }
}

#[test]
fn garbage_never_panics() {
    // Every prefix of a realistic scene, and some noise, gives Ok or a located error.
    let scene = "LookAt 0 0 5 0 0 0 0 1 0 Camera \"perspective\" \"float fov\" [45]\n\
                 WorldBegin AttributeBegin Material \"matte\" \"rgb Kd\" [.5 .5 .5]\n\
                 Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\n\
                 AttributeEnd WorldEnd\n";
    assert!(!ok_or_located_error(scene), "the whole scene parses");
    let mut errors = 0;
    for end in 0..=scene.len() {
        errors += usize::from(ok_or_located_error(&scene[..end]));
    }
    for noise in [
        "\u{0}\u{1}",
        "[[[[",
        "]]]",
        "\"",
        "#",
        "-",
        "+.e",
        "\u{feff}WorldBegin",
        "é",
    ] {
        errors += usize::from(ok_or_located_error(noise));
    }
    // Most prefixes end inside a directive: the check above ran on their errors.
    assert!(errors > scene.len() / 2, "only {errors} errors");
}

#[test]
fn a_trianglemesh_keeps_its_arrays_once_in_its_mesh_and_the_dump_is_unchanged() {
    // A 3x3 grid of vertices: 9 positions, 8 triangles, normals and uvs, longer than the 12
    // values the dump shows.
    let mut p = Vec::new();
    let mut uv = Vec::new();
    for y in 0..3 {
        for x in 0..3 {
            p.extend([x as f64 * 0.1, y as f64 * 0.3, 0.7]);
            uv.extend([x as f64 * 0.5, y as f64 * 0.5]);
        }
    }
    let mut ix = Vec::new();
    for y in 0..2 {
        for x in 0..2 {
            let v = y * 3 + x;
            ix.extend([v, v + 1, v + 4, v, v + 4, v + 3]);
        }
    }
    let join = |v: &[f64]| {
        v.iter()
            .map(|x| x.to_string())
            .collect::<Vec<_>>()
            .join(" ")
    };
    let n = [0.0, 0.0, 1.0].repeat(9);
    let text =
        format!(
        "WorldBegin\nShape \"trianglemesh\" \"point P\" [{}] \"normal N\" [{}] \"float uv\" [{}] \
         \"integer indices\" [{}]\nWorldEnd\n",
        join(&p),
        join(&n),
        join(&uv),
        ix.iter().map(|i: &i32| i.to_string()).collect::<Vec<_>>().join(" ")
    );
    let d = parse(&text);
    let shape = &d.shapes[0];
    let mesh = shape.mesh.as_ref().expect("a mesh");
    let p32: Vec<[f32; 3]> = p
        .chunks(3)
        .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32])
        .collect();
    assert_eq!(mesh.positions, p32);
    assert_eq!(
        mesh.indices,
        ix.iter().map(|&i| i as u32).collect::<Vec<_>>()
    );
    assert_eq!(mesh.normals.as_ref().map(Vec::len), Some(9));
    assert_eq!(mesh.uvs.as_ref().map(Vec::len), Some(9));
    // The parameters hold the first values alone, and print as the whole list did.
    let params = &shape.plugin.params;
    for (name, full) in [("P", p.len()), ("N", n.len()), ("uv", uv.len())] {
        let param = params.get(name).unwrap();
        assert_eq!(param.values.len(), 12, "{name}");
        let shown = param.to_string();
        assert!(
            shown.ends_with(&format!(" ... ({full} values)]")),
            "{shown}"
        );
    }
    assert_eq!(
        params.get("P").unwrap().to_string(),
        "point3 P = [0 0 0.7 0.1 0 0.7 0.2 0 0.7 0 0.3 0.7 ... (27 values)]"
    );
    assert_eq!(params.get("indices").unwrap().values.len(), 12);
    assert!(params
        .get("indices")
        .unwrap()
        .to_string()
        .ends_with("(24 values)]"));
    assert_eq!(d.unused_parameter_warnings().len(), 0);
}
