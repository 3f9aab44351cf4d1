//! The smooth conductor in lanes ([`crate::materials::Conductor`]), in the
//! front-side frame (mirroring is the caller's): the mirror direction with
//! weight `tint` and probability 1.

use super::{BsdfSamples16, Materials16};
use crate::simd::{F32x16, Lanes, Mask16, U32x16, Vec3x16};

/// `Conductor::sample` in the `lanes` (all found), `wi` local.
#[inline(always)]
pub(super) fn sample<B: Lanes>(
    t: &Materials16,
    k: B,
    material: U32x16<B>,
    wi: Vec3x16<B>,
    lanes: Mask16,
) -> BsdfSamples16<B> {
    BsdfSamples16 {
        found: lanes,
        wo: Vec3x16::new(-wi.x, -wi.y, wi.z),
        weight: t.colour(k, material, lanes),
        pdf: F32x16::splat(k, 1.0),
        delta: lanes,
        ..BsdfSamples16::none(k)
    }
}
