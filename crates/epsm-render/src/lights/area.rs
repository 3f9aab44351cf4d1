//! Area lights: emissive objects, sampled uniformly by area.
//!
//! An object with `emission` emits that radiance (W·sr⁻¹·m⁻²) from the front
//! face of every triangle, the side of the geometric normal
//! `normalize((P1 − P0) × (P2 − P0))` of the **world-space** vertices (so a
//! mirroring transform flips the emitting side with the winding, as the BVH
//! does). A triangle is chosen in proportion to its area and a point on it
//! uniformly (square-root parameterisation, pbrt-v4 §6.5.1), so the area
//! density is `1 / total area` of the object. Its power is
//! `mean(emission) · area · π`.
//!
//! | key | unit | default | range |
//! |---|---|---|---|
//! | `objects[i].emission` | linear RGB radiance | none | ≥ 0 per channel |
//!
//! ```toml
//! [[objects]]
//! name = "ceiling_light"
//! mesh = "meshes/quad.obj"
//! material = "white"
//! emission = [17.0, 12.0, 4.0]
//! ```

use glam::{Vec2, Vec3};

use super::distribution::Distribution1D;
use crate::scene::{Object, ObjectId};

/// The world-space emitting triangles of one object.
#[derive(Clone, Debug, PartialEq)]
pub struct AreaEmitter {
    /// The emissive object.
    pub object: ObjectId,
    /// Emitted radiance.
    pub emission: Vec3,
    /// The triangles, world space.
    triangles: Vec<EmitterTriangle>,
    /// Triangle choice by area; `None` when the object has no area.
    by_area: Option<Distribution1D>,
    /// Total world-space area.
    area: f64,
    /// `1 / area` (zero for a degenerate object), the density of [`Self::sample`].
    pdf_area: f64,
}

/// One world-space emitting triangle: what sampling a point on it reads,
/// in one record.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct EmitterTriangle {
    /// First vertex, `f32` (transformed in `f64`).
    pub(super) p0: Vec3,
    /// `p1 − p0` of the `f32` vertices.
    pub(super) e1: Vec3,
    /// `p2 − p0` of the `f32` vertices.
    pub(super) e2: Vec3,
    /// Unit front-face normal (zero for a degenerate triangle).
    pub(super) normal: Vec3,
}

/// A uniformly sampled point on an emitter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaPoint {
    /// Triangle index in the object's mesh.
    pub triangle: u32,
    /// Barycentric `b1`.
    pub b1: f32,
    /// Barycentric `b2`.
    pub b2: f32,
    /// World-space position.
    pub position: Vec3,
    /// Unit front-face normal.
    pub normal: Vec3,
}

impl AreaEmitter {
    /// Transforms the object's triangles to world space (in `f64`) and builds
    /// the area table.
    pub fn new(object_id: ObjectId, object: &Object, emission: Vec3) -> Self {
        let mesh = &object.mesh;
        let mut triangles = Vec::with_capacity(mesh.len());
        let mut areas = Vec::with_capacity(mesh.len());
        for tri in 0..mesh.len() as u32 {
            let [p0, p1, p2] = mesh
                .triangle(tri)
                .map(|p| object.world_from_object.transform_point3(p.as_dvec3()));
            let cross = (p1 - p0).cross(p2 - p0);
            let len = cross.length();
            areas.push(0.5 * len);
            let [p0, p1, p2] = [p0, p1, p2].map(|p| p.as_vec3());
            triangles.push(EmitterTriangle {
                p0,
                e1: p1 - p0,
                e2: p2 - p0,
                normal: if len > 0.0 {
                    (cross / len).as_vec3()
                } else {
                    Vec3::ZERO
                },
            });
        }
        let area = areas.iter().sum();
        Self {
            object: object_id,
            emission,
            triangles,
            by_area: Distribution1D::new(&areas),
            area,
            pdf_area: if area > 0.0 { 1.0 / area } else { 0.0 },
        }
    }

    /// Radiant power `mean(emission) · area · π` (W).
    pub fn power(&self) -> f64 {
        mean(self.emission) * self.area * std::f64::consts::PI
    }

    /// Area density `1 / area` (m⁻²) of [`Self::sample`] (zero for a
    /// degenerate object).
    pub fn pdf_area(&self) -> f64 {
        self.pdf_area
    }

    /// The world-space triangles, in mesh order.
    #[cfg(target_arch = "x86_64")]
    pub(super) fn triangles(&self) -> &[EmitterTriangle] {
        &self.triangles
    }

    /// The triangle choice by area (`None` when the object has no area).
    #[cfg(target_arch = "x86_64")]
    pub(super) fn by_area(&self) -> Option<&Distribution1D> {
        self.by_area.as_ref()
    }

    /// The unit front-face normal of `triangle`.
    pub fn normal(&self, triangle: u32) -> Vec3 {
        self.triangles[triangle as usize].normal
    }

    /// A uniform point on the object: `u_triangle` picks the triangle by area,
    /// `u` the point on it.
    #[inline(always)]
    pub fn sample(&self, u_triangle: f64, u: Vec2) -> Option<AreaPoint> {
        let pick = self.by_area.as_ref()?.sample_discrete(u_triangle);
        let tri = &self.triangles[pick.index];
        let su = u.x.sqrt();
        let (b1, b2) = (su * (1.0 - u.y), su * u.y);
        Some(AreaPoint {
            triangle: pick.index as u32,
            b1,
            b2,
            position: tri.p0 + b1 * tri.e1 + b2 * tri.e2,
            normal: tri.normal,
        })
    }
}

/// Mean of the three channels, in `f64`.
pub(super) fn mean(c: Vec3) -> f64 {
    (c.x as f64 + c.y as f64 + c.z as f64) / 3.0
}

/// Solid-angle density (sr⁻¹) at a reference point `p` of an area density
/// `pdf_area` (m⁻²) at the emitter point `y = p + d` with unit normal `n`:
/// `pdf_area · r² / |cos θ_light|` with `r = |d|`, computed in `f32` as
/// `pdf_area · r³ / |n · d|` (one square root and one division, which
/// overlap the light sample's other work). Zero when `p` lies in the
/// emitter's plane or on `y`. Callers check the emitting side.
#[inline(always)]
pub(super) fn solid_angle_pdf(pdf_area: f32, d: Vec3, n: Vec3) -> f32 {
    let dist2 = d.length_squared();
    let pdf = pdf_area * dist2 * dist2.sqrt() / n.dot(d).abs();
    // In the plane or on `y`, `n · d = 0` makes the quotient ∞ or NaN.
    if pdf < f32::INFINITY { pdf } else { 0.0 }
}

/// Whether a reference point `p` sees the emitting (front) side of a surface
/// with front normal `n` at `y = p + d`: `n · (p − y) > 0`, tested as
/// `n · d < 0` (the same products negated, so the same outcome).
#[inline(always)]
pub(super) fn in_front(d: Vec3, n: Vec3) -> bool {
    n.dot(d) < 0.0
}
