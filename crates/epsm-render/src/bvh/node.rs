//! Ray against the eight child boxes of a wide node ([`ChildBoxes`], used by
//! the triangle BVHs of module `flat` and by the top level's CWBVH nodes,
//! module `cwbvh`).
//!
//! Model: Ylitie, Karras and Laine, "Efficient Incoherent Ray Traversal on
//! GPUs Through Compressed Wide BVHs" (HPG 2017), as built by obvhs; the top
//! level is walked in obvhs's order by our own loop (module `walk`). Five
//! changes to obvhs's node test:
//! - child boxes are stored as exact `f32` planes ([`ChildBoxes`]; 224 bytes
//!   per node instead of 80): converting 48 quantised bytes to floats was a
//!   third of the instructions per node, and exact boxes are tighter. Measured
//!   on the bench's bumpy sphere: 29 % fewer instructions per ray, 25 % more
//!   coherent rays per CPU-second, about the same for incoherent rays (more
//!   cache misses); the exit distance is widened by [`EXIT_SCALE`] so rounding
//!   never culls a box a ray touches;
//! - the ray's own `t_min` bounds the slabs (obvhs clamps at a fixed 1e-4,
//!   which culls geometry closer than that whatever the scene's scale);
//! - a direction component smaller than [`TINY_DIR`] in magnitude is replaced
//!   by `±TINY_DIR` for the slab test only (obvhs uses `±f32::EPSILON`, which
//!   can cull boxes the ray runs along a few ULPs inside), with the sign
//!   matching the octant test `dir < 0`, so rays with zero components never
//!   produce NaN;
//! - per axis, the entry and exit distances are the smaller and the larger
//!   of the distances to the box's two planes, rather than the distances to
//!   the planes the direction's signs pick: the same values for every box
//!   (up to the sign of a zero, which compares equal), without the per-ray
//!   plane offsets the walk had to keep in registers (2.4 % fewer
//!   instructions per sample on `scenes/caustic-box.toml`). Absent children
//!   (inverted boxes) then count as entered: callers mask the children a
//!   node has;
//! - the eight child boxes are tested in one pass of 256-bit AVX operations
//!   where the CPU has AVX ([`Avx`](super::box_test::Avx), detected at run time), else as two
//!   halves of 128-bit operations ([`Portable`](super::box_test::Portable)); both do the same operations
//!   in the same order, so they give the same masks.
//!
//! No parameters.

use glam::{Vec3A, Vec4};
use obvhs::aabb::Aabb;

use super::triangle::RayShear;

/// Widening of each box's exit distance: the slab distances `(plane − o)·inv`
/// carry a relative rounding error of at most `3ε` (Ize, "Robust BVH Ray
/// Traversal", JCGT 2013, uses `1 + 2γ₃`), so a ray touching a box is never
/// culled, however far its origin.
pub(super) const EXIT_SCALE: f32 = 1.0 + 4.0 * f32::EPSILON;

/// Smallest direction magnitude used in slab tests.
pub(super) const TINY_DIR: f32 = 1e-18;

/// A ray prepared for box tests: origin, direction, clamped reciprocal
/// direction and `t` range, and the shear of the watertight triangle test.
///
/// An occlusion walk ([`FlatBvh::trace`](super::flat::FlatBvh) with `ANY`)
/// computes the shear itself before each packet test, so occlusion rays are
/// made [`TraceRay::without_shear`]: shadow rays rarely reach a packet (0.06
/// packet tests per shadow ray on `scenes/caustic-box.toml`), and the
/// shear's division and its store and indexed reload of the direction would
/// then cost every shadow ray for nothing.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TraceRay {
    /// Origin.
    pub origin: Vec3A,
    /// Direction (not normalised; not clamped).
    pub dir: Vec3A,
    /// Constants of the watertight triangle test ([`RayShear::UNSET`] on a
    /// ray made [`TraceRay::without_shear`] until a walk sets them).
    pub shear: RayShear,
    /// Reciprocals of the clamped direction components.
    inv_dir: Vec3A,
    /// Smallest accepted `t`.
    pub t_min: f32,
    /// Largest accepted `t`; traversal lowers it to the closest hit so far.
    pub t_max: f32,
}

impl TraceRay {
    /// Prepares `origin + t·dir`, `t` in `[t_min, t_max]`.
    #[inline(always)]
    pub fn new(origin: Vec3A, dir: Vec3A, t_min: f32, t_max: f32) -> Self {
        let inv_dir = clamped_recip(dir);
        Self {
            origin,
            dir,
            shear: RayShear::new(dir),
            inv_dir,
            t_min,
            t_max,
        }
    }

    /// [`TraceRay::new`] without the triangle test's shear, for occlusion
    /// walks only (which set it before each packet test). Its packet tests
    /// would find no hit: [`RayShear::UNSET`] makes every edge function NaN.
    #[inline(always)]
    pub fn without_shear(origin: Vec3A, dir: Vec3A, t_min: f32, t_max: f32) -> Self {
        Self {
            origin,
            dir,
            shear: RayShear::UNSET,
            inv_dir: clamped_recip(dir),
            t_min,
            t_max,
        }
    }

    /// The ray for a walk with `ANY`: [`TraceRay::without_shear`] for an
    /// occlusion walk, else [`TraceRay::new`].
    #[inline(always)]
    pub fn for_walk<const ANY: bool>(origin: Vec3A, dir: Vec3A, t_min: f32, t_max: f32) -> Self {
        if ANY {
            Self::without_shear(origin, dir, t_min, t_max)
        } else {
            Self::new(origin, dir, t_min, t_max)
        }
    }

    /// The octant code obvhs's traversal order uses (its
    /// `ray_get_octant_inv4`); only the top-level walk needs it, so it is
    /// not stored (4.4 instructions per ray on `scenes/caustic-box.toml`,
    /// which has no instances).
    #[inline(always)]
    pub fn oct_inv4(&self) -> u32 {
        // Branch-free: a per-ray branch on the octant mispredicts.
        let bits = self.dir.cmplt(Vec3A::ZERO).bitmask();
        OCT_INV4[(!bits & 7) as usize]
    }
}

/// The reciprocals of `dir`'s components, each clamped to at least
/// [`TINY_DIR`] in magnitude first (with the sign of the octant test
/// `dir < 0`), for the slab tests.
#[inline(always)]
fn clamped_recip(dir: Vec3A) -> Vec3A {
    // Branch-free: a per-ray branch on the octant mispredicts.
    let neg = dir.cmplt(Vec3A::ZERO);
    let tiny = Vec3A::select(neg, Vec3A::splat(-TINY_DIR), Vec3A::splat(TINY_DIR));
    Vec3A::select(dir.abs().cmpge(Vec3A::splat(TINY_DIR)), dir, tiny).recip()
}

/// obvhs's `ray_get_octant_inv4` by the mask of positive direction
/// components (bit `a` for axis `a`): axis x weighs 4, y 2, z 1, repeated in
/// each byte.
const OCT_INV4: [u32; 8] = {
    let mut table = [0; 8];
    let mut pos = 0;
    while pos < 8 {
        table[pos] =
            ((pos as u32 & 1) * 4 + ((pos as u32 >> 1) & 1) * 2 + (pos as u32 >> 2)) * 0x0101_0101;
        pos += 1;
    }
    table
};

/// Eight `f32` lanes, one per child, aligned for one 256-bit load.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub(crate) struct Lanes8(pub [f32; 8]);

/// The eight child boxes of a wide node as exact `f32` planes (one lane per
/// child, in child order); absent children get inverted boxes, which the
/// slab test reports as entered (callers mask them).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ChildBoxes {
    /// `planes[axis][0 = min, 1 = max]`.
    planes: [[Lanes8; 2]; 3],
}

/// The result of a ray against [`ChildBoxes`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct BoxHits {
    /// Bit `c` set when the ray enters child `c`'s box within its `t` range
    /// (always for an absent child).
    pub mask: u32,
    /// Per child, the entry distance (in units of the ray's direction,
    /// clamped below by `t_min`); meaningful only where `mask` is set.
    pub entry: Lanes8,
}

impl ChildBoxes {
    /// The boxes `children`; those with `present[c]` false are absent.
    pub fn new(children: &[Aabb; 8], present: [bool; 8]) -> Self {
        let mut planes = [[Lanes8([0.0; 8]); 2]; 3];
        for (child, aabb) in children.iter().enumerate() {
            for (axis, [lo, hi]) in planes.iter_mut().enumerate() {
                let (min, max) = if present[child] {
                    (aabb.min[axis], aabb.max[axis])
                } else {
                    (f32::INFINITY, f32::NEG_INFINITY)
                };
                lo.0[child] = min;
                hi.0[child] = max;
            }
        }
        Self { planes }
    }

    /// The box of child `child` (`< 8`; an absent child's is inverted,
    /// `+∞` to `−∞`).
    pub fn child(&self, child: usize) -> Aabb {
        let plane = |axis: usize, side: usize| self.planes[axis][side].0[child];
        Aabb {
            min: Vec3A::new(plane(0, 0), plane(1, 0), plane(2, 0)),
            max: Vec3A::new(plane(0, 1), plane(1, 1), plane(2, 1)),
        }
    }

    /// The boxes `ray` enters within its `t` range, four children at a time
    /// with 128-bit vectors (SSE2 on x86-64).
    #[inline(always)]
    pub(super) fn hits_4x2(&self, ray: &TraceRay) -> BoxHits {
        let mut mask = 0u32;
        let mut entry = Lanes8([0.0; 8]);
        for half in 0..2 {
            let lanes = |plane: &Lanes8| Vec4::from_slice(&plane.0[4 * half..4 * half + 4]);
            let slab = |axis: usize| {
                let o = Vec4::splat(ray.origin[axis]);
                let inv = Vec4::splat(ray.inv_dir[axis]);
                let lo = (lanes(&self.planes[axis][0]) - o) * inv;
                let hi = (lanes(&self.planes[axis][1]) - o) * inv;
                (lo.min(hi), lo.max(hi))
            };
            let ((x0, x1), (y0, y1), (z0, z1)) = (slab(0), slab(1), slab(2));
            let t0 = x0.max(y0).max(z0).max(Vec4::splat(ray.t_min));
            let t1 = (x1.min(y1).min(z1) * EXIT_SCALE).min(Vec4::splat(ray.t_max));
            mask |= t0.cmple(t1).bitmask() << (4 * half);
            t0.write_to_slice(&mut entry.0[4 * half..4 * half + 4]);
        }
        BoxHits { mask, entry }
    }

    /// [`ChildBoxes::hits_4x2`] on all eight children at once with 256-bit
    /// AVX vectors: the same operations in the same operand order (`max`
    /// and `min` return their second operand when one is NaN, as SSE's do),
    /// so the same mask and entry distances.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    #[inline]
    #[allow(unsafe_code)]
    pub(super) fn hits_8(&self, ray: &TraceRay) -> BoxHits {
        use std::arch::x86_64::{
            __m256, _CMP_LE_OS, _mm256_cmp_ps, _mm256_load_ps, _mm256_max_ps, _mm256_min_ps,
            _mm256_movemask_ps, _mm256_mul_ps, _mm256_set1_ps, _mm256_store_ps, _mm256_sub_ps,
        };
        // SAFETY: `Lanes8` is eight `f32` aligned to 32 bytes, exactly what
        // the aligned load reads; AVX is enabled on this function.
        let load = |plane: &Lanes8| -> __m256 { unsafe { _mm256_load_ps(plane.0.as_ptr()) } };
        let slab = |axis: usize| {
            let o = _mm256_set1_ps(ray.origin[axis]);
            let inv = _mm256_set1_ps(ray.inv_dir[axis]);
            let lo = _mm256_mul_ps(_mm256_sub_ps(load(&self.planes[axis][0]), o), inv);
            let hi = _mm256_mul_ps(_mm256_sub_ps(load(&self.planes[axis][1]), o), inv);
            (_mm256_min_ps(lo, hi), _mm256_max_ps(lo, hi))
        };
        let ((x0, x1), (y0, y1), (z0, z1)) = (slab(0), slab(1), slab(2));
        let t0 = _mm256_max_ps(
            _mm256_max_ps(_mm256_max_ps(x0, y0), z0),
            _mm256_set1_ps(ray.t_min),
        );
        let exit = _mm256_mul_ps(
            _mm256_min_ps(_mm256_min_ps(x1, y1), z1),
            _mm256_set1_ps(EXIT_SCALE),
        );
        let t1 = _mm256_min_ps(exit, _mm256_set1_ps(ray.t_max));
        let mut entry = Lanes8([0.0; 8]);
        // SAFETY: as the loads: eight `f32` aligned to 32 bytes.
        unsafe { _mm256_store_ps(entry.0.as_mut_ptr(), t0) };
        BoxHits {
            mask: _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OS>(t0, t1)) as u32,
            entry,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::box_test::{Avx, BoxTest, Portable};
    use epsm_testkit::Rng;

    /// The reference slab test: per axis, the distances to the planes the
    /// direction's sign picks (near plane `max` when `dir < 0`), as before
    /// the min/max form.
    fn sign_picked(boxes: &[Aabb; 8], ray: &TraceRay, child: usize) -> (bool, f32) {
        let (mut t0, mut t1) = (ray.t_min, f32::INFINITY);
        for axis in 0..3 {
            let (lo, hi) = (boxes[child].min[axis], boxes[child].max[axis]);
            let (near, far) = if ray.dir[axis] < 0.0 {
                (hi, lo)
            } else {
                (lo, hi)
            };
            let o = ray.origin[axis];
            t0 = ((near - o) * ray.inv_dir[axis]).max(t0);
            t1 = t1.min((far - o) * ray.inv_dir[axis]);
        }
        let t1 = (t1 * EXIT_SCALE).min(ray.t_max);
        (t0 <= t1, t0)
    }

    /// For present children, the min/max slab test gives the masks and
    /// entry distances of the sign-picked one (rays with zero direction
    /// components and origins on box planes included), with both box tests.
    #[test]
    fn min_max_slabs_match_sign_picked_planes() {
        let mut rng = Rng::new(11);
        let mut entered = 0;
        for i in 0..20_000 {
            let boxes: [Aabb; 8] = std::array::from_fn(|_| {
                let a = Vec3A::from(rng.dvec3(-2.0, 2.0).as_vec3());
                let b = a + Vec3A::from(rng.dvec3(0.0, 1.0).as_vec3());
                Aabb::new(a, b)
            });
            let present: [bool; 8] = std::array::from_fn(|_| rng.below(4) != 0);
            let child_boxes = ChildBoxes::new(&boxes, present);
            let mut origin = Vec3A::from(rng.dvec3(-3.0, 3.0).as_vec3());
            if i % 7 == 0 {
                origin[rng.below(3)] = boxes[rng.below(8)].min[rng.below(3)];
            }
            let mut dir = if i % 2 == 0 {
                // At a box, so that many rays enter some.
                let b = &boxes[rng.below(8)];
                (b.min + b.max) * 0.5 - origin
            } else {
                Vec3A::from(rng.unit().as_vec3())
            };
            if i % 5 == 0 {
                dir[rng.below(3)] = if i % 2 == 0 { 0.0 } else { -0.0 };
            }
            let t_max = if i % 3 == 0 {
                rng.range(0.0, 3.0) as f32
            } else {
                f32::INFINITY
            };
            let ray = TraceRay::new(origin, dir, 0.0, t_max);
            let hits = [Portable.hits(&child_boxes, &ray)]
                .into_iter()
                .chain(Avx::detect().map(|avx| avx.hits(&child_boxes, &ray)));
            for hits in hits {
                for child in (0..8).filter(|&c| present[c]) {
                    let (enters, entry) = sign_picked(&boxes, &ray, child);
                    assert_eq!(
                        hits.mask & (1 << child) != 0,
                        enters,
                        "ray {i} child {child}"
                    );
                    if enters {
                        assert!(hits.entry.0[child] == entry, "ray {i} child {child}");
                        entered += 1;
                    }
                }
            }
        }
        assert!(entered > 10_000, "{entered}");
    }
}
