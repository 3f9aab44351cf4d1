//! Tangent parameterisation of a path vertex on a surface: a triangle or an
//! exact sphere (docs/design.md §5.1).
//!
//! Units and frames: object-space points and normals of the object's
//! [`Surface`]; world-space results through the placement `M(θ)` (linear
//! part `L`, normal matrix `N = L⁻ᵀ`); `u` is in world scene units at θ₀.
//!
//! At the base configuration θ₀ a vertex gets world tangents `T1, T2`: the
//! Duff basis of its world normal (the triangle's geometric normal, or the
//! placed sphere's normal `normalize(N·p)`), mapped to object space by
//! `L₀⁻¹ = N₀ᵀ`. Its object-space chart is `q(u) = p_obj + u1 T1_obj +
//! u2 T2_obj`:
//! - **Triangle**: the point is `q(u)` itself (its plane extends beyond the
//!   triangle's edges: fine for local derivatives). Barycentrics are affine
//!   in `u`; the shading normal is `normalize(N(θ)·n_obj(b(u)))`, `n_obj`
//!   the barycentric interpolation of the mesh's vertex normals (the
//!   geometric normal for flat meshes).
//! - **Sphere** (the unit sphere, normal = position): the point is the
//!   gnomonic projection `p(u) = q(u) / |q(u)|`, `∂p/∂u_i = (T_i − p (p·T_i))
//!   / |q|`; `T_obj ⊥ p_obj` (built so), so `|q| ≥ 1` and the chart covers
//!   the open hemisphere around the vertex. The shading normal is `normalize(N(θ)·q)`
//!   (the object normal `p` up to scale).
//!
//! Either way `x(u, θ) = M(θ)·p(u)` and `∂x/∂u = L T` is orthonormal at
//! (u, θ) = (0, θ₀), whatever the triangle's size or shape or the sphere's
//! placement. [`Anchor::shifted`] keeps the chart (`q` unnormalised), so the
//! shifted anchor at `u'` is the original at `u + u'`.

use epsm_render::Scene;
use epsm_render::frame::basis_f64;
use epsm_render::record::TrianglePoint;
use epsm_render::scene::{Object, ObjectId, Surface};
use epsm_render::sphere;
use glam::DVec3;

use crate::motion::{AffineGrad, Motion, ObjectMotion};

/// A vertex anchored on a triangle or an exact sphere, in object space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Anchor {
    /// The object the vertex lies on.
    pub object: ObjectId,
    /// The surface of the chart: a triangle's plane or the unit sphere.
    surface: Surface,
    /// The chart's `q` at `u = 0`, object space (on a sphere: the point up
    /// to scale).
    p_obj: DVec3,
    /// `∂q/∂u`, object space.
    tangents: [DVec3; 2],
    /// Unnormalised object-space normal at `u = 0` (on a sphere: `p_obj`).
    n_obj: DVec3,
    /// `∂n_obj/∂u` (zero for flat meshes; on a sphere: `tangents`).
    n_du: [DVec3; 2],
}

/// A vertex evaluated at some `(u, θ)`: position, normal and their
/// derivatives with respect to `u` (world space).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VertexState {
    /// Position.
    pub x: DVec3,
    /// Unit shading normal.
    pub n: DVec3,
    /// `∂x/∂u1`, `∂x/∂u2`.
    pub dx_du: [DVec3; 2],
    /// `∂n/∂u1`, `∂n/∂u2`.
    pub dn_du: [DVec3; 2],
    p_obj: DVec3,
    n_obj: DVec3,
    inv_len: f64,
}

/// Removes the component of `v` along the unit `n`.
fn tangential(n: DVec3, v: DVec3) -> DVec3 {
    v - n * n.dot(v)
}

impl Anchor {
    /// The anchor at local coordinates `(b1, b2)` of `object`, with tangents
    /// built in the placement `om`: barycentrics of triangle `triangle` of a
    /// mesh, or octahedral coordinates ([`sphere::point`]) on an exact
    /// sphere (`triangle` ignored; coordinates clamped into `[-1, 1]²`).
    /// `None` for an index out of range, a degenerate triangle, NaN sphere
    /// coordinates or a singular placement.
    pub fn new(
        object: &Object,
        id: ObjectId,
        triangle: u32,
        b1: f64,
        b2: f64,
        om: &ObjectMotion,
    ) -> Option<Self> {
        match object.surface {
            Surface::Mesh => Self::on_triangle(object, id, triangle, b1, b2, om),
            Surface::Sphere => Self::on_sphere(id, b1, b2, om),
        }
    }

    /// [`Anchor::new`] on the unit sphere.
    fn on_sphere(id: ObjectId, b1: f64, b2: f64, om: &ObjectMotion) -> Option<Self> {
        let p_obj = sphere::point([b1, b2]);
        let n_world = (om.normal * p_obj).try_normalize()?;
        let (t1, t2) = basis_f64(n_world);
        let world_to_obj = om.normal.transpose();
        let tangents = [world_to_obj * t1, world_to_obj * t2];
        Some(Self {
            object: id,
            surface: Surface::Sphere,
            p_obj,
            tangents,
            n_obj: p_obj,
            n_du: tangents,
        })
    }

    /// [`Anchor::new`] on a triangle.
    fn on_triangle(
        object: &Object,
        id: ObjectId,
        triangle: u32,
        b1: f64,
        b2: f64,
        om: &ObjectMotion,
    ) -> Option<Self> {
        let mesh = &object.mesh;
        let idx = *mesh.indices.get(triangle as usize)?;
        let pos = |i: u32| mesh.positions.get(i as usize).map(|p| p.as_dvec3());
        let [p0, p1, p2] = [pos(idx[0])?, pos(idx[1])?, pos(idx[2])?];
        let (e1, e2) = (p1 - p0, p2 - p0);
        let cross = e1.cross(e2);
        let det = e1.length_squared() * e2.length_squared() - e1.dot(e2).powi(2);
        if !det.is_finite() || det <= 1e-24 * e1.length_squared() * e2.length_squared() {
            return None;
        }
        let ng_world = (om.normal * cross).try_normalize()?;
        let (t1, t2) = basis_f64(ng_world);
        let world_to_obj = om.normal.transpose();
        let tangents = [world_to_obj * t1, world_to_obj * t2];
        let p_obj = p0 + e1 * b1 + e2 * b2;
        let (n_obj, n_du) = if mesh.normals.len() == mesh.positions.len() {
            let n = |i: u32| mesh.normals[i as usize].as_dvec3();
            let [n0, n1, n2] = idx.map(n);
            // Barycentric change per tangent step: [e1 e2] db = T (exact: T lies in the plane).
            let db = tangents.map(|t| {
                let (r1, r2) = (e1.dot(t), e2.dot(t));
                let (g11, g12, g22) = (e1.length_squared(), e1.dot(e2), e2.length_squared());
                ((g22 * r1 - g12 * r2) / det, (g11 * r2 - g12 * r1) / det)
            });
            (
                n0 + (n1 - n0) * b1 + (n2 - n0) * b2,
                db.map(|(d1, d2)| (n1 - n0) * d1 + (n2 - n0) * d2),
            )
        } else {
            (cross.normalize(), [DVec3::ZERO; 2])
        };
        Some(Self {
            object: id,
            surface: Surface::Mesh,
            p_obj,
            tangents,
            n_obj,
            n_du,
        })
    }

    /// The anchor of the recorded point `at` of `scene`, tangents built in
    /// `motion`. `None` as for [`Anchor::new`], or for an unknown object.
    pub fn at_point(scene: &Scene, motion: &Motion, at: &TrianglePoint) -> Option<Self> {
        Self::new(
            scene.objects().get(at.object as usize)?,
            at.object,
            at.triangle,
            f64::from(at.b1),
            f64::from(at.b2),
            motion.objects.get(at.object as usize)?,
        )
    }

    /// Position, normal and `u`-derivatives at `u` in placement `om`.
    pub fn eval(&self, om: &ObjectMotion, u: [f64; 2]) -> VertexState {
        let q = self.p_obj + self.tangents[0] * u[0] + self.tangents[1] * u[1];
        let (p_obj, dp_du) = match self.surface {
            Surface::Mesh => (q, self.tangents),
            Surface::Sphere => {
                let inv_q = 1.0 / q.length();
                let p = q * inv_q;
                (p, self.tangents.map(|t| tangential(p, t) * inv_q))
            }
        };
        let n_obj = self.n_obj + self.n_du[0] * u[0] + self.n_du[1] * u[1];
        let nw = om.normal * n_obj;
        let inv_len = 1.0 / nw.length();
        let n = nw * inv_len;
        VertexState {
            x: om.linear * p_obj + om.translation,
            n,
            dx_du: dp_du.map(|t| om.linear * t),
            dn_du: self.n_du.map(|d| tangential(n, om.normal * d) * inv_len),
            p_obj,
            n_obj,
            inv_len,
        }
    }

    /// `(∂x/∂θ, ∂n/∂θ)` at fixed `u` for one parameter driving the object.
    pub fn dtheta(state: &VertexState, g: &AffineGrad) -> [DVec3; 2] {
        [
            g.linear * state.p_obj + g.translation,
            tangential(state.n, g.normal * state.n_obj) * state.inv_len,
        ]
    }

    /// The same anchor moved to the point at `u` (tangents unchanged; on a
    /// sphere the chart's unnormalised `q(u)`, so that the result at `u'` is
    /// this anchor at `u + u'`).
    pub fn shifted(&self, u: [f64; 2]) -> Self {
        Self {
            p_obj: self.p_obj + self.tangents[0] * u[0] + self.tangents[1] * u[1],
            n_obj: self.n_obj + self.n_du[0] * u[0] + self.n_du[1] * u[1],
            ..*self
        }
    }
}
