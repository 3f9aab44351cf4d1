//! Sampler tests: bijective permutations, blocks against single draws,
//! stratification, uniformity and independence of the streams.

use super::*;

#[test]
fn permutations_are_bijections() {
    for count in [1u32, 2, 3, 7, 16, 17, 64, 100, 256] {
        for pixel in [0u32, 1, 0xDEAD_BEEF, 12345] {
            let keys = PixelKeys::new(9, pixel, count);
            for dim in 0..STRATIFIED {
                let mut seen = vec![false; count as usize];
                for i in 0..count {
                    let j = keys.stratum(i, dim) as usize;
                    assert!(!seen[j], "count {count}, pixel {pixel}: {j} twice");
                    seen[j] = true;
                }
            }
        }
    }
}

#[test]
fn blocks_give_the_numbers_of_their_dimensions() {
    // Counts past 2^30 take the scalar path (`avx2::MAX_COUNT`).
    let huge = 3 << 30;
    let cases = [1u32, 16, 37].map(|spp| (spp, (0..spp).collect::<Vec<_>>()));
    let cases = cases
        .into_iter()
        .chain([(huge, vec![0, 1, 12_345, huge - 1])]);
    for (spp, samples) in cases {
        let keys = PixelKeys::new(3, 4321, spp);
        for sample in samples {
            let sampler = keys.sampler(sample);
            for first in 0..40 {
                let block = sampler.block(first);
                for offset in 0..BLOCK as u32 {
                    let dim = first + offset;
                    assert_eq!(block.get_1d(offset), sampler.get_1d(dim), "dim {dim}");
                    if offset + 1 < BLOCK as u32 {
                        assert_eq!(block.get_2d(offset), sampler.get_2d(dim), "dim {dim}");
                    }
                }
            }
        }
    }
}

#[test]
fn every_dimension_is_stratified_over_the_pixel_samples() {
    for (spp, pixel) in [(37, 1234), (64, 99), (100, 5)] {
        let keys = PixelKeys::new(7, pixel, spp);
        for dim in 0..STRATIFIED_DIMENSIONS {
            let mut strata = vec![0u32; spp as usize];
            for s in 0..spp {
                let x = keys.sampler(s).get_1d(dim);
                assert!((0.0..1.0).contains(&x));
                strata[(x * spp as f32) as usize] += 1;
            }
            assert!(
                strata.iter().all(|&c| c == 1),
                "{spp} spp, dim {dim}: {strata:?}"
            );
        }
    }
}

/// Two stratified dimensions of a pixel's samples fill a coarse grid
/// (high bits of the two strata) and a fine one (low bits) about as two
/// random permutations would: the mean χ² over many pixels is within
/// 15 % of its expectation under random permutations (measured: +4 %
/// and +10 % at 16 strata, under 2 % at 64 and 256; a permutation that
/// leaks its low bits or repeats across dimensions is off by 1.5–10×).
/// Each row of cells holds a fixed number of samples, so a cell count is
/// hypergeometric (drawing a row's samples out of all, the column's
/// being successes).
#[test]
fn stratified_pairs_look_like_random_permutations() {
    let pixels = 1000;
    for (spp, grid) in [(16u32, 4u32), (64, 8), (256, 16)] {
        let (n, g) = (spp as f64, grid as f64);
        let per_row = n / g;
        let mean = per_row * per_row / n;
        let var = per_row * (per_row / n) * (1.0 - per_row / n) * (n - per_row) / (n - 1.0);
        let expected = g * g * var / mean;
        let (mut coarse, mut fine) = (0.0, 0.0);
        let pairs = [(0, 1), (2, 3), (3, 4), (5, 6), (0, 8)];
        for pixel in 0..pixels {
            let keys = PixelKeys::new(11, pixel, spp);
            for (da, db) in pairs {
                let mut cells = vec![[0.0f64; 2]; (grid * grid) as usize];
                for s in 0..spp {
                    let sa = keys.stratum(s, da);
                    let sb = keys.stratum(s, db);
                    cells[(sa / (spp / grid) * grid + sb / (spp / grid)) as usize][0] += 1.0;
                    cells[(sa % grid * grid + sb % grid) as usize][1] += 1.0;
                }
                let chi2 =
                    |k: usize| -> f64 { cells.iter().map(|c| (c[k] - mean).powi(2) / mean).sum() };
                coarse += chi2(0);
                fine += chi2(1);
            }
        }
        let trials = (pixels as usize * pairs.len()) as f64;
        for (name, total) in [("coarse", coarse), ("fine", fine)] {
            let got = total / trials;
            assert!(
                (got / expected - 1.0).abs() < 0.15,
                "{spp} spp, {name} grid: mean χ² {got}, random permutations {expected}"
            );
        }
    }
}

/// Pairs of neighbouring unstratified dimensions fill a 16 × 16 grid
/// evenly (χ² over many pixels and samples) and are uncorrelated.
#[test]
fn unstratified_pairs_are_uniform() {
    for first in [STRATIFIED_DIMENSIONS, 17, 40] {
        let mut cells = [0u32; 256];
        let n = 256 * 400;
        for i in 0..n {
            let keys = PixelKeys::new(5, i / 16, 16);
            let v = keys.sampler(i % 16).get_2d(first);
            cells[(v.x * 16.0) as usize * 16 + (v.y * 16.0) as usize] += 1;
        }
        let expected = n as f64 / 256.0;
        let chi2: f64 = cells
            .iter()
            .map(|&c| (c as f64 - expected).powi(2) / expected)
            .sum();
        // 255 degrees of freedom: mean 255, sd ≈ 22.6; 350 is > 4 sd.
        assert!(chi2 < 350.0, "dims {first}, {}: χ² {chi2}", first + 1);
    }
}

#[test]
fn streams_are_pure_functions_of_their_key_and_differ_between_keys() {
    let stream = |seed, pixel, sample, dim| {
        let keys = PixelKeys::new(seed, pixel, 16);
        keys.sampler(sample).get_2d(dim)
    };
    for dim in [0, 30] {
        let a = stream(1, 2, 3, dim);
        assert_eq!(a, stream(1, 2, 3, dim));
        assert_ne!(a, stream(1, 3, 3, dim));
        assert_ne!(a, stream(2, 2, 3, dim));
        assert_ne!(a, stream(1, 2, 4, dim));
    }
}

#[test]
fn pairs_of_dimensions_are_uncorrelated() {
    // Correlation between two dimensions over many pixels must be ~0, for
    // a stratified pair and an unstratified one.
    let n = 20_000u32;
    for dim in [0, 12] {
        let (mut sx, mut sy, mut sxy, mut sxx, mut syy) = (0.0f64, 0.0, 0.0, 0.0, 0.0);
        for px in 0..n {
            let keys = PixelKeys::new(3, px, 4);
            let v = keys.sampler(px % 4).get_2d(dim);
            let (x, y) = (v.x as f64, v.y as f64);
            sx += x;
            sy += y;
            sxy += x * y;
            sxx += x * x;
            syy += y * y;
        }
        let nf = n as f64;
        let cov = sxy / nf - sx * sy / (nf * nf);
        let var = |s: f64, ss: f64| ss / nf - (s / nf).powi(2);
        let corr = cov / (var(sx, sxx) * var(sy, syy)).sqrt();
        assert!(corr.abs() < 0.03, "dim {dim}: correlation {corr}");
        assert!((sx / nf - 0.5).abs() < 0.01);
    }
}
