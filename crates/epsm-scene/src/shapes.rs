//! Built-in shapes, following Mitsuba 3's conventions so scenes port over
//! unchanged. All are in object space, counter-clockwise front faces.
//!
//! | shape | geometry | normals | uvs | `subdivisions` |
//! |---|---|---|---|---|
//! | `rectangle` | `[-1, 1]²` in `z = 0` | `+z` | `[0, 1]²` | — |
//! | `cube` | `[-1, 1]³`, 24 vertices, 12 triangles | outward, flat per face | `[0, 1]²` per face | — |
//! | `sphere` | unit icosphere at the origin | smooth (= position) | none | levels, default 3, in [0, 8] |
//! | `disk` | unit disk in `z = 0`, a fan | `+z` | `(0.5 + x/2, 0.5 + y/2)` | segments, default 64, in [3, 65536] |
//!
//! ```toml
//! [[objects]]
//! name = "ball"
//! shape = "sphere"
//! subdivisions = 4
//! material = "white"
//! ```

use std::collections::HashMap;

use glam::{Vec2, Vec3};

use crate::desc::ShapeKind;
use epsm_render::scene::Mesh;

/// Default icosphere levels of `sphere`.
pub const DEFAULT_SPHERE_LEVELS: u32 = 3;
/// Largest accepted icosphere level (20·4⁸ ≈ 1.3 M triangles).
pub const MAX_SPHERE_LEVELS: u32 = 8;
/// Default number of segments of `disk`.
pub const DEFAULT_DISK_SEGMENTS: u32 = 64;
/// Fewest accepted disk segments.
pub const MIN_DISK_SEGMENTS: u32 = 3;
/// Most accepted disk segments.
pub const MAX_DISK_SEGMENTS: u32 = 65536;

/// The mesh of a built-in shape; `subdivisions` (already range-checked) is
/// the sphere's levels or the disk's segments and is ignored by the others.
pub fn build(kind: ShapeKind, subdivisions: Option<u32>) -> Mesh {
    match kind {
        ShapeKind::Rectangle => rectangle(),
        ShapeKind::Cube => cube(),
        ShapeKind::Sphere => sphere(subdivisions.unwrap_or(DEFAULT_SPHERE_LEVELS)),
        ShapeKind::Disk => disk(subdivisions.unwrap_or(DEFAULT_DISK_SEGMENTS)),
    }
}

/// `[-1, 1]²` in the plane `z = 0`, normal `+z`.
pub fn rectangle() -> Mesh {
    let mut mesh = Mesh::default();
    push_quad(&mut mesh, Vec3::ZERO, Vec3::Z, Vec3::X, Vec3::Y);
    mesh
}

/// `[-1, 1]³` with flat outward normals: four vertices per face.
pub fn cube() -> Mesh {
    let mut mesh = Mesh::default();
    // (normal, u, v) with u × v = normal, so the quad winds counter-clockwise seen from outside.
    for (n, u, v) in [
        (Vec3::X, Vec3::Y, Vec3::Z),
        (Vec3::NEG_X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::Z, Vec3::X),
        (Vec3::NEG_Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (Vec3::NEG_Z, Vec3::Y, Vec3::X),
    ] {
        push_quad(&mut mesh, n, n, u, v);
    }
    mesh
}

/// Appends the quad `center + s·u + t·v`, `s, t ∈ [-1, 1]`, facing `n = u × v`.
fn push_quad(mesh: &mut Mesh, center: Vec3, n: Vec3, u: Vec3, v: Vec3) {
    let base = mesh.positions.len() as u32;
    for (s, t) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
        mesh.positions.push(center + u * s + v * t);
        mesh.normals.push(n);
        mesh.uvs.push(Vec2::new(0.5 * (s + 1.0), 0.5 * (t + 1.0)));
    }
    mesh.indices.push([base, base + 1, base + 2]);
    mesh.indices.push([base, base + 2, base + 3]);
}

/// The regular icosahedron with unit-length vertices: 12 positions and 20
/// counter-clockwise (outward-facing) triangles.
pub fn icosahedron() -> Mesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let positions: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .into_iter()
    .map(|(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let indices: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    Mesh {
        positions,
        normals: Vec::new(),
        uvs: Vec::new(),
        indices,
    }
}

/// Unit sphere: an icosahedron subdivided `levels` times, vertices projected
/// onto the sphere; normals equal positions.
pub fn sphere(levels: u32) -> Mesh {
    let Mesh {
        mut positions,
        mut indices,
        ..
    } = icosahedron();
    for _ in 0..levels {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, positions: &mut Vec<Vec3>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let p = (positions[a as usize] + positions[b as usize]).normalize();
                positions.push(p);
                positions.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(indices.len() * 4);
        for [a, b, c] in indices {
            let ab = midpoint(a, b, &mut positions);
            let bc = midpoint(b, c, &mut positions);
            let ca = midpoint(c, a, &mut positions);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        indices = next;
    }
    Mesh {
        normals: positions.clone(),
        positions,
        uvs: Vec::new(),
        indices,
    }
}

/// Unit disk in `z = 0` facing `+z`: a fan of `segments` triangles around
/// the centre.
pub fn disk(segments: u32) -> Mesh {
    let mut mesh = Mesh::default();
    mesh.positions.push(Vec3::ZERO);
    for i in 0..segments {
        let phi = std::f32::consts::TAU * i as f32 / segments as f32;
        let (sin, cos) = phi.sin_cos();
        mesh.positions.push(Vec3::new(cos, sin, 0.0));
    }
    mesh.normals = vec![Vec3::Z; mesh.positions.len()];
    mesh.uvs = mesh
        .positions
        .iter()
        .map(|p| Vec2::new(0.5 + 0.5 * p.x, 0.5 + 0.5 * p.y))
        .collect();
    mesh.indices = (0..segments)
        .map(|i| [0, 1 + i, 1 + (i + 1) % segments])
        .collect();
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Total area, and asserts every triangle is non-degenerate and its
    /// geometric normal agrees with its vertex normals.
    fn area_checked(mesh: &Mesh) -> f64 {
        let mut area = 0.0;
        for (t, &[a, b, c]) in mesh.indices.iter().enumerate() {
            let [p0, p1, p2] = mesh.triangle(t as u32);
            let cross = (p1 - p0).cross(p2 - p0);
            assert!(cross.length() > 1e-9, "triangle {t} is degenerate");
            for i in [a, b, c] {
                let n = mesh.normals[i as usize];
                assert!(
                    n.dot(cross.normalize()) > 0.5,
                    "triangle {t} winds against its normals"
                );
                assert!((n.length() - 1.0).abs() < 1e-5);
            }
            area += 0.5 * cross.as_dvec3().length();
        }
        area
    }

    /// Whether every face points away from the origin (closed convex shapes).
    fn faces_outward(mesh: &Mesh) -> bool {
        (0..mesh.len() as u32).all(|t| {
            let [p0, p1, p2] = mesh.triangle(t);
            (p1 - p0).cross(p2 - p0).dot(p0 + p1 + p2) > 0.0
        })
    }

    #[test]
    fn rectangle_has_area_four_and_faces_plus_z() {
        let m = rectangle();
        assert!((area_checked(&m) - 4.0).abs() < 1e-6);
        assert!(m.positions.iter().all(|p| p.z == 0.0 && p.x.abs() == 1.0));
        let [p0, p1, p2] = m.triangle(0);
        assert!(
            (p1 - p0)
                .cross(p2 - p0)
                .normalize()
                .abs_diff_eq(Vec3::Z, 1e-6)
        );
    }

    #[test]
    fn cube_has_area_twenty_four_and_faces_outward() {
        let m = cube();
        assert_eq!((m.positions.len(), m.len()), (24, 12));
        assert!((area_checked(&m) - 24.0).abs() < 1e-5);
        assert!(faces_outward(&m));
        assert!(m.positions.iter().all(|p| p.abs().max_element() == 1.0));
    }

    #[test]
    fn sphere_area_converges_to_four_pi_and_faces_outward() {
        let four_pi = 4.0 * std::f64::consts::PI;
        let mut last_error = f64::INFINITY;
        for levels in 0..=4 {
            let m = sphere(levels);
            assert_eq!(m.len(), 20 * 4usize.pow(levels));
            assert!(faces_outward(&m));
            assert!(m.positions.iter().all(|p| (p.length() - 1.0).abs() < 1e-6));
            let error = four_pi - area_checked(&m);
            assert!(
                error > 0.0 && error < last_error,
                "level {levels}: error {error}"
            );
            last_error = error;
        }
        assert!(last_error < 0.01 * four_pi);
    }

    #[test]
    fn disk_area_converges_to_pi_and_faces_plus_z() {
        let pi = std::f64::consts::PI;
        assert!((area_checked(&disk(3)) - 0.75 * 3f64.sqrt() * 1.0).abs() < 1e-5);
        let fine = disk(1024);
        assert!((area_checked(&fine) - pi).abs() < 1e-4);
        assert!(
            fine.positions
                .iter()
                .all(|p| p.z == 0.0 && p.length() <= 1.0 + 1e-6)
        );
    }

    #[test]
    fn build_uses_documented_defaults() {
        assert_eq!(
            build(ShapeKind::Sphere, None).len(),
            20 * 4usize.pow(DEFAULT_SPHERE_LEVELS)
        );
        assert_eq!(
            build(ShapeKind::Disk, None).len(),
            DEFAULT_DISK_SEGMENTS as usize
        );
        assert_eq!(build(ShapeKind::Disk, Some(5)).len(), 5);
    }
}
