//! A subpath's vertices kept from path to path: the slots past the path's length keep their
//! storage, so that a surface vertex's interaction (about 0.2 kB) and BSDF (about 0.7 kB, held
//! by value) are written in place where they were built, moved into its vertex and moved into
//! the list for every vertex of every path (docs/light-transport.md, `## bdpt`).

use super::vertex::{SurfacePoint, Vertex, VertexKind};
use crate::bsdf::Bsdf;
use crate::geometry::{Spectrum, SurfaceInteraction, Vec3};
use crate::material::Material;
use crate::medium::MediumInterface;
use std::ops::{Deref, DerefMut};

/// The vertices of a camera or light subpath; it reads as the slice of its vertices.
#[derive(Clone, Debug, Default)]
pub struct Subpath {
    /// The vertices, then slots kept from longer paths.
    slots: Vec<Vertex>,
    /// How many of `slots` are the path's.
    len: usize,
}

impl Subpath {
    /// An empty subpath.
    pub const fn new() -> Self {
        Self {
            slots: Vec::new(),
            len: 0,
        }
    }

    /// Empties it, keeping the slots.
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Appends `v`.
    pub fn push(&mut self, v: Vertex) {
        if self.len < self.slots.len() {
            self.slots[self.len] = v;
        } else {
            self.slots.push(v);
        }
        self.len += 1;
    }

    /// Appends [`Vertex::endpoint`]'s vertex, written field by field into a kept slot; returns
    /// it.
    pub fn push_endpoint(
        &mut self,
        kind: VertexKind,
        (p, n, time): (Vec3, Vec3, f32),
        beta: Spectrum,
        light: Option<u32>,
    ) -> &mut Vertex {
        if self.len < self.slots.len() {
            self.slots[self.len].make_endpoint(kind, (p, n, time), beta, light);
        } else {
            self.slots
                .push(Vertex::endpoint(kind, p, n, time, beta, light));
        }
        self.len += 1;
        &mut self.slots[self.len - 1]
    }

    /// The interaction of the vertex that comes next, for the walk to write the hit into and
    /// shade in place; [`Subpath::push_surface`] makes it a vertex (else it is not one).
    pub fn next_interaction(&mut self) -> &mut SurfaceInteraction {
        if self.len == self.slots.len() {
            let at = (Vec3::ZERO, Vec3::ZERO, 0.0);
            self.slots.push(Vertex::endpoint(
                VertexKind::Surface,
                at.0,
                at.1,
                at.2,
                Spectrum::ZERO,
                None,
            ));
        }
        let point = self.slots[self.len].surface.get_or_insert_with(|| {
            let si = SurfaceInteraction::default();
            SurfacePoint {
                bsdf: Bsdf::new(&si, 1.0),
                si,
            }
        });
        &mut point.si
    }

    /// Appends the surface vertex at the (shaded) hit [`Subpath::next_interaction`] holds,
    /// with `material`'s BSDF refilled in place (none without one), reached from the last
    /// vertex with solid-angle density `pdf`.
    pub fn push_surface(
        &mut self,
        material: Option<&Material>,
        at: (Option<u32>, MediumInterface),
        beta: Spectrum,
        pdf: f32,
    ) {
        let n = self.len;
        debug_assert!(n > 0, "a surface vertex follows the subpath's start");
        let (done, rest) = self.slots.split_at_mut(n);
        rest[0].make_surface(material, at, beta, pdf, &done[n - 1]);
        self.len += 1;
    }
}

impl Deref for Subpath {
    type Target = [Vertex];

    fn deref(&self) -> &[Vertex] {
        &self.slots[..self.len]
    }
}

impl DerefMut for Subpath {
    fn deref_mut(&mut self) -> &mut [Vertex] {
        &mut self.slots[..self.len]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A kept slot reads as the vertex pushed, not as what it held before.
    #[test]
    fn a_kept_slot_reads_as_the_vertex_pushed() {
        let mut path = Subpath::new();
        let one = Spectrum::ONE;
        path.push_endpoint(VertexKind::Camera, (Vec3::X, Vec3::Z, 0.5), one, None);
        path.push_endpoint(VertexKind::Light, (Vec3::Y, Vec3::Y, 0.5), one, Some(3));
        assert_eq!(path.len(), 2);
        path.clear();
        assert!(path.is_empty());
        let v = path.push_endpoint(
            VertexKind::Light,
            (Vec3::Z, Vec3::X, 0.25),
            one * 2.0,
            Some(1),
        );
        v.pdf_fwd = 0.5;
        assert_eq!(path.len(), 1);
        let v = &path[0];
        assert_eq!(
            (v.kind, v.p, v.ng, v.ns),
            (VertexKind::Light, Vec3::Z, Vec3::X, Vec3::X)
        );
        assert_eq!(
            (v.time, v.beta, v.light, v.pdf_fwd),
            (0.25, one * 2.0, Some(1), 0.5)
        );
        assert!(v.surface.is_none() && v.phase.is_none());
    }
}
