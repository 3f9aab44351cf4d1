//! Every lane of [`Materials16`]'s functions against [`Material`]'s scalar
//! functions, bit for bit (`f32` bits, or both NaN; masks exactly), on the
//! inputs of `cases.rs`, on every backend the CPU has (the portable one
//! always).

use glam::Vec3;

use super::cases::{Case, direction, materials};
use super::*;
use crate::frame::Frame;
use crate::materials::test_support::Rng;
use crate::simd::LANES;

/// Equal bit patterns, or both NaN.
fn same(a: f32, b: f32) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

/// [`same`] for every component.
fn same3(a: Vec3, b: Vec3) -> bool {
    (0..3).all(|c| same(a[c], b[c]))
}

#[test]
fn samples_match_the_scalar_materials_in_every_lane() {
    fn on<B: Lanes>(k: B) {
        let mut rng = Rng::new(31);
        let mut found = 0;
        for round in 0..600 {
            let materials = materials(&mut rng);
            let wide = Materials16::new(&materials);
            for _ in 0..4 {
                let c = Case::random(&mut rng, &materials);
                let s = wide.sample16(
                    k,
                    c.material(k),
                    Vec3x16::from_lanes(k, &c.wi),
                    &c.uv(k),
                    F32x16::from_array(k, c.u_lobe),
                    [
                        F32x16::from_array(k, c.u.map(|u| u.x)),
                        F32x16::from_array(k, c.u.map(|u| u.y)),
                    ],
                    c.active,
                );
                for lane in 0..LANES {
                    let m = &materials[c.material[lane] as usize];
                    let scalar = c
                        .active
                        .test(lane)
                        .then(|| m.sample(c.wi[lane], c.uv[lane], c.u_lobe[lane], c.u[lane]));
                    let at = || format!("round {round} lane {lane}: {m:?} wi {}", c.wi[lane]);
                    assert_eq!(
                        s.found.test(lane),
                        matches!(scalar, Some(Some(_))),
                        "{}",
                        at()
                    );
                    let Some(Some(e)) = scalar else { continue };
                    found += 1;
                    assert!(same3(s.wo.lane(lane), e.wo), "wo {}", at());
                    assert!(same3(s.weight.lane(lane), e.weight), "weight {}", at());
                    assert!(same(s.pdf.lane(lane), e.pdf), "pdf {}", at());
                    assert!(same(s.eta.lane(lane), e.eta), "eta {}", at());
                    assert!(same3(s.m.lane(lane), e.m), "m {}", at());
                    assert_eq!(s.delta.test(lane), e.lobe.is_delta(), "{}", at());
                    assert_eq!(
                        s.transmission.test(lane),
                        e.lobe.is_transmission(),
                        "{}",
                        at()
                    );
                }
            }
        }
        // Most active lanes scatter (one-sided back faces and rejections do not).
        assert!(found > 600 * 4 * LANES / 3, "{found}");
    }
    crate::simd::each_backend!(on);
}

#[test]
fn eval_and_pdf_match_the_scalar_materials_in_every_lane() {
    fn on<B: Lanes>(k: B) {
        let mut rng = Rng::new(32);
        let mut nonzero = 0;
        for _ in 0..600 {
            let materials = materials(&mut rng);
            let wide = Materials16::new(&materials);
            for _ in 0..4 {
                let c = Case::random(&mut rng, &materials);
                let (wi, wo) = (Vec3x16::from_lanes(k, &c.wi), Vec3x16::from_lanes(k, &c.wo));
                let f = wide.eval16(k, c.material(k), wi, wo, &c.uv(k), c.active);
                let pdf = wide.pdf16(k, c.material(k), wi, wo, c.active);
                for lane in 0..LANES {
                    let m = &materials[c.material[lane] as usize];
                    let (wi, wo, uv) = (c.wi[lane], c.wo[lane], c.uv[lane]);
                    let (ef, epdf) = if c.active.test(lane) {
                        (m.eval(wi, wo, uv), m.pdf(wi, wo, uv))
                    } else {
                        (Vec3::ZERO, 0.0)
                    };
                    let at = format!("lane {lane}: {m:?} wi {wi} wo {wo}");
                    assert!(
                        same3(f.lane(lane), ef),
                        "eval {} against {ef}, {at}",
                        f.lane(lane)
                    );
                    assert!(
                        same(pdf.lane(lane), epdf),
                        "pdf {} against {epdf}, {at}",
                        pdf.lane(lane)
                    );
                    nonzero += usize::from(epdf > 0.0);
                }
            }
        }
        assert!(nonzero > 600 * 4 * LANES / 10, "{nonzero}");
    }
    crate::simd::each_backend!(on);
}

#[test]
fn local_directions_and_delta_lanes_match_the_scalar_materials() {
    fn on<B: Lanes>(k: B) {
        let mut rng = Rng::new(33);
        let materials = materials(&mut rng);
        let wide = Materials16::new(&materials);
        for _ in 0..500 {
            let c = Case::random(&mut rng, &materials);
            let frames: [Frame; LANES] = std::array::from_fn(|_| Frame::from_normal(rng.sphere()));
            let v: [Vec3; LANES] = std::array::from_fn(|_| direction(&mut rng, true));
            let local = wide.to_local16(
                k,
                c.material(k),
                &Frames16::from_lanes(k, &frames),
                Vec3x16::from_lanes(k, &v),
                c.active,
            );
            let delta = wide.is_delta16(k, c.material(k), c.active);
            for lane in 0..LANES {
                let m = &materials[c.material[lane] as usize];
                if c.active.test(lane) {
                    let expected = m.to_local(&frames[lane], v[lane]);
                    assert!(same3(local.lane(lane), expected), "{m:?}: {}", v[lane]);
                }
                assert_eq!(delta.test(lane), c.active.test(lane) && m.is_delta());
            }
        }
    }
    crate::simd::each_backend!(on);
}
