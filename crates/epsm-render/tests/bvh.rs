//! Tests of the two-level BVH against brute force, and of the `f64` hit side.

mod bvh_util;

use std::sync::Arc;

use bvh_util::{Rng, object, random_scene, random_transform};
use epsm_render::Ray;
use epsm_render::bvh::Accel;
use epsm_render::hit::{Hit, intersect_triangle_f64, surface_point_f64};
use epsm_render::scene::{Mesh, Object, Surface};
use epsm_render::sphere;
use glam::{DAffine3, DVec3, Vec3};

/// What brute force in `f64` says about a ray: the closest hit that is
/// certainly inside its triangle and `t` range (`strict`), and the closest
/// hit within tolerance of them (`loose`), as `(t, object, triangle, tol)`.
#[derive(Default)]
struct Reference {
    strict: Option<(f64, u32, u32)>,
    loose: Option<(f64, f64)>,
}

/// Margin (world distance to the triangle's edges, in units of the scene's
/// size `unit`) below which a hit counts as a tie `f32` may decide either way.
const MARGIN: f64 = 2e-5;

/// Tolerance on `t` of a hit at `t` with `|cos|` between ray and normal, for
/// a ray direction of length `dir_len` in a scene of size `unit`.
fn t_tol(t: f64, cos: f64, dir_len: f64, unit: f64) -> f64 {
    1e-5 * (t.abs() + unit / dir_len) / cos.max(1e-3)
}

/// The `f64` ray test of one triangle: `(t, min edge distance, |cos|)`.
fn reference_hit(object: &Object, tri: u32, o: DVec3, d: DVec3) -> Option<(f64, f64, f64)> {
    let h = intersect_triangle_f64(object, tri, o, d)?;
    let sp = surface_point_f64(object, tri, h.b1, h.b2);
    let area2 = sp.dp_db1.cross(sp.dp_db2).length();
    let edges = [sp.dp_db2 - sp.dp_db1, sp.dp_db2, sp.dp_db1].map(|e| area2 / e.length());
    let bary = [1.0 - h.b1 - h.b2, h.b1, h.b2];
    let margin = (0..3)
        .map(|k| bary[k] * edges[k])
        .fold(f64::INFINITY, f64::min);
    let cos = (d.normalize().dot(sp.dp_db1.cross(sp.dp_db2) / area2)).abs();
    (area2 > 0.0).then_some((h.t, margin, cos))
}

/// The `f64` roots of an exact sphere object along the world ray
/// `o + t·d`, each as `(t, margin, |cos|)` like [`reference_hit`] (a sphere
/// has no edges: the margin is infinite).
fn sphere_roots(object: &Object, o: DVec3, d: DVec3) -> Vec<(f64, f64, f64)> {
    let to_object = object.world_from_object.inverse();
    let (lo, ld) = (
        to_object.transform_point3(o),
        to_object.transform_vector3(d),
    );
    let (a, b, c) = (ld.length_squared(), lo.dot(ld), lo.length_squared() - 1.0);
    let disc = b * b - a * c;
    if !(disc >= 0.0 && a > 0.0) {
        return Vec::new();
    }
    let normal_from_object = to_object.matrix3.transpose();
    [-1.0, 1.0]
        .map(|sign| (-b + sign * disc.sqrt()) / a)
        .into_iter()
        .map(|t| {
            let n = (normal_from_object * (lo + ld * t)).normalize();
            (t, f64::INFINITY, d.normalize().dot(n).abs())
        })
        .collect()
}

/// Every `f64` candidate hit of `object` along `o + t·d`: `(t, margin,
/// |cos|, triangle)`.
fn candidates(object: &Object, o: DVec3, d: DVec3) -> Vec<(f64, f64, f64, u32)> {
    match object.surface {
        Surface::Sphere => sphere_roots(object, o, d)
            .into_iter()
            .map(|(t, m, c)| (t, m, c, 0))
            .collect(),
        Surface::Mesh => (0..object.mesh.len() as u32)
            .filter_map(|tri| reference_hit(object, tri, o, d).map(|(t, m, c)| (t, m, c, tri)))
            .collect(),
    }
}

fn brute_force(objects: &[Object], ray: &Ray, unit: f64) -> Reference {
    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
    let (t_min, t_max) = (ray.t_min as f64, ray.t_max as f64);
    let mut r = Reference::default();
    for (id, object) in objects.iter().enumerate() {
        for (t, margin, cos, tri) in candidates(object, o, d) {
            let tol = t_tol(t, cos, d.length(), unit);
            if margin >= -MARGIN * unit
                && t >= t_min - tol
                && t <= t_max + tol
                && r.loose.is_none_or(|l| t < l.0)
            {
                r.loose = Some((t, tol));
            }
            let certain =
                margin >= MARGIN * unit && cos > 1e-2 && t >= t_min + tol && t <= t_max - tol;
            if certain && r.strict.is_none_or(|s| t < s.0) {
                r.strict = Some((t, id as u32, tri));
            }
        }
    }
    r
}

/// Random rays: origins inside and outside the scene, random directions
/// (a third with zeroed components or axis-aligned), some with `t` limits
/// and non-unit directions.
fn random_ray(rng: &mut Rng, lo: DVec3, hi: DVec3) -> Ray {
    let centre = 0.5 * (lo + hi);
    let radius = 0.5 * (hi - lo).length();
    let inside = lo + (hi - lo) * rng.dvec3(0.0, 1.0);
    let (origin, mut dir) = if rng.below(2) == 0 {
        (inside, rng.unit())
    } else {
        let o = centre + 2.0 * radius * rng.unit();
        (o, (inside - o).normalize())
    };
    match rng.below(6) {
        0 => dir[rng.below(3)] = 0.0,
        1 => {
            let keep = rng.below(3);
            dir = DVec3::ZERO;
            dir[keep] = if rng.below(2) == 0 { 1.0 } else { -1.0 };
        }
        _ => {}
    }
    let mut ray = Ray::new(origin.as_vec3(), (dir * rng.range(0.3, 3.0)).as_vec3());
    if rng.below(4) == 0 {
        ray.t_min = rng.range(0.0, radius) as f32;
        ray.t_max = ray.t_min + rng.range(0.0, 2.0 * radius) as f32;
    }
    ray
}

/// Checks `closest_hit` and `occluded` against brute force on `n` rays;
/// returns the number of rays with a certain hit.
fn check_against_brute_force(rng: &mut Rng, objects: &[Object], accel: &Accel, n: usize) -> usize {
    let (lo, hi) = accel.world_bounds().expect("scene has geometry");
    let unit = (hi - lo).max_element() / 4.0;
    let (mut certain, mut exact, mut hits) = (0, 0, 0);
    for i in 0..n {
        let ray = random_ray(rng, lo, hi);
        let reference = brute_force(objects, &ray, unit);
        let hit = accel.closest_hit(&ray);
        assert_eq!(
            accel.occluded(&ray),
            hit.is_some(),
            "ray {i}: occluded disagrees with closest_hit: {ray:?}"
        );
        if let Some((t, object, triangle)) = reference.strict {
            certain += 1;
            let h =
                hit.unwrap_or_else(|| panic!("ray {i}: missed certain hit at t = {t}: {ray:?}"));
            let tol = t_tol(t, 1.0, ray.dir.as_dvec3().length(), unit);
            assert!(
                (h.t as f64) <= t + tol,
                "ray {i}: hit {h:?} beyond certain t = {t}"
            );
            exact += usize::from(h.object == object && h.triangle == triangle);
        }
        if let Some(h) = hit {
            hits += 1;
            verify_hit(objects, &ray, &h, unit, i);
            let (t_loose, tol) = reference
                .loose
                .expect("a hit must be a loose reference hit");
            assert!(
                (h.t as f64) >= t_loose - tol,
                "ray {i}: hit {h:?} before closest t = {t_loose}"
            );
        }
    }
    eprintln!("{n} rays: {hits} hits, {certain} certain, {exact} exact");
    assert!(
        exact * 100 >= certain * 98,
        "{exact} of {certain} certain hits on the same triangle"
    );
    certain
}

/// The reported triangle (or sphere) is really hit at the reported `t` and
/// local coordinates.
fn verify_hit(objects: &[Object], ray: &Ray, h: &Hit, unit: f64, i: usize) {
    let object = &objects[h.object as usize];
    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
    let (t, margin, cos) = match object.surface {
        Surface::Mesh => {
            reference_hit(object, h.triangle, o, d).expect("reported triangle is hittable")
        }
        Surface::Sphere => {
            // The root nearest the reported `t`, and the point the local
            // coordinates name on the ray there.
            let root = sphere_roots(object, o, d)
                .into_iter()
                .min_by(|a, b| {
                    (a.0 - h.t as f64)
                        .abs()
                        .total_cmp(&(b.0 - h.t as f64).abs())
                })
                .expect("reported sphere is hit");
            let at = object
                .world_from_object
                .transform_point3(sphere::point([h.b1 as f64, h.b2 as f64]));
            let tol = t_tol(root.0, root.2, d.length(), unit) * d.length();
            assert!(
                at.distance(o + d * root.0) <= tol + 1e-6 * unit,
                "ray {i}: {h:?}: local coordinates name {at}, not the hit"
            );
            root
        }
    };
    let tol = t_tol(t, cos, d.length(), unit);
    assert!(
        margin >= -MARGIN * unit,
        "ray {i}: {h:?} lies outside its triangle by {margin}"
    );
    assert!(
        (h.t as f64 - t).abs() <= tol,
        "ray {i}: {h:?} t differs from f64 t = {t}"
    );
    assert!(h.b1.is_finite() && h.b2.is_finite() && h.t >= ray.t_min && h.t <= ray.t_max);
}

#[test]
fn random_scenes_match_brute_force() {
    let mut rng = Rng::new(7);
    let mut certain = 0;
    for round in 0..4 {
        let objects = random_scene(&mut rng);
        // Everything static (one world-space BVH), or a mix with instances.
        let dynamic: &[u32] = if round % 2 == 0 { &[] } else { &[0, 2, 3] };
        let accel = Accel::build_with_dynamic(&objects, dynamic);
        certain += check_against_brute_force(&mut rng, &objects, &accel, 2000);
    }
    eprintln!("certain hits: {certain}");
    assert!(
        certain > 1000,
        "too few certain hits to be a test: {certain}"
    );
}

/// An exact sphere object placed by `world_from_object`.
fn exact_sphere(name: String, world_from_object: DAffine3) -> Object {
    Object {
        name,
        mesh: Arc::new(Mesh::default()),
        world_from_object,
        material: 0,
        emission: None,
        surface: Surface::Sphere,
    }
}

#[test]
fn scenes_with_exact_spheres_match_brute_force_listed_instanced_and_moved() {
    let mut rng = Rng::new(29);
    let mut certain = 0;
    // Two spheres are listed (tested one by one beside the static walk), seven
    // go behind the top level; both static and dynamic, some mirrored.
    for (round, spheres) in [2, 7, 2, 7].into_iter().enumerate() {
        let mut objects = random_scene(&mut rng);
        let first = objects.len() as u32;
        for k in 0..spheres {
            let w = random_transform(&mut rng, k % 3 == 1);
            objects.push(exact_sphere(format!("s{k}"), w));
        }
        let dynamic: Vec<u32> = if round < 2 {
            vec![]
        } else {
            vec![0, first, first + 1]
        };
        let mut accel = Accel::build_with_dynamic(&objects, &dynamic);
        assert_eq!(accel.stats().spheres, spheres);
        certain += check_against_brute_force(&mut rng, &objects, &accel, 1500);
        for id in [first, first + 1] {
            objects[id as usize].world_from_object = random_transform(&mut rng, false);
            accel.update_instance(&objects, id);
        }
        certain += check_against_brute_force(&mut rng, &objects, &accel, 1000);
    }
    assert!(
        certain > 2000,
        "too few certain hits to be a test: {certain}"
    );
}

#[test]
fn tiny_and_huge_scenes_match_brute_force() {
    // Scaled by 1e-4 the whole scene is closer than obvhs's fixed 1e-4 slab
    // clamp; scaled by 1e4 coordinates are large.
    let mut rng = Rng::new(13);
    for scale in [1e-4, 1e4] {
        let mut objects = random_scene(&mut rng);
        for o in &mut objects {
            o.world_from_object = DAffine3::from_scale(DVec3::splat(scale)) * o.world_from_object;
        }
        let accel = Accel::build(&objects);
        assert!(check_against_brute_force(&mut rng, &objects, &accel, 1500) > 150);
    }
}

#[test]
fn moved_instances_match_brute_force_without_new_blas() {
    let mut rng = Rng::new(11);
    let mut objects = random_scene(&mut rng);
    let mut accel = Accel::build_with_dynamic(&objects, &[0, 2, 4, 5]);
    let before = accel.stats();
    for round in 0..4 {
        let ids = [0, 2, 4 + round % 2];
        for id in ids {
            objects[id].world_from_object = random_transform(&mut rng, round == 1);
            if round < 3 {
                accel.update_instance(&objects, id as u32);
            }
        }
        if round == 3 {
            accel.update_instances(&objects, &ids.map(|id| id as u32));
        }
        check_against_brute_force(&mut rng, &objects, &accel, 800);
    }
    let after = accel.stats();
    assert_eq!(
        (after.blas_count, after.triangles),
        (before.blas_count, before.triangles)
    );
    assert_eq!(
        (after.build_seconds, after.static_seconds),
        (before.build_seconds, before.static_seconds),
        "update must not rebuild"
    );
}

#[test]
fn moving_static_objects_makes_them_dynamic() {
    let mut rng = Rng::new(23);
    let mut objects = random_scene(&mut rng);
    let mut accel = Accel::build(&objects);
    let before = accel.stats();
    // Object 3 (soup(20)) and object 1 (a grid shared with object 4) start static.
    for id in [3, 1] {
        objects[id].world_from_object = random_transform(&mut rng, false);
        accel.update_instance(&objects, id as u32);
        check_against_brute_force(&mut rng, &objects, &accel, 600);
    }
    let after = accel.stats();
    assert_eq!(after.blas_count, before.blas_count + 2);
    assert_eq!(after.triangles, before.triangles);
    assert_eq!(after.degenerate_triangles, before.degenerate_triangles);
    // Moving again touches no bottom level.
    objects[3].world_from_object = random_transform(&mut rng, true);
    accel.update_instance(&objects, 3);
    assert_eq!(accel.stats().static_seconds, after.static_seconds);
    check_against_brute_force(&mut rng, &objects, &accel, 600);
}

#[test]
fn shared_meshes_share_blas_and_empty_meshes_are_skipped() {
    let mut rng = Rng::new(3);
    let objects = random_scene(&mut rng);
    // All dynamic: one BVH per distinct mesh.
    let stats = Accel::build_with_dynamic(&objects, &[0, 1, 2, 3, 4, 5, 6]).stats();
    assert_eq!(stats.blas_count, 3);
    assert_eq!(stats.objects, 6);
    // soup(200) and soup(20) have 50 and 6 repeated-vertex or collinear triangles.
    assert_eq!(stats.degenerate_triangles, 56);
    assert_eq!(stats.triangles, 200 + 20 + 72 - 56);
    assert!(stats.bytes > 0);
    // All static: one world-space BVH with every object's triangles.
    let stats = Accel::build(&objects).stats();
    assert_eq!(stats.blas_count, 1);
    assert_eq!(stats.degenerate_triangles, 3 * 50 + 6);
    assert_eq!(stats.triangles, 3 * 200 + 20 + 2 * 72 - 3 * 50 - 6);
    // Copies of a large shared mesh stay instanced, static or not.
    let big = Arc::new(bvh_util::cube_sphere(6));
    let copies: Vec<Object> = (0..2)
        .map(|k| object(format!("c{k}"), &big, random_transform(&mut rng, false)))
        .collect();
    let stats = Accel::build(&copies).stats();
    assert_eq!((stats.blas_count, stats.triangles), (1, big.len()));
    assert!(stats.bytes > 0);
    let empty = Accel::build(&[object(
        "e".into(),
        &Arc::new(Mesh::default()),
        DAffine3::IDENTITY,
    )]);
    assert!(empty.world_bounds().is_none());
    assert!(empty.closest_hit(&Ray::new(Vec3::ZERO, Vec3::X)).is_none());
    assert!(!empty.occluded(&Ray::new(Vec3::ZERO, Vec3::X)));
}

#[test]
fn closed_mesh_has_no_leaks_at_edges_and_vertices() {
    let mut rng = Rng::new(17);
    let mesh = Arc::new(bvh_util::cube_sphere(6));
    let obj = object("s".into(), &mesh, random_transform(&mut rng, false));
    let accel = Accel::build(std::slice::from_ref(&obj));
    let w = obj.world_from_object;
    let mut leaks = 0;
    for k in 0..20_000 {
        // Aim at a vertex or at a point on an edge, from inside or from far
        // outside (then only at points facing the origin, away from the
        // silhouette the rounded ray could legitimately pass).
        let [a, b, _] =
            mesh.indices[rng.below(mesh.len())].map(|i| mesh.positions[i as usize].as_dvec3());
        let target = if k % 2 == 0 {
            a
        } else {
            a + (b - a) * rng.f64()
        };
        let local_origin = if k % 3 == 0 {
            let o = rng.range(10.0, 1000.0) * rng.unit();
            if (o - target).normalize().dot(target.normalize()) < 0.5 {
                continue;
            }
            o
        } else {
            0.5 * rng.dvec3(-0.5, 0.5)
        };
        let origin = w.transform_point3(local_origin);
        let ray = Ray::new(
            origin.as_vec3(),
            (w.transform_point3(target) - origin).as_vec3(),
        );
        leaks += usize::from(accel.closest_hit(&ray).is_none());
    }
    assert_eq!(leaks, 0, "rays escaped through edges or vertices");
}

#[test]
fn degenerate_rays_never_hit() {
    let mut rng = Rng::new(19);
    let objects = random_scene(&mut rng);
    let accel = Accel::build(&objects);
    let (lo, hi) = accel.world_bounds().expect("geometry");
    let centre = (0.5 * (lo + hi)).as_vec3();
    for ray in [
        Ray::new(centre, Vec3::ZERO),
        Ray::new(Vec3::splat(f32::NAN), Vec3::X),
        Ray::new(centre, Vec3::new(f32::NAN, 1.0, 0.0)),
        Ray {
            t_min: 2.0,
            t_max: 1.0,
            ..Ray::new(centre, Vec3::Y)
        },
    ] {
        assert_eq!(accel.closest_hit(&ray), None, "{ray:?}");
        assert!(!accel.occluded(&ray), "{ray:?}");
    }
}
