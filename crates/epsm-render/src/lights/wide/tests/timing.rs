//! How long `sample16` takes per lane against the scalar `sample` (an
//! ignored test: a timing, not a check).

use std::path::Path;

use super::super::super::LightTable;
use super::{Inputs, token};
use crate::simd::{Avx512, LANES, Mask16};
use epsm_testkit::Rng;

/// `sample16` against 16 calls of `sample` on the Cornell box's table, per
/// lane, both compiled for AVX-512 (run with `--release --ignored`; the
/// machine is shared, so the times are rough).
#[test]
#[ignore = "a timing, not a check"]
#[allow(unsafe_code)]
fn sample16_speed_on_the_cornell_box() {
    #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,bmi1,bmi2,lzcnt,popcnt")]
    fn wide(k: Avx512, table: &LightTable, batches: &[Inputs]) {
        for b in batches {
            let (p, u_select, u) = b.lanes(k);
            std::hint::black_box(table.sample16(k, p, u_select, u, Mask16::ALL));
        }
    }
    #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,bmi1,bmi2,lzcnt,popcnt")]
    fn scalar(table: &LightTable, batches: &[Inputs]) {
        for b in batches {
            for i in 0..LANES {
                std::hint::black_box(table.sample(b.p[i], b.u_select[i], b.u[i]));
            }
        }
    }
    let Some(k) = token() else { return };
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-box.toml");
    let scene = crate::scene::load::load_scene(&path).expect("shipped scene loads");
    let mut rng = Rng::new(33);
    let batches: Vec<Inputs> = (0..4096)
        .map(|_| Inputs {
            p: std::array::from_fn(|_| rng.dvec3(-1.0, 1.0).as_vec3()),
            u_select: std::array::from_fn(|_| rng.f32()),
            u: std::array::from_fn(|_| rng.vec2()),
        })
        .collect();
    let (passes, lanes) = (16, (4096 * 16 * LANES) as f64);
    for _ in 0..3 {
        let start = std::time::Instant::now();
        for _ in 0..passes {
            // SAFETY: the token `k` exists only on a CPU with every feature `wide` enables.
            unsafe { wide(k, scene.lights(), &batches) };
        }
        let t_wide = start.elapsed().as_nanos() as f64 / lanes;
        let start = std::time::Instant::now();
        for _ in 0..passes {
            // SAFETY: as above, for `scalar`.
            unsafe { scalar(scene.lights(), &batches) };
        }
        let t_scalar = start.elapsed().as_nanos() as f64 / lanes;
        eprintln!("ns per lane: sample16 {t_wide:.2}, sample {t_scalar:.2}");
    }
}
