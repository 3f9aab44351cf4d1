//! Light tests: pdf consistency for MIS, irradiance against closed forms,
//! power-proportional selection and environment-map sampling.

use std::f64::consts::PI;
use std::sync::Arc;

use glam::{DAffine3, DMat3, DVec3, Vec2, Vec3};

use super::*;
use crate::film::Image;
use crate::materials::test_support::{
    Rng, assert_chi2, expected_counts, histogram, integrate_sphere,
};
use crate::scene::{Mesh, Object, Surface};

/// The unit square `[−½, ½]²` in the object xy plane, front face `+z`.
fn square_mesh() -> Arc<Mesh> {
    Arc::new(Mesh {
        positions: vec![
            Vec3::new(-0.5, -0.5, 0.0),
            Vec3::new(0.5, -0.5, 0.0),
            Vec3::new(0.5, 0.5, 0.0),
            Vec3::new(-0.5, 0.5, 0.0),
        ],
        normals: Vec::new(),
        uvs: Vec::new(),
        indices: vec![[0, 1, 2], [0, 2, 3]],
    })
}

fn emitter(world_from_object: DAffine3, emission: Vec3) -> Object {
    Object {
        name: "light".into(),
        mesh: square_mesh(),
        world_from_object,
        material: 0,
        emission: Some(emission),
        surface: Surface::Mesh,
    }
}

fn black() -> Background {
    Background::Constant(Vec3::ZERO)
}

/// Irradiance factor `∫ cos θr cos θl / d² dA` at a point under the corner of
/// an `a × b` rectangle parallel to the receiver at height `h`
/// (the point-to-rectangle form factor times π).
fn corner_rectangle(a: f64, b: f64, h: f64) -> f64 {
    let (x, y) = (a / h, b / h);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    0.5 * (x / sx * (y / sx).atan() + y / sy * (x / sy).atan())
}

#[test]
fn square_light_irradiance_matches_the_form_factor() {
    // A square of side s at height h facing down (−y), centred over the origin.
    let (s, h) = (0.3, 1.0);
    let to_world = DAffine3::from_translation(DVec3::new(0.0, h, 0.0))
        * DAffine3::from_mat3(
            DMat3::from_rotation_x(PI / 2.0) * DMat3::from_diagonal(DVec3::splat(s)),
        );
    let radiance = Vec3::new(2.0, 1.0, 0.5);
    let table = LightTable::build(&[emitter(to_world, radiance)], &[], &black(), None);
    let exact = 4.0 * corner_rectangle(s / 2.0, s / 2.0, h);
    let mut rng = Rng::new(11);
    let n = 40_000;
    let mut sum = 0.0f64;
    for _ in 0..n {
        let ls = table
            .sample(Vec3::ZERO, rng.f32(), rng.vec2())
            .expect("the receiver faces the light");
        assert_eq!(ls.radiance, radiance);
        sum += (ls.radiance.x * ls.wo.y / ls.pdf) as f64;
    }
    let estimate = sum / n as f64 / radiance.x as f64;
    assert!(
        ((estimate - exact) / exact).abs() < 0.01,
        "{estimate} vs {exact}"
    );
    // Behind the light nothing is emitted.
    let behind = Vec3::new(0.0, 2.0, 0.0);
    assert!(table.sample(behind, 0.3, Vec2::new(0.4, 0.6)).is_none());
}

#[test]
fn area_and_background_sample_pdfs_equal_the_mis_pdfs() {
    // A mirroring transform (negative determinant) flips the emitting side.
    let mirror = DAffine3::from_translation(DVec3::new(0.3, 1.0, -0.2))
        * DAffine3::from_mat3(
            DMat3::from_diagonal(DVec3::new(1.0, -2.0, 0.5)) * DMat3::from_rotation_x(1.2),
        );
    let objects = [
        emitter(
            DAffine3::from_translation(DVec3::new(0.0, 0.0, 2.0)),
            Vec3::ONE,
        ),
        emitter(mirror, Vec3::new(3.0, 2.0, 1.0)),
    ];
    let point = PointLight {
        name: "p".into(),
        position: DVec3::new(1.0, 1.0, 1.0),
        intensity: Vec3::splat(2.0),
    };
    let table = LightTable::build(
        &objects,
        &[point],
        &Background::Constant(Vec3::splat(0.2)),
        None,
    );
    let mut rng = Rng::new(12);
    let mut kinds = [0usize; 3];
    for _ in 0..20_000 {
        let p = rng.sphere() * 0.5;
        let Some(ls) = table.sample(p, rng.f32(), rng.vec2()) else {
            continue;
        };
        assert!(ls.pdf > 0.0 && ls.pdf.is_finite());
        match ls.source {
            LightPoint::Area {
                object,
                triangle,
                b1,
                b2,
            } => {
                kinds[0] += 1;
                let o = &objects[object as usize];
                let [p0, p1, p2] = o
                    .mesh
                    .triangle(triangle)
                    .map(|v| o.world_from_object.transform_point3(v.as_dvec3()));
                let y = p0 + b1 as f64 * (p1 - p0) + b2 as f64 * (p2 - p0);
                assert!(y.as_vec3().distance(ls.position) < 1e-5);
                let n = (p1 - p0).cross(p2 - p0).normalize().as_vec3();
                assert!(
                    n.distance(ls.normal) < 1e-5,
                    "normal follows the world winding"
                );
                assert!(
                    n.dot(p - ls.position) > 0.0,
                    "emits from the front face only"
                );
                assert!(ls.position.distance(p + ls.wo * ls.dist) < 1e-4);
                assert_eq!(
                    table.pdf_area(object, triangle, p, ls.position, ls.normal),
                    ls.pdf
                );
                assert_eq!(
                    table.pdf_area(object, triangle, p, ls.position, -ls.normal),
                    ls.pdf
                );
            }
            LightPoint::Point { index } => {
                kinds[1] += 1;
                assert!(ls.delta && ls.pdf == table.pdf_point(index));
            }
            LightPoint::Background => {
                kinds[2] += 1;
                assert_eq!(ls.dist, f32::INFINITY);
                assert_eq!(table.pdf_background(ls.wo), ls.pdf);
                assert_eq!(ls.radiance, Vec3::splat(0.2));
            }
        }
    }
    assert!(kinds.iter().all(|&k| k > 100), "{kinds:?}");
}

#[test]
fn selection_is_proportional_to_power_and_skips_dark_lights() {
    // Area: mean 1 · area 1 · π = π; point: 4π·mean(I) = 8π; background:
    // π·0.5·π·r² with r = √3/2 (unit-cube bounds) = 3π²/8.
    let objects = [
        emitter(DAffine3::IDENTITY, Vec3::ONE),
        emitter(DAffine3::IDENTITY, Vec3::ZERO),
    ];
    let lights = [
        PointLight {
            name: "a".into(),
            position: DVec3::Y,
            intensity: Vec3::splat(2.0),
        },
        PointLight {
            name: "b".into(),
            position: DVec3::Y,
            intensity: Vec3::ZERO,
        },
    ];
    let bounds = Some((DVec3::ZERO, DVec3::ONE));
    let table = LightTable::build(
        &objects,
        &lights,
        &Background::Constant(Vec3::splat(0.5)),
        bounds,
    );
    let powers = [PI, 8.0 * PI, 3.0 * PI * PI / 8.0];
    let total: f64 = powers.iter().sum();
    let p = Vec3::new(0.1, 0.2, 3.0);
    let mut counts = [0usize; 3];
    let n = 30_000;
    for i in 0..n {
        let u = (i as f32 + 0.5) / n as f32;
        match table
            .sample(p, u, Vec2::new(0.3, 0.6))
            .expect("all lights visible")
            .source
        {
            LightPoint::Area { object, .. } => {
                assert_eq!(object, 0, "dark emitter selected");
                counts[0] += 1;
            }
            LightPoint::Point { index } => {
                assert_eq!(index, 0, "dark point light selected");
                counts[1] += 1;
            }
            LightPoint::Background => counts[2] += 1,
        }
    }
    for k in 0..3 {
        let frac = counts[k] as f64 / n as f64;
        assert!((frac - powers[k] / total).abs() < 1e-3, "light {k}: {frac}");
    }
    assert!((table.pdf_point(0) as f64 - powers[1] / total).abs() < 1e-6);
    assert_eq!(table.pdf_point(1), 0.0);
    assert_eq!(table.pdf_area(1, 0, p, Vec3::ZERO, Vec3::Z), 0.0);
    assert!(LightTable::build(&objects[1..], &lights[1..], &black(), None).is_empty());
}

#[test]
fn point_light_irradiance_is_intensity_cos_over_d2() {
    let intensity = Vec3::new(3.0, 2.0, 1.0);
    let light = PointLight {
        name: "p".into(),
        position: DVec3::new(1.0, 2.0, 0.5),
        intensity,
    };
    let table = LightTable::build(&[], &[light], &black(), None);
    let (p, n) = (Vec3::new(0.2, -0.1, 0.3), Vec3::Y);
    let ls = table
        .sample(p, 0.7, Vec2::new(0.1, 0.9))
        .expect("point light");
    let d = Vec3::new(1.0, 2.0, 0.5) - p;
    let exact = intensity * n.dot(d.normalize()) / d.length_squared();
    let estimate = ls.radiance * n.dot(ls.wo) / ls.pdf;
    assert!(
        estimate.distance(exact) < 1e-5 * exact.length(),
        "{estimate} vs {exact}"
    );
    assert!(ls.delta && ls.pdf == 1.0 && (ls.dist - d.length()).abs() < 1e-5);
}

/// A 40 × 20 map (texel edges align with the χ² bins) with a bright spot.
fn test_map(rotate_y: f32) -> EnvMap {
    let mut image = Image::new(40, 20);
    for y in 0..20 {
        for x in 0..40 {
            let spot = if (10..14).contains(&x) && (4..7).contains(&y) {
                30.0
            } else {
                0.0
            };
            image.set(
                x,
                y,
                Vec3::new(0.2 + spot + 0.05 * x as f32, 0.3 + 0.1 * y as f32, 0.1),
            );
        }
    }
    image.set(5, 0, Vec3::ZERO);
    EnvMap::new(image, 1.5, rotate_y)
}

/// Env-map `+y`-up directions as test-binning `+z`-up ones, φ preserved.
fn z_up(d: Vec3) -> Vec3 {
    Vec3::new(-d.z, d.x, d.y)
}

#[test]
fn envmap_pdf_integrates_to_one_and_sampling_matches_it() {
    for rotate_y in [0.0f32, 0.7] {
        let map = test_map(rotate_y);
        let integral = integrate_sphere(400, |d| map.pdf(d) as f64);
        assert!((integral - 1.0).abs() < 3e-3, "∫pdf = {integral}");
        let from_z_up = |w: Vec3| Vec3::new(w.y, w.z, -w.x);
        let mut rng = Rng::new(13);
        let n = 200_000;
        let observed = histogram(n, || map.sample(rng.vec2()).map(|s| z_up(s.dir)));
        let expected = expected_counts(n, 8, |w| map.pdf(from_z_up(w)) as f64);
        assert_chi2(
            &format!("envmap rotate_y = {rotate_y}"),
            &observed,
            &expected,
            2,
        );
        for _ in 0..1000 {
            let s = map.sample(rng.vec2()).expect("non-black map");
            assert_eq!(s.pdf, map.pdf(s.dir));
            let lum = envmap::luminance(map.eval(s.dir)) as f64;
            assert!(lum > 0.0, "never samples black texels");
        }
    }
}

#[test]
fn envmap_lookup_convention_and_constant_map_value() {
    let mut image = Image::new(8, 4);
    image.pixels.fill(Vec3::new(0.5, 1.0, 2.0));
    let map = EnvMap::new(image, 3.0, 0.4);
    let mut rng = Rng::new(14);
    for _ in 0..100 {
        let d = rng.sphere();
        assert_eq!(map.eval(d), Vec3::new(1.5, 3.0, 6.0));
        assert!(map.direction(map.uv(d)).distance(d) < 1e-5);
    }
    assert!((map.mean_radiance() - Vec3::new(1.5, 3.0, 6.0)).length() < 1e-5);
    // Row 0 is up; u = 0.5 looks down −z when rotate_y = 0.
    let plain = test_map(0.0);
    assert!(plain.direction(Vec2::new(0.5, 0.5)).distance(-Vec3::Z) < 1e-6);
    assert!(plain.uv(Vec3::Y).y < 1e-6);
    assert_eq!(plain.pdf(Vec3::Y), 0.0);
    let centre = plain.direction(Vec2::new(12.5 / 40.0, 5.5 / 20.0));
    let texel = plain.image().get(12, 5) * 1.5;
    assert_eq!(Background::EnvMap(Arc::new(plain)).eval(centre), texel);
}

#[test]
fn area_pdf_integrates_to_one_over_the_directions_that_see_the_light() {
    // A 0.5 × 0.5 square at height 1 facing down, tilted a little about x.
    let to_world = DAffine3::from_translation(DVec3::new(0.1, 1.0, 0.0))
        * DAffine3::from_mat3(
            DMat3::from_rotation_x(PI / 2.0 + 0.2) * DMat3::from_diagonal(DVec3::splat(0.5)),
        );
    let object = emitter(to_world, Vec3::ONE);
    let table = LightTable::build(std::slice::from_ref(&object), &[], &black(), None);
    let corners: Vec<DVec3> = object
        .mesh
        .positions
        .iter()
        .map(|p| to_world.transform_point3(p.as_dvec3()))
        .collect();
    let (origin, normal) = (
        corners[0],
        (corners[1] - corners[0])
            .cross(corners[3] - corners[0])
            .normalize(),
    );
    let (e1, e2) = (corners[1] - corners[0], corners[3] - corners[0]);
    // Midpoint rule over the cap θ < 0.6 about +y, which contains the square.
    let (n, cap) = (1000usize, 0.6f64);
    let (dt, dp) = (cap / n as f64, 2.0 * PI / (2 * n) as f64);
    let mut integral = 0.0;
    for i in 0..n {
        let theta = (i as f64 + 0.5) * dt;
        for j in 0..2 * n {
            let phi = (j as f64 + 0.5) * dp;
            let dir = DVec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            // Ray from the origin against the square's plane, then its parameters.
            let t = origin.dot(normal) / dir.dot(normal);
            let rel = dir * t - origin;
            let (a, b) = (
                rel.dot(e1) / e1.length_squared(),
                rel.dot(e2) / e2.length_squared(),
            );
            if t > 0.0 && (0.0..1.0).contains(&a) && (0.0..1.0).contains(&b) {
                let y = (dir * t).as_vec3();
                let triangle = if b <= a { 0 } else { 1 };
                let pdf = table.pdf_area(0, triangle, Vec3::ZERO, y, normal.as_vec3());
                integral += pdf as f64 * theta.sin() * dt * dp;
            }
        }
    }
    assert!((integral - 1.0).abs() < 2e-3, "∫ pdf dω = {integral}");
}
