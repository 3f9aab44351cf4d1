//! The wide walks' values: sixteen rays ([`Rays16`]), hits ([`Hits16`])
//! and shading points ([`SurfacePoints16`], with their [`Frames16`]), one
//! per lane, each lane the scalar value's fields.

use glam::Vec2;

use crate::bvh::NO_WORLD_INDEX;
use crate::frame::Frame;
use crate::hit::{Hit, SurfacePoint, TexCoords};
use crate::simd::{F32x16, LANES, Lanes, Mask16, U32x16, Vec3x16};

/// Sixteen rays, one per lane ([`Ray`](crate::ray::Ray)'s fields by lane), for the wide
/// tracer.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rays16<B: Lanes> {
    /// Origins.
    pub origin: Vec3x16<B>,
    /// Directions (not necessarily unit).
    pub dir: Vec3x16<B>,
    /// Start of the `t` ranges.
    pub t_min: F32x16<B>,
    /// End of the `t` ranges.
    pub t_max: F32x16<B>,
}

/// Sixteen shading frames, one per lane ([`Frame`](crate::frame::Frame) by lane), for the wide
/// tracer.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Frames16<B: Lanes> {
    /// First tangents.
    pub s: Vec3x16<B>,
    /// Second tangents.
    pub t: Vec3x16<B>,
    /// Shading normals.
    pub n: Vec3x16<B>,
}

impl<B: Lanes> Frames16<B> {
    /// [`Frame::from_normal`](crate::frame::Frame::from_normal) in every lane (the same operations, so the
    /// same frames bit for bit).
    #[inline(always)]
    pub fn from_normal(k: B, n: Vec3x16<B>) -> Self {
        let one = F32x16::splat(k, 1.0);
        let sign = one.copysign(n.z);
        let a = -one / (sign + n.z);
        let b = n.x * n.y * a;
        Self {
            s: Vec3x16::new(one + sign * n.x * n.x * a, sign * b, -sign * n.x),
            t: Vec3x16::new(b, sign + n.y * n.y * a, -n.y),
            n,
        }
    }

    /// The frames of `frames`, lane `i` from `frames[i]`.
    #[inline(always)]
    pub fn from_lanes(k: B, frames: &[Frame; LANES]) -> Self {
        Self {
            s: Vec3x16::from_lanes(k, &frames.map(|f| f.s)),
            t: Vec3x16::from_lanes(k, &frames.map(|f| f.t)),
            n: Vec3x16::from_lanes(k, &frames.map(|f| f.n)),
        }
    }

    #[cfg(test)]
    /// Lane `lane` as a [`Frame`](crate::frame::Frame).
    #[inline(always)]
    pub fn lane(&self, lane: usize) -> Frame {
        Frame {
            s: self.s.lane(lane),
            t: self.t.lane(lane),
            n: self.n.lane(lane),
        }
    }

    /// `a` in the lanes of `m`, `b` in the others.
    #[inline(always)]
    pub fn select(m: Mask16, a: &Self, b: &Self) -> Self {
        Self {
            s: Vec3x16::select(m, a.s, b.s),
            t: Vec3x16::select(m, a.t, b.t),
            n: Vec3x16::select(m, a.n, b.n),
        }
    }

    /// [`Frame::to_world`](crate::frame::Frame::to_world) in every lane.
    #[inline(always)]
    pub fn to_world(self, v: Vec3x16<B>) -> Vec3x16<B> {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

/// Sixteen [`Hit`]s, one per lane, as the wide walks return them; lanes
/// outside `found` hold no hit (their other fields are unspecified).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Hits16<B: Lanes> {
    /// Lanes whose ray hit something.
    pub found: Mask16,
    /// The object hit.
    pub object: U32x16<B>,
    /// The triangle hit (0 on an exact sphere).
    pub triangle: U32x16<B>,
    /// Local coordinates on it (module docs).
    pub b1: F32x16<B>,
    /// Local coordinates on it (module docs).
    pub b2: F32x16<B>,
    /// Ray parameter, in units of the ray's direction.
    pub t: F32x16<B>,
    /// [`Hit`]'s index in the static BVH's shading data.
    pub world_index: U32x16<B>,
}

impl<B: Lanes> Hits16<B> {
    /// No hit in any lane, each lane's `t` its ray's `t_max`.
    #[inline(always)]
    pub fn none(k: B, rays: &Rays16<B>) -> Self {
        let (zero, zero_f) = (U32x16::splat(k, 0), F32x16::splat(k, 0.0));
        Self {
            found: Mask16::NONE,
            object: zero,
            triangle: zero,
            b1: zero_f,
            b2: zero_f,
            t: rays.t_max,
            world_index: U32x16::splat(k, NO_WORLD_INDEX),
        }
    }

    #[cfg(test)]
    /// Lane `lane` as a [`Hit`] (`None` outside `found`).
    #[inline(always)]
    pub fn lane(&self, lane: usize) -> Option<Hit> {
        self.found.test(lane).then(|| Hit {
            object: self.object.lane(lane),
            triangle: self.triangle.lane(lane),
            b1: self.b1.lane(lane),
            b2: self.b2.lane(lane),
            t: self.t.lane(lane),
            world_index: self.world_index.lane(lane),
        })
    }

    /// The hits of the lanes (`None` outside `found`), as plain values.
    #[inline(always)]
    pub fn to_lanes(self) -> [Option<Hit>; LANES] {
        let (object, triangle) = (self.object.to_array(), self.triangle.to_array());
        let (b1, b2, t) = (self.b1.to_array(), self.b2.to_array(), self.t.to_array());
        let world_index = self.world_index.to_array();
        std::array::from_fn(|i| {
            self.found.test(i).then_some(Hit {
                object: object[i],
                triangle: triangle[i],
                b1: b1[i],
                b2: b2[i],
                t: t[i],
                world_index: world_index[i],
            })
        })
    }

    /// The lanes of `hits` (`None`: not found, and zeros).
    #[inline(always)]
    pub fn from_lanes(k: B, hits: &[Option<Hit>; LANES]) -> Self {
        let mut found = Mask16::NONE;
        let (mut object, mut triangle, mut world_index) = ([0; LANES], [0; LANES], [0; LANES]);
        let (mut b1, mut b2, mut t) = ([0.0; LANES], [0.0; LANES], [0.0; LANES]);
        for (lane, h) in hits.iter().enumerate() {
            if let Some(h) = h {
                found.0 |= 1 << lane;
                (object[lane], triangle[lane], world_index[lane]) =
                    (h.object, h.triangle, h.world_index);
                (b1[lane], b2[lane], t[lane]) = (h.b1, h.b2, h.t);
            }
        }
        Self {
            found,
            object: U32x16::from_array(k, object),
            triangle: U32x16::from_array(k, triangle),
            b1: F32x16::from_array(k, b1),
            b2: F32x16::from_array(k, b2),
            t: F32x16::from_array(k, t),
            world_index: U32x16::from_array(k, world_index),
        }
    }
}

/// Sixteen [`TexCoords`], one per lane: lanes in `sphere` hold a
/// [`TexCoords::Sphere`] point in `a`, the others a [`TexCoords::Uv`] in
/// `a.x`, `a.y`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TexCoords16<B: Lanes> {
    /// Lanes on exact spheres.
    pub sphere: Mask16,
    /// The coordinates (see the type).
    pub a: Vec3x16<B>,
}

impl<B: Lanes> TexCoords16<B> {
    /// Lane `lane` as [`TexCoords`].
    #[inline(always)]
    pub fn lane(&self, lane: usize) -> TexCoords {
        let a = self.a.lane(lane);
        if self.sphere.test(lane) {
            TexCoords::Sphere(a)
        } else {
            TexCoords::Uv(Vec2::new(a.x, a.y))
        }
    }
}

/// Sixteen [`SurfacePoint`]s, one per lane.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SurfacePoints16<B: Lanes> {
    /// Positions, world space.
    pub p: Vec3x16<B>,
    /// Unit geometric normals, world space.
    pub ng: Vec3x16<B>,
    /// Texture coordinates.
    pub uv: TexCoords16<B>,
    /// Shading frames (`frame.n` the shading normal).
    pub frame: Frames16<B>,
}

impl<B: Lanes> SurfacePoints16<B> {
    /// The points of `points`, lane `i` from `points[i]`.
    #[inline(always)]
    pub fn from_lanes(k: B, points: &[SurfacePoint; LANES]) -> Self {
        let mut sphere = Mask16::NONE;
        let a = points.map(|sp| match sp.uv {
            TexCoords::Uv(uv) => uv.extend(0.0),
            TexCoords::Sphere(p) => p,
        });
        for (lane, sp) in points.iter().enumerate() {
            sphere.0 |= u16::from(matches!(sp.uv, TexCoords::Sphere(_))) << lane;
        }
        Self {
            p: Vec3x16::from_lanes(k, &points.map(|sp| sp.p)),
            ng: Vec3x16::from_lanes(k, &points.map(|sp| sp.ng)),
            uv: TexCoords16 {
                sphere,
                a: Vec3x16::from_lanes(k, &a),
            },
            frame: Frames16::from_lanes(k, &points.map(|sp| sp.frame)),
        }
    }

    #[cfg(test)]
    /// Lane `lane` as a [`SurfacePoint`].
    #[inline(always)]
    pub fn lane(&self, lane: usize) -> SurfacePoint {
        SurfacePoint {
            p: self.p.lane(lane),
            ng: self.ng.lane(lane),
            uv: self.uv.lane(lane),
            frame: self.frame.lane(lane),
        }
    }
}
