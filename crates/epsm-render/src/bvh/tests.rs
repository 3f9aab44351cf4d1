//! The BVH's own checks: spheres listed first or after, AVX and portable
//! box tests, and the exact-sphere miss test.

use super::trace::exact_sphere_hit;
use super::*;
#[cfg(target_arch = "x86_64")]
use crate::bvh::Avx;
use crate::ray::Ray;
use crate::sphere;
use epsm_testkit::Rng;
use glam::{DAffine3, DQuat};

/// A triangle soup of `count` triangles in `[-1, 1]³`.
fn soup(rng: &mut Rng, count: usize) -> Arc<Mesh> {
    let mut mesh = Mesh::default();
    for _ in 0..count {
        let a = rng.dvec3(-1.0, 1.0).as_vec3();
        let base = mesh.positions.len() as u32;
        mesh.positions.extend([
            a,
            a + rng.dvec3(-0.4, 0.4).as_vec3(),
            a + rng.dvec3(-0.4, 0.4).as_vec3(),
        ]);
        mesh.indices.push([base, base + 1, base + 2]);
    }
    Arc::new(mesh)
}

/// An object of `mesh` (empty for a sphere) and `surface`, scaled by
/// `scale`, then rotated about a random axis and moved into `[-2, 2]³`.
fn placed(rng: &mut Rng, mesh: Arc<Mesh>, surface: Surface, scale: DVec3) -> Object {
    Object {
        name: "placed".into(),
        mesh,
        world_from_object: DAffine3::from_scale_rotation_translation(
            scale,
            DQuat::from_axis_angle(rng.unit(), rng.range(0.0, 6.0)),
            rng.dvec3(-2.0, 2.0),
        ),
        material: 0,
        emission: None,
        surface,
    }
}

/// Listed spheres tested first ([`SpheresFirst`]) or after the static
/// walk give the same closest hit and the same occlusion, with portable
/// and (when the CPU has it) AVX tests, on scenes with static and
/// dynamic meshes and spheres, one of them mirrored.
#[test]
fn spheres_first_and_after_find_the_same_hits() {
    let mut rng = Rng::new(23);
    let (big, small) = (soup(&mut rng, 2000), soup(&mut rng, 40));
    let mut objects: Vec<Object> = (0..4)
        .map(|i| {
            let mesh = Arc::clone(if i % 2 == 0 { &big } else { &small });
            let scale = rng.dvec3(0.3, 1.5);
            placed(&mut rng, mesh, Surface::Mesh, scale)
        })
        .collect();
    for i in 0..MAX_LISTED_SPHERES {
        let mut scale = rng.dvec3(0.7, 1.5);
        if i == 1 {
            scale.y = -scale.y;
        }
        let sphere = placed(&mut rng, Arc::default(), Surface::Sphere, scale);
        objects.push(sphere);
    }
    let first = SpheresFirst(Portable);
    #[cfg(target_arch = "x86_64")]
    let avx = Avx::detect().map(|avx| (avx, SpheresFirst(avx)));
    for dynamic in [&[][..], &[1, 5]] {
        let accel = Accel::build_with_dynamic(&objects, dynamic);
        assert!(accel.lists_spheres());
        let mut on_spheres = 0;
        for i in 0..20_000 {
            let origin = rng.dvec3(-4.0, 4.0).as_vec3();
            let mut ray = Ray::new(origin, rng.unit().as_vec3() * rng.range(0.5, 2.0) as f32);
            if i % 3 == 0 {
                ray.t_max = rng.range(0.0, 4.0) as f32;
            }
            let after = accel.trace::<false>(&ray, Portable);
            let occluded = accel.trace::<true>(&ray, Portable).is_some();
            assert_eq!(accel.trace::<false>(&ray, first), after, "ray {i}: {ray:?}");
            assert_eq!(accel.trace::<true>(&ray, first).is_some(), occluded);
            assert_eq!(occluded, after.is_some());
            #[cfg(target_arch = "x86_64")]
            if let Some((avx, avx_first)) = avx {
                assert_eq!(accel.trace::<false>(&ray, avx), after, "ray {i}");
                assert_eq!(accel.trace::<false>(&ray, avx_first), after, "ray {i}");
                assert_eq!(accel.trace::<true>(&ray, avx).is_some(), occluded);
                assert_eq!(accel.trace::<true>(&ray, avx_first).is_some(), occluded);
            }
            on_spheres += usize::from(after.is_some_and(|h| h.object >= 4));
        }
        assert!(on_spheres > 500, "{on_spheres} sphere hits");
    }
}

/// The AVX box tests (when the CPU has AVX) find exactly the hits of the
/// portable ones, through the static BVH and through instances.
#[test]
fn avx_and_portable_box_tests_agree() {
    // Without AVX, the portable tests against themselves: the walk's hit
    // counts are still checked.
    #[cfg(target_arch = "x86_64")]
    match Avx::detect() {
        Some(avx) => box_tests_agree(avx),
        None => box_tests_agree(Portable),
    }
    #[cfg(not(target_arch = "x86_64"))]
    box_tests_agree(Portable);
}

/// [`avx_and_portable_box_tests_agree`] with the box tests `avx`.
fn box_tests_agree(avx: impl BoxTest) {
    let mut rng = Rng::new(17);
    let (big, small) = (soup(&mut rng, 3000), soup(&mut rng, 50));
    let objects: Vec<Object> = (0..6)
        .map(|i| {
            let mesh = Arc::clone(if i % 2 == 0 { &big } else { &small });
            let scale = rng.dvec3(0.3, 2.0);
            placed(&mut rng, mesh, Surface::Mesh, scale)
        })
        .collect();
    let accel = Accel::build_with_dynamic(&objects, &[1, 4]);
    let (mut hits, mut occluded) = (0, 0);
    for i in 0..20_000 {
        let origin = rng.dvec3(-4.0, 4.0).as_vec3();
        let mut dir = rng.unit().as_vec3();
        if i % 5 == 0 {
            dir[rng.below(3)] = 0.0;
        }
        let mut ray = Ray::new(origin, dir * rng.range(0.5, 2.0) as f32);
        if i % 3 == 0 {
            ray.t_max = rng.range(0.0, 4.0) as f32;
        }
        let portable = accel.trace::<false>(&ray, Portable);
        assert_eq!(
            accel.trace::<false>(&ray, avx),
            portable,
            "ray {i}: {ray:?}"
        );
        let any = accel.trace::<true>(&ray, Portable).is_some();
        assert_eq!(accel.trace::<true>(&ray, avx).is_some(), any);
        assert_eq!(any, portable.is_some());
        hits += usize::from(portable.is_some());
        occluded += usize::from(any);
    }
    assert!(hits > 2000 && occluded == hits, "{hits} hits");
}

/// A random placement of the unit sphere: a rotation, a scale (uniform,
/// 0.003 to 10, or per axis up to 25 : 1 with some axes mirrored) and a
/// translation of up to `reach` per axis.
fn sphere_placement(rng: &mut Rng, uniform: bool, reach: f64) -> DAffine3 {
    let scale = if uniform {
        DVec3::splat(10f64.powf(rng.range(-2.5, 1.0)))
    } else {
        rng.dvec3(0.2, 5.0) * DVec3::new(1.0, if rng.below(3) == 0 { -1.0 } else { 1.0 }, 1.0)
    };
    DAffine3::from_scale_rotation_translation(
        scale,
        DQuat::from_axis_angle(rng.unit(), rng.range(0.0, 6.3)),
        rng.dvec3(-reach, reach),
    )
}

/// A world-space ray whose line passes at object-space distance
/// `1 + gap` from the centre of the sphere placed by `w`, its origin
/// `back` units (object space) before the closest point, and its
/// direction of random length.
fn ray_at_distance(rng: &mut Rng, w: &DAffine3, gap: f64, back: f64) -> (Vec3A, Vec3A) {
    let q = rng.unit();
    let u = q.cross(rng.unit()).normalize();
    let origin = w.transform_point3(q * (1.0 + gap) - u * back);
    let dir = w.transform_vector3(u) * rng.range(0.1, 10.0);
    (origin.as_vec3a(), dir.as_vec3a())
}

/// The miss test of a placed sphere never rejects a ray the exact test
/// (the ray mapped to object space in `f32`, solved in `f64`) hits:
/// rays grazing the surface (in or out by 10⁻⁸ to 1 % of the radius,
/// where the `f32` mapping decides) from near and far (up to 10⁴
/// object-space units), on uniform and skewed, mirrored placements up to
/// 10³ from the origin, and random rays.
#[test]
fn sphere_miss_test_never_rejects_a_hit() {
    let mut rng = Rng::new(41);
    let (mut grazing_hits, mut rejected) = (0, 0);
    for i in 0..400 {
        let w = sphere_placement(&mut rng, i % 2 == 0, if i % 4 < 2 { 1e3 } else { 2.0 });
        let placement = hit::Placement::new(&w).expect("invertible");
        for j in 0..200 {
            let (origin, dir) = if j % 4 == 0 {
                let origin = w.translation + rng.dvec3(-8.0, 8.0) * w.matrix3.x_axis.length();
                (origin.as_vec3a(), rng.unit().as_vec3a())
            } else {
                let sign = if rng.below(2) == 0 { -1.0 } else { 1.0 };
                let gap = sign * 10f64.powf(rng.range(-8.0, -2.0));
                let back = 10f64.powf(rng.range(-1.0, 4.0));
                ray_at_distance(&mut rng, &w, gap, back)
            };
            let exact = exact_sphere_hit(&placement, origin, dir, 0.0, f32::INFINITY).is_some();
            let misses = placement.sphere.misses(origin, dir);
            assert!(!(exact && misses), "{w:?}: {origin} {dir}");
            grazing_hits += usize::from(exact && j % 4 != 0);
            rejected += usize::from(misses);
        }
    }
    assert!(
        grazing_hits > 10_000 && rejected > 5_000,
        "{grazing_hits} grazing hits, {rejected} rejected"
    );
}

/// On rotated, uniformly scaled spheres near the origin (within 1 per
/// axis), the miss test
/// rejects every ray that passes 1 % of the radius or more outside,
/// from up to ten radii away; the identity's test is
/// [`MissTest::UNIT`](sphere::MissTest::UNIT).
#[test]
fn sphere_miss_test_rejects_clear_misses() {
    let mut rng = Rng::new(43);
    for _ in 0..200 {
        let w = sphere_placement(&mut rng, true, 1.0);
        let placement = hit::Placement::new(&w).expect("invertible");
        for _ in 0..200 {
            let (gap, back) = (10f64.powf(rng.range(-2.0, 1.0)), rng.range(0.0, 10.0));
            let (origin, dir) = ray_at_distance(&mut rng, &w, gap, back);
            assert!(
                placement.sphere.misses(origin, dir),
                "{w:?}: {origin} {dir}"
            );
        }
    }
    assert_eq!(
        sphere::MissTest::new(&DAffine3::IDENTITY),
        sphere::MissTest::UNIT
    );
}
