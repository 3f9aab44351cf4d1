//! Test functions shared by the BVH tests (module `flat`'s and the wide
//! walks').

use epsm_testkit::Rng;

use crate::scene::Mesh;

/// Appends triangle `i` of a random soup in `[-1, 1]³` to `mesh`: for
/// `i % 7` 0 or 3 a thin sliver, for 5 an exactly degenerate one (its third
/// vertex the midpoint of its first edge), else a random one; for
/// `i % 4 == 1` also a second triangle sharing its edge `(c, b)`. The soup
/// of the flat BVH tests, the geometry of the wide walks' random soups.
pub(super) fn push_soup_triangle(rng: &mut Rng, mesh: &mut Mesh, i: usize) {
    let a = rng.dvec3(-1.0, 1.0).as_vec3();
    let b = a + rng.dvec3(-0.4, 0.4).as_vec3();
    let c = match i % 7 {
        0 | 3 => a + (b - a) * rng.range(0.1, 0.9) as f32 + rng.dvec3(-1e-5, 1e-5).as_vec3(),
        5 => a + (b - a) * 0.5,
        _ => a + rng.dvec3(-0.4, 0.4).as_vec3(),
    };
    let base = mesh.positions.len() as u32;
    mesh.positions.extend([a, b, c]);
    mesh.indices.push([base, base + 1, base + 2]);
    if i % 4 == 1 {
        mesh.positions.push(c + rng.dvec3(-0.3, 0.3).as_vec3());
        mesh.indices.push([base + 2, base + 1, base + 3]);
    }
}
