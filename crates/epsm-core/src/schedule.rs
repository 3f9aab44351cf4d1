//! Methods and the hybrid schedule (docs/design.md §5.8).
//!
//! | method | loss | screen-position gradients |
//! |---|---|---|
//! | `epsm` | the problem's loss (OT), then L2 for the final `l2_fraction` | every path type (manifold solves) |
//! | `drot` | OT, then L2 for the final `l2_fraction` | primary paths only (Xing et al. 2022) |
//! | `l2` | L2 throughout | none: colour derivatives only |
//!
//! Adam is reset at the switch from OT to L2.

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
}

impl Method {
    /// Every method, in report order.
    pub const ALL: [Method; 3] = [Method::Epsm, Method::Drot, Method::L2];

    /// The method named `name` (`epsm`, `drot`, `l2`).
    pub fn parse(name: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == name)
    }

    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            Method::Epsm => "epsm",
            Method::Drot => "drot",
            Method::L2 => "l2",
        }
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

/// The loss and path use of every iteration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Schedule {
    /// The method.
    pub method: Method,
    /// The problem's loss (used before the switch).
    pub loss: LossKind,
    /// Total iterations.
    pub iterations: u32,
    /// Fraction of the iterations run with L2 at the end, in `[0, 1]`.
    pub l2_fraction: f64,
}

impl Schedule {
    /// The first iteration run with L2 (`iterations` when none is).
    pub fn switch(&self) -> u32 {
        if self.method == Method::L2 || !self.loss.is_ot() {
            return 0;
        }
        let l2 = (f64::from(self.iterations) * self.l2_fraction.clamp(0.0, 1.0)).round() as u32;
        self.iterations - l2.min(self.iterations)
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
            (false, _) | (_, Method::L2) => PathUse::ColourOnly,
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
        let s = Schedule {
            method: Method::Epsm,
            loss: LossKind::OtExact,
            iterations: 10,
            l2_fraction: 0.3,
        };
        assert_eq!(s.switch(), 7);
        assert_eq!(s.loss_at(6), LossKind::OtExact);
        assert_eq!(s.loss_at(7), LossKind::L2);
        assert!(s.resets_at(7) && !s.resets_at(0) && !s.resets_at(8));
        assert_eq!(s.paths_at(0), PathUse::All);
        assert_eq!(s.paths_at(9), PathUse::ColourOnly);
        let d = Schedule {
            method: Method::Drot,
            ..s
        };
        assert_eq!(d.paths_at(0), PathUse::PrimaryOnly);
        let l = Schedule {
            method: Method::L2,
            ..s
        };
        assert_eq!((l.switch(), l.paths_at(0)), (0, PathUse::ColourOnly));
        assert!(!l.resets_at(0));
        assert_eq!(Method::parse("drot"), Some(Method::Drot));
        assert_eq!(Method::parse("x"), None);
    }
}
