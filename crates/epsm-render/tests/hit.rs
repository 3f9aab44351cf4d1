//! Tests of shading points (`f32`) and of the exact `f64` hit side.

mod bvh_util;

use std::sync::Arc;

use bvh_util::{Rng, grid, object, random_scene, random_transform, soup};
use epsm_render::Ray;
use epsm_render::bvh::Accel;
use epsm_render::frame::Frame;
use epsm_render::hit::{TexCoords, intersect_triangle_f64, surface_point_f64};
use epsm_render::scene::{Mesh, Object, Surface};
use glam::{DAffine3, DVec2, DVec3, Vec2, Vec3};

#[test]
fn surface_points_are_unit_consistent_and_on_the_ray() {
    let mut rng = Rng::new(5);
    let objects = random_scene(&mut rng);
    let accel = Accel::build(&objects);
    let (lo, hi) = accel.world_bounds().expect("geometry");
    let mut checked = [0usize; 2];
    for _ in 0..3000 {
        let origin = lo + (hi - lo) * rng.dvec3(0.0, 1.0);
        let ray = Ray::new(origin.as_vec3(), rng.unit().as_vec3());
        let Some(hit) = accel.closest_hit(&ray) else {
            continue;
        };
        let object = &objects[hit.object as usize];
        let sp = accel.surface_point(&objects, &hit);
        assert!((sp.ng.length() - 1.0).abs() < 1e-5 && (sp.ns().length() - 1.0).abs() < 1e-5);
        assert!(
            sp.p.distance(ray.at(hit.t)) < 1e-4 * (1.0 + hit.t),
            "{sp:?} off the ray"
        );
        let w = object.world_from_object;
        let [p0, p1, p2] = object.mesh.triangle(hit.triangle).map(|p| p.as_dvec3());
        let mirror = w.matrix3.determinant().signum();
        if object.mesh.normals.is_empty() {
            // Mirroring flips the world winding against the mapped object normal.
            let mapped = w.matrix3.inverse().transpose() * (p1 - p0).cross(p2 - p0);
            let expected = (mirror * mapped).normalize().as_vec3();
            assert!(sp.ng.distance(expected) < 1e-4, "{sp:?} vs {expected}");
            assert_eq!(sp.ns(), sp.ng);
            assert_eq!(sp.uv.get(), Vec2::new(hit.b1, hit.b2));
            checked[0] += 1;
        } else {
            assert!(
                sp.ng.dot(sp.ns()) >= 0.0,
                "ng not in the shading hemisphere: {sp:?}"
            );
            // The grid's uvs map its x and z from [-1, 1] to [0, 1].
            let local = w.inverse().transform_point3(sp.p.as_dvec3());
            let expected = Vec2::new(local.x as f32 + 1.0, local.z as f32 + 1.0) * 0.5;
            assert!(
                sp.uv.get().distance(expected) < 1e-4,
                "uv {} vs {expected}",
                sp.uv.get()
            );
            checked[1] += 1;
        }
    }
    assert!(
        checked[0] > 100 && checked[1] > 40,
        "too few hits checked: {checked:?}"
    );
}

#[test]
fn f64_refinement_of_f32_hits_reaches_1e12() {
    let mut rng = Rng::new(9);
    let mesh = Arc::new(grid(8));
    let mut refined = 0;
    for k in 0..200 {
        let obj = object("g".into(), &mesh, random_transform(&mut rng, k % 2 == 1));
        let accel = Accel::build(std::slice::from_ref(&obj));
        let tri = rng.below(mesh.len()) as u32;
        let (b1, b2) = (rng.range(0.05, 0.5), rng.range(0.05, 0.45));
        let target = surface_point_f64(&obj, tri, b1, b2);
        let origin = target.p + rng.range(0.5, 5.0) * rng.unit();
        let dir = target.p - origin;
        let Some(hit) = accel.closest_hit(&Ray::new(origin.as_vec3(), dir.as_vec3())) else {
            continue;
        };
        if hit.triangle != tri {
            continue; // another bump of the grid is in front
        }
        assert!((hit.t - 1.0).abs() < 1e-4 && (hit.b1 as f64 - b1).abs() < 1e-3);
        let exact = intersect_triangle_f64(&obj, hit.triangle, origin, dir).expect("not parallel");
        assert!((exact.t - 1.0).abs() < 1e-12, "t = {}", exact.t);
        assert!(
            (exact.b1 - b1).abs() < 1e-12 && (exact.b2 - b2).abs() < 1e-12,
            "{exact:?} vs ({b1}, {b2})"
        );
        refined += 1;
    }
    assert!(refined > 100, "only {refined} rays reached their triangle");
}

#[test]
fn intersect_triangle_f64_reports_outside_barycentrics_and_parallel_rays() {
    let mesh = Arc::new(soup(&mut Rng::new(1), 4));
    let obj = object(
        "s".into(),
        &mesh,
        DAffine3::from_translation(DVec3::new(1.0, 2.0, 3.0)),
    );
    // Triangle 3 is a generic one (0 is a sliver, 1 and 2 are degenerate).
    let target = surface_point_f64(&obj, 3, 1.5, -0.25);
    let origin = target.p + 2.0 * target.ng;
    let hit = intersect_triangle_f64(&obj, 3, origin, target.p - origin).expect("not parallel");
    assert!(
        (hit.b1 - 1.5).abs() < 1e-12
            && (hit.b2 + 0.25).abs() < 1e-12
            && (hit.t - 1.0).abs() < 1e-12
    );
    assert!(intersect_triangle_f64(&obj, 3, origin, target.dp_db2).is_none());
}

#[test]
fn surface_derivatives_match_central_differences() {
    let mut rng = Rng::new(21);
    let mesh = Arc::new(grid(5));
    for k in 0..50 {
        let obj = object("g".into(), &mesh, random_transform(&mut rng, k % 2 == 0));
        let tri = rng.below(mesh.len()) as u32;
        let (b1, b2) = (rng.range(0.1, 0.5), rng.range(0.1, 0.4));
        let sp = surface_point_f64(&obj, tri, b1, b2);
        assert!((sp.ns.length() - 1.0).abs() < 1e-14 && (sp.ng.length() - 1.0).abs() < 1e-14);
        assert!(sp.ng.dot(sp.ns) >= 0.0);
        let h = 1e-5;
        let diff = |f: &dyn Fn(f64, f64) -> DVec3, d1: f64, d2: f64| {
            (f(b1 + h * d1, b2 + h * d2) - f(b1 - h * d1, b2 - h * d2)) / (2.0 * h)
        };
        let p = |u: f64, v: f64| surface_point_f64(&obj, tri, u, v).p;
        let ns = |u: f64, v: f64| surface_point_f64(&obj, tri, u, v).ns;
        let close = |a: DVec3, b: DVec3| (a - b).length() <= 1e-7 * (1.0 + b.length());
        assert!(close(sp.dp_db1, diff(&p, 1.0, 0.0)) && close(sp.dp_db2, diff(&p, 0.0, 1.0)));
        assert!(
            close(sp.dns_db1, diff(&ns, 1.0, 0.0)),
            "{:?} vs {:?}",
            sp.dns_db1,
            diff(&ns, 1.0, 0.0)
        );
        assert!(close(sp.dns_db2, diff(&ns, 0.0, 1.0)));
        assert!(sp.dns_db1.length() > 1e-3, "the bumpy grid's normals vary");
    }
}

#[test]
fn accel_surface_point_matches_f64_side() {
    let mut rng = Rng::new(2);
    let mesh = Arc::new(grid(4));
    let obj = object("g".into(), &mesh, random_transform(&mut rng, true));
    let accel = Accel::build(std::slice::from_ref(&obj));
    let target = surface_point_f64(&obj, 7, 0.3, 0.3);
    let origin = target.p + 3.0 * target.ng;
    let hit = accel
        .closest_hit(&Ray::new(origin.as_vec3(), (target.p - origin).as_vec3()))
        .expect("hit");
    let sp = accel.surface_point(std::slice::from_ref(&obj), &hit);
    let exact = surface_point_f64(&obj, hit.triangle, hit.b1 as f64, hit.b2 as f64);
    let near = |a: Vec3, b: DVec3| a.as_dvec3().distance(b) < 1e-5;
    assert!(
        near(sp.p, exact.p) && near(sp.ng, exact.ng) && near(sp.ns(), exact.ns),
        "{sp:?} vs {exact:?}"
    );
}

/// Static objects shade from the static BVH's table, instances from their
/// cached placement: the same hits give the same shading points either way,
/// also for hits kept across the rebuild that made half the objects dynamic
/// (their table indices are stale then and must not be used).
#[test]
fn static_table_and_instance_placement_agree() {
    let mut rng = Rng::new(11);
    let objects = random_scene(&mut rng);
    let statics = Accel::build(&objects);
    let mut mixed = statics.clone();
    let even: Vec<u32> = (0..objects.len() as u32).step_by(2).collect();
    mixed.update_instances(&objects, &even);
    let (lo, hi) = statics.world_bounds().expect("geometry");
    let mut checked = 0;
    for _ in 0..3000 {
        let origin = lo + (hi - lo) * rng.dvec3(0.0, 1.0);
        let ray = Ray::new(origin.as_vec3(), rng.unit().as_vec3());
        let Some(hit) = statics.closest_hit(&ray) else {
            continue;
        };
        let a = statics.surface_point(&objects, &hit);
        let b = mixed.surface_point(&objects, &hit);
        // Each path's frame is the one made from its shading normal.
        assert_eq!(a.frame, Frame::from_normal(a.ns()));
        assert_eq!(b.frame, Frame::from_normal(b.ns()));
        assert!(
            a.p.distance(b.p) < 1e-4 * (1.0 + hit.t)
                && a.ng.distance(b.ng) < 1e-4
                && a.ns().distance(b.ns()) < 1e-4
                && a.uv.get().distance(b.uv.get()) < 1e-5,
            "{a:?} vs {b:?}"
        );
        checked += 1;
    }
    assert!(checked > 500, "{checked} hits");
}

/// On an exact sphere the shading point's texture coordinates are pbrt-v4's
/// spherical coordinates of the object-space hit point, made only when read
/// (a triangle's are known when the point is made).
#[test]
fn exact_sphere_texture_coordinates_are_spherical_and_lazy() {
    let mut rng = Rng::new(41);
    let objects: Vec<Object> = (0..3)
        .map(|i| Object {
            name: format!("s{i}"),
            mesh: Arc::new(Mesh::default()),
            world_from_object: random_transform(&mut rng, i == 1),
            material: 0,
            emission: None,
            surface: Surface::Sphere,
        })
        .collect();
    let accel = Accel::build(&objects);
    let mut checked = 0;
    for _ in 0..2000 {
        let origin = rng.dvec3(-4.0, 4.0).as_vec3();
        let ray = Ray::new(origin, rng.unit().as_vec3());
        let Some(hit) = accel.closest_hit(&ray) else {
            continue;
        };
        let sp = accel.surface_point(&objects, &hit);
        let TexCoords::Sphere(local) = sp.uv else {
            panic!("{:?} on a sphere", sp.uv);
        };
        let w = objects[hit.object as usize].world_from_object;
        let p = w.inverse().transform_point3(sp.p.as_dvec3()).normalize();
        assert!(local.as_dvec3().distance(p) < 1e-4, "{local} vs {p}");
        let phi = p.y.atan2(p.x).rem_euclid(std::f64::consts::TAU);
        let expected = DVec2::new(
            phi / std::f64::consts::TAU,
            p.z.acos() / std::f64::consts::PI,
        );
        let uv = sp.uv.get().as_dvec2();
        // `u` wraps at φ = 0.
        let du = (uv.x - expected.x).abs();
        assert!(
            du.min(1.0 - du) < 1e-4 && (uv.y - expected.y).abs() < 1e-4,
            "uv {uv} vs {expected}"
        );
        checked += 1;
    }
    assert!(checked > 200, "{checked} hits");
}
