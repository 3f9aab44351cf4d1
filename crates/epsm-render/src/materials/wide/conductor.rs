//! The smooth conductor in lanes ([`crate::materials::Conductor`]), in the
//! front-side frame (mirroring is the caller's): the mirror direction with
//! weight `tint` and probability 1.

use super::{BsdfSamples16, Materials16};
use crate::simd::{Avx512, F32x16, Mask16, U32x16, Vec3x16};

/// `Conductor::sample` in the `lanes` (all found), `wi` local.
#[inline(always)]
pub(super) fn sample(
    t: &Materials16,
    k: Avx512,
    material: U32x16,
    wi: Vec3x16,
    lanes: Mask16,
) -> BsdfSamples16 {
    BsdfSamples16 {
        found: lanes,
        wo: Vec3x16::new(-wi.x, -wi.y, wi.z),
        weight: t.colour(k, material, lanes),
        pdf: F32x16::splat(k, 1.0),
        delta: lanes,
        ..BsdfSamples16::none(k)
    }
}
