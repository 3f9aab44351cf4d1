//! Which static objects bound a convex solid, so that a ray inside one can
//! stop at the first of its triangles it hits (the exit walk of module
//! `flat`).
//!
//! Model: a closed, consistently wound triangle mesh is the boundary of a
//! convex polytope with its fronts outward when
//! 1. every edge is convex: the far vertex of the triangle across it lies on
//!    or behind the triangle's plane (the plane's front given by the
//!    winding);
//! 2. the mean of its vertices, `c`, lies strictly behind every triangle's
//!    plane;
//! 3. the triangles' solid angles seen from `c` (all positive, by 2) sum to
//!    `4π`, not a multiple of it.
//!
//! By 2 and 3, projecting the mesh from `c` onto a sphere around it covers
//! the sphere once, with every triangle facing away from `c`: the mesh is a
//! radial graph about `c` and bounds a solid star-shaped about it. By 1,
//! that solid is locally convex along every edge, hence (its vertex cones,
//! simple and convex along every edge, being convex) at every boundary
//! point, and a connected closed set that is locally convex everywhere is
//! convex (Tietze–Nakajima). Conversely every convex polytope's boundary
//! passes all three (the vertex mean is interior). A ray whose origin lies
//! inside it leaves it exactly once: no triangle but the exit (and those
//! sharing the exit point, at the same `t` up to rounding) has a hit at
//! `t > 0`.
//!
//! Checked on the `f32` world-space vertices the BVH holds, in `f64`, in
//! time linear in the triangles:
//! - closed and consistent: with vertices identified by their coordinates'
//!   bits (so a mesh split at texture seams still counts as closed), every
//!   directed edge `a → b` occurs once and its reverse `b → a` once;
//! - 1 with `n · (v − p0) ≤ TOLERANCE · |n| · D` for the triangle's winding
//!   normal `n` (unnormalised) and `D` the diagonal of the mesh's box: the
//!   `f32` world-space vertices of a flat face split into several triangles
//!   lie up to about `1e-7·D` on either side of its plane, and a fold this
//!   shallow moves a hit by no more than that rounding does; 2 strictly; 3
//!   to within `π` (the sum is a multiple of `4π` up to rounding).
//!
//! | constant | value | meaning |
//! |---|---|---|
//! | `TOLERANCE` | 1e-6 | relative distance in front of a plane still taken as on it |
//!
//! No parameters.

use std::f64::consts::PI;

use glam::{DVec3, Vec3A};
use rustc_hash::FxHashMap;

/// Relative distance in front of a plane still taken as on it.
const TOLERANCE: f64 = 1e-6;

/// Whether `triangles` (world space, front by the winding) bound a convex
/// solid with their fronts outward (module docs).
pub(crate) fn bounds_convex_solid(triangles: &[[Vec3A; 3]]) -> bool {
    if triangles.len() < 4 {
        return false;
    }
    // Vertices by their coordinates' bits (−0 as +0); each directed edge
    // with the vertex across from it in its triangle.
    let key = |p: Vec3A| p.to_array().map(|c| (c + 0.0).to_bits());
    let mut index: FxHashMap<[u32; 3], usize> = FxHashMap::default();
    let mut vertices: Vec<DVec3> = Vec::new();
    let mut edges: FxHashMap<(usize, usize), usize> = FxHashMap::default();
    edges.reserve(3 * triangles.len());
    let mut ids = Vec::with_capacity(triangles.len());
    for triangle in triangles {
        let t = triangle.map(|p| {
            *index.entry(key(p)).or_insert_with(|| {
                vertices.push(p.as_dvec3());
                vertices.len() - 1
            })
        });
        for k in 0..3 {
            // A repeated directed edge: not consistently wound (or not a
            // manifold).
            if edges
                .insert((t[k], t[(k + 1) % 3]), t[(k + 2) % 3])
                .is_some()
            {
                return false;
            }
        }
        ids.push(t);
    }
    let (lo, hi) = vertices
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    let diagonal = (hi - lo).length();
    let centre = vertices.iter().sum::<DVec3>() / vertices.len() as f64;
    let mut solid_angle = 0.0;
    for t in &ids {
        let [p0, p1, p2] = t.map(|i| vertices[i]);
        let n = (p1 - p0).cross(p2 - p0);
        let on_or_behind = |v: DVec3| n.dot(v - p0) <= TOLERANCE * n.length() * diagonal;
        for k in 0..3 {
            // Closed: every edge has its reverse, whose far vertex is on or
            // behind this plane (1).
            match edges.get(&(t[(k + 1) % 3], t[k])) {
                Some(&across) if on_or_behind(vertices[across]) => {}
                _ => return false,
            }
        }
        // 2, and the triangle's solid angle from `c` (Van Oosterom and
        // Strackee).
        let behind = n.dot(centre - p0) < 0.0;
        if !behind {
            return false;
        }
        let [a, b, c] = [p0, p1, p2].map(|p| p - centre);
        let (la, lb, lc) = (a.length(), b.length(), c.length());
        let numerator = a.dot(b.cross(c));
        let denominator = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
        solid_angle += 2.0 * numerator.atan2(denominator);
    }
    (solid_angle - 4.0 * PI).abs() < PI
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::desc::ShapeKind;
    use crate::scene::shapes::build;
    use glam::{Mat3, Vec3};

    fn triangles(
        kind: ShapeKind,
        subdivisions: Option<u32>,
        map: impl Fn(Vec3) -> Vec3,
    ) -> Vec<[Vec3A; 3]> {
        let mesh = build(kind, subdivisions);
        (0..mesh.len() as u32)
            .map(|t| mesh.triangle(t).map(|p| Vec3A::from(map(p))))
            .collect()
    }

    /// Spheres, cubes and a tetrahedron, placed anyhow, are convex solids;
    /// a rectangle, a disk, a mesh wound inward, a dented or bumped sphere, a
    /// sphere missing one triangle and two spheres as one mesh are not.
    #[test]
    fn convex_solids_and_others() {
        let place = |p: Vec3| {
            Mat3::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 2.0) * (p * Vec3::new(1.0, 0.5, 2.0))
                + Vec3::new(3.0, -1.0, 0.5)
        };
        for subdivisions in [1, 4] {
            assert!(bounds_convex_solid(&triangles(
                ShapeKind::Sphere,
                Some(subdivisions),
                place
            )));
        }
        let cube = triangles(ShapeKind::Cube, None, place);
        assert!(bounds_convex_solid(&cube));
        assert!(!bounds_convex_solid(&triangles(
            ShapeKind::Rectangle,
            None,
            place
        )));
        assert!(!bounds_convex_solid(&triangles(
            ShapeKind::Disk,
            None,
            place
        )));
        let [a, b, c, d] = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z].map(|p| Vec3A::from(place(p)));
        assert!(bounds_convex_solid(&[
            [a, c, b],
            [a, b, d],
            [b, c, d],
            [a, d, c]
        ]));
        let inward: Vec<_> = cube.iter().map(|&[a, b, c]| [a, c, b]).collect();
        assert!(!bounds_convex_solid(&inward));
        let sphere = triangles(ShapeKind::Sphere, Some(3), |p| p);
        let moved = sphere[0][0];
        for scale in [0.9, 1.1] {
            let dented: Vec<_> = sphere
                .iter()
                .map(|t| t.map(|p| if p == moved { p * scale } else { p }))
                .collect();
            assert!(!bounds_convex_solid(&dented), "{scale}");
        }
        assert!(!bounds_convex_solid(&sphere[1..]));
        let mut two = sphere.clone();
        two.extend(sphere.iter().map(|t| t.map(|p| p + Vec3A::X * 3.0)));
        assert!(!bounds_convex_solid(&two));
    }
}
