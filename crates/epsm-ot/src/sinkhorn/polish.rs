//! Step 4 of the ε-scaling loop ([`super::dual`]): Anderson-accelerated
//! full updates at the final ε until the source marginal is within
//! tolerance, with the stall test that ends a polish early.

use super::SinkhornSettings;
use super::anderson::{Anderson, Guarded};
use super::dual::{Dual, Guards, Loop, converged, row_marginal_error};
use super::pass::{Cut, Level, softmin};
use crate::clusters::{Clustered, Support};
use crate::plan::PhaseTimes;

/// Polish: Anderson-accelerated updates at the final ε, from potentials `f, g`, until the source
/// marginal is within tolerance; `pairs` and `iterations` carry the work done so far.
pub(crate) fn polish(
    x: &Clustered,
    y: &Clustered,
    mut f: Vec<f64>,
    mut g: Vec<f64>,
    settings: &SinkhornSettings,
    pairs: u64,
    iterations: usize,
) -> Dual {
    let mut lp = Loop {
        x,
        y,
        settings,
        pairs,
        iterations,
        guards: Guards::default(),
    };
    let (fx, fy) = (Level::fine(x), Level::fine(y));
    let start = std::time::Instant::now();
    let eps = settings.blur * settings.blur;
    let anderson = Anderson::new(settings.anderson_memory, settings.overrelaxation);
    let mut guarded = Guarded::new(anderson, &f);
    let threshold = settings.truncation * eps;
    let mut support = lp.support(&f, &g, threshold);
    let mut marginal_error = f64::INFINITY;
    // `g ← softmin(f)`: the target marginal exact.
    let target_update = |support: &Support, f: &[f64], g: &[f64]| {
        softmin(
            &fy,
            &fx,
            &support.cols,
            f,
            eps,
            Some(Cut { own: g, threshold }),
        )
    };
    // The smallest marginal error after each update (NaN ignored), for the stall test.
    let mut best: Vec<f64> = Vec::new();
    for round in 0..settings.max_polish_iterations {
        // One full update from f: g exact for the target marginal, then the source update.
        let (gt, p1) = target_update(&support, &f, &g);
        g = gt;
        let (ft, p2) = softmin(
            &fx,
            &fy,
            &support.rows,
            &g,
            eps,
            Some(Cut { own: &f, threshold }),
        );
        lp.pairs += p1 + p2;
        lp.iterations += 1;
        marginal_error = row_marginal_error(&f, &ft, eps);
        if converged(marginal_error, settings.marginal_tolerance) {
            break;
        }
        best.push(
            best.last()
                .map_or(marginal_error, |&b| b.min(marginal_error)),
        );
        if stalled(&best, settings) {
            break;
        }
        let restarted;
        (f, restarted) = guarded.step(&f, &ft, marginal_error);
        if !restarted && round % SUPPORT_REFRESH == SUPPORT_REFRESH - 1 {
            support = lp.support(&f, &g, threshold);
        }
    }
    if !converged(marginal_error, settings.marginal_tolerance) {
        // Out of iterations (or a NaN error): f moved after the last g update; make the
        // target marginal exact again. After a stall (the loop left before its step) f
        // has not moved, and this repeats the round's g update with the new g as the cut.
        let (gt, pairs) = target_update(&support, &f, &g);
        lp.pairs += pairs;
        g = gt;
    }
    let mut phases = PhaseTimes::default();
    phases.add("polish", start.elapsed().as_secs_f64());
    Dual {
        f,
        g,
        eps,
        support,
        iterations: lp.iterations,
        pairs: lp.pairs,
        marginal_error,
        guards: Guards::default(),
        phases,
    }
}

/// Polish iterations between two refreshes of the truncated support.
const SUPPORT_REFRESH: usize = 8;

/// Updates before the polish's stall test applies (the first updates of an
/// Anderson polish are too noisy to extrapolate).
const STALL_MIN_UPDATES: usize = 100;

/// Whether a polish has stalled (see `SinkhornSettings::stall_margin`):
/// after `best.len()` updates (`best[k]`: the smallest error after update
/// `k + 1`), whether even `stall_margin` times the rate at which the smallest
/// error fell over the second half of those updates (per update, in log
/// error) falls short of reaching `marginal_tolerance` within the updates
/// left. A polish with no finite error after [`STALL_MIN_UPDATES`] has stalled.
fn stalled(best: &[f64], settings: &SinkhornSettings) -> bool {
    let k = best.len();
    if k < STALL_MIN_UPDATES || settings.stall_margin.is_infinite() {
        return false;
    }
    let now = best[k - 1];
    if !now.is_finite() {
        return true;
    }
    let half = k / 2;
    // Infinite when the second half found the first finite error: not stalled.
    let rate = (best[half - 1] / now).ln() / (k - half) as f64;
    let left = settings.max_polish_iterations.saturating_sub(k) as f64;
    (now / settings.marginal_tolerance).ln() > settings.stall_margin * rate * left
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synthetic::uniform_cloud;

    #[test]
    fn a_nan_marginal_error_is_not_converged_and_the_target_marginal_is_restored() {
        let n = 8;
        let (Some(a), Some(b)) = (uniform_cloud(n, 1), uniform_cloud(n, 2)) else {
            panic!("fixture");
        };
        // One cluster each: every pass streams all n² pairs.
        let (x, y) = (Clustered::new(&a, 32), Clustered::new(&b, 32));
        let settings = SinkhornSettings {
            max_polish_iterations: 1,
            ..SinkhornSettings::default()
        };
        let mut f = vec![0.0; n];
        f[3] = f64::NAN;
        let dual = polish(&x, &y, f, vec![0.0; n], &settings, 0, 0);
        assert!(dual.marginal_error.is_nan());
        assert!(!converged(dual.marginal_error, settings.marginal_tolerance));
        // The round's two updates, then the final target update of the unconverged exit.
        assert_eq!(dual.pairs, 3 * (n * n) as u64);
    }
}
