//! Triangle meshes in object space.

use glam::{Vec2, Vec3};

/// An indexed triangle mesh in object space. Shared between objects through
/// `Arc`, so instancing a mesh costs no copy.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions, object space.
    pub positions: Vec<Vec3>,
    /// Unit per-vertex shading normals, object space; empty means flat shading
    /// (the geometric normal).
    pub normals: Vec<Vec3>,
    /// Per-vertex texture coordinates; empty means none (`uv = (b1, b2)`).
    pub uvs: Vec<Vec2>,
    /// Counter-clockwise triangles (front face by the right-hand rule).
    pub indices: Vec<[u32; 3]>,
}

impl Mesh {
    /// The three object-space positions of triangle `tri`.
    #[inline]
    pub fn triangle(&self, tri: u32) -> [Vec3; 3] {
        let [a, b, c] = self.indices[tri as usize];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// Number of triangles.
    #[inline]
    pub fn len(&self) -> usize {
        self.indices.len()
    }

    /// Whether the mesh has no triangles.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }
}
