//! Sixteen 3-vectors: [`glam::Vec3`]'s operations lane by lane, each in the
//! operation order glam uses (so a lane rounds as glam does).

use std::ops::{Add, Mul, Neg, Sub};

use glam::Vec3;

use super::{F32x16, LANES, Lanes, Mask16};

/// Sixteen 3-vectors, one per lane, stored by component.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Vec3x16<B: Lanes> {
    pub x: F32x16<B>,
    pub y: F32x16<B>,
    pub z: F32x16<B>,
}

impl<B: Lanes> Add for Vec3x16<B> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}

impl<B: Lanes> Sub for Vec3x16<B> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}

impl<B: Lanes> Mul for Vec3x16<B> {
    type Output = Self;
    /// Component by component.
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        Self::new(self.x * o.x, self.y * o.y, self.z * o.z)
    }
}

impl<B: Lanes> Mul<F32x16<B>> for Vec3x16<B> {
    type Output = Self;
    /// Every component times the lane's scalar (`Vec3 * f32`).
    #[inline(always)]
    fn mul(self, s: F32x16<B>) -> Self {
        Self::new(self.x * s, self.y * s, self.z * s)
    }
}

impl<B: Lanes> Neg for Vec3x16<B> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self::new(-self.x, -self.y, -self.z)
    }
}

impl<B: Lanes> Vec3x16<B> {
    /// The vectors with components `x`, `y`, `z`.
    #[inline(always)]
    pub fn new(x: F32x16<B>, y: F32x16<B>, z: F32x16<B>) -> Self {
        Self { x, y, z }
    }

    /// Every lane `v`.
    #[inline(always)]
    pub fn splat(k: B, v: Vec3) -> Self {
        Self::new(
            F32x16::splat(k, v.x),
            F32x16::splat(k, v.y),
            F32x16::splat(k, v.z),
        )
    }

    /// Lane `i` is `lanes[i]`.
    #[inline(always)]
    pub fn from_lanes(k: B, lanes: &[Vec3; LANES]) -> Self {
        Self::new(
            F32x16::from_array(k, lanes.map(|v| v.x)),
            F32x16::from_array(k, lanes.map(|v| v.y)),
            F32x16::from_array(k, lanes.map(|v| v.z)),
        )
    }

    /// The lanes as vectors.
    #[inline(always)]
    pub fn to_lanes(self) -> [Vec3; LANES] {
        let (x, y, z) = (self.x.to_array(), self.y.to_array(), self.z.to_array());
        std::array::from_fn(|i| Vec3::new(x[i], y[i], z[i]))
    }

    /// Lane `lane` (`< 16`).
    #[inline(always)]
    pub fn lane(self, lane: usize) -> Vec3 {
        Vec3::new(self.x.lane(lane), self.y.lane(lane), self.z.lane(lane))
    }

    /// Every component divided by the lane's scalar (`Vec3 / f32`).
    #[inline(always)]
    pub fn div(self, s: F32x16<B>) -> Self {
        Self::new(self.x / s, self.y / s, self.z / s)
    }

    /// `a` in the lanes of `m`, `b` in the others.
    #[inline(always)]
    pub fn select(m: Mask16, a: Self, b: Self) -> Self {
        Self::new(
            F32x16::select(m, a.x, b.x),
            F32x16::select(m, a.y, b.y),
            F32x16::select(m, a.z, b.z),
        )
    }

    /// `(x·x' + y·y') + z·z'`, glam's order.
    #[inline(always)]
    pub fn dot(self, o: Self) -> F32x16<B> {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// `dot(self, self)`.
    #[inline(always)]
    pub fn length_squared(self) -> F32x16<B> {
        self.dot(self)
    }

    /// `sqrt(dot(self, self))`.
    #[inline(always)]
    pub fn length(self) -> F32x16<B> {
        self.length_squared().sqrt()
    }

    /// glam's `normalize`: `self * (1 / length)`.
    #[inline(always)]
    pub fn normalize(self, k: B) -> Self {
        self * (F32x16::splat(k, 1.0) / self.length())
    }

    /// `max(x, max(y, z))` with `max(a, b) = if a > b { a } else { b }`
    /// (glam's `max_element`).
    #[inline(always)]
    pub fn max_element(self) -> F32x16<B> {
        self.x.max(self.y.max(self.z))
    }

    /// Lanes equal to the zero vector (`== Vec3::ZERO`, so `−0` counts).
    #[inline(always)]
    pub fn is_zero(self, k: B) -> Mask16 {
        let zero = F32x16::splat(k, 0.0);
        self.x.eq(zero) & self.y.eq(zero) & self.z.eq(zero)
    }
}
