//! World-space shading data of the static triangles, computed once when the
//! static BVH is built, so a hit on static geometry costs no transform and no
//! index lookups: position, unit geometric normal, shading normal and frame
//! and texture coordinates come from one record.
//!
//! Model: the same as `hit::surface_point` (see the `hit` module), on
//! the world-space vertices of the static BVH (transformed in `f64`, rounded
//! to `f32` once). The unit geometric normal is the `f64` winding
//! `normalize((P1 − P0) × (P2 − P0))` rounded to `f32`. Vertex normals are
//! mapped to world space by the inverse transpose in `f64` and stored
//! unnormalised; when all three are equal (flat faces such as the built-in
//! rectangles), or without vertex normals, the shading normal is the same
//! over the triangle and its shading frame (`Frame::from_normal`, the same
//! value the hit would make) is stored instead, with the geometric normal
//! flipped into its hemisphere up front.
//!
//! No parameters.

use glam::{DMat3, DVec3, Vec2, Vec3};

use crate::frame::Frame;
use crate::hit::{self, SurfacePoint, TexCoords};
use crate::scene::Object;

/// How a static triangle's shading normal is found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Normals {
    /// The same unit shading normal over the whole triangle (the geometric
    /// normal without vertex normals, or three equal vertex normals): its
    /// shading frame, `Frame::from_normal(ns)`, made once.
    Flat(Frame),
    /// `n0` and the differences `n1 − n0`, `n2 − n0` of the world-space
    /// vertex normals (unnormalised): `normalize(n0 + b1·d1 + b2·d2)`.
    Interpolated([Vec3; 3]),
}

/// One static triangle's world-space shading data.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ShadingTriangle {
    /// First vertex.
    pub(super) p0: Vec3,
    /// `p1 − p0`.
    pub(super) e1: Vec3,
    /// `p2 − p0`.
    pub(super) e2: Vec3,
    /// Unit geometric normal (already flipped toward a constant shading
    /// normal).
    pub(super) ng: Vec3,
    pub(super) normals: Normals,
    /// The three vertices' texture coordinates, when the mesh has them
    /// (interpolated at the hit by [`hit::interpolate_uv`]; without them the
    /// texture coordinates are `(b1, b2)`).
    pub(super) uvs: Option<[Vec2; 3]>,
}

impl ShadingTriangle {
    /// The shading data of `triangle` of `object`, whose world-space vertices
    /// are `world` (`f64`) and whose normals map to world space by
    /// `normal_from_object`.
    pub fn new(
        object: &Object,
        normal_from_object: &DMat3,
        triangle: u32,
        world: [DVec3; 3],
    ) -> Self {
        let mesh = &object.mesh;
        let [p0, p1, p2] = world.map(|p| p.as_vec3());
        let mut ng = (world[1] - world[0])
            .cross(world[2] - world[0])
            .try_normalize()
            .unwrap_or(DVec3::Z)
            .as_vec3();
        let normals = if mesh.normals.is_empty() {
            Normals::Flat(Frame::from_normal(ng))
        } else {
            let [n0, n1, n2] = mesh.indices[triangle as usize]
                .map(|i| (*normal_from_object * mesh.normals[i as usize].as_dvec3()).as_vec3());
            if n0 == n1 && n1 == n2 {
                match n0.try_normalize() {
                    Some(ns) => {
                        if ng.dot(ns) < 0.0 {
                            ng = -ng;
                        }
                        Normals::Flat(Frame::from_normal(ns))
                    }
                    None => Normals::Flat(Frame::from_normal(ng)),
                }
            } else {
                Normals::Interpolated([n0, n1 - n0, n2 - n0])
            }
        };
        Self {
            p0,
            e1: p1 - p0,
            e2: p2 - p0,
            ng,
            normals,
            uvs: (!mesh.uvs.is_empty())
                .then(|| mesh.indices[triangle as usize].map(|i| mesh.uvs[i as usize])),
        }
    }

    /// The shading point at `(b1, b2)`.
    #[inline(always)]
    pub fn point(&self, b1: f32, b2: f32) -> SurfacePoint {
        let p = self.p0 + b1 * self.e1 + b2 * self.e2;
        let (ng, frame) = match self.normals {
            Normals::Flat(frame) => (self.ng, frame),
            Normals::Interpolated([n0, d1, d2]) => {
                let ns = (n0 + b1 * d1 + b2 * d2).try_normalize().unwrap_or(self.ng);
                let ng = if self.ng.dot(ns) < 0.0 {
                    -self.ng
                } else {
                    self.ng
                };
                (ng, Frame::from_normal(ns))
            }
        };
        let uv = match self.uvs {
            Some(uvs) => hit::interpolate_uv(uvs, b1, b2),
            None => Vec2::new(b1, b2),
        };
        SurfacePoint {
            p,
            ng,
            uv: TexCoords::Uv(uv),
            frame,
        }
    }
}
