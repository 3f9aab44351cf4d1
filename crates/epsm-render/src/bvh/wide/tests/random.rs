//! Random scenes: triangle soups (thin, degenerate and edge-sharing
//! triangles, flat, constant or interpolated normals, with and without
//! texture coordinates), an axis-aligned open box, static and dynamic
//! objects, none to four exact spheres (mirrored and skewed; up to two
//! listed, more behind the top level), scaled from 10⁻³ to 10³; rays from
//! anywhere, from inside the spheres, along axes, aimed at triangles'
//! vertices and edges, with `t_min` and `t_max` limits; random active lanes.

use std::sync::Arc;

use glam::{DAffine3, DQuat, DVec3, Vec2, Vec3};

use super::super::instances::LINEAR_INSTANCES;
use super::{Tally, compare};
use crate::bvh::Accel;
use crate::bvh::test_support::push_soup_triangle;
use crate::ray::Ray;
use crate::scene::{Mesh, Object, ObjectId, Surface};
use crate::simd::{LANES, Lanes, Mask16};
use epsm_testkit::Rng;

/// A soup of `count` triangles in `[-1, 1]³`: a third thin slivers, a few
/// exactly degenerate, some sharing an edge with the one before; `normals`
/// 0: none, 1: one per triangle (a constant shading normal), 2: random per
/// vertex; texture coordinates when `uvs`.
fn soup(rng: &mut Rng, count: usize, normals: usize, uvs: bool) -> Mesh {
    let mut mesh = Mesh::default();
    let unit = |rng: &mut Rng| rng.unit().as_vec3();
    for i in 0..count {
        let base = mesh.positions.len();
        push_soup_triangle(rng, &mut mesh, i);
        let added = mesh.positions.len() - base;
        let n = unit(rng);
        for _ in 0..added {
            match normals {
                1 => mesh.normals.push(n),
                2 => mesh.normals.push(unit(rng)),
                _ => {}
            }
            if uvs {
                mesh.uvs.push(Vec2::new(rng.f32(), rng.f32()));
            }
        }
    }
    mesh
}

/// An open box `[-2, 2]³` without its `+z` side: two triangles per side,
/// axis-aligned, sharing their diagonals and edges.
fn open_box() -> Mesh {
    let mut mesh = Mesh::default();
    let corner = |i: u32| {
        let s = |bit: u32| if i & bit == 0 { -2.0 } else { 2.0 };
        Vec3::new(s(1), s(2), s(4))
    };
    mesh.positions = (0..8).map(corner).collect();
    for [a, b, c, d] in [
        [0, 1, 3, 2],
        [0, 4, 5, 1],
        [0, 2, 6, 4],
        [1, 5, 7, 3],
        [2, 3, 7, 6],
    ] {
        mesh.indices.extend([[a, b, c], [a, c, d]]);
    }
    mesh
}

/// A placement: random rotation, scale (uniform or per axis, sometimes
/// mirrored) and translation, all scaled by `scale`.
fn placement(rng: &mut Rng, scale: f64, skew: bool) -> DAffine3 {
    let mut s = if skew {
        rng.dvec3(0.3, 1.5)
    } else {
        DVec3::splat(rng.range(0.3, 1.5))
    };
    if rng.below(3) == 0 {
        s.y = -s.y;
    }
    DAffine3::from_scale_rotation_translation(
        s * scale,
        DQuat::from_axis_angle(rng.unit(), rng.range(0.0, 6.3)),
        rng.dvec3(-1.5, 1.5) * scale,
    )
}

fn object(mesh: Mesh, world_from_object: DAffine3, surface: Surface) -> Object {
    Object {
        name: "random".into(),
        mesh: Arc::new(mesh),
        world_from_object,
        material: 0,
        emission: None,
        surface,
    }
}

/// Scene `case`: its objects and the dynamic ones among them.
fn scene(rng: &mut Rng, case: usize) -> (Vec<Object>, Vec<ObjectId>) {
    let scale = [1.0, 1e-3, 1e3][case % 3];
    let mut objects = vec![object(
        open_box(),
        DAffine3::from_scale(DVec3::splat(scale)),
        Surface::Mesh,
    )];
    for i in 0..2 + case % 3 {
        let mesh = soup(
            rng,
            [20, 300, 1500][(case + i) % 3],
            (case + i) % 3,
            i % 2 == 1,
        );
        objects.push(object(
            mesh,
            placement(rng, scale, i % 2 == 0),
            Surface::Mesh,
        ));
    }
    for _ in 0..[0, 1, 2, 4][case % 4] {
        let at = placement(rng, scale, case.is_multiple_of(2));
        objects.push(object(Mesh::default(), at, Surface::Sphere));
    }
    let mut dynamic = if case % 5 == 2 { vec![2] } else { vec![] };
    if case % 8 == 7 {
        // More instances than the packet walks take: the scalar top-level
        // walk per lane.
        for i in 0..LINEAR_INSTANCES {
            let mesh = soup(rng, 20, i % 3, false);
            objects.push(object(mesh, placement(rng, scale, true), Surface::Mesh));
        }
        dynamic = (1..objects.len() as ObjectId)
            .filter(|&id| objects[id as usize].surface == Surface::Mesh)
            .collect();
    }
    (objects, dynamic)
}

/// A random ray for `objects` (see the module docs).
fn ray(rng: &mut Rng, objects: &[Object], scale: f64, i: usize) -> Ray {
    let pick = &objects[rng.below(objects.len())];
    let mut origin = (rng.dvec3(-2.5, 2.5) * scale).as_vec3();
    let mut dir = rng.unit().as_vec3() * rng.range(0.3, 3.0) as f32;
    match i % 6 {
        // From inside a sphere (or anything's centre).
        0 => origin = pick.world_from_object.translation.as_vec3(),
        // At a vertex or an edge point of a triangle.
        1 if !pick.mesh.is_empty() => {
            let tri = pick.mesh.triangle(rng.below(pick.mesh.len()) as u32);
            let w = if rng.below(2) == 0 { 1.0 } else { 0.5 };
            let local = tri[0] * w + tri[1] * (1.0 - w);
            let target = pick.world_from_object.transform_point3(local.as_dvec3());
            dir = target.as_vec3() - origin;
        }
        // Along axes.
        2 => {
            dir[rng.below(3)] = 0.0;
            if rng.below(2) == 0 {
                dir[rng.below(3)] = 0.0;
            }
        }
        _ => {}
    }
    let mut ray = Ray::new(origin, dir);
    if i.is_multiple_of(3) {
        ray.t_max = rng.range(0.0, 3.0) as f32;
    }
    if i.is_multiple_of(7) {
        ray.t_min = rng.range(0.0, 1.0) as f32;
    }
    ray
}

/// Random scenes: every active lane's closest hit, occlusion and shading
/// point is the scalar one bit for bit, but for rare ties of rays aimed at
/// vertices and edges (none elsewhere).
#[test]
fn random_scenes_match_the_scalar_walks() {
    fn on<B: Lanes>(k: B) {
        let mut rng = Rng::new(29);
        let mut total = Tally::default();
        // Scenes whose instances are walked in lanes, and per lane.
        let mut instance_walks = [0; 2];
        for case in 0..24 {
            let (objects, dynamic) = scene(&mut rng, case);
            let accel = Accel::build_with_dynamic(&objects, &dynamic);
            if !accel.tlas.slots.is_empty() {
                instance_walks[usize::from(!accel.instances_in_lanes())] += 1;
            }
            let scale = [1.0, 1e-3, 1e3][case % 3];
            let mut tally = Tally::default();
            for p in 0..120 {
                let rays: [Ray; LANES] =
                    std::array::from_fn(|i| ray(&mut rng, &objects, scale, p + i));
                let active = if p % 4 == 0 {
                    Mask16(rng.below(1 << 16) as u16)
                } else {
                    Mask16::ALL
                };
                let ties = compare(k, &accel, &objects, &rays, active, &mut tally);
                // Ties only where a ray is aimed at a vertex or an edge
                // (`ray`'s case 1), which triangles may share.
                let aimed = (0..LANES).filter(|i| (p + i) % 6 == 1);
                let aimed = Mask16(aimed.fold(0, |m, i| m | 1 << i));
                assert!(!ties.and_not(aimed).any(), "case {case}: ties {ties:?}");
            }
            assert!(tally.hits > tally.rays / 4, "case {case}: {tally:?}");
            let spheres = objects
                .iter()
                .filter(|o| o.surface == Surface::Sphere)
                .count();
            assert!(
                spheres == 0 || tally.sphere_hits > 0,
                "case {case}: {tally:?}"
            );
            for (sum, add) in [
                (&mut total.rays, tally.rays),
                (&mut total.hits, tally.hits),
                (&mut total.sphere_hits, tally.sphere_hits),
                (&mut total.occluded, tally.occluded),
                (&mut total.ties, tally.ties),
                (&mut total.points, tally.points),
            ] {
                *sum += add;
            }
        }
        eprintln!("{total:?}, instance walks in lanes / per lane {instance_walks:?}");
        assert!(instance_walks.iter().all(|&n| n > 0), "{instance_walks:?}");
        assert!(total.ties * 1000 <= total.rays, "{total:?}");
        assert!(
            total.sphere_hits > 1000 && total.occluded > 10_000,
            "{total:?}"
        );
    }
    crate::simd::each_backend!(on);
}
