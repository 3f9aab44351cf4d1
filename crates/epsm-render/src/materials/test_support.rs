//! Test functions shared by the material and light tests: the shared
//! deterministic random stream (`epsm_testkit::Rng`), spherical binning and Pearson's χ² goodness-of-fit test with
//! pbrt's pooling of low-expectation bins (pbrt-v3 `bsdfs_test`).

use glam::Vec3;

pub use epsm_testkit::Rng;

/// The unit direction with polar angle `theta` (from `+z`) and azimuth `phi`.
pub fn spherical(theta: f64, phi: f64) -> Vec3 {
    Vec3::new(
        (theta.sin() * phi.cos()) as f32,
        (theta.sin() * phi.sin()) as f32,
        theta.cos() as f32,
    )
}

/// Integrates `f(ω)` over the sphere with an `n_theta × 2 n_theta` midpoint rule in (θ, φ).
pub fn integrate_sphere(n_theta: usize, mut f: impl FnMut(Vec3) -> f64) -> f64 {
    let n_phi = 2 * n_theta;
    let (dt, dp) = (
        std::f64::consts::PI / n_theta as f64,
        2.0 * std::f64::consts::PI / n_phi as f64,
    );
    let mut sum = 0.0;
    for i in 0..n_theta {
        let theta = (i as f64 + 0.5) * dt;
        for j in 0..n_phi {
            let phi = (j as f64 + 0.5) * dp;
            sum += f(spherical(theta, phi)) * theta.sin() * dt * dp;
        }
    }
    sum
}

/// Bins of a (θ, φ) histogram over the sphere.
pub const THETA_BINS: usize = 20;
/// Azimuthal bins.
pub const PHI_BINS: usize = 40;

fn bin_of(w: Vec3) -> usize {
    let theta = (w.z as f64).clamp(-1.0, 1.0).acos();
    let phi = (w.y as f64)
        .atan2(w.x as f64)
        .rem_euclid(2.0 * std::f64::consts::PI);
    let i = ((theta / std::f64::consts::PI * THETA_BINS as f64) as usize).min(THETA_BINS - 1);
    let j = ((phi / (2.0 * std::f64::consts::PI) * PHI_BINS as f64) as usize).min(PHI_BINS - 1);
    i * PHI_BINS + j
}

/// Histogram of sampled directions (`None` = a sample that carried no energy).
pub fn histogram(n: usize, mut sample: impl FnMut() -> Option<Vec3>) -> Vec<f64> {
    let mut h = vec![0.0; THETA_BINS * PHI_BINS];
    for _ in 0..n {
        if let Some(w) = sample() {
            h[bin_of(w)] += 1.0;
        }
    }
    h
}

/// Expected counts per bin: `n · ∫_bin pdf dω` with a `sub × sub` midpoint rule.
pub fn expected_counts(n: usize, sub: usize, mut pdf: impl FnMut(Vec3) -> f64) -> Vec<f64> {
    let (dt, dp) = (
        std::f64::consts::PI / (THETA_BINS * sub) as f64,
        2.0 * std::f64::consts::PI / (PHI_BINS * sub) as f64,
    );
    let mut e = vec![0.0; THETA_BINS * PHI_BINS];
    for i in 0..THETA_BINS * sub {
        let theta = (i as f64 + 0.5) * dt;
        for j in 0..PHI_BINS * sub {
            let phi = (j as f64 + 0.5) * dp;
            let bin = (i / sub) * PHI_BINS + j / sub;
            e[bin] += pdf(spherical(theta, phi)) * theta.sin() * dt * dp * n as f64;
        }
    }
    e
}

/// Pearson's χ² test with bins of expectation < 5 pooled (pbrt-v3). Returns
/// the p-value; panics with a message when a bin of zero expectation is hit.
pub fn chi2_p_value(observed: &[f64], expected: &[f64]) -> f64 {
    let mut order: Vec<usize> = (0..observed.len()).collect();
    order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let (mut pooled_o, mut pooled_e, mut pooled_n) = (0.0, 0.0, 0);
    let (mut chi2, mut dof) = (0.0, 0i64);
    for &i in &order {
        let (o, e) = (observed[i], expected[i]);
        if e == 0.0 {
            assert!(o <= 0.0, "{o} samples in bin {i} of zero expectation");
        } else if e < 5.0 {
            pooled_o += o;
            pooled_e += e;
            pooled_n += 1;
        } else if pooled_n > 0 && pooled_e < 5.0 {
            // Close the pool with this bin.
            chi2 += (o + pooled_o - e - pooled_e).powi(2) / (e + pooled_e);
            dof += 1;
            pooled_o = 0.0;
            pooled_e = 0.0;
            pooled_n = 0;
        } else {
            chi2 += (o - e).powi(2) / e;
            dof += 1;
        }
    }
    if pooled_n > 0 {
        chi2 += (pooled_o - pooled_e).powi(2) / pooled_e.max(1e-12);
        dof += 1;
    }
    let dof = (dof - 1).max(1) as f64;
    gamma_q(dof / 2.0, chi2 / 2.0)
}

/// Asserts the χ² test passes at overall significance 0.01 over `tests`
/// tests run together (Šidák correction, as pbrt-v3).
pub fn assert_chi2(what: &str, observed: &[f64], expected: &[f64], tests: usize) {
    let p = chi2_p_value(observed, expected);
    let threshold = 1.0 - 0.99f64.powf(1.0 / tests.max(1) as f64);
    assert!(
        p > threshold,
        "{what}: χ² test rejects the sampler, p = {p:.3e} < {threshold:.3e}"
    );
}

/// Regularised upper incomplete gamma `Q(a, x)` (Numerical Recipes §6.2).
fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let ln_pre = -x + a * x.ln() - ln_gamma(a);
    if x < a + 1.0 {
        let (mut ap, mut sum, mut del) = (a, 1.0 / a, 1.0 / a);
        for _ in 0..10_000 {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * ln_pre.exp()
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-15 {
                break;
            }
        }
        ln_pre.exp() * h
    }
}

/// `ln Γ(x)` for `x > 0` (Lanczos, g = 7, n = 9).
fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    let x = x - 1.0;
    let t = x + 7.5;
    let mut s = C[0];
    for (i, c) in C.iter().enumerate().skip(1) {
        s += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + s.ln()
}

#[test]
fn chi2_test_accepts_a_fair_die_and_rejects_a_loaded_one() {
    assert!((ln_gamma(5.0) - 24f64.ln()).abs() < 1e-10);
    // Q(1, x) = e^{-x}.
    assert!((gamma_q(1.0, 2.0) - (-2f64).exp()).abs() < 1e-10);
    assert!((gamma_q(1.0, 0.3) - (-0.3f64).exp()).abs() < 1e-10);
    let mut rng = Rng::new(7);
    let mut fair = vec![0.0; 6];
    let mut loaded = vec![0.0; 6];
    for _ in 0..60_000 {
        fair[(rng.f32() * 6.0) as usize] += 1.0;
        let u = rng.f32();
        loaded[((u * u.sqrt()) * 6.0) as usize] += 1.0;
    }
    let expected = vec![10_000.0; 6];
    assert!(chi2_p_value(&fair, &expected) > 0.01);
    assert!(chi2_p_value(&loaded, &expected) < 1e-6);
}
