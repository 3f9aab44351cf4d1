//! Hit data: what the BVH returns, the `f32` shading point recomputed from it,
//! and the exact `f64` surface point, its barycentric derivatives and an
//! `f64` ray–triangle test for the derivative side.
//!
//! Model: a triangle `(p0, p1, p2)` with barycentrics `(b1, b2)`,
//! `p = (1 − b1 − b2)·p0 + b1·p1 + b2·p2` (see the crate conventions). World
//! positions are `world_from_object · p`; normals map by the inverse
//! transpose of the linear part. The geometric normal is the world-space
//! winding `normalize((P1 − P0) × (P2 − P0))` of the transformed vertices, so
//! a mirroring transform (negative determinant) keeps it consistent with the
//! front face of the placed triangle; when the mesh has vertex normals it is
//! flipped into the shading normal's hemisphere (pbrt-v4's convention). The
//! shading normal is the interpolated vertex normal, mapped to world space and
//! normalised; without vertex normals it is the geometric normal. Texture
//! coordinates interpolate the mesh's `uvs`, or are `(b1, b2)` without them.
//!
//! No parameters.

use glam::{Affine3A, DAffine3, DMat3, DVec3, Mat3A, Vec2, Vec3};

use crate::frame::Frame;
use crate::scene::{Mesh, Object, ObjectId};
use crate::sphere::MissTest;

/// A ray hit as the BVH reports it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// The object hit.
    pub object: ObjectId,
    /// Triangle index within the object's mesh (0 on an exact sphere).
    pub triangle: u32,
    /// Barycentric `b1` (first octahedral coordinate on an exact sphere,
    /// [`crate::sphere`]).
    pub b1: f32,
    /// Barycentric `b2` (second octahedral coordinate on an exact sphere).
    pub b2: f32,
    /// Ray parameter of the hit (distance in units of the ray's `dir`).
    pub t: f32,
    /// Index of the triangle in the static BVH's shading table, or
    /// `u32::MAX` for a hit on an instance (checked against `object` and
    /// `triangle` before use, so a stale index only costs the slower path).
    pub(crate) world_index: u32,
}

/// A shading point's texture coordinates, evaluated when a texture reads
/// them ([`TexCoords::get`]): a triangle's are known when the point is made;
/// an exact sphere's cost two inverse trigonometric functions, which
/// materials without an image texture never pay (`scenes/cornell-box.toml`'s
/// glass sphere reads none; measured 2.5–3 % of its render time in one pair
/// of runs, inside the noise in another).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TexCoords {
    /// Known coordinates.
    Uv(Vec2),
    /// A point of the exact unit sphere, object space: pbrt-v4's spherical
    /// coordinates of it ([`crate::sphere::uv`]).
    Sphere(Vec3),
}

impl TexCoords {
    /// The coordinates.
    #[inline]
    pub fn get(self) -> Vec2 {
        match self {
            TexCoords::Uv(uv) => uv,
            TexCoords::Sphere(p) => crate::sphere::uv(p),
        }
    }
}

impl From<Vec2> for TexCoords {
    fn from(uv: Vec2) -> Self {
        TexCoords::Uv(uv)
    }
}

/// A shading point in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Position, world space.
    pub p: Vec3,
    /// Unit geometric normal, world space (front face by winding; flipped into
    /// the shading normal's hemisphere when the mesh has vertex normals).
    pub ng: Vec3,
    /// Texture coordinates, evaluated when read.
    pub uv: TexCoords,
    /// The shading frame, world space: `Frame::from_normal` of the unit
    /// shading normal `frame.n` ([`SurfacePoint::ns`]; made once per triangle
    /// in the static shading table where that normal is constant).
    pub frame: Frame,
}

impl SurfacePoint {
    /// Unit shading normal, world space (the frame's normal).
    #[inline(always)]
    pub fn ns(&self) -> Vec3 {
        self.frame.n
    }
}

/// An object's placement in `f32`: the world transform and the matrix that
/// maps object-space normals to world space (inverse transpose).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Placement {
    /// Object → world.
    pub world_from_object: Affine3A,
    /// World → object.
    pub object_from_world: Affine3A,
    /// Object-space normal → world-space normal (not normalised).
    pub normal_from_object: Mat3A,
    /// The world-space miss test of the unit sphere so placed (for objects
    /// that are exact spheres).
    pub sphere: MissTest,
}

impl Placement {
    /// The identity placement.
    pub const IDENTITY: Self = Self {
        world_from_object: Affine3A::IDENTITY,
        object_from_world: Affine3A::IDENTITY,
        normal_from_object: Mat3A::IDENTITY,
        sphere: MissTest::UNIT,
    };

    /// The `f32` placement of `world_from_object`; `None` when the transform
    /// is singular or not finite.
    pub fn new(world_from_object: &DAffine3) -> Option<Self> {
        let det = world_from_object.matrix3.determinant();
        if !(det.is_finite() && det != 0.0 && world_from_object.translation.is_finite()) {
            return None;
        }
        let inverse = world_from_object.inverse();
        let placement = Self {
            world_from_object: world_from_object.as_affine3a(),
            object_from_world: inverse.as_affine3a(),
            normal_from_object: inverse.matrix3.transpose().as_mat3().into(),
            sphere: MissTest::new(world_from_object),
        };
        let finite = placement.object_from_world.is_finite()
            && placement.world_from_object.is_finite()
            && placement.normal_from_object.is_finite();
        finite.then_some(placement)
    }
}

/// The shading point of triangle `triangle` of `mesh` at `(b1, b2)`, placed by
/// `placement`. All normals unit and finite. Always inlined (see
/// `tracer::render_tile_avx2`).
#[inline(always)]
pub(crate) fn surface_point(
    mesh: &Mesh,
    placement: &Placement,
    triangle: u32,
    b1: f32,
    b2: f32,
) -> SurfacePoint {
    let [i0, i1, i2] = mesh.indices[triangle as usize].map(|i| i as usize);
    let b0 = 1.0 - b1 - b2;
    let lerp3 = |a: Vec3, b: Vec3, c: Vec3| b0 * a + b1 * b + b2 * c;
    let [p0, p1, p2] = mesh
        .triangle(triangle)
        .map(|p| placement.world_from_object.transform_point3(p));
    let p = lerp3(p0, p1, p2);
    let mut ng = unit_winding(p1 - p0, p2 - p0);
    let ns = if mesh.normals.is_empty() {
        ng
    } else {
        let n = lerp3(mesh.normals[i0], mesh.normals[i1], mesh.normals[i2]);
        let ns = (placement.normal_from_object * n)
            .try_normalize()
            .unwrap_or(ng);
        if ng.dot(ns) < 0.0 {
            ng = -ng;
        }
        ns
    };
    SurfacePoint {
        p,
        ng,
        uv: TexCoords::Uv(texture_uv(mesh, triangle, b1, b2)),
        frame: Frame::from_normal(ns),
    }
}

/// The shading point of the exact unit sphere at octahedral coordinates
/// `(b1, b2)` ([`crate::sphere`]), placed by `placement`: the normal is the
/// placed sphere's (outward), geometric and shading alike.
#[inline(always)]
pub(crate) fn sphere_point(placement: &Placement, b1: f32, b2: f32) -> SurfacePoint {
    let local = crate::sphere::point([f64::from(b1), f64::from(b2)]).as_vec3();
    let n = (placement.normal_from_object * local)
        .try_normalize()
        .unwrap_or(local);
    SurfacePoint {
        p: placement.world_from_object.transform_point3(local),
        ng: n,
        uv: TexCoords::Sphere(local),
        frame: Frame::from_normal(n),
    }
}

/// The texture coordinates of `triangle` of `mesh` at `(b1, b2)`: the
/// interpolated `uvs`, or `(b1, b2)` without them.
#[inline(always)]
fn texture_uv(mesh: &Mesh, triangle: u32, b1: f32, b2: f32) -> Vec2 {
    if mesh.uvs.is_empty() {
        return Vec2::new(b1, b2);
    }
    let uvs = mesh.indices[triangle as usize].map(|i| mesh.uvs[i as usize]);
    interpolate_uv(uvs, b1, b2)
}

/// Texture coordinates `uvs` of a triangle's three vertices interpolated at
/// `(b1, b2)`.
#[inline(always)]
pub(crate) fn interpolate_uv([uv0, uv1, uv2]: [Vec2; 3], b1: f32, b2: f32) -> Vec2 {
    (1.0 - b1 - b2) * uv0 + b1 * uv1 + b2 * uv2
}

/// `normalize(e1 × e2)` in `f32`, or in `f64` when the cross product
/// underflows or overflows `f32`; `+z` for a degenerate triangle.
#[inline]
fn unit_winding(e1: Vec3, e2: Vec3) -> Vec3 {
    let w = e1.cross(e2);
    let len2 = w.length_squared();
    if (f32::MIN_POSITIVE..f32::MAX).contains(&len2) {
        w / len2.sqrt()
    } else {
        let w = e1.as_dvec3().cross(e2.as_dvec3());
        w.try_normalize().unwrap_or(DVec3::Z).as_vec3()
    }
}

/// The exact surface point of a triangle at `(b1, b2)` and its derivatives
/// with respect to the barycentrics, world space, `f64`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint64 {
    /// Position, world space.
    pub p: DVec3,
    /// Unit geometric normal (world winding; flipped into the shading normal's
    /// hemisphere when the mesh has vertex normals).
    pub ng: DVec3,
    /// Unit shading normal (the geometric normal without vertex normals).
    pub ns: DVec3,
    /// `∂p/∂b1 = W·(p1 − p0)`.
    pub dp_db1: DVec3,
    /// `∂p/∂b2 = W·(p2 − p0)`.
    pub dp_db2: DVec3,
    /// `∂ns/∂b1` of the normalised interpolated normal (zero without vertex normals).
    pub dns_db1: DVec3,
    /// `∂ns/∂b2` of the normalised interpolated normal (zero without vertex normals).
    pub dns_db2: DVec3,
}

/// An `f64` ray–plane hit with the triangle's barycentrics (not range-limited:
/// values outside `[0, 1]` tell how far outside the triangle the ray passes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit64 {
    /// Ray parameter, in units of the ray's `dir`.
    pub t: f64,
    /// Barycentric `b1`.
    pub b1: f64,
    /// Barycentric `b2`.
    pub b2: f64,
}

/// World-space vertices of `triangle` of `object`, `f64`.
fn world_triangle64(object: &Object, triangle: u32) -> [DVec3; 3] {
    object
        .mesh
        .triangle(triangle)
        .map(|p| object.world_from_object.transform_point3(p.as_dvec3()))
}

/// The exact surface point of `triangle` of `object` at `(b1, b2)` with its
/// barycentric derivatives, from `object.world_from_object` in `f64`.
///
/// # Panics
/// If `triangle` is not a triangle of the object's mesh (an exact sphere
/// has none: `epsm-core` parameterises those itself).
pub fn surface_point_f64(object: &Object, triangle: u32, b1: f64, b2: f64) -> SurfacePoint64 {
    let mesh = &object.mesh;
    let [q0, q1, q2] = world_triangle64(object, triangle);
    let b0 = 1.0 - b1 - b2;
    let p = b0 * q0 + b1 * q1 + b2 * q2;
    let (dp_db1, dp_db2) = (q1 - q0, q2 - q0);
    let mut ng = dp_db1.cross(dp_db2).try_normalize().unwrap_or(DVec3::Z);
    // Flat shading: no vertex normals, or normals that cancel at this point.
    let flat = SurfacePoint64 {
        p,
        ng,
        ns: ng,
        dp_db1,
        dp_db2,
        dns_db1: DVec3::ZERO,
        dns_db2: DVec3::ZERO,
    };
    if mesh.normals.is_empty() {
        return flat;
    }
    let normal_from_object: DMat3 = object.world_from_object.matrix3.inverse().transpose();
    let [n0, n1, n2] = mesh.indices[triangle as usize]
        .map(|i| normal_from_object * mesh.normals[i as usize].as_dvec3());
    let m = b0 * n0 + b1 * n1 + b2 * n2;
    let len = m.length();
    if !(len > 0.0 && len.is_finite()) {
        return flat;
    }
    let ns = m / len;
    // d(m/|m|) = (I − ns nsᵀ)·dm / |m|
    let project = |dm: DVec3| (dm - ns * ns.dot(dm)) / len;
    if ng.dot(ns) < 0.0 {
        ng = -ng;
    }
    SurfacePoint64 {
        p,
        ng,
        ns,
        dp_db1,
        dp_db2,
        dns_db1: project(n1 - n0),
        dns_db2: project(n2 - n0),
    }
}

/// `f64` Möller–Trumbore of the world-space ray `origin + t·dir` against
/// `triangle` of `object` (placed by `object.world_from_object`), with no
/// range limits on `t` or the barycentrics; `None` only when the ray is
/// parallel to the triangle's plane (or the triangle is degenerate).
///
/// # Panics
/// If `triangle` is not a triangle of the object's mesh.
pub fn intersect_triangle_f64(
    object: &Object,
    triangle: u32,
    origin: DVec3,
    dir: DVec3,
) -> Option<TriangleHit64> {
    let [q0, q1, q2] = world_triangle64(object, triangle);
    let (e1, e2) = (q1 - q0, q2 - q0);
    let pvec = dir.cross(e2);
    let det = e1.dot(pvec);
    if !(det != 0.0 && det.is_finite()) {
        return None;
    }
    let inv = 1.0 / det;
    let s = origin - q0;
    let qvec = s.cross(e1);
    let hit = TriangleHit64 {
        t: e2.dot(qvec) * inv,
        b1: s.dot(pvec) * inv,
        b2: dir.dot(qvec) * inv,
    };
    (hit.t.is_finite() && hit.b1.is_finite() && hit.b2.is_finite()).then_some(hit)
}
