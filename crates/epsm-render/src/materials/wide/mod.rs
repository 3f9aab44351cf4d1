//! The materials in sixteen lanes, for the wide tracer: lane `i` of every
//! function here returns the bits [`Material`]'s scalar function returns for
//! lane `i`'s material and inputs.
//!
//! Model: [`Materials16`] holds the scene's materials as tables indexed by
//! material (kind, sidedness, colour, α, IOR), gathered per lane, so the
//! sixteen lanes of one call may hold different materials and kinds. Each
//! kind present among the active lanes runs its lane code under its mask
//! (kinds no lane holds are skipped); each lane code is the scalar code's
//! IEEE operations in the scalar order, its branches turned into masks, and
//! shares the scalar formulas where they are branch-free ([`super::real`]).
//! Two-sided materials seen from behind are mirrored through the tangent
//! plane as [`Material::sample`] does (dielectrics never are).
//!
//! | file | holds |
//! |---|---|
//! | `mod.rs` | kind dispatch and sidedness |
//! | `tables.rs` | the per-material tables |
//! | `diffuse.rs` | Lambertian lanes and the concentric map |
//! | `conductor.rs` | mirror lanes |
//! | `dielectric.rs` | Fresnel, refraction and the lobe choice |
//! | `rough_conductor.rs` | GGX lanes |
//! | `cases.rs`, `tests.rs` | bit-identity against the scalar functions |
//!
//! Per-lane fallback: image-textured albedo ([`Texture::eval`] per lane
//! that reads it; no shipped scene has one).

mod conductor;
mod dielectric;
mod diffuse;
mod rough_conductor;
mod tables;

#[cfg(test)]
mod cases;
#[cfg(test)]
mod tests;

use glam::Vec3;

use super::real::Real;
#[cfg(doc)]
use super::{Material, Texture};
use crate::bvh::{Frames16, TexCoords16};
use crate::simd::{F32x16, Lanes, Mask16, U32x16, Vec3x16};
use tables::Kinds;
pub(crate) use tables::Materials16;

/// Sixteen BSDF samples ([`super::BsdfSample`]'s fields by lane). Fields
/// other than `found` are meaningful only in the lanes of `found`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BsdfSamples16<B: Lanes> {
    /// Lanes where `sample` returned `Some`.
    pub found: Mask16,
    /// Sampled directions, local frame.
    pub wo: Vec3x16<B>,
    /// `f·|cos θo| / pdf` (delta lobes: the lobe's weight).
    pub weight: Vec3x16<B>,
    /// Solid-angle pdf (delta lobes: the lobe choice's probability).
    pub pdf: F32x16<B>,
    /// Relative IOR `η(wo side) / η(wi side)`; 1 for reflection.
    pub eta: F32x16<B>,
    /// Microfacet normals, local frame.
    pub m: Vec3x16<B>,
    /// Lanes whose lobe is a delta ([`super::Lobe::is_delta`]).
    pub delta: Mask16,
    /// Lanes whose lobe transmits ([`super::Lobe::is_transmission`]).
    pub transmission: Mask16,
}

impl<B: Lanes> BsdfSamples16<B> {
    /// No sample: every field zero but `eta` (1) and `m` (`+z`).
    #[inline(always)]
    fn none(k: B) -> Self {
        let zero = Vec3x16::splat(k, Vec3::ZERO);
        Self {
            found: Mask16::NONE,
            wo: zero,
            weight: zero,
            pdf: F32x16::splat(k, 0.0),
            eta: F32x16::splat(k, 1.0),
            m: Vec3x16::splat(k, Vec3::Z),
            delta: Mask16::NONE,
            transmission: Mask16::NONE,
        }
    }

    /// `s` in `lanes`, `self` in the others.
    #[inline(always)]
    fn merge(&mut self, lanes: Mask16, s: &Self) {
        let pick = |a: Mask16, b: Mask16| (a & lanes) | b.and_not(lanes);
        *self = Self {
            found: pick(s.found, self.found),
            wo: Vec3x16::select(lanes, s.wo, self.wo),
            weight: Vec3x16::select(lanes, s.weight, self.weight),
            pdf: F32x16::select(lanes, s.pdf, self.pdf),
            eta: F32x16::select(lanes, s.eta, self.eta),
            m: Vec3x16::select(lanes, s.m, self.m),
            delta: pick(s.delta, self.delta),
            transmission: pick(s.transmission, self.transmission),
        };
    }
}

/// Which side `wi` sees in the lanes of materials that are not dielectric
/// ([`Material`]'s `side`): `seen` where they scatter (front, or back of
/// a two-sided material), `back` where they are mirrored.
#[derive(Clone, Copy, Debug)]
struct Sides {
    /// Lanes that scatter.
    seen: Mask16,
    /// Lanes seen from behind and mirrored.
    back: Mask16,
}

impl Sides {
    /// The sides of the non-dielectric lanes of `kinds` seen from `wi_z`.
    #[inline(always)]
    fn of<B: Lanes>(k: B, kinds: &Kinds, wi_z: F32x16<B>) -> Self {
        let zero = F32x16::splat(k, 0.0);
        let opaque = kinds.diffuse | kinds.conductor | kinds.rough;
        let front = wi_z.gt(zero) & opaque;
        let back = wi_z.lt(zero) & kinds.two_sided & opaque;
        Self {
            seen: front | back,
            back,
        }
    }

    /// `Side::apply` in every lane: `w` mirrored through the tangent plane
    /// in the `back` lanes.
    #[inline(always)]
    fn apply<B: Lanes>(&self, w: Vec3x16<B>) -> Vec3x16<B> {
        Vec3x16::new(w.x, w.y, F32x16::select(self.back, -w.z, w.z))
    }
}

impl Materials16 {
    /// Lane `i` in `active`: `materials[material.lane(i)].to_local(&frame.lane(i), v.lane(i))`
    /// bit for bit; the other lanes are unspecified.
    #[inline(always)]
    pub(crate) fn to_local16<B: Lanes>(
        &self,
        k: B,
        material: U32x16<B>,
        frame: &Frames16<B>,
        v: Vec3x16<B>,
        active: Mask16,
    ) -> Vec3x16<B> {
        let zero = F32x16::splat(k, 0.0);
        let z = v.dot(frame.n);
        let diffuse = self.kinds(k, material, active).diffuse;
        if diffuse == active {
            return Vec3x16::new(zero, zero, z);
        }
        Vec3x16::new(
            F32x16::select(diffuse, zero, v.dot(frame.s)),
            F32x16::select(diffuse, zero, v.dot(frame.t)),
            z,
        )
    }

    /// Lanes in `active` whose material `is_delta()`.
    #[inline(always)]
    pub(crate) fn is_delta16<B: Lanes>(&self, k: B, material: U32x16<B>, active: Mask16) -> Mask16 {
        let kinds = self.kinds(k, material, active);
        kinds.conductor | kinds.dielectric
    }

    /// Lane `i` in `active`: `materials[m_i].sample(wi_i, uv_i, u_lobe_i,
    /// Vec2(u0_i, u1_i))`, `found` iff `Some`, then every field bit for bit.
    /// Lanes outside `active` are not found.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)] // the scalar `sample`'s inputs by lane, the token, the lanes
    pub(crate) fn sample16<B: Lanes>(
        &self,
        k: B,
        material: U32x16<B>,
        wi: Vec3x16<B>,
        uv: &TexCoords16<B>,
        u_lobe: F32x16<B>,
        u: [F32x16<B>; 2],
        active: Mask16,
    ) -> BsdfSamples16<B> {
        let kinds = self.kinds(k, material, active);
        let sides = Sides::of(k, &kinds, wi.z);
        let wi_front = sides.apply(wi);
        let mut out = BsdfSamples16::none(k);
        let diffuse = kinds.diffuse & sides.seen;
        if diffuse.any() {
            let s = diffuse::sample(self, k, material, uv, u, diffuse, kinds.image);
            out.merge(diffuse, &s);
        }
        let conductor = kinds.conductor & sides.seen;
        if conductor.any() {
            out.merge(
                conductor,
                &conductor::sample(self, k, material, wi_front, conductor),
            );
        }
        let rough = kinds.rough & sides.seen;
        if rough.any() {
            let s = rough_conductor::sample(self, k, material, wi_front, u, rough);
            out.merge(rough, &s);
        }
        if sides.back.any() {
            out.wo = sides.apply(out.wo);
            out.m = sides.apply(out.m);
        }
        if kinds.dielectric.any() {
            let s = dielectric::sample(self, k, material, wi, u_lobe, kinds.dielectric);
            out.merge(kinds.dielectric, &s);
        }
        out
    }

    /// Lane `i` in `active`: `materials[m_i].eval(wi_i, wo_i, uv_i)` bit for
    /// bit; 0 in the other lanes.
    #[inline(always)]
    pub(crate) fn eval16<B: Lanes>(
        &self,
        k: B,
        material: U32x16<B>,
        wi: Vec3x16<B>,
        wo: Vec3x16<B>,
        uv: &TexCoords16<B>,
        active: Mask16,
    ) -> Vec3x16<B> {
        // Smooth conductors and dielectrics, and unseen sides, give 0.
        let kinds = self.kinds(k, material, active);
        let sides = Sides::of(k, &kinds, wi.z);
        let (wi, wo) = (sides.apply(wi), sides.apply(wo));
        let mut f = Vec3x16::splat(k, Vec3::ZERO);
        let diffuse = kinds.diffuse & sides.seen;
        if diffuse.any() {
            let d = diffuse::eval(self, k, material, wo, uv, diffuse, kinds.image);
            f = Vec3x16::select(diffuse, d, f);
        }
        let rough = kinds.rough & sides.seen;
        if rough.any() {
            let r = rough_conductor::eval(self, k, material, wi, wo, rough);
            f = Vec3x16::select(rough, r, f);
        }
        f
    }

    /// Lane `i` in `active`: `materials[m_i].pdf(wi_i, wo_i, uv_i)` bit for
    /// bit (no pdf reads the texture coordinates); 0 in the other lanes.
    #[inline(always)]
    pub(crate) fn pdf16<B: Lanes>(
        &self,
        k: B,
        material: U32x16<B>,
        wi: Vec3x16<B>,
        wo: Vec3x16<B>,
        active: Mask16,
    ) -> F32x16<B> {
        let kinds = self.kinds(k, material, active);
        let sides = Sides::of(k, &kinds, wi.z);
        let (wi, wo) = (sides.apply(wi), sides.apply(wo));
        let mut pdf = F32x16::splat(k, 0.0);
        let diffuse = kinds.diffuse & sides.seen;
        if diffuse.any() {
            pdf = F32x16::select(diffuse, diffuse::pdf(k, wo), pdf);
        }
        let rough = kinds.rough & sides.seen;
        if rough.any() {
            let r = rough_conductor::pdf(self, k, material, wi, wo, rough);
            pdf = F32x16::select(rough, r, pdf);
        }
        pdf
    }
}

impl<B: Lanes> Real for F32x16<B> {
    type Token = B;

    #[inline(always)]
    fn constant(k: B, c: f32) -> Self {
        F32x16::splat(k, c)
    }

    #[inline(always)]
    fn sqrt(self) -> Self {
        F32x16::sqrt(self)
    }

    #[inline(always)]
    fn max(self, o: Self) -> Self {
        F32x16::max(self, o)
    }
}
