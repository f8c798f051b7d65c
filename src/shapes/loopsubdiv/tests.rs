//! Loop subdivision's tests.

use super::*;
use crate::geometry::Ray;
use crate::scene::Scene;
use std::collections::HashMap;
use std::path::Path;

/// The regular octahedron |x| + |y| + |z| = 1, faces counter-clockwise seen from outside.
fn octahedron() -> (Vec<[f32; 3]>, Vec<u32>) {
    let p = vec![
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ];
    let i = vec![
        0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5,
    ];
    (p, i)
}

/// A tetrahedron, faces counter-clockwise seen from outside.
fn tetrahedron() -> (Vec<[f32; 3]>, Vec<u32>) {
    let p = vec![
        [1.0, 1.0, 1.0],
        [1.0, -1.0, -1.0],
        [-1.0, 1.0, -1.0],
        [-1.0, -1.0, 1.0],
    ];
    (p, vec![0, 1, 2, 0, 2, 3, 0, 3, 1, 1, 3, 2])
}

/// An n x n grid of unit squares in z = 0, two counter-clockwise triangles each.
fn grid(n: u32) -> (Vec<[f32; 3]>, Vec<u32>) {
    let mut p = Vec::new();
    for y in 0..=n {
        for x in 0..=n {
            p.push([x as f32, y as f32, 0.0]);
        }
    }
    let mut i = Vec::new();
    let at = |x: u32, y: u32| y * (n + 1) + x;
    for y in 0..n {
        for x in 0..n {
            // Alternate the diagonals so boundary valences vary.
            if (x + y) % 2 == 0 {
                i.extend([at(x, y), at(x + 1, y), at(x + 1, y + 1)]);
                i.extend([at(x, y), at(x + 1, y + 1), at(x, y + 1)]);
            } else {
                i.extend([at(x, y), at(x + 1, y), at(x, y + 1)]);
                i.extend([at(x + 1, y), at(x + 1, y + 1), at(x, y + 1)]);
            }
        }
    }
    (p, i)
}

fn subdivide(p: &[[f32; 3]], i: &[u32], levels: u32) -> Mesh {
    let mut w = Vec::new();
    let m = loop_subdivide(p, i, levels, &mut w).unwrap();
    assert!(w.is_empty(), "{w:?}");
    m.validate().unwrap();
    m
}

/// Every undirected edge is used by exactly two triangles, once in each direction.
fn assert_watertight(m: &Mesh) {
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for t in m.indices.chunks_exact(3) {
        for k in 0..3 {
            *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &directed {
        assert_eq!(n, 1, "edge {a}-{b} used {n} times in one direction");
        assert_eq!(directed.get(&(b, a)), Some(&1), "edge {a}-{b} has no twin");
    }
}

fn face_normal(m: &Mesh, t: &[u32]) -> Vec3 {
    let p = |i: u32| Vec3::from_array(m.positions[i as usize]);
    (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0]))
}

#[test]
fn closed_meshes_refine_into_watertight_limit_surfaces() {
    for (name, (p, i)) in [("octahedron", octahedron()), ("tetrahedron", tetrahedron())] {
        let faces = i.len() / 3;
        for levels in 0..=4 {
            let m = subdivide(&p, &i, levels);
            assert_eq!(m.triangle_count(), faces << (2 * levels), "{name} {levels}");
            // Euler characteristic 2: V = F / 2 + 2 for a closed triangle mesh.
            assert_eq!(m.positions.len(), m.triangle_count() / 2 + 2, "{name}");
            assert_watertight(&m);
            let normals = m.normals.as_ref().unwrap();
            assert_eq!(normals.len(), m.positions.len());
            for (&q, &n) in m.positions.iter().zip(normals) {
                let (q, n) = (Vec3::from_array(q), Vec3::from_array(n));
                assert!(q.is_finite() && n.is_finite(), "{name}: {q} {n}");
                // Inside the convex hull of the control mesh (the faces' planes).
                for t in i.chunks_exact(3) {
                    let a = Vec3::from_array(p[t[0] as usize]);
                    let fn_ = (Vec3::from_array(p[t[1] as usize]) - a)
                        .cross(Vec3::from_array(p[t[2] as usize]) - a);
                    assert!((q - a).dot(fn_) <= 1e-5, "{name} {levels}: {q} outside");
                }
                // pbrt-v3's limit normals point into a counter-clockwise closed mesh
                // (its one-ring runs clockwise); the centre is the origin.
                assert!(n.length() > 0.0 && n.normalize().dot(q.normalize()) < -0.5);
            }
            // Triangles keep the orientation of the control mesh.
            for t in m.indices.chunks_exact(3) {
                let c = t
                    .iter()
                    .map(|&v| Vec3::from_array(m.positions[v as usize]))
                    .sum::<Vec3>();
                assert!(face_normal(&m, t).dot(c) > 0.0);
            }
        }
    }
}

#[test]
fn limit_positions_follow_pbrt_weights() {
    // Octahedron vertices have valence 4: beta = 3/32, gamma = 1/(4 + 4) = 1/8, so the
    // limit of (1, 0, 0) is (1 - 4/8) (1, 0, 0) + 1/8 (sum of its ring = 0) = (0.5, 0, 0).
    let (p, i) = octahedron();
    let m0 = subdivide(&p, &i, 0);
    assert_eq!(m0.positions[0], [0.5, 0.0, 0.0]);
    // The limit point of an original vertex does not depend on the level.
    for levels in 1..=3 {
        let m = subdivide(&p, &i, levels);
        for (a, b) in m0.positions.iter().zip(&m.positions) {
            assert!((Vec3::from_array(*a) - Vec3::from_array(*b)).length() < 1e-5);
        }
    }
    // One level by hand: the even vertex (1, 0, 0) moves to (1 - 4 beta) (1, 0, 0) = 5/8,
    // the odd vertex of edge 0-2 to 3/8 (1, 0, 0) + 3/8 (0, 1, 0) + 1/8 (z + -z) =
    // (3/8, 3/8, 0); its limit (valence 6, gamma = 1/12) is (1/2) itself + 1/12 ring.
    let m1 = subdivide(&p, &i, 1);
    assert_eq!(m1.positions.len(), 18);
    let q = Vec3::from_array(m1.positions[0]);
    // Even (5/8, 0, 0), ring: four odd vertices (3/8, +-3/8, 0), (3/8, 0, +-3/8);
    // gamma(4) = 1/8: (1 - 1/2) 5/8 + 1/8 * 4 * 3/8 = 5/16 + 3/16 = 1/2.
    assert!((q - Vec3::new(0.5, 0.0, 0.0)).length() < 1e-6, "{q}");
}

#[test]
fn planar_patch_stays_planar_with_z_normals() {
    let (p, i) = grid(3);
    for levels in 0..=3 {
        let m = subdivide(&p, &i, levels);
        assert_eq!(m.triangle_count(), 18 << (2 * levels));
        let normals = m.normals.as_ref().unwrap();
        let mut sign = 0.0f32;
        for (&q, &n) in m.positions.iter().zip(normals) {
            assert_eq!(q[2], 0.0);
            assert!(
                (0.0..=3.0).contains(&q[0]) && (0.0..=3.0).contains(&q[1]),
                "{q:?}"
            );
            let n = Vec3::from_array(n);
            assert!(n.z != 0.0, "{q:?}: {n}");
            assert!(n.x.abs() <= 1e-5 * n.z.abs() && n.y.abs() <= 1e-5 * n.z.abs());
            if sign == 0.0 {
                sign = n.z.signum();
            }
            assert_eq!(n.z.signum(), sign, "normals disagree at {q:?}");
        }
        // As for closed meshes, opposite to the counter-clockwise faces' normal (+z).
        assert_eq!(sign, -1.0);
        for t in m.indices.chunks_exact(3) {
            assert!(face_normal(&m, t).z > 0.0);
        }
    }
}

#[test]
fn bad_inputs_are_errors_not_panics() {
    let (p, i) = octahedron();
    let mut w = Vec::new();
    let err = |p: &[[f32; 3]], i: &[u32], levels: u32| match loop_subdivide(
        p,
        i,
        levels,
        &mut Vec::new(),
    ) {
        Ok(m) => panic!("no error ({} triangles)", m.triangle_count()),
        Err(e) => e,
    };
    assert!(err(&p, &i[..7], 1).contains("multiple of 3"));
    assert!(err(&p, &[0, 1, 6], 1).contains("out of range"));
    assert!(err(&p, &i, 11).contains("too many"));
    let (gp, gi) = grid(6);
    assert!(err(&gp, &gi, MAX_LEVELS as u32).contains("triangles"));
    let mut nan = p.clone();
    nan[3][1] = f32::NAN;
    assert!(err(&nan, &i, 1).contains("not finite"));
    // Three faces on the edge 0-1.
    let q = [
        [0.0; 3],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    assert!(err(&q, &[0, 1, 2, 1, 0, 3, 0, 1, 4], 1).contains("more than two faces"));
    // Two faces through edge 0-1 the same way.
    assert!(err(&q, &[0, 1, 2, 0, 1, 3], 1).contains("oriented"));
    // A repeated vertex: the face is skipped, with a warning.
    let m = loop_subdivide(&q, &[0, 1, 2, 0, 0, 3], 1, &mut w).unwrap();
    assert_eq!(m.triangle_count(), 4);
    assert_eq!(w.len(), 2, "{w:?}"); // the face, and vertex 3 now unused
                                     // Nothing at all.
    let m = loop_subdivide(&[], &[], 3, &mut w).unwrap();
    assert_eq!(m.triangle_count(), 0);
    // Two fans meeting at one vertex (a bow tie): subdivided, with a warning.
    let bow = [
        [0.0; 3],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 0.0, 0.0],
        [-1.0, -1.0, 0.0],
    ];
    w.clear();
    let m = loop_subdivide(&bow, &[0, 1, 2, 0, 3, 4], 2, &mut w).unwrap();
    assert_eq!(m.triangle_count(), 32);
    assert!(w.iter().any(|m| m.contains("fans")), "{w:?}");
    m.validate().unwrap();
}

#[test]
fn random_meshes_never_panic() {
    let mut rng = crate::shapes::test_util::Rng::new(11);
    for _ in 0..500 {
        let nv = 3 + (rng.f() * 8.0) as usize;
        let p: Vec<[f32; 3]> = (0..nv).map(|_| rng.v3().to_array()).collect();
        let nf = 1 + (rng.f() * 12.0) as usize;
        let i: Vec<u32> = (0..3 * nf).map(|_| (rng.f() * nv as f32) as u32).collect();
        if let Ok(m) = loop_subdivide(&p, &i, 2, &mut Vec::new()) {
            m.validate().unwrap();
            assert!(m.positions.iter().flatten().all(|c| c.is_finite()));
        }
    }
}

/// A scene with the camera at the world origin: render space is then world space.
fn scene(shape: &str) -> acr_parser::SceneDescription {
    let text = format!(
        "LookAt 0 0 0  0 0 -1  0 1 0\nCamera \"perspective\"\nWorldBegin\n{shape}\nWorldEnd\n"
    );
    acr_parser::parse_str(&text, Path::new("/tmp/loop.pbrt")).unwrap()
}

const OCTAHEDRON: &str = "\"point P\" [1 0 0 -1 0 0 0 1 0 0 -1 0 0 0 1 0 0 -1] \
     \"integer indices\" [0 2 4 2 1 4 1 3 4 3 0 4 2 0 5 1 2 5 3 1 5 0 3 5]";

#[test]
fn loopsubdiv_shapes_render_as_triangle_meshes() {
    let desc = scene(&format!(
        "Shape \"loopsubdiv\" \"integer nlevels\" [2] \"string scheme\" \"loop\" {OCTAHEDRON}"
    ));
    let mut w = Vec::new();
    let s = Scene::build(&desc, &mut w).unwrap();
    assert!(w.is_empty(), "{w:?}");
    // The limit point of the vertex (0, 0, 1) is (0, 0, 0.5), and the surface is smooth
    // there. Both directions must hit: -Vec3::Z has -0.0 components, which obvhs's
    // traversal once missed.
    let ray = |d: Vec3| Ray::new(Vec3::new(0.0, 0.0, 5.0), d, 0.0);
    assert!(s.intersect(&ray(-Vec3::Z)).is_some(), "-0.0 components");
    let hit = s
        .intersect(&ray(Vec3::new(0.0, 0.0, -1.0)))
        .expect("the ray hits the subdivided octahedron");
    assert!(
        (hit.si.p - Vec3::new(0.0, 0.0, 0.5)).length() < 1e-4,
        "{}",
        hit.si.p
    );
    assert!(hit.si.shading_n.z.abs() > 0.999, "{}", hit.si.shading_n);
    // Default levels (3) and "levels" winning over "nlevels", as in pbrt-v3.
    let params = |shape: &str| scene(shape).shapes[0].plugin.clone();
    for (shape, tris) in [
        (format!("Shape \"loopsubdiv\" {OCTAHEDRON}"), 8 * 64),
        (
            format!(
                "Shape \"loopsubdiv\" \"integer levels\" [1] \"integer nlevels\" [4] \
                 {OCTAHEDRON}"
            ),
            8 * 4,
        ),
    ] {
        let p = params(&shape);
        let m = mesh_from_params(&p.params, &p.loc, &mut w).unwrap();
        assert_eq!(m.triangle_count(), tris);
    }
}

#[test]
fn loopsubdiv_parameter_errors_point_at_the_parameter() {
    let line_col = |shape: &str| {
        let desc = scene(shape);
        match Scene::build(&desc, &mut Vec::new()) {
            Err(Error::At { loc, message }) => (loc.line_col(), message),
            Err(e) => panic!("{e}"),
            Ok(_) => panic!("no error for {shape}"),
        }
    };
    let ((line, col), m) = line_col(&format!(
        "Shape \"loopsubdiv\" \"integer nlevels\" [11] {OCTAHEDRON}"
    ));
    assert_eq!((line, col), (4, 20), "{m}");
    assert!(m.contains("nlevels"), "{m}");
    let (_, m) = line_col(&format!(
        "Shape \"loopsubdiv\" \"integer levels\" [-1] {OCTAHEDRON}"
    ));
    assert!(m.contains("levels"), "{m}");
    let ((_, col), m) = line_col(
        "Shape \"loopsubdiv\" \"point P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 3]",
    );
    assert!(m.contains("out of range"), "{m}");
    assert_eq!(col, 50, "{m}");
    let (_, m) = line_col(
        "Shape \"loopsubdiv\" \"point P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 -2]",
    );
    assert!(m.contains("negative"), "{m}");
    let ((_, col), m) = line_col(
        "Shape \"loopsubdiv\" \"point P\" [0 0 0 1 0 0 0 1 1e39] \"integer indices\" [0 1 2]",
    );
    assert!(m.contains("not finite"), "{m}");
    assert_eq!(col, 20, "{m}");
    let (_, m) = line_col("Shape \"loopsubdiv\" \"integer indices\" [0 1 2]");
    assert!(m.contains("\"point3 P\""), "{m}");
    let (_, m) = line_col("Shape \"loopsubdiv\" \"point P\" [0 0 0 1 0 0 0 1 0]");
    assert!(m.contains("indices"), "{m}");
}
