//! Spawned rays' origins in lanes: [`offset_origin`] per lane.

#[cfg(doc)]
use crate::ray::offset_origin;
use crate::ray::{FLOAT_SCALE, INT_SCALE, ORIGIN};
use crate::simd::{F32x16, Lanes, Vec3x16};

/// [`offset_origin`] in sixteen lanes: the operations of
/// `ray::offset_origin_sse2` lane by lane, so the same origins bit for bit.
#[inline(always)]
pub(crate) fn offset_origins16<B: Lanes>(k: B, p: Vec3x16<B>, ng: Vec3x16<B>) -> Vec3x16<B> {
    Vec3x16::new(
        offset_components16(k, p.x, ng.x),
        offset_components16(k, p.y, ng.y),
        offset_components16(k, p.z, ng.z),
    )
}

/// One coordinate of [`offset_origins16`].
#[inline(always)]
fn offset_components16<B: Lanes>(k: B, pc: F32x16<B>, nc: F32x16<B>) -> F32x16<B> {
    let of_i = (nc * k.f32(INT_SCALE)).trunc_i32();
    let bits = pc.to_bits();
    let negative = bits.shr_signed(31);
    let moved = F32x16::from_bits(bits + ((of_i ^ negative) - negative));
    let near = pc + k.f32(FLOAT_SCALE) * nc;
    F32x16::select(pc.abs().lt(k.f32(ORIGIN)), near, moved)
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::ray::offset_origin;
    use epsm_testkit::Rng;

    /// The lanes' offsets are the scalar offsets, bit for bit.
    #[test]
    fn lane_offsets_are_the_scalar_offsets() {
        crate::simd::each_backend!(offsets_match);
    }

    fn offsets_match<B: Lanes>(k: B) {
        let mut rng = Rng::new(0x2545_F491_4F6C_DD1D);
        let mut uniform = || rng.f32();
        for round in 0..2000 {
            let scale = [1e-3, 0.02, 1.0, 1e3, 1e6][round % 5];
            let p: [Vec3; 16] = std::array::from_fn(|i| {
                let v = (Vec3::new(uniform(), uniform(), uniform()) - 0.5) * 2.0 * scale;
                if i == 3 { Vec3::new(-0.0, 0.0, v.z) } else { v }
            });
            let n: [Vec3; 16] = std::array::from_fn(|_| {
                (Vec3::new(uniform(), uniform(), uniform()) - 0.5).normalize_or_zero()
            });
            let got = offset_origins16(k, Vec3x16::from_lanes(k, &p), Vec3x16::from_lanes(k, &n));
            for lane in 0..16 {
                assert_eq!(
                    got.lane(lane).to_array().map(f32::to_bits),
                    offset_origin(p[lane], n[lane]).to_array().map(f32::to_bits),
                    "p {} n {}",
                    p[lane],
                    n[lane]
                );
            }
        }
    }
}
