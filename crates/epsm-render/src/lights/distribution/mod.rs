//! Piecewise-constant 1D and 2D distributions for importance sampling
//! (pbrt-v4 §A.4): light selection by power, triangle selection by area and
//! environment-map texel selection by luminance.
//!
//! Cumulative sums are kept in `f64` so that tables of millions of entries
//! stay exact to `f32` precision; entries of weight zero are never sampled.

use glam::Vec2;

/// Distributions of at most this many entries are sampled from a [`Small`]
/// table (a branch-free count and a resolved pick) instead of a binary search.
const SMALL_MAX: usize = 16;
const _: () = assert!(SMALL_MAX.is_power_of_two());

/// A discrete choice: the index, its probability and the uniform number
/// re-stretched to `[0, 1)` within the chosen entry (reusable for a further
/// independent choice).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiscreteSample {
    /// Chosen entry.
    pub index: usize,
    /// Probability of the entry.
    pub pmf: f64,
    /// The uniform number remapped into `[0, 1)` inside the entry.
    pub u_remapped: f64,
}

/// A piecewise-constant density on `[0, 1)` (equal-width entries), also used
/// as a discrete distribution over its entries.
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution1D {
    /// Non-negative weights.
    func: Vec<f64>,
    /// Normalised cumulative sums, `cdf[0] = 0`, `cdf[n] = 1`.
    cdf: Vec<f64>,
    /// Sum of the weights.
    total: f64,
    /// The only entry of non-zero weight, when there is exactly one (a scene
    /// with one light): sampling then needs no search.
    single: Option<usize>,
    /// The count-and-pick table of a distribution of at most [`SMALL_MAX`]
    /// entries (light selection, the triangles of a small emitter).
    small: Option<Box<Small>>,
}

/// The sampling table of a distribution of `n ≤ SMALL_MAX` entries. The
/// entry that `u` selects is found as the count `k` of inner boundaries
/// `cdf[1..n]` with `cdf[i] ≤ u` (`cdf[0] = 0 ≤ u` and `cdf[n] = 1` need no
/// test). Padded with +∞ (never `≤ u`) to a fixed length, the sorted
/// boundaries are counted by a branch-free binary search of `log2 P` steps
/// (`P ≥ n` the next power of two: one step for two entries, four for 16);
/// `pick[k]` is the entry count `k` lands in with zero-weight entries skipped
/// downward, and its cdf bounds, precomputed. So it selects exactly what the
/// binary search of [`Distribution1D::sample_discrete`] does.
#[derive(Clone, Debug, PartialEq)]
struct Small {
    /// `cdf[1..n]`, then +∞.
    inner: [f64; SMALL_MAX],
    /// The pick of each count `k < n` (unused past `n − 1`).
    pick: [SmallPick; SMALL_MAX],
    /// `P / 2`, the search's first step (0 for one entry).
    first_step: usize,
}

/// The entry a [`Small`] count selects and its cdf bounds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct SmallPick {
    /// The entry (of non-zero weight unless entry 0 is the only candidate).
    pub(super) index: usize,
    /// `cdf[index]`.
    pub(super) lo: f64,
    /// `cdf[index + 1]`.
    pub(super) hi: f64,
}

impl Small {
    /// The table of `func` with normalised cumulative sums `cdf`; `None` for
    /// more than [`SMALL_MAX`] entries.
    fn new(func: &[f64], cdf: &[f64]) -> Option<Box<Self>> {
        let n = func.len();
        if n > SMALL_MAX {
            return None;
        }
        let mut small = Box::new(Self {
            inner: [f64::INFINITY; SMALL_MAX],
            pick: [SmallPick::default(); SMALL_MAX],
            first_step: n.next_power_of_two() / 2,
        });
        small.inner[..n - 1].copy_from_slice(&cdf[1..n]);
        for (k, pick) in small.pick.iter_mut().enumerate().take(n) {
            let mut index = k;
            while func[index] == 0.0 && index > 0 {
                index -= 1;
            }
            *pick = SmallPick {
                index,
                lo: cdf[index],
                hi: cdf[index + 1],
            };
        }
        Some(small)
    }

    /// The pick for `u ∈ [0, 1]`.
    #[inline(always)]
    fn pick(&self, u: f64) -> SmallPick {
        // Upper bound in the sorted `inner`: after the step of size `s`, `k`
        // is the count among the first `k + s` boundaries, so after P/2, …,
        // 2 and 1 it counts all of the first P − 1 ≥ n − 1 (the rest are
        // +∞). The masks only spare the bounds checks: `k + s − 1 ≤ 14`,
        // `k ≤ 15`. Each step's compare is a coin flip (a light's two
        // triangles of equal area), so it selects without a branch: LLVM
        // turned `step * usize::from(..)` into one, mispredicted on 1.5 of
        // `scenes/cornell-box.toml`'s 12 simulated mispredicts per sample.
        let mut k = 0;
        let mut step = self.first_step;
        while step > 0 {
            let below = self.inner[(k + step - 1) & (SMALL_MAX - 1)] <= u;
            k += std::hint::select_unpredictable(below, step, 0);
            step /= 2;
        }
        self.pick[k & (SMALL_MAX - 1)]
    }
}

impl Distribution1D {
    /// A distribution over `weights` (negative and non-finite weights count as
    /// zero). `None` when all weights are zero or there are none.
    pub fn new(weights: &[f64]) -> Option<Self> {
        let func: Vec<f64> = weights
            .iter()
            .map(|&w| if w.is_finite() && w > 0.0 { w } else { 0.0 })
            .collect();
        let mut cdf = Vec::with_capacity(func.len() + 1);
        let mut acc = 0.0;
        cdf.push(0.0);
        for &w in &func {
            acc += w;
            cdf.push(acc);
        }
        if !(acc > 0.0 && acc.is_finite()) {
            return None;
        }
        for c in &mut cdf {
            *c /= acc;
        }
        let mut nonzero = func.iter().enumerate().filter(|(_, w)| **w > 0.0);
        let single = match (nonzero.next(), nonzero.next()) {
            (Some((index, _)), None) => Some(index),
            _ => None,
        };
        let small = Small::new(&func, &cdf);
        Some(Self {
            func,
            cdf,
            total: acc,
            single,
            small,
        })
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.func.len()
    }

    /// Whether there are no entries (never true for a constructed distribution).
    pub fn is_empty(&self) -> bool {
        self.func.is_empty()
    }

    /// Sum of the weights.
    pub fn total(&self) -> f64 {
        self.total
    }

    /// The only entry of non-zero weight, when there is exactly one (then
    /// [`Self::sample_discrete`] needs no table).
    #[cfg(target_arch = "x86_64")]
    pub(super) fn single(&self) -> Option<usize> {
        self.single
    }

    /// The [`Small`] table of a distribution of `n ≤ 16` entries: its inner
    /// boundaries `cdf[1..n]` (sorted) and the pick of each count `0..n` of
    /// boundaries `≤ u`, so the pick for `u` is `picks[count]`.
    #[cfg(target_arch = "x86_64")]
    pub(super) fn small_table(&self) -> Option<(&[f64], &[SmallPick])> {
        let n = self.func.len();
        let small = self.small.as_deref()?;
        Some((&small.inner[..n - 1], &small.pick[..n]))
    }

    /// Probability of entry `index`.
    pub fn pmf(&self, index: usize) -> f64 {
        self.func.get(index).map_or(0.0, |w| w / self.total)
    }

    /// Chooses an entry with probability proportional to its weight.
    #[inline(always)]
    pub fn sample_discrete(&self, u: f64) -> DiscreteSample {
        // The entry i with cdf[i] ≤ u < cdf[i + 1]; zero-weight entries have an
        // empty interval and are skipped.
        let u = u.clamp(0.0, 1.0);
        if let Some(index) = self.single {
            // What the search below gives: cdf = 0 up to the entry and 1 from
            // it on (w / w is exact), so pmf 1 and u unchanged.
            return DiscreteSample {
                index,
                pmf: 1.0,
                u_remapped: u.min(1.0 - f64::EPSILON),
            };
        }
        let SmallPick { index, lo, hi } = match &self.small {
            Some(small) => small.pick(u),
            None => self.search(u),
        };
        let u_remapped = ((u - lo) / (hi - lo)).clamp(0.0, 1.0 - f64::EPSILON);
        DiscreteSample {
            index,
            pmf: hi - lo,
            u_remapped,
        }
    }

    /// The entry `u ∈ [0, 1]` selects by binary search over the cdf (the
    /// entry `i` with `cdf[i] ≤ u < cdf[i + 1]`, zero-weight entries skipped
    /// downward) and its cdf bounds.
    #[inline(always)]
    fn search(&self, u: f64) -> SmallPick {
        let n = self.func.len();
        let mut index = self
            .cdf
            .partition_point(|&c| c <= u)
            .saturating_sub(1)
            .min(n - 1);
        while self.func[index] == 0.0 && index > 0 {
            index -= 1;
        }
        SmallPick {
            index,
            lo: self.cdf[index],
            hi: self.cdf[index + 1],
        }
    }

    /// Samples `x ∈ [0, 1)` from the piecewise-constant density; returns
    /// `(x, density at x, entry)`.
    pub fn sample_continuous(&self, u: f64) -> ContinuousSample {
        let d = self.sample_discrete(u);
        let n = self.func.len() as f64;
        ContinuousSample {
            x: ((d.index as f64 + d.u_remapped) / n).min(1.0 - f64::EPSILON),
            pdf: d.pmf * n,
            index: d.index,
        }
    }

    /// Density at `x ∈ [0, 1]` of [`Self::sample_continuous`].
    pub fn pdf(&self, x: f64) -> f64 {
        let n = self.func.len();
        let i = ((x * n as f64) as usize).min(n - 1);
        self.pmf(i) * n as f64
    }
}

/// A sampled point of a continuous piecewise-constant density.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContinuousSample {
    /// The point in `[0, 1)`.
    pub x: f64,
    /// Density at `x`.
    pub pdf: f64,
    /// The entry `x` lies in.
    pub index: usize,
}

/// A piecewise-constant density on `[0, 1)²` over a `width × height` table
/// (row `y` covers `v ∈ [y/h, (y+1)/h)`), sampled as a marginal over rows and
/// a conditional within the row.
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution2D {
    rows: Vec<Option<Distribution1D>>,
    marginal: Distribution1D,
}

/// A sampled point of a [`Distribution2D`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample2D {
    /// The point `(u, v)` in `[0, 1)²`.
    pub uv: Vec2,
    /// Density at the point with respect to `du dv`.
    pub pdf: f64,
}

impl Distribution2D {
    /// A distribution over a row-major `width × height` table of weights.
    /// `None` when every weight is zero.
    pub fn new(weights: &[f64], width: usize, height: usize) -> Option<Self> {
        debug_assert_eq!(weights.len(), width * height);
        let rows: Vec<Option<Distribution1D>> = weights
            .chunks(width.max(1))
            .take(height)
            .map(Distribution1D::new)
            .collect();
        let row_weights: Vec<f64> = rows
            .iter()
            .map(|r| r.as_ref().map_or(0.0, |r| r.total()))
            .collect();
        let marginal = Distribution1D::new(&row_weights)?;
        Some(Self { rows, marginal })
    }

    /// Samples `(u, v)` with density proportional to the table.
    pub fn sample(&self, u: Vec2) -> Option<Sample2D> {
        let row = self.marginal.sample_continuous(u.y as f64);
        let col = self.rows[row.index].as_ref()?.sample_continuous(u.x as f64);
        Some(Sample2D {
            uv: Vec2::new(col.x as f32, row.x as f32),
            pdf: row.pdf * col.pdf,
        })
    }

    /// Density at `uv` of [`Self::sample`].
    pub fn pdf(&self, uv: Vec2) -> f64 {
        let h = self.rows.len();
        let y = ((uv.y as f64 * h as f64) as usize).min(h - 1);
        match &self.rows[y] {
            Some(row) => self.marginal.pdf(uv.y as f64) * row.pdf(uv.x as f64),
            None => 0.0,
        }
    }
}

#[cfg(test)]
mod tests;
