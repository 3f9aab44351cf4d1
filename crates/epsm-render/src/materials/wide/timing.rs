//! Time per lane of `sample16 + eval16 + pdf16` against the scalar
//! `sample + eval + pdf`, for diffuse and for dielectric lanes, each compiled
//! into a `#[target_feature]` loop as the tracers are. Ignored by default:
//! `cargo test --release -p epsm-render --lib wide::timing -- --ignored --nocapture`.

use std::hint::black_box;
use std::time::Instant;

use glam::{Vec2, Vec3};

use super::*;
use crate::materials::test_support::Rng;
use crate::materials::{Bsdf, Dielectric, Diffuse, Material, Texture};
use crate::simd::LANES;

/// Lanes per measured batch.
const N: usize = 1 << 14;
/// Batches timed (the best is kept).
const REPEATS: usize = 20;

/// Random inputs, upper hemisphere: directions and sample numbers in lane
/// order, and the same by sixteen lanes and component (loaded by the wide
/// loop as whole vectors, as the wide tracer will hold them).
struct Inputs {
    /// Incident directions.
    wi: Vec<Vec3>,
    /// Outgoing directions.
    wo: Vec<Vec3>,
    /// Lobe and direction numbers.
    u: Vec<[f32; 3]>,
    /// `wi`, `wo` and `u` by group of sixteen lanes: nine vectors.
    lanes: Vec<[[f32; LANES]; 9]>,
}

impl Inputs {
    /// `N` random lanes.
    fn random(rng: &mut Rng) -> Self {
        let upper = |rng: &mut Rng| {
            let v = rng.sphere();
            Vec3::new(v.x, v.y, v.z.abs())
        };
        let wi: Vec<Vec3> = (0..N).map(|_| upper(rng)).collect();
        let wo: Vec<Vec3> = (0..N).map(|_| upper(rng)).collect();
        let u: Vec<[f32; 3]> = (0..N).map(|_| [rng.f32(), rng.f32(), rng.f32()]).collect();
        let lanes = (0..N / LANES)
            .map(|g| {
                std::array::from_fn(|v| {
                    std::array::from_fn(|j| {
                        let i = g * LANES + j;
                        match v {
                            0..3 => wi[i][v],
                            3..6 => wo[i][v - 3],
                            _ => u[i][v - 6],
                        }
                    })
                })
            })
            .collect();
        Self { wi, wo, u, lanes }
    }
}

/// The scalar functions over every lane; a checksum.
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
fn scalar(material: &Material, x: &Inputs) -> f32 {
    let mut sum = 0.0;
    for i in 0..N {
        let (wi, wo, [a, b, c]) = (x.wi[i], x.wo[i], x.u[i]);
        if let Some(s) = material.sample(wi, Vec2::ZERO, a, Vec2::new(b, c)) {
            sum += s.weight.x + s.pdf;
        }
        sum += material.eval(wi, wo, Vec2::ZERO).x + material.pdf(wi, wo, Vec2::ZERO);
    }
    sum
}

/// The wide functions over every lane, sixteen at a time; a checksum.
#[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,bmi1,bmi2,lzcnt,popcnt")]
fn wide(k: Avx512, t: &Materials16, x: &Inputs) -> f32 {
    let material = U32x16::splat(k, 0);
    let uv = TexCoords16 {
        sphere: Mask16::NONE,
        a: Vec3x16::splat(k, Vec3::ZERO),
    };
    let mut sum = F32x16::splat(k, 0.0);
    for group in &x.lanes {
        let v = group.map(|lanes| F32x16::from_array(k, lanes));
        let (wi, wo) = (
            Vec3x16::new(v[0], v[1], v[2]),
            Vec3x16::new(v[3], v[4], v[5]),
        );
        let s = t.sample16(k, material, wi, &uv, v[6], [v[7], v[8]], Mask16::ALL);
        let f = t.eval16(k, material, wi, wo, &uv, Mask16::ALL);
        let pdf = t.pdf16(k, material, wi, wo, Mask16::ALL);
        sum = sum + F32x16::select(s.found, s.weight.x + s.pdf, F32x16::splat(k, 0.0)) + f.x + pdf;
    }
    sum.to_array().iter().sum()
}

/// The best of `REPEATS` timings of `run`, in nanoseconds per lane.
fn best(mut run: impl FnMut() -> f32) -> f64 {
    (0..REPEATS)
        .map(|_| {
            let start = Instant::now();
            black_box(run());
            start.elapsed().as_secs_f64() * 1e9 / N as f64
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
#[ignore = "timing: run in release with --ignored --nocapture"]
#[allow(unsafe_code)]
fn wide_materials_time_per_lane_against_scalar() {
    let Some(k) = Avx512::detect() else {
        eprintln!("no AVX-512 on this CPU: timing skipped");
        return;
    };
    let mut rng = Rng::new(41);
    let inputs = Inputs::random(&mut rng);
    for bsdf in [
        Bsdf::Diffuse(Diffuse {
            albedo: Texture::Constant(Vec3::new(0.7, 0.5, 0.3)),
        }),
        Bsdf::Dielectric(Dielectric { ior: 1.5 }),
    ] {
        let material = Material {
            name: String::new(),
            bsdf,
            two_sided: false,
        };
        let table = Materials16::new(std::slice::from_ref(&material));
        // SAFETY: `scalar` needs AVX2, BMI1/2, LZCNT and POPCNT, which the
        // AVX-512 token `k` proves (simd module docs).
        let s = best(|| unsafe { scalar(black_box(&material), black_box(&inputs)) });
        // SAFETY: `wide` needs the features the token `k` proves.
        let w = best(|| unsafe { wide(k, black_box(&table), black_box(&inputs)) });
        eprintln!(
            "{:?}: scalar {s:.2} ns/lane, wide {w:.2} ns/lane ({:.1}×)",
            material.bsdf,
            s / w
        );
    }
}
