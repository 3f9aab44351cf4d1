//! Methods and the hybrid schedule (docs/design.md §5.8).
//!
//! | method | loss | screen-position gradients |
//! |---|---|---|
//! | `epsm` | the problem's loss (OT), then L2 for the final `l2_fraction` | every path type (manifold solves) |
//! | `drot` | OT, then L2 for the final `l2_fraction` | primary paths only (Xing et al. 2022) |
//! | `l2` | L2 throughout | none: colour derivatives only |
//!
//! The switch from OT to L2 comes at a fixed iteration
//! (`optimizer.l2_fraction`) or, by default, when the OT phase stops
//! improving ([`Plateau`]). Problems whose parameters are all material
//! values, and problems with an L2 loss, are L2 throughout. Adam is reset
//! at the switch ([`crate::optim::Adam::reset`]: new moments, and the step
//! size of half the iterations run so far).

use serde::{Deserialize, Serialize};

use crate::loss::LossKind;

/// Which method an optimization runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Full EPSM + OT.
    Epsm,
    /// OT with primary paths only.
    Drot,
    /// L2 with colour derivatives only.
    L2,
    /// The L2 loss smoothed by a Gaussian in parameter space, its gradient
    /// estimated from forward renders at perturbed θ (`crate::run::prdpt`).
    Prdpt,
}

impl Method {
    /// Every method, in report order.
    pub const ALL: [Method; 4] = [Method::Epsm, Method::Drot, Method::L2, Method::Prdpt];

    /// The method named `name` (`epsm`, `drot`, `l2`, `prdpt`).
    pub fn parse(name: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == name)
    }

    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            Method::Epsm => "epsm",
            Method::Drot => "drot",
            Method::L2 => "l2",
            Method::Prdpt => "prdpt",
        }
    }

    /// Whether the method runs the problem's OT loss before its switch (the
    /// `l2` and `prdpt` methods use L2 throughout).
    pub fn uses_ot(self) -> bool {
        matches!(self, Method::Epsm | Method::Drot)
    }
}

/// Which paths contribute screen-position gradients in an iteration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PathUse {
    /// None: colour derivatives only.
    ColourOnly,
    /// Primary paths only.
    PrimaryOnly,
    /// Every differentiable path type.
    All,
}

/// Detects that a loss has stopped improving: its exponential moving
/// average (weight [`Plateau::SMOOTHING`] on the newest value) has not
/// fallen by [`Plateau::MIN_GAIN`] (relative) below its best for `window`
/// observations.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Plateau {
    /// Observations without improvement that make a plateau.
    pub window: u32,
    /// Observations so far.
    pub seen: u32,
    /// The moving average (`None` before the first observation).
    pub average: Option<f64>,
    /// Its lowest value so far (`None` before the first observation).
    pub best: Option<f64>,
    /// The observation (0-based) that set `best`.
    pub best_at: u32,
}

impl Plateau {
    /// Weight of the newest value in the moving average.
    pub const SMOOTHING: f64 = 0.3;
    /// The relative fall of the average that counts as an improvement.
    pub const MIN_GAIN: f64 = 0.01;

    /// A detector with no observations.
    pub fn new(window: u32) -> Self {
        Self {
            window: window.max(1),
            seen: 0,
            average: None,
            best: None,
            best_at: 0,
        }
    }

    /// Adds `value`; returns whether the average has now gone `window`
    /// observations without improving.
    pub fn observe(&mut self, value: f64) -> bool {
        let a = self.average.map_or(value, |a| {
            Self::SMOOTHING * value + (1.0 - Self::SMOOTHING) * a
        });
        self.average = Some(a);
        if self.best.is_none_or(|b| a < b * (1.0 - Self::MIN_GAIN)) {
            self.best = Some(a);
            self.best_at = self.seen;
        }
        self.seen += 1;
        self.seen - self.best_at > self.window
    }
}

/// When the OT phase ends.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Switch {
    /// At this iteration (0: L2 throughout; `iterations`: never).
    At(u32),
    /// When the OT loss reaches a plateau, at the latest at iteration
    /// `latest`.
    OnPlateau {
        /// The detector.
        plateau: Plateau,
        /// The last iteration that may still run OT.
        latest: u32,
    },
}

/// The loss and path use of every iteration.
#[derive(Clone, Debug, PartialEq)]
pub struct Schedule {
    /// The method.
    pub method: Method,
    /// The problem's loss (used before the switch).
    pub loss: LossKind,
    /// Total iterations.
    pub iterations: u32,
    /// When the OT phase ends (changes from [`Switch::OnPlateau`] to
    /// [`Switch::At`] once it does).
    pub switch: Switch,
}

impl Schedule {
    /// Ends the OT phase after `fraction` of the `iterations`; L2
    /// throughout for the `l2` and `prdpt` methods or an L2 loss.
    pub fn fixed(method: Method, loss: LossKind, iterations: u32, fraction: f64) -> Self {
        let l2 = (f64::from(iterations) * fraction.clamp(0.0, 1.0)).round() as u32;
        let at = if !method.uses_ot() || !loss.is_ot() {
            0
        } else {
            iterations - l2.min(iterations)
        };
        Self {
            method,
            loss,
            iterations,
            switch: Switch::At(at),
        }
    }

    /// Ends the OT phase once its loss has not improved for `window`
    /// iterations, and at the latest after `latest` iterations; L2
    /// throughout for the `l2` and `prdpt` methods or an L2 loss.
    pub fn on_plateau(
        method: Method,
        loss: LossKind,
        iterations: u32,
        window: u32,
        latest: u32,
    ) -> Self {
        let switch = if !method.uses_ot() || !loss.is_ot() {
            Switch::At(0)
        } else {
            Switch::OnPlateau {
                plateau: Plateau::new(window),
                latest,
            }
        };
        Self {
            method,
            loss,
            iterations,
            switch,
        }
    }

    /// The first iteration run with L2 (`iterations` when none is, or when
    /// the switch is not decided yet).
    pub fn switch(&self) -> u32 {
        match self.switch {
            Switch::At(at) => at,
            Switch::OnPlateau { .. } => self.iterations,
        }
    }

    /// Records the loss of OT iteration `iteration`; decides the switch
    /// when the loss has reached its plateau or the latest iteration has
    /// come, so that L2 starts at `iteration + 1`.
    pub fn observe(&mut self, iteration: u32, loss: f64) {
        if let Switch::OnPlateau { plateau, latest } = &mut self.switch {
            let flat = plateau.observe(loss);
            if flat || iteration + 1 >= *latest {
                self.switch = Switch::At(iteration + 1);
            }
        }
    }

    /// The loss of `iteration` (0-based).
    pub fn loss_at(&self, iteration: u32) -> LossKind {
        if iteration >= self.switch() {
            LossKind::L2
        } else {
            self.loss
        }
    }

    /// Whether Adam is reset before `iteration`.
    pub fn resets_at(&self, iteration: u32) -> bool {
        iteration > 0 && iteration == self.switch()
    }

    /// The paths that give screen-position gradients at `iteration`.
    pub fn paths_at(&self, iteration: u32) -> PathUse {
        match (self.loss_at(iteration).is_ot(), self.method) {
            (false, _) | (_, Method::L2 | Method::Prdpt) => PathUse::ColourOnly,
            (true, Method::Drot) => PathUse::PrimaryOnly,
            (true, Method::Epsm) => PathUse::All,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hybrid_switches_to_l2_for_the_final_fraction() {
        let s = Schedule::fixed(Method::Epsm, LossKind::OtExact, 10, 0.3);
        assert_eq!(s.switch(), 7);
        assert_eq!(s.loss_at(6), LossKind::OtExact);
        assert_eq!(s.loss_at(7), LossKind::L2);
        assert!(s.resets_at(7) && !s.resets_at(0) && !s.resets_at(8));
        assert_eq!(s.paths_at(0), PathUse::All);
        assert_eq!(s.paths_at(9), PathUse::ColourOnly);
        let d = Schedule {
            method: Method::Drot,
            ..s.clone()
        };
        assert_eq!(d.paths_at(0), PathUse::PrimaryOnly);
        let l = Schedule::fixed(Method::L2, LossKind::OtExact, 10, 0.3);
        assert_eq!((l.switch(), l.paths_at(0)), (0, PathUse::ColourOnly));
        assert!(!l.resets_at(0));
        assert_eq!(Method::parse("drot"), Some(Method::Drot));
        assert_eq!(Method::parse("x"), None);
    }

    #[test]
    fn the_switch_follows_a_plateau_of_the_loss_or_the_latest_iteration() {
        let mut s = Schedule::on_plateau(Method::Epsm, LossKind::OtExact, 40, 3, 30);
        let mut i = 0;
        // Falling by 10 % per iteration: no switch.
        while i < 10 {
            s.observe(i, 0.9f64.powi(i as i32));
            i += 1;
        }
        assert_eq!(s.switch(), 40);
        // Flat from here: the average's lag keeps it improving for several
        // iterations, then the switch follows the window.
        while s.switch() == 40 {
            s.observe(i, 0.9f64.powi(10));
            i += 1;
        }
        assert!((14..=26).contains(&s.switch()), "switch at {}", s.switch());
        assert!(s.resets_at(s.switch()) && s.loss_at(s.switch()) == LossKind::L2);
        // Still falling at the latest iteration: the switch comes then.
        let mut t = Schedule::on_plateau(Method::Epsm, LossKind::OtExact, 40, 3, 30);
        for i in 0..40 {
            if t.loss_at(i).is_ot() {
                t.observe(i, 0.8f64.powi(i as i32));
            }
        }
        assert_eq!(t.switch(), 30);
        let l = Schedule::on_plateau(Method::L2, LossKind::OtExact, 40, 3, 30);
        assert_eq!(l.switch(), 0);
    }
}
