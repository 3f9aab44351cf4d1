//! The logarithmic y axis of a panel: its range snapped outward to
//! `m × 10^k`, labels at `1…9 × 10^k`, `1, 2, 5 × 10^k` or every n-th `10^k`
//! (the densest that keeps at most `MAX_LABELS`), and short tick labels.

/// A logarithmic axis: its range widened by `MARGIN` each way and snapped
/// outward to `m × 10^k` (m in 1…10), the labelled values and the minor grid
/// values inside it.
#[derive(Debug)]
pub(super) struct LogAxis {
    /// Lowest value on the axis.
    pub lo: f64,
    /// Highest value on the axis.
    pub hi: f64,
    /// Labelled values, ascending.
    pub labels: Vec<f64>,
    /// Minor grid values, ascending (none when there would be too many).
    pub minor: Vec<f64>,
}

/// Most labels on one axis.
const MAX_LABELS: usize = 12;
/// Factor by which the data's range is widened before snapping, so that no
/// curve runs along the frame.
const MARGIN: f64 = 1.08;

impl LogAxis {
    /// The axis for data in `[lo, hi]` (`0 < lo ≤ hi`; anything else, as
    /// when there is no data, gives `[0.001, 1]`).
    pub fn new(lo: f64, hi: f64) -> Self {
        let (lo, hi) = if lo.is_finite() && hi.is_finite() && lo > 0.0 && lo <= hi {
            (lo, hi)
        } else {
            (1e-3, 1.0)
        };
        let lo = snap_down(lo / MARGIN);
        let mut hi = snap_up(hi * MARGIN);
        if hi <= lo {
            hi = snap_up(lo * 1.0001);
        }
        let all = values_between(lo, hi, &[1, 2, 3, 4, 5, 6, 7, 8, 9], 1);
        let labels = [
            (&[1u32, 2, 3, 4, 5, 6, 7, 8, 9][..], 1),
            (&[1, 2, 5][..], 1),
        ]
        .iter()
        .map(|(m, every)| values_between(lo, hi, m, *every))
        .chain((1..).map(|every| values_between(lo, hi, &[1], every)))
        .find(|v| v.len() <= MAX_LABELS)
        .unwrap_or_default();
        let minor = if all.len() <= 90 { all } else { Vec::new() };
        Self {
            lo,
            hi,
            labels,
            minor,
        }
    }
}

/// The largest `m × 10^k ≤ v` with m in 1…9.
fn snap_down(v: f64) -> f64 {
    let p = 10f64.powf(v.log10().floor());
    let m = (v / p * (1.0 + 1e-12)).floor().clamp(1.0, 10.0);
    m * p
}

/// The smallest `m × 10^k ≥ v` with m in 1…10.
fn snap_up(v: f64) -> f64 {
    let p = 10f64.powf(v.log10().floor());
    let m = (v / p * (1.0 - 1e-12)).ceil().clamp(1.0, 10.0);
    m * p
}

/// `m × 10^k` for the mantissas `m` and every `every`-th decade `k` from the
/// first power of ten in the range, within `[lo, hi]` (to rounding),
/// ascending.
fn values_between(lo: f64, hi: f64, mantissas: &[u32], every: i32) -> Vec<f64> {
    let (k0, k1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let first = lo.log10().ceil() as i32;
    let mut out = Vec::new();
    for k in (k0..=k1).filter(|k| (k - first).rem_euclid(every) == 0) {
        for &m in mantissas {
            let v = f64::from(m) * 10f64.powi(k);
            if v >= lo * (1.0 - 1e-9) && v <= hi * (1.0 + 1e-9) {
                out.push(v);
            }
        }
    }
    out
}

/// A short label for a value `m × 10^k`: plain decimals between 0.001 and
/// 10⁴, else `me±k`.
pub(super) fn tick(v: f64) -> String {
    if (1e-3..1e4).contains(&v.abs()) {
        let decimals = (-v.abs().log10() - 1e-9).ceil().max(0.0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.0e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn labels(lo: f64, hi: f64) -> Vec<String> {
        LogAxis::new(lo, hi)
            .labels
            .iter()
            .map(|v| tick(*v))
            .collect()
    }

    #[test]
    fn a_range_within_one_decade_is_labelled_throughout() {
        // An image RMSE between 0.021 and 0.047: no power of ten inside.
        assert_eq!(
            labels(0.021, 0.047),
            ["0.01", "0.02", "0.03", "0.04", "0.05", "0.06"]
        );
        // A parameter error from 0.5 down to 0.1.
        assert_eq!(
            labels(0.1, 0.5),
            ["0.09", "0.1", "0.2", "0.3", "0.4", "0.5", "0.6"]
        );
    }

    #[test]
    fn the_axis_covers_the_data_and_its_ends_are_labelled() {
        for (lo, hi) in [
            (0.0072, 1.06),
            (3.1e-5, 0.4),
            (0.25, 0.26),
            (2.0, 2.0),
            (1e-9, 1e3),
        ] {
            let a = LogAxis::new(lo, hi);
            assert!(a.lo <= lo && a.hi >= hi, "{a:?} misses [{lo}, {hi}]");
            assert!(a.labels.len() >= 2, "{a:?}: fewer than two labels");
            assert!(a.labels.len() <= MAX_LABELS, "{a:?}: too many labels");
            // No decade of the data without a label at its ends' scale: the
            // lowest label is within a factor 10 of the axis' start, the
            // highest within a factor 10 of its end.
            assert!(a.labels[0] < a.lo * 10.0 + 1e-300, "{a:?}");
            assert!(a.labels[a.labels.len() - 1] > a.hi / 10.0, "{a:?}");
        }
    }

    #[test]
    fn wide_ranges_thin_their_labels_to_decades() {
        assert_eq!(
            labels(1e-6, 0.9),
            ["1e-6", "1e-5", "1e-4", "0.001", "0.01", "0.1", "1"]
        );
        let every_other = labels(1e-20, 1.0);
        assert!(every_other.len() <= MAX_LABELS, "{every_other:?}");
    }

    #[test]
    fn no_data_gives_a_default_axis() {
        let a = LogAxis::new(f64::INFINITY, 0.0);
        assert!(a.lo <= 1e-3 && a.hi >= 1.0, "{a:?}");
        assert!(a.labels.len() >= 2, "{a:?}");
    }

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(tick(0.05), "0.05");
        assert_eq!(tick(0.1), "0.1");
        assert_eq!(tick(3.0 * 10f64.powi(-2)), "0.03");
        assert_eq!(tick(20.0), "20");
        assert_eq!(tick(2e-5), "2e-5");
    }
}
