//! Triangle meshes, from `trianglemesh` parameters or PLY files.

/// An indexed triangle mesh in the shape's object space.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Per-vertex shading normals, if given (same length as `positions`).
    pub normals: Option<Vec<[f32; 3]>>,
    /// Per-vertex texture coordinates, if given (same length as `positions`).
    pub uvs: Option<Vec<[f32; 2]>>,
    /// Three vertex indices per triangle; every index is below `positions.len()`.
    pub indices: Vec<u32>,
}

impl Mesh {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Checks the invariants: indices a multiple of 3 and in range, attribute lengths match.
    /// Returns a message describing the first violation.
    pub fn validate(&self) -> Result<(), String> {
        if self.indices.len() % 3 != 0 {
            return Err(format!(
                "mesh has {} vertex indices, not a multiple of 3",
                self.indices.len()
            ));
        }
        let n = self.positions.len();
        if let Some((i, &bad)) = self
            .indices
            .iter()
            .enumerate()
            .find(|&(_, &v)| v as usize >= n)
        {
            return Err(format!(
                "vertex index {bad} (index #{i}) is out of range: the mesh has {n} vertices"
            ));
        }
        if let Some(normals) = &self.normals {
            if normals.len() != n {
                return Err(format!(
                    "mesh has {} normals for {n} vertices",
                    normals.len()
                ));
            }
        }
        if let Some(uvs) = &self.uvs {
            if uvs.len() != n {
                return Err(format!("mesh has {} uvs for {n} vertices", uvs.len()));
            }
        }
        if let Some(p) = self
            .positions
            .iter()
            .find(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(format!("vertex position {p:?} is not finite"));
        }
        Ok(())
    }
}
