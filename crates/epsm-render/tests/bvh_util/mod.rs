//! Shared functions of the BVH and hit tests: a deterministic generator,
//! random triangle soups, a bumpy grid with normals and uvs, random transforms
//! and random scenes.

#![allow(dead_code)]

use std::sync::Arc;

use epsm_render::scene::{Mesh, Object, Surface};
use glam::{DAffine3, DQuat, Vec2, Vec3};

pub use epsm_testkit::Rng;

/// Random triangles in `[-1, 1]³`, with thin and degenerate ones mixed in.
pub fn soup(rng: &mut Rng, count: usize) -> Mesh {
    let mut mesh = Mesh::default();
    for i in 0..count {
        let a = rng.dvec3(-1.0, 1.0).as_vec3();
        let b = a + rng.dvec3(-0.6, 0.6).as_vec3();
        let c = match i % 8 {
            0 => a + (b - a) * 0.37 + rng.dvec3(-1e-4, 1e-4).as_vec3(), // sliver
            1 => a,                                                     // repeated vertex
            2 => {
                // Exactly collinear: coordinates on a 1/64 grid keep f32 exact.
                let q = |v: Vec3| (v * 64.0).round() / 64.0;
                let (a, v) = (q(a), q(b - a));
                let base = mesh.positions.len() as u32;
                mesh.positions.extend([a, a + v, a + 2.0 * v]);
                mesh.indices.push([base, base + 1, base + 2]);
                continue;
            }
            _ => a + rng.dvec3(-0.6, 0.6).as_vec3(),
        };
        let base = mesh.positions.len() as u32;
        mesh.positions.extend([a, b, c]);
        mesh.indices.push([base, base + 1, base + 2]);
    }
    mesh
}

/// A bumpy `n × n` height-field grid over `[-1, 1]²` with normals and uvs.
pub fn grid(n: u32) -> Mesh {
    let mut mesh = Mesh::default();
    for j in 0..=n {
        for i in 0..=n {
            let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
            let (x, z) = (2.0 * u - 1.0, 2.0 * v - 1.0);
            mesh.positions
                .push(Vec3::new(x, 0.2 * (3.0 * x).sin() * (2.0 * z).cos(), z));
            let (dx, dz) = (
                0.6 * (3.0 * x).cos() * (2.0 * z).cos(),
                -0.4 * (3.0 * x).sin() * (2.0 * z).sin(),
            );
            mesh.normals.push(Vec3::new(-dx, 1.0, -dz).normalize());
            mesh.uvs.push(Vec2::new(u, v));
        }
    }
    for j in 0..n {
        for i in 0..n {
            let k = j * (n + 1) + i;
            mesh.indices.push([k, k + n + 1, k + 1]);
            mesh.indices.push([k + 1, k + n + 1, k + n + 2]);
        }
    }
    mesh
}

pub fn random_transform(rng: &mut Rng, mirror: bool) -> DAffine3 {
    let rotation = DQuat::from_axis_angle(rng.unit(), rng.range(0.0, std::f64::consts::TAU));
    let mut scale = rng.dvec3(0.3, 2.0);
    if mirror {
        scale.y = -scale.y;
    }
    DAffine3::from_scale_rotation_translation(scale, rotation, rng.dvec3(-1.5, 1.5))
}

pub fn object(name: String, mesh: &Arc<Mesh>, world_from_object: DAffine3) -> Object {
    Object {
        name,
        mesh: Arc::clone(mesh),
        world_from_object,
        material: 0,
        emission: None,
        surface: Surface::Mesh,
    }
}

/// Six objects on three meshes (two shared), one mirrored, plus an empty mesh.
pub fn random_scene(rng: &mut Rng) -> Vec<Object> {
    let meshes = [
        Arc::new(soup(rng, 200)),
        Arc::new(grid(6)),
        Arc::new(soup(rng, 20)),
        Arc::new(Mesh::default()),
    ];
    let pick = [0, 1, 0, 2, 1, 3, 0];
    pick.iter()
        .enumerate()
        .map(|(i, &m)| object(format!("o{i}"), &meshes[m], random_transform(rng, i == 2)))
        .collect()
}

/// A closed unit "cube sphere": the surface of the integer grid cube
/// `[-n, n]³` with each vertex normalised, `48·n²` outward-facing triangles
/// sharing their vertices (one `f32` position per grid point).
pub fn cube_sphere(n: i32) -> Mesh {
    let mut mesh = Mesh::default();
    let mut index = std::collections::HashMap::new();
    let mut vertex = |mesh: &mut Mesh, p: [i32; 3]| {
        *index.entry(p).or_insert_with(|| {
            let v = Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32).normalize();
            mesh.positions.push(v);
            mesh.positions.len() as u32 - 1
        })
    };
    for axis in 0..3 {
        for side in [-n, n] {
            for i in -n..n {
                for j in -n..n {
                    let at = |a: i32, b: i32| {
                        let mut p = [0; 3];
                        p[axis] = side;
                        p[(axis + 1) % 3] = a;
                        p[(axis + 2) % 3] = b;
                        p
                    };
                    let q = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]
                        .map(|p| vertex(&mut mesh, p));
                    let tris = if side > 0 {
                        [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
                    } else {
                        [[q[0], q[2], q[1]], [q[0], q[3], q[2]]]
                    };
                    mesh.indices.extend(tris);
                }
            }
        }
    }
    mesh
}
