//! The exact unit sphere of [`Surface::Sphere`](crate::scene::Surface): ray
//! intersection, local coordinates, texture coordinates.
//!
//! Model: object space holds the unit sphere `|p| = 1` centred at the
//! origin, outward normal `p`. An object places it by any invertible affine
//! map `W` (an ellipsoid in world space); the world normal at `W·p` is
//! `normalize(N·p)` with `N` the inverse transpose of `W`'s linear part,
//! outward whatever the sign of `W`'s determinant (`N·p · W_lin·p = |p|²`).
//!
//! A point's local coordinates `(b1, b2)` (what [`Hit`](crate::hit::Hit)
//! and the path records carry where a triangle has barycentrics) are the
//! octahedral coordinates of `p` in `[-1, 1]²`: `(x, y) / (|x| + |y| + |z|)`,
//! with the lower half (`z < 0`) folded over the square's diagonals. The map
//! is continuous and needs no trigonometry; an `f32` pair places a point to
//! about 1e-7 of the radius. Texture coordinates are pbrt-v4's:
//! `u = φ / 2π`, `φ = atan2(y, x)` in `[0, 2π)`, and `v = θ / π`,
//! `θ = acos(z)`.
//!
//! Intersection is solved in `f64` with the discriminant taken from the
//! line's closest point to the centre (Haines et al., "Precision
//! Improvements for Ray/Sphere Intersection", Ray Tracing Gems, 2019), so
//! a ray leaving the surface by [`offset_origin`](crate::ray::offset_origin)'s
//! step does not find the surface again at `t ≈ 0`.
//!
//! No parameters.

use std::f32::consts::{FRAC_1_PI, TAU};

use glam::{DAffine3, DVec3, Vec2, Vec3, Vec3A};

/// The smallest root of `|origin + t·dir| = 1` in `[t_min, t_max]` (object
/// space, `dir` need not be unit); `None` for a miss, a zero or non-finite
/// `dir`, or roots outside the range.
#[inline(always)]
pub fn intersect(origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<f64> {
    let a = dir.length_squared();
    let h = -origin.dot(dir);
    // `a·l` with `l` the closest point to the centre, so `a² − |a·l|²` is
    // `a` times the discriminant `h² − a·c` without the cancellation of a
    // ray that starts far away, and a miss costs no division.
    let m = origin * a + dir * h;
    let a_disc = a * a - m.length_squared();
    if !(a_disc >= 0.0 && a > 0.0) {
        return None;
    }
    let inv_a = 1.0 / a;
    let disc = a_disc * inv_a;
    let q = h + disc.sqrt().copysign(h);
    let c = origin.length_squared() - 1.0;
    let (r0, r1) = (c / q, q * inv_a);
    let (near, far) = if r0 <= r1 { (r0, r1) } else { (r1, r0) };
    if (t_min..=t_max).contains(&near) {
        Some(near)
    } else if (t_min..=t_max).contains(&far) {
        Some(far)
    } else {
        None
    }
}

/// A world-space test that rules out rays certain to miss the unit sphere
/// placed by an affine map `W = (L, c)` (an ellipsoid centred at `c`), run
/// before the ray is mapped to object space and solved in `f64`
/// ([`intersect`]): most rays of a scene miss its spheres, and this test
/// needs no transform, no conversion to `f64` and no division.
///
/// Model: the ellipsoid lies in the ball of radius `σ = σ_max(L)` about `c`,
/// so a line farther than `σ` from `c` misses it. The exact test sees the
/// ray mapped to object space in `f32`, which moves the line by at most
/// about `δ = 18 ε κ² (|o| + |c|) ≤ 18 ε κ² |oc| + 36 ε κ² |c|` in world
/// units (`ε = 2⁻²⁴`, `κ` the condition number of `L`, `o` the ray origin,
/// `oc = c − o`), so a miss is certain beyond `σ + δ`. With
/// `(a + b)² ≤ 1.001 a² + 1001 b²`, that holds when the squared distance
/// exceeds `r2 + k |oc|²`: `r2 = 1.002 (σ + 64 ε κ² |c|)²` and
/// `k = 10⁻⁵ κ⁴`, which also covers this test's own `f32` rounding (at most
/// `8 ε |oc|²` relative to `|d|²`). The test compares
/// `|oc|²|d|² − (oc·d)² = |d|² dist²` with `|d|² (r2 + k |oc|²)`.
/// `σ²` and `κ²` are bounded by Gershgorin's discs of `LᵀL`: exact for a
/// rotation times a uniform scale; where a disc reaches zero the test never
/// rejects. A ray whose numbers overflow (`∞` or NaN) is not rejected. The
/// ray's `t` range is not looked at, so the test rejects only rays the
/// exact test misses whatever the range: images are unchanged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct MissTest {
    /// `c`, world space.
    pub(crate) center: Vec3A,
    /// `1.002 (σ + 64 ε κ² |c|)²` (∞: never rejects).
    pub(crate) r2: f32,
    /// `10⁻⁵ κ⁴`.
    pub(crate) k: f32,
}

impl MissTest {
    /// The test of the unit sphere itself (identity placement), what
    /// [`MissTest::new`] gives for the identity.
    pub const UNIT: Self = Self {
        center: Vec3A::ZERO,
        r2: 1.002,
        k: 1e-5,
    };

    /// The test of the unit sphere placed by `world_from_object`.
    pub fn new(world_from_object: &DAffine3) -> Self {
        let l = world_from_object.matrix3;
        let gram = (l.transpose() * l).to_cols_array_2d();
        // Gershgorin's bounds on the eigenvalues of `LᵀL`, `σ_min² ≥ low`
        // and `σ_max² ≤ high`.
        let (mut low, mut high) = (f64::INFINITY, 0.0f64);
        for (i, row) in gram.iter().enumerate() {
            let off: f64 = (0..3).filter(|&j| j != i).map(|j| row[j].abs()).sum();
            low = low.min(row[i] - off);
            high = high.max(row[i] + off);
        }
        let c = world_from_object.translation;
        if !(low > 0.0 && high.is_finite() && c.is_finite()) {
            return Self {
                center: Vec3A::ZERO,
                r2: f32::INFINITY,
                k: 0.0,
            };
        }
        let cond2 = high / low;
        let radius = high.sqrt() + 64.0 * f64::from(f32::EPSILON / 2.0) * cond2 * c.length();
        Self {
            center: c.as_vec3a(),
            r2: (1.002 * radius * radius) as f32,
            k: (1e-5 * cond2 * cond2) as f32,
        }
    }

    /// Whether the world-space line `origin + t·dir` surely misses the
    /// placed sphere.
    #[inline(always)]
    pub fn misses(&self, origin: Vec3A, dir: Vec3A) -> bool {
        let oc = self.center - origin;
        let a = dir.length_squared();
        let h = oc.dot(dir);
        let oc2 = oc.length_squared();
        let far = oc2 * a - h * h;
        far > a * (self.r2 + self.k * oc2) && far < f32::INFINITY
    }
}

/// The octahedral coordinates of the direction of `p` (non-zero), in
/// `[-1, 1]²`.
#[inline(always)]
pub fn local_coords(p: DVec3) -> [f64; 2] {
    let q = p / (p.x.abs() + p.y.abs() + p.z.abs());
    if q.z >= 0.0 {
        [q.x, q.y]
    } else {
        fold([q.x, q.y])
    }
}

/// The point on the unit sphere with octahedral coordinates `b` (clamped
/// into `[-1, 1]²`; the inverse of [`local_coords`]).
#[inline(always)]
pub fn point(b: [f64; 2]) -> DVec3 {
    let [x, y] = b.map(|v| v.clamp(-1.0, 1.0));
    let z = 1.0 - x.abs() - y.abs();
    let [x, y] = if z >= 0.0 { [x, y] } else { fold([x, y]) };
    DVec3::new(x, y, z).normalize()
}

/// The fold of the lower half (`z < 0`) over the square's diagonals, its own
/// inverse: `(x, y) → ((1 − |y|)·sign x, (1 − |x|)·sign y)`.
#[inline(always)]
fn fold([x, y]: [f64; 2]) -> [f64; 2] {
    [(1.0 - y.abs()).copysign(x), (1.0 - x.abs()).copysign(y)]
}

/// pbrt-v4's texture coordinates of the unit-sphere point `p`.
#[inline(always)]
pub fn uv(p: Vec3) -> Vec2 {
    let phi = p.y.atan2(p.x);
    let phi = if phi < 0.0 { phi + TAU } else { phi };
    Vec2::new(phi / TAU, p.z.clamp(-1.0, 1.0).acos() * FRAC_1_PI)
}

#[cfg(test)]
mod tests {
    use super::*;
    use epsm_testkit::Rng;

    #[test]
    fn local_coordinates_round_trip_on_both_halves_and_the_seams() {
        let mut rng = Rng::new(3);
        let mut dirs: Vec<DVec3> = (0..10_000).map(|_| rng.unit()).collect();
        dirs.extend([
            DVec3::X,
            -DVec3::X,
            DVec3::Y,
            -DVec3::Y,
            DVec3::Z,
            -DVec3::Z,
            DVec3::new(1.0, -1.0, 0.0).normalize(),
            DVec3::new(-1.0, 0.0, -1.0).normalize(),
        ]);
        for d in dirs {
            let b = local_coords(d * 3.7);
            assert!(b.iter().all(|v| v.abs() <= 1.0), "{d} -> {b:?}");
            let back = point(b);
            assert!((back - d).length() < 1e-14, "{d} -> {b:?} -> {back}");
            // f32 local coordinates, as hits and records store them.
            let back32 = point(b.map(|v| f64::from(v as f32)));
            assert!((back32 - d).length() < 3e-7, "{d}: f32 {back32}");
        }
    }

    #[test]
    fn intersections_lie_on_the_sphere_and_respect_the_range() {
        let mut rng = Rng::new(5);
        let (mut hits, mut inside) = (0, 0);
        for _ in 0..20_000 {
            let origin = rng.dvec3(-3.0, 3.0);
            let dir = rng.unit() * rng.range(0.1, 5.0);
            let Some(t) = intersect(origin, dir, 0.0, f64::INFINITY) else {
                // A miss: the line passes outside, or the sphere is behind.
                let closest = origin + dir * (-origin.dot(dir) / dir.length_squared());
                let ahead = origin.length() <= 1.0 || origin.dot(dir) < 0.0;
                assert!(closest.length() >= 1.0 - 1e-12 || !ahead, "{origin} {dir}");
                continue;
            };
            hits += 1;
            inside += usize::from(origin.length() < 1.0);
            assert!(t >= 0.0);
            assert!(((origin + t * dir).length() - 1.0).abs() < 1e-12);
            // The first root: nothing of the sphere before it.
            assert!(intersect(origin, dir, 0.0, t * (1.0 - 1e-9)).is_none());
        }
        assert!(
            hits > 800 && inside > 200,
            "{hits} hits, {inside} from inside"
        );
    }

    #[test]
    fn a_ray_leaving_the_surface_by_the_offset_step_does_not_find_it_again() {
        let mut rng = Rng::new(9);
        for _ in 0..20_000 {
            let n = rng.unit();
            let scale = rng.range(1e-3, 1e3);
            let p = (n * scale).as_vec3();
            let dir = rng.unit();
            let outward = dir.dot(n) > 0.0;
            let side = if outward { n } else { -n };
            let o = crate::ray::offset_origin(p, side.as_vec3()).as_dvec3() / scale;
            let t = intersect(o, dir, 0.0, f64::INFINITY);
            if outward {
                assert_eq!(t, None, "n {n} dir {dir} scale {scale}");
            } else {
                // Inside: the exit, across the sphere.
                let t = t.expect("an inside ray exits");
                assert!(t > 1e-6, "{t}: n {n} dir {dir} scale {scale}");
            }
        }
    }

    #[test]
    fn texture_coordinates_follow_pbrt() {
        assert_eq!(uv(Vec3::Z), Vec2::new(0.0, 0.0));
        assert!((uv(-Vec3::Z).y - 1.0).abs() < 1e-6);
        assert!((uv(-Vec3::X) - Vec2::new(0.5, 0.5)).length() < 1e-6);
        assert!((uv(Vec3::Y) - Vec2::new(0.25, 0.5)).length() < 1e-6);
        assert!((uv(-Vec3::Y) - Vec2::new(0.75, 0.5)).length() < 1e-6);
    }
}
