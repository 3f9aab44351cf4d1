//! Hit data: what the BVH returns, and the surface point recomputed from it.

use glam::{Vec2, Vec3};

use crate::scene::ObjectId;

/// A ray hit as the BVH reports it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// The object hit.
    pub object: ObjectId,
    /// Triangle index within the object's mesh.
    pub triangle: u32,
    /// Barycentric `b1`.
    pub b1: f32,
    /// Barycentric `b2`.
    pub b2: f32,
    /// Ray parameter of the hit.
    pub t: f32,
}

/// A shading point in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Position, world space.
    pub p: Vec3,
    /// Unit geometric normal, world space (front face by winding; flipped into
    /// the shading normal's hemisphere when the mesh has vertex normals).
    pub ng: Vec3,
    /// Unit shading normal, world space.
    pub ns: Vec3,
    /// Texture coordinates.
    pub uv: Vec2,
}
