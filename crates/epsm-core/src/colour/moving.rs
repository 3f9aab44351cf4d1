//! A path node moving along one parameter: position, normal and their
//! derivatives, and the small forward-mode algebra the colour factors need
//! (unit directions, cosines, `∂ ln r`).

use glam::{DVec2, DVec3};

/// A node's position and normal at θ and their derivatives.
#[derive(Clone, Debug, Default)]
pub(super) struct Placed {
    pub(super) x: DVec3,
    /// Unit normal (zero for the camera and point lights).
    pub(super) n: DVec3,
    /// `(param, ∂x/∂θ, ∂n/∂θ)`.
    pub(super) grads: Vec<(usize, DVec3, DVec3)>,
    /// `(param, ∂ ln(area)/∂θ)` of the object's area measure.
    pub(super) area: Vec<(usize, f64)>,
    /// `∂x/∂u`, `∂n/∂u` of a surface point's tangent parameterisation.
    pub(super) dx_du: [DVec3; 2],
    pub(super) dn_du: [DVec3; 2],
}

impl Placed {
    pub(super) fn d(&self, k: usize) -> Moving {
        let (dx, dn) = self
            .grads
            .iter()
            .filter(|g| g.0 == k)
            .fold((DVec3::ZERO, DVec3::ZERO), |a, g| (a.0 + g.1, a.1 + g.2));
        Moving {
            x: self.x,
            dx,
            n: self.n,
            dn,
        }
    }

    /// The gradient entry of parameter `k` after the tangent step `du`.
    pub(super) fn stepped(&self, k: usize, m: &Moving, du: DVec2) -> (usize, DVec3, DVec3) {
        (
            k,
            m.dx + self.dx_du[0] * du.x + self.dx_du[1] * du.y,
            m.dn + self.dn_du[0] * du.x + self.dn_du[1] * du.y,
        )
    }

    pub(super) fn area_rate(&self, k: usize) -> f64 {
        self.area.iter().filter(|a| a.0 == k).map(|a| a.1).sum()
    }
}

/// One node moving along one parameter.
#[derive(Clone, Copy, Debug)]
pub(super) struct Moving {
    pub(super) x: DVec3,
    pub(super) dx: DVec3,
    pub(super) n: DVec3,
    pub(super) dn: DVec3,
}

impl Moving {
    pub(super) fn still(&self) -> bool {
        self.dx == DVec3::ZERO && self.dn == DVec3::ZERO
    }
}

/// A unit direction and its derivative.
#[derive(Clone, Copy, Debug)]
pub(super) struct Dir {
    pub(super) w: DVec3,
    pub(super) dw: DVec3,
}

/// The direction from `a` to `b` and the segment's `∂ ln r`.
pub(super) fn toward(a: &Moving, b: &Moving) -> (Dir, f64) {
    let (d, dd) = (b.x - a.x, b.dx - a.dx);
    let len = d.length();
    let w = d / len;
    (
        Dir {
            w,
            dw: (dd - w * w.dot(dd)) / len,
        },
        w.dot(dd) / len,
    )
}

/// `(cos, ∂cos)` of `n·w`.
pub(super) fn cos(m: &Moving, w: &Dir) -> (f64, f64) {
    (m.n.dot(w.w), m.dn.dot(w.w) + m.n.dot(w.dw))
}
