//! Watertight ray–triangle intersection in `f32`: the per-ray constants,
//! the stored triangle and the one-triangle reference test (traversal tests
//! eight at a time, module `packet`, rounding exactly as this one).
//!
//! Model: Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection"
//! (JCGT 2013). Per ray ([`RayShear`]): the axis `kz` where the direction is
//! largest, the two others `kx, ky` (swapped when `dir[kz] < 0` to keep the
//! winding), and the shear `(Sx, Sy, Sz) = (dx/dz, dy/dz, 1/dz)` that maps the
//! direction to `+z`, applied as `v[kx] − Sx·v[kz]` etc. Per triangle: the
//! vertices relative to the origin are sheared to 2D and the edge functions `U, V, W` (weights of `p0, p1, p2`)
//! are evaluated; an edge function that rounds to exactly zero is recomputed
//! in `f64`, so a ray through a shared edge or vertex hits at least one of the
//! triangles sharing it: closed meshes do not leak (Möller–Trumbore leaked
//! 2 % of rays aimed at edges and vertices in the test
//! `closed_mesh_has_no_leaks_at_edges_and_vertices`). Both faces are hit;
//! edges and vertices count as inside. `t = T/det` with `det = U + V + W` is
//! in units of the ray's (unnormalised) direction, and `(b1, b2) = (V, W)/det`.
//! Range tests come before the one division and are written so that a NaN
//! fails them. Triangles with zero `f32` area or a non-finite vertex are not
//! stored at all (see [`PackedTriangle::new`]).
//!
//! No parameters.

use glam::{Vec3A, Vec4};
use obvhs::aabb::Aabb;

/// Per-ray constants of the watertight test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct RayShear {
    /// The axes `[kx, ky, kz]`, each below 3 (set only by
    /// [`RayShear::new`]; the AVX packet test indexes by them unchecked).
    axes: [usize; 3],
    /// `(−Sx, −Sy, Sz)`: a vertex `v` relative to the origin shears to
    /// `(v[kx] + (−Sx)·v[kz], v[ky] + (−Sy)·v[kz], Sz·v[kz])`.
    pub kz_col: [f32; 3],
}

impl RayShear {
    /// No shear: a triangle test with it computes NaN edge functions and
    /// finds nothing ([`TraceRay::without_shear`](super::node::TraceRay)).
    pub const UNSET: Self = Self {
        axes: [0, 1, 2],
        kz_col: [f32::NAN; 3],
    };

    /// The shear of direction `dir` (a zero direction gives non-finite
    /// constants, and then no hits).
    #[inline(always)]
    pub fn new(dir: Vec3A) -> Self {
        // Branch-free (a per-ray branch on the largest axis mispredicts on
        // incoherent rays): `kz` is x when |x| is largest, else y when
        // |y| ≥ |z|, else z, as comparisons that a NaN fails.
        let a = dir.abs();
        let x_largest = (a.x >= a.y) & (a.x >= a.z);
        let y_ge_z = a.y >= a.z;
        let kz = usize::from(!x_largest) + usize::from(!x_largest & !y_ge_z);
        // Four components, indexed by `k & 3` (a no-op for `k < 3`), so the
        // loads below need no bounds checks. Selecting `dz` by comparisons
        // and the axes from a packed constant instead (no store and reload
        // before the packet test's vertex loads) compiled to two branches:
        // shadow rays took 17.3 against 14.1 ns, walks timed alone.
        let d = Vec4::from((dir, 0.0)).to_array();
        let dz = d[kz & 3];
        let [kx, ky] = AXES_ACROSS[2 * kz + usize::from(dz < 0.0)];
        // `S = dir[k]·sz`, as the paper rounds it. `sz` equals the box
        // test's reciprocal of the same component (for `|dz| ≥ TINY_DIR`),
        // but taking it from there (one vector division for both, NaN
        // below `TINY_DIR`) measured neutral to −1 % in time: the two
        // divisions overlap.
        let sz = 1.0 / dz;
        Self {
            axes: [kx, ky, kz],
            kz_col: [-(d[kx & 3] * sz), -(d[ky & 3] * sz), sz],
        }
    }

    /// The axes `[kx, ky, kz]`, each below 3.
    #[inline(always)]
    pub fn axes(&self) -> [usize; 3] {
        self.axes
    }
}

/// The axes `[kx, ky]` across the ray for largest axis `kz` (row `2·kz`),
/// swapped when the direction along `kz` is negative (row `2·kz + 1`) to
/// keep the winding.
const AXES_ACROSS: [[usize; 2]; 6] = [[1, 2], [2, 1], [2, 0], [0, 2], [0, 1], [1, 0]];

/// One triangle's vertices, object space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PackedTriangle {
    p: [Vec3A; 3],
}

/// A ray–triangle hit: ray parameter and barycentrics `(b1, b2)`.
#[cfg(test)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TriangleHit {
    /// Ray parameter.
    pub t: f32,
    /// Barycentric weight of `p1`.
    pub b1: f32,
    /// Barycentric weight of `p2`.
    pub b2: f32,
}

impl PackedTriangle {
    /// Packs triangle `(p0, p1, p2)`; `None` when it has zero area in `f32`
    /// or a non-finite vertex (such a triangle can never be hit).
    pub fn new(p: [Vec3A; 3]) -> Option<Self> {
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        let finite = p.iter().all(|v| v.is_finite()) && n.is_finite();
        (finite && n != Vec3A::ZERO).then_some(Self { p })
    }

    /// The vertices `[p0, p1, p2]`.
    pub fn vertices(&self) -> &[Vec3A; 3] {
        &self.p
    }

    /// The triangle's bounding box.
    pub fn aabb(&self) -> Aabb {
        Aabb::from_points(&self.p)
    }

    /// The hit of the ray `origin + t·dir` (`dir` given by its `shear`) with
    /// `t` in `[t_min, t_max]`, if any: the one-triangle reference of
    /// [`TrianglePacket::intersect`](super::packet::TrianglePacket::intersect).
    #[cfg(test)]
    pub fn intersect(
        &self,
        origin: Vec3A,
        shear: &RayShear,
        t_min: f32,
        t_max: f32,
    ) -> Option<TriangleHit> {
        // Vertices relative to the origin, sheared: (x, y) in the plane
        // across the ray, z along it.
        let [kx, ky, kz] = shear.axes();
        let [nsx, nsy, sz] = shear.kz_col;
        let [a, b, c] = self.p.map(|p| {
            let r = (p - origin).to_array();
            Vec3A::new(r[kx] + nsx * r[kz], r[ky] + nsy * r[kz], sz * r[kz])
        });
        let edge = |p: Vec3A, q: Vec3A| p.x * q.y - p.y * q.x;
        let (mut u, mut v, mut w) = (edge(c, b), edge(a, c), edge(b, a));
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let edge64 = |p: Vec3A, q: Vec3A| {
                (f64::from(p.x) * f64::from(q.y) - f64::from(p.y) * f64::from(q.x)) as f32
            };
            (u, v, w) = (edge64(c, b), edge64(a, c), edge64(b, a));
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        let sign = det.to_bits() & 0x8000_0000;
        let flip = |x: f32| f32::from_bits(x.to_bits() ^ sign);
        let t_num = flip(u * a.z + v * b.z + w * c.z);
        let den = det.abs();
        if !(den > 0.0 && t_num >= t_min * den && t_num <= t_max * den) {
            return None;
        }
        let inv = 1.0 / den;
        let t = t_num * inv;
        (t.is_finite() && t >= t_min && t <= t_max).then_some(TriangleHit {
            t,
            b1: flip(v) * inv,
            b2: flip(w) * inv,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::vec3a;

    fn hit(
        tri: &PackedTriangle,
        o: Vec3A,
        d: Vec3A,
        t_min: f32,
        t_max: f32,
    ) -> Option<TriangleHit> {
        tri.intersect(o, &RayShear::new(d), t_min, t_max)
    }

    fn unit() -> PackedTriangle {
        PackedTriangle::new([
            vec3a(0.0, 0.0, 0.0),
            vec3a(2.0, 0.0, 0.0),
            vec3a(0.0, 2.0, 0.0),
        ])
        .expect("non-degenerate")
    }

    #[test]
    fn hits_inside_with_correct_barycentrics_from_both_sides() {
        let tri = unit();
        for (oz, dz) in [(1.0, -1.0), (-1.0, 1.0)] {
            let hit = hit(
                &tri,
                vec3a(0.5, 0.5, oz),
                vec3a(0.0, 0.0, dz * 0.5),
                0.0,
                f32::INFINITY,
            )
            .expect("hit");
            assert!((hit.t - 2.0).abs() < 1e-6);
            assert!((hit.b1 - 0.25).abs() < 1e-6 && (hit.b2 - 0.25).abs() < 1e-6);
        }
    }

    #[test]
    fn misses_outside_behind_and_out_of_range() {
        let tri = unit();
        let down = vec3a(0.0, 0.0, -1.0);
        assert!(hit(&tri, vec3a(1.5, 1.5, 1.0), down, 0.0, f32::INFINITY).is_none());
        assert!(hit(&tri, vec3a(0.5, 0.5, -1.0), down, 0.0, f32::INFINITY).is_none());
        assert!(hit(&tri, vec3a(0.5, 0.5, 1.0), down, 0.0, 0.5).is_none());
        assert!(hit(&tri, vec3a(0.5, 0.5, 1.0), down, 1.5, 9.0).is_none());
        // Parallel to the plane.
        assert!(hit(&tri, vec3a(-1.0, 0.5, 0.0), vec3a(1.0, 0.0, 0.0), 0.0, 9.0).is_none());
    }

    #[test]
    fn degenerate_triangles_are_rejected() {
        let a = vec3a(1.0, 2.0, 3.0);
        assert!(PackedTriangle::new([a, a, vec3a(0.0, 1.0, 0.0)]).is_none());
        assert!(PackedTriangle::new([a, 2.0 * a, 3.0 * a]).is_none());
        assert!(PackedTriangle::new([a, vec3a(f32::NAN, 0.0, 0.0), Vec3A::ZERO]).is_none());
    }
}
