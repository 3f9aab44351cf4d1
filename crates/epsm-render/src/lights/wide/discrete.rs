//! Sixteen discrete choices from one [`Distribution1D`] (light selection by
//! power, a triangle of an emitter by area), each lane bit for bit
//! [`Distribution1D::sample_discrete`] of its `u`.
//!
//! A distribution with one entry of non-zero weight needs no table, as in
//! the scalar code. A small one (≤ 16 entries) picks `picks[count]`, `count`
//! the number of its sorted inner boundaries `≤ u`: the entry its scalar
//! binary search finds, since the upper bound of `u` in a sorted list is that
//! count. The boundaries are tested one by one against all sixteen lanes,
//! each raising the lanes at or above it to the next pick. A larger one is
//! searched per lane by the scalar function.

use super::super::distribution::{DiscreteSample, Distribution1D};
use crate::simd::{F64x16, LANES, Lanes, Mask16, U32x16};

/// Sixteen [`DiscreteSample`]s, by field.
#[derive(Clone, Copy, Debug)]
pub(super) struct DiscreteSamples16<B: Lanes> {
    /// Chosen entry.
    pub index: U32x16<B>,
    /// Probability of the entry.
    pub pmf: F64x16<B>,
    /// The uniform number remapped into `[0, 1)` inside the entry.
    pub u_remapped: F64x16<B>,
}

impl Distribution1D {
    /// Lane `i` in `active`: `self.sample_discrete(u[i])`, bit for bit
    /// (other lanes unspecified). Always inlined (module docs of `simd`).
    #[inline(always)]
    pub(super) fn sample_discrete16<B: Lanes>(
        &self,
        k: B,
        u: F64x16<B>,
        active: Mask16,
    ) -> DiscreteSamples16<B> {
        let below_one = F64x16::splat(k, 1.0 - f64::EPSILON);
        let clamped = u.clamp(F64x16::splat(k, 0.0), F64x16::splat(k, 1.0));
        if let Some(index) = self.single() {
            return DiscreteSamples16 {
                index: U32x16::splat(k, index as u32),
                pmf: F64x16::splat(k, 1.0),
                u_remapped: clamped.min(below_one),
            };
        }
        let Some((inner, picks)) = self.small_table() else {
            let samples = self.sample_lanes(&u.to_array(), active);
            let index = samples.map(|s| s.map_or(0, |s| s.index as u32));
            let pmf = samples.map(|s| s.map_or(0.0, |s| s.pmf));
            let u_remapped = samples.map(|s| s.map_or(0.0, |s| s.u_remapped));
            return DiscreteSamples16 {
                index: U32x16::from_array(k, index),
                pmf: F64x16::from_array(k, pmf),
                u_remapped: F64x16::from_array(k, u_remapped),
            };
        };
        let (mut index, mut lo, mut hi) = (
            U32x16::splat(k, picks[0].index as u32),
            F64x16::splat(k, picks[0].lo),
            F64x16::splat(k, picks[0].hi),
        );
        for (&boundary, pick) in inner.iter().zip(&picks[1..]) {
            let above = F64x16::splat(k, boundary).le(clamped);
            index = U32x16::select(above, U32x16::splat(k, pick.index as u32), index);
            lo = F64x16::select(above, F64x16::splat(k, pick.lo), lo);
            hi = F64x16::select(above, F64x16::splat(k, pick.hi), hi);
        }
        let u_remapped = ((clamped - lo) / (hi - lo)).clamp(F64x16::splat(k, 0.0), below_one);
        DiscreteSamples16 {
            index,
            pmf: hi - lo,
            u_remapped,
        }
    }

    /// [`Self::sample_discrete`] for each lane of `lanes` (`None` in the others).
    #[inline(never)]
    fn sample_lanes(&self, u: &[f64; LANES], lanes: Mask16) -> [Option<DiscreteSample>; LANES] {
        let mut samples = [None; LANES];
        for lane in lanes.lanes() {
            samples[lane] = Some(self.sample_discrete(u[lane]));
        }
        samples
    }
}
