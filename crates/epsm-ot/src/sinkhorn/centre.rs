//! Centring: each cloud is moved so its bounding box is centred at the origin before the solve.
//!
//! The entropic plan does not change when either cloud is translated. With
//! `x = x' + a`, `y = y' + b` and `d = a − b`,
//! `‖x − y‖² = ‖x' − y'‖² + 2⟨x', d⟩ − 2⟨y', d⟩ + ‖d‖²`: the terms of one
//! point only are absorbed by the potentials (`f = f' + 2⟨x', d⟩ + ‖d‖²`,
//! `g = g' − 2⟨y', d⟩`), so `π` is the same plan, `OT_ε` and the transport
//! cost grow by the mean of those terms, `2⟨x̄' − ȳ', d⟩ + ‖d‖²` (and so does
//! `S_ε`: its self-transport terms do not move), the barycentres move by `b`
//! and the gradient `2 (P_i − T_i)/n` by `2d/n`.
//!
//! The solve on the centred clouds keeps the potentials, and the `f32`
//! kernel scores that are rounded relative to them, on the scale of the
//! clouds' own extents instead of their distance: two 100-point clouds 1000
//! apart at blur 0.01 ended with an infinite marginal error before. The only
//! change to the input is the rounding of `P − a` to `f32`, within half a
//! unit in the last place of `P` itself.

use crate::cost::diameter_sq;
use crate::plan::EntropicPlan;
use crate::points::{DIM, Point, PointCloud};

/// The two origins a solve's clouds were moved to, and the clouds moved.
pub(super) struct Centred {
    /// The source cloud minus `a`.
    pub source: PointCloud,
    /// The target cloud minus `b`.
    pub target: PointCloud,
    /// `b`, the centre of the target's bounding box.
    target_origin: [f64; DIM],
    /// `d = a − b`.
    shift: [f64; DIM],
    /// `2⟨x̄' − ȳ', d⟩ + ‖d‖²`: what `OT_ε`, `S_ε` and the transport cost grow by.
    value_shift: f64,
}

impl Centred {
    /// Each cloud minus the centre of its own bounding box.
    pub fn new(source: &PointCloud, target: &PointCloud) -> Self {
        let (source_origin, source) = moved(source);
        let (target_origin, target) = moved(target);
        let shift: [f64; DIM] = std::array::from_fn(|d| source_origin[d] - target_origin[d]);
        let mean_along =
            |c: &PointCloud| c.points().map(|p| along(&shift, p)).sum::<f64>() / c.len() as f64;
        let value_shift =
            mean_along(&source) - mean_along(&target) + shift.iter().map(|s| s * s).sum::<f64>();
        Self {
            source,
            target,
            target_origin,
            shift,
            value_shift,
        }
    }

    /// The squared diameter of the centred clouds together (what the kernel sees).
    pub fn diameter_sq(&self) -> f64 {
        diameter_sq(&self.source, &self.target)
    }

    /// What `OT_ε`, `S_ε` and the transport cost grow by: `2⟨x̄' − ȳ', d⟩ + ‖d‖²`.
    pub fn value_shift(&self) -> f64 {
        self.value_shift
    }

    /// The plan of the centred clouds made the plan of the original ones
    /// (potentials, barycentres and transport cost; see the module doc).
    pub fn restore_plan(&self, plan: &mut EntropicPlan) {
        self.move_potentials(&mut plan.f, &mut plan.g, 1.0);
        for t in &mut plan.barycentres {
            *t = std::array::from_fn(|k| (f64::from(t[k]) + self.target_origin[k]) as f32);
        }
        plan.transport_cost += self.value_shift;
    }

    /// Potentials `f, g` of the original clouds (input order) made those of the
    /// centred ones: the inverse of [`Self::restore_plan`]'s (used to warm-start a solve).
    pub fn centre_potentials(&self, f: &mut [f64], g: &mut [f64]) {
        self.move_potentials(f, g, -1.0);
    }

    /// `f += sign (2⟨x'_i, d⟩ + ‖d‖²)`, `g −= sign 2⟨y'_j, d⟩` (see the module doc).
    fn move_potentials(&self, f: &mut [f64], g: &mut [f64], sign: f64) {
        let shift_sq: f64 = self.shift.iter().map(|s| s * s).sum();
        f.iter_mut()
            .zip(self.source.points())
            .for_each(|(f, p)| *f += sign * (along(&self.shift, p) + shift_sq));
        g.iter_mut()
            .zip(self.target.points())
            .for_each(|(g, q)| *g -= sign * along(&self.shift, q));
    }

    /// The gradient `2 (P'_i − T'_i) / n` of the centred clouds plus `2d/n`, from
    /// the centred pull targets (`f64` sums, rounded once).
    pub fn gradient(&self, pull: &[Point]) -> Vec<Point> {
        let scale = 2.0 / self.source.len() as f64;
        self.source
            .points()
            .zip(pull)
            .map(|(p, t)| {
                std::array::from_fn(|k| {
                    (scale * (f64::from(p[k]) - f64::from(t[k]) + self.shift[k])) as f32
                })
            })
            .collect()
    }
}

/// `2⟨p, d⟩` in `f64`.
fn along(d: &[f64; DIM], p: Point) -> f64 {
    (0..DIM).map(|k| 2.0 * f64::from(p[k]) * d[k]).sum()
}

/// The centre of `cloud`'s bounding box and the cloud minus it.
fn moved(cloud: &PointCloud) -> ([f64; DIM], PointCloud) {
    let (lo, hi) = cloud.bounds();
    let origin: [f64; DIM] = std::array::from_fn(|k| 0.5 * (f64::from(lo[k]) + f64::from(hi[k])));
    let columns = std::array::from_fn(|k| {
        cloud.columns()[k]
            .iter()
            .map(|&v| (f64::from(v) - origin[k]) as f32)
            .collect()
    });
    (origin, PointCloud::from_trusted_columns(columns))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sinkhorn::{SinkhornSettings, solve};
    use crate::synthetic::uniform_cloud;

    #[test]
    fn a_translated_pair_has_the_same_plan_moved() {
        let (Some(a), Some(b)) = (uniform_cloud(60, 3), uniform_cloud(60, 4)) else {
            panic!("fixture");
        };
        let shift = |c: &PointCloud, t: f32| {
            let points: Vec<Point> = c.points().map(|p| p.map(|v| v + t)).collect();
            PointCloud::from_points(&points).unwrap_or_else(|e| panic!("{e}"))
        };
        let settings = SinkhornSettings::default();
        let r0 = solve(&a, &b, &settings).unwrap_or_else(|e| panic!("{e}"));
        // d = (1000, …, 1000) − (−500, …): the old code's marginal error was infinite.
        let (a1, b1) = (shift(&a, 1000.0), shift(&b, -500.0));
        let r1 = solve(&a1, &b1, &settings).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(r1.stats.unconverged_solves, 0);
        // OT_ε(a + D, b) = OT_ε(a, b) + 2⟨ā − b̄, D⟩ + ‖D‖², D = 1500 along every axis.
        // The inputs moved by up to half an ulp of 1000 (3e-5): plans agree to about that.
        let sum = |c: &PointCloud| c.points().flatten().map(f64::from).sum::<f64>() / 60.0;
        let d2 = 5.0 * 1500.0 * 1500.0;
        let expected = r0.loss + 2.0 * 1500.0 * (sum(&a) - sum(&b)) + d2;
        assert!(
            (r1.loss - expected).abs() <= 1e-8 * d2,
            "{expected} {}",
            r1.loss
        );
        assert_eq!(r0.gradient.len(), r1.gradient.len());
        for (g0, g1) in r0.gradient.iter().zip(&r1.gradient) {
            for k in 0..DIM {
                let expected = f64::from(g0[k]) + 2.0 * 1500.0 / 60.0;
                assert!((f64::from(g1[k]) - expected).abs() <= 1e-3, "{g0:?} {g1:?}");
            }
        }
    }
}
