//! Path constraints: one 2-D constraint per unknown vertex (docs/design.md §5.3).
//!
//! Every constraint is a function of four world vectors: the vertex before
//! `a`, the vertex itself `x`, the vertex after `b`, and the shading normal `n`
//! at `x` (for the shadow receiver `a` is the occluder point and `b` the light
//! point). [`Constraint::eval`] is generic over the scalar, so the same code
//! gives values in `f64` and its 2×12 local Jacobian with forward-mode duals
//! ([`Constraint::local`]). Fixed points are no constraints: their vertices
//! are not unknowns.

pub(crate) mod assembly;
mod collinear;
mod fixed_direction;
mod half_vector;
mod jacobian;
#[cfg(test)]
mod receiver_tests;

use glam::DVec3;
use nalgebra::{RealField, Vector3};

use crate::frame::BaseFrame;

/// The kind of a constraint and its constants.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ConstraintKind {
    /// Smooth specular: `[F·(wi + η wo)]_xy = 0`.
    Specular {
        /// Relative IOR `η(wo side)/η(wi side)` (1 for reflection).
        eta: f64,
        /// Whether the vertex refracts (`wi`, `wo` on opposite sides).
        transmit: bool,
    },
    /// Glossy reflection: `[F·normalize(wi + wo)]_xy = m`.
    Glossy {
        /// The kept microfacet normal in the base frame.
        m: [f64; 2],
    },
    /// Caustic receiver: `[F·wo]_xy = c`.
    FixedDirection {
        /// The kept local direction toward the next vertex.
        c: [f64; 2],
    },
    /// Shadow receiver: stays on the line light → occluder.
    Collinear,
    /// Test-only alternative caustic receiver: the segment `a → b` keeps its
    /// world direction (its frame is built around that base direction).
    #[cfg(test)]
    Segment {
        /// The kept direction in the segment frame.
        c: [f64; 2],
    },
}

/// One constraint of a path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Constraint {
    /// Kind and constants.
    pub kind: ConstraintKind,
    /// The transported frame's base.
    pub frame: BaseFrame,
    /// Node indices of `a`, `x`, `b` in the path.
    pub nodes: [usize; 3],
}

/// A constraint's value and local Jacobian.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Local {
    /// `C` (two rows).
    pub value: [f64; 2],
    /// `∂C_r/∂(a, x, b, n)`: per row, four gradient vectors.
    pub grad: [[DVec3; 4]; 2],
}

pub(crate) fn na<T: RealField>(v: DVec3) -> Vector3<T> {
    Vector3::new(v.x, v.y, v.z).map(nalgebra::convert)
}

impl Constraint {
    /// `C(a, x, b, n)` in any scalar type.
    pub fn eval<T: RealField + Copy>(
        &self,
        a: &Vector3<T>,
        x: &Vector3<T>,
        b: &Vector3<T>,
        n: &Vector3<T>,
    ) -> [T; 2] {
        let f = &self.frame;
        let wi = || (a - x).normalize();
        let wo = || (b - x).normalize();
        match self.kind {
            ConstraintKind::Specular { eta, .. } => half_vector::smooth(f, n, &wi(), &wo(), eta),
            ConstraintKind::Glossy { m } => half_vector::glossy(f, n, &wi(), &wo(), m),
            ConstraintKind::FixedDirection { c } => fixed_direction::receiver(f, n, &wo(), c),
            ConstraintKind::Collinear => collinear::collinear(f, n, &wi(), &wo()),
            #[cfg(test)]
            ConstraintKind::Segment { c } => fixed_direction::segment(f, a, b, c),
        }
    }

    /// `C` in `f64`.
    pub fn value(&self, a: DVec3, x: DVec3, b: DVec3, n: DVec3) -> [f64; 2] {
        self.eval(&na(a), &na(x), &na(b), &na(n))
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{Const, U1};
    use num_dual::DualSVec64;

    use super::*;

    /// The reference: value and 2×12 Jacobian of the generic `eval` with duals.
    fn local_dual(con: &Constraint, a: DVec3, x: DVec3, b: DVec3, n: DVec3) -> Local {
        let lift = |v: DVec3, slot: usize| {
            Vector3::from_fn(|i, _| DualSVec64::<12>::from_re(v[i]).derivative(3 * slot + i))
        };
        let c = con.eval(&lift(a, 0), &lift(x, 1), &lift(b, 2), &lift(n, 3));
        let grad = c.map(|ci| {
            let d = ci.eps.unwrap_generic(Const::<12>, U1);
            [0, 1, 2, 3].map(|s| DVec3::new(d[3 * s], d[3 * s + 1], d[3 * s + 2]))
        });
        Local {
            value: c.map(|ci| ci.re),
            grad,
        }
    }

    #[test]
    fn local_jacobians_match_central_differences() {
        let (a, x, b) = (
            DVec3::new(0.2, 1.0, 0.9),
            DVec3::new(0.05, -0.02, 0.01),
            DVec3::new(-0.7, 0.8, -0.3),
        );
        let n = DVec3::new(0.1, 0.2, 1.0).normalize();
        let frame = BaseFrame::new(DVec3::new(0.0, 0.1, 1.0).normalize());
        for kind in [
            ConstraintKind::Specular {
                eta: 1.0,
                transmit: false,
            },
            ConstraintKind::Specular {
                eta: 1.0 / 1.5,
                transmit: true,
            },
            ConstraintKind::Glossy { m: [0.1, -0.05] },
            ConstraintKind::FixedDirection { c: [0.3, 0.2] },
            ConstraintKind::Collinear,
            ConstraintKind::Segment { c: [0.0, 0.1] },
        ] {
            let con = Constraint {
                kind,
                frame,
                nodes: [0, 1, 2],
            };
            let local = con.local(a, x, b, n);
            let dual = local_dual(&con, a, x, b, n);
            for r in 0..2 {
                assert!((local.value[r] - dual.value[r]).abs() < 1e-14, "{kind:?}");
                for slot in 0..4 {
                    let (g, d) = (local.grad[r][slot], dual.grad[r][slot]);
                    assert!(
                        (g - d).length() < 1e-13 * (1.0 + d.length()),
                        "{kind:?} row {r} slot {slot}: {g} vs {d}"
                    );
                }
            }
            let value = con.value(a, x, b, n);
            assert!((0..2).all(|r| (local.value[r] - value[r]).abs() < 1e-15));
            let h = 1e-6;
            for slot in 0..4 {
                for axis in 0..3 {
                    let mut v = [a, x, b, n];
                    v[slot][axis] += h;
                    let plus = con.value(v[0], v[1], v[2], v[3]);
                    v[slot][axis] -= 2.0 * h;
                    let minus = con.value(v[0], v[1], v[2], v[3]);
                    for r in 0..2 {
                        let fd = (plus[r] - minus[r]) / (2.0 * h);
                        let an = local.grad[r][slot][axis];
                        assert!(
                            (fd - an).abs() < 1e-7 * (1.0 + an.abs()),
                            "{kind:?} slot {slot}: {fd} vs {an}"
                        );
                    }
                }
            }
        }
    }
}
