//! The benchmark's scene and ray sets: a displaced geodesic sphere (an
//! icosahedron whose faces are split into `k²` triangles each, projected to
//! the unit sphere and displaced radially by a few sines) placed once at the
//! origin and four times smaller around it, and uniform random rays.

use std::sync::Arc;

use epsm_render::Ray;
use epsm_render::scene::{Mesh, Object, Surface};
use glam::{DAffine3, DQuat, DVec3, Vec3};

/// A uniform scale by `scale`, a turn about `y` by `at.x` radians, then a move to `at`.
pub fn placement(at: DVec3, scale: f64) -> DAffine3 {
    DAffine3::from_scale_rotation_translation(DVec3::splat(scale), DQuat::from_rotation_y(at.x), at)
}

/// The big sphere at the origin and four smaller instances around it.
pub fn scene(mesh: &Arc<Mesh>) -> Vec<Object> {
    let mut places = vec![DAffine3::IDENTITY];
    places.extend((0..4).map(|k| {
        let a = k as f64 * std::f64::consts::FRAC_PI_2 + 0.3;
        placement(
            DVec3::new(2.5 * a.cos(), 0.3 * k as f64 - 0.5, 2.5 * a.sin()),
            0.4,
        )
    }));
    places
        .into_iter()
        .enumerate()
        .map(|(i, world_from_object)| Object {
            name: format!("sphere{i}"),
            mesh: Arc::clone(mesh),
            world_from_object,
            material: 0,
            emission: None,
            surface: Surface::Mesh,
        })
        .collect()
}

/// Uniform origins in the box `[lo, hi]` and uniform directions.
pub fn random_rays(n: usize, lo: DVec3, hi: DVec3) -> Vec<Ray> {
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let (lo, size) = (lo.as_vec3(), (hi - lo).as_vec3());
    (0..n)
        .map(|_| {
            let origin = lo + size * Vec3::new(uniform(), uniform(), uniform());
            let z = 1.0 - 2.0 * uniform();
            let phi = std::f32::consts::TAU * uniform();
            let r = (1.0 - z * z).max(0.0).sqrt();
            Ray::new(origin, Vec3::new(r * phi.cos(), r * phi.sin(), z))
        })
        .collect()
}

/// A unit geodesic sphere with about `triangles` triangles (20·k²), displaced
/// radially by ±10 % of sines.
pub fn bumpy_sphere(triangles: usize) -> Mesh {
    let k = ((triangles as f64 / 20.0).sqrt().round() as u32).max(1);
    let ico = epsm_scene::shapes::icosahedron();
    let v = &ico.positions;
    let displace = |p: Vec3| {
        let d = p.normalize();
        let bump = (9.0 * d.x).sin() * (7.0 * d.y).sin() * (8.0 * d.z).sin()
            + 0.3 * (31.0 * d.x + 17.0 * d.z).sin();
        d * (1.0 + 0.08 * bump)
    };
    let mut mesh = Mesh::default();
    for &[a, b, c] in &ico.indices {
        let base = mesh.positions.len() as u32;
        let row_start = |i: u32| base + i * (k + 1) - i * (i.saturating_sub(1)) / 2;
        for i in 0..=k {
            for j in 0..=(k - i) {
                let (u, w) = (i as f32 / k as f32, j as f32 / k as f32);
                mesh.positions.push(displace(
                    v[a as usize]
                        + (v[b as usize] - v[a as usize]) * u
                        + (v[c as usize] - v[a as usize]) * w,
                ));
            }
        }
        for i in 0..k {
            let (r0, r1) = (row_start(i), row_start(i + 1));
            for j in 0..(k - i) {
                mesh.indices.push([r0 + j, r1 + j, r0 + j + 1]);
                if j + 1 < k - i {
                    mesh.indices.push([r0 + j + 1, r1 + j, r1 + j + 1]);
                }
            }
        }
    }
    mesh
}
