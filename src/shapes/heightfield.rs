//! pbrt-v3's `heightfield` shape: `nu` x `nv` heights `Pz` over the unit square, made into a
//! triangle mesh exactly as pbrt-v3's `CreateHeightfield` does (vertex (x, y) at
//! (x / (nu - 1), y / (nv - 1), Pz), uv the same fractions, two triangles per cell).

use acr_parser::{Error, Loc, Mesh, ParamList, Result};

/// Most vertices a heightfield may have (a mesh's indices are 32-bit).
const MAX_VERTICES: i64 = 1 << 30;

/// The heightfield's mesh, or a located error for missing or inconsistent parameters.
pub fn mesh_from_params(params: &ParamList, loc: &Loc) -> Result<Mesh> {
    let at = |name: &str| {
        params
            .get(name)
            .map_or_else(|| loc.clone(), |p| p.loc.clone())
    };
    let nu = i64::from(params.int_or("nu", -1)?);
    let nv = i64::from(params.int_or("nv", -1)?);
    if nu < 2 || nv < 2 {
        let name = if nu < 2 { "nu" } else { "nv" };
        return Err(Error::at(
            &at(name),
            format!(
                "heightfield needs \"integer nu\" and \"nv\" of at least 2 (found {nu} x {nv})"
            ),
        ));
    }
    let Some(z) = params.floats("Pz")? else {
        return Err(Error::at(loc, "heightfield needs a \"float Pz\" parameter"));
    };
    // One height per vertex: a count that differs is the usual mistake, whatever nu and nv.
    if z.len() as i64 != nu * nv {
        return Err(Error::at(
            &at("Pz"),
            format!(
                "heightfield: Pz has {} values, but nu x nv = {nu} x {nv} = {} (one height per \
                 vertex)",
                z.len(),
                nu * nv
            ),
        ));
    }
    if nu * nv > MAX_VERTICES {
        return Err(Error::at(
            &at("nu"),
            format!(
                "heightfield: nu x nv = {nu} x {nv} = {} vertices, more than {MAX_VERTICES}",
                nu * nv
            ),
        ));
    }
    let (nx, ny) = (nu as u32, nv as u32);
    let mut positions = Vec::with_capacity(z.len());
    let mut uvs = Vec::with_capacity(z.len());
    for y in 0..ny {
        for x in 0..nx {
            let (u, v) = (x as f32 / (nx - 1) as f32, y as f32 / (ny - 1) as f32);
            positions.push([u, v, z[(y * nx + x) as usize] as f32]);
            uvs.push([u, v]);
        }
    }
    let vert = |x: u32, y: u32| x + y * nx;
    let mut indices = Vec::with_capacity(6 * (nx as usize - 1) * (ny as usize - 1));
    for y in 0..ny - 1 {
        for x in 0..nx - 1 {
            indices.extend([vert(x, y), vert(x + 1, y), vert(x + 1, y + 1)]);
            indices.extend([vert(x, y), vert(x + 1, y + 1), vert(x, y + 1)]);
        }
    }
    Ok(Mesh {
        positions,
        normals: None,
        uvs: Some(uvs),
        indices,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shape_params(text: &str) -> (ParamList, Loc) {
        super::super::test_util::shape_params(text, "h.pbrt")
    }

    #[test]
    fn a_grid_of_heights_becomes_pbrt_v3_s_triangles() {
        let (p, loc) = shape_params(
            r#"Shape "heightfield" "integer nu" 3 "integer nv" 2 "float Pz" [0 1 2 3 4 5]"#,
        );
        let m = mesh_from_params(&p, &loc).unwrap();
        assert_eq!(m.positions.len(), 6);
        assert_eq!(m.positions[4], [0.5, 1.0, 4.0]);
        assert_eq!(m.uvs.as_ref().unwrap()[5], [1.0, 1.0]);
        assert_eq!(
            m.indices,
            vec![0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 4],
            "two triangles per cell, in pbrt-v3's order"
        );
        assert!(m.validate().is_ok());
    }

    #[test]
    fn missing_or_inconsistent_parameters_are_located_errors() {
        for (text, says) in [
            (
                r#"Shape "heightfield" "integer nu" 3 "float Pz" [0 1 2]"#,
                "nu",
            ),
            (r#"Shape "heightfield" "integer nu" 2 "integer nv" 2"#, "Pz"),
            (
                r#"Shape "heightfield" "integer nu" 2 "integer nv" 2 "float Pz" [0 1 2]"#,
                "Pz has 3 values, but nu x nv = 2 x 2 = 4",
            ),
            // Large counts with too few heights: the heights are the cause, not nu or nv.
            (
                r#"Shape "heightfield" "integer nu" 100000 "integer nv" 100000 "float Pz" [0 1 2]"#,
                "Pz has 3 values, but nu x nv = 100000 x 100000 = 10000000000",
            ),
        ] {
            let (p, loc) = shape_params(text);
            let e = mesh_from_params(&p, &loc).unwrap_err();
            assert!(e.to_string().contains(says), "{e}");
            assert!(e.to_string().contains("h.pbrt:1:"), "{e}");
        }
    }
}
