//! Closed forms (docs/design.md §7): a point seen in a flat mirror moves as its
//! reflection; a point seen through a parallel slab is offset by the known
//! lateral shift and follows the slab's thickness by the 1-D refraction
//! equation; a point light's shadow of a point occluder on a plane moves by
//! similar triangles. Pixel Jacobians come from `epsm_render::Camera`, an
//! implementation independent of this crate's projection.

mod common;

use common::manual::{Manual, Surface, quad_triangle};
use epsm_core::newton::{NewtonSettings, project};
use epsm_core::paths::Node;
use epsm_core::{DiffPath, ParamTable, PathKind, SolveSettings, classify, solve_forward};
use epsm_render::lights::{LightPoint, PointLight};
use epsm_render::materials::Lobe;
use epsm_render::record::{ConnectionRecord, OccluderRecord, PathRecord};
use epsm_render::{Camera, Scene};
use glam::{DVec2, DVec3, Vec3};

fn camera(eye: DVec3, target: DVec3) -> Camera {
    Camera::look_at(eye, target, DVec3::Y, 40.0, 64, 64).expect("valid camera")
}

/// `J_π(x)·dx` by the render crate's camera.
fn pixel_motion(cam: &Camera, x: DVec3, dx: DVec3) -> DVec2 {
    let (_, j) = cam.project_with_jacobian(x).expect("in front");
    DVec2::new(j[0].dot(dx), j[1].dot(dx))
}

/// The only path of `kind` in the record, re-solved onto `C = 0`.
fn solved(record: &PathRecord, scene: &Scene, table: &ParamTable, kind: PathKind) -> DiffPath {
    let motion = table.motion(&table.values());
    let paths = classify(record, scene, &motion, &SolveSettings::for_radius(1.0)).paths;
    let path = paths
        .iter()
        .find(|p| p.kind == kind)
        .expect("path of the kind");
    project(
        path,
        &motion,
        &SolveSettings::for_radius(1.0),
        &NewtonSettings::default(),
    )
    .expect("re-solved")
}

fn columns(path: &DiffPath, table: &ParamTable) -> Vec<DVec2> {
    let motion = table.motion(&table.values());
    solve_forward(path, &motion, &SolveSettings::for_radius(1.0))
        .expect("solved")
        .columns
}

fn assert_close(a: DVec2, b: DVec2, tol: f64) {
    assert!(
        (a - b).length() <= tol * b.length().max(1e-12),
        "{a} vs {b}"
    );
}

#[test]
fn a_point_seen_in_a_flat_mirror_moves_as_its_reflection() {
    let mut m = Manual::default();
    let mirror = m.object(
        &[quad_triangle(DVec3::ZERO, DVec3::X, DVec3::Y, 8.0)],
        None,
        Surface::Mirror,
    );
    let p = DVec3::new(-0.25, 0.125, 1.5);
    let point = m.object(
        &[quad_triangle(p, DVec3::X, DVec3::Z, 0.25)],
        None,
        Surface::Diffuse,
    );
    let image = p * DVec3::new(1.0, 1.0, -1.0);
    let eye = DVec3::new(0.3, 0.2, 3.0);
    let x1 = eye + (image - eye) * (eye.z / (eye.z - image.z));
    let cam = camera(eye, image);
    let record = PathRecord {
        film: cam.project(x1).expect("visible").as_vec2(),
        vertices: vec![
            m.vertex(mirror, 0, x1, Some(Lobe::SpecularReflection), 1.0),
            m.vertex(point, 0, p, None, 1.0),
        ],
        ..PathRecord::default()
    };
    let scene = m.scene(cam.clone());
    let mut table = ParamTable::new(&scene);
    for key in [
        "o1.translate.x",
        "o1.translate.y",
        "o1.translate.z",
        "o0.translate.z",
    ] {
        table.add(key).expect("valid key");
    }
    let path = solved(&record, &scene, &table, PathKind::ChainToSurface);
    let expected = [DVec3::X, DVec3::Y, -DVec3::Z, 2.0 * DVec3::Z];
    let cols = columns(&path, &table);
    assert_eq!(cols.len(), expected.len(), "one column per parameter");
    for (col, dx) in cols.into_iter().zip(expected) {
        assert_close(col, pixel_motion(&cam, image, dx), 1e-9);
    }
}

#[test]
fn a_point_behind_a_glass_slab_is_offset_laterally_and_follows_the_thickness() {
    let (n, h, d, g, x_total) = (1.5f64, 2.0, 0.5, 0.75, 1.5);
    // Incidence angle θi: (h + g) tan θi + d tan θt = X with sin θi = n sin θt.
    let miss = |ti: f64| (h + g) * ti.tan() + d * (ti.sin() / n).asin().tan() - x_total;
    let (mut lo, mut hi) = (0.0, 1.5);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if miss(mid) > 0.0 { hi = mid } else { lo = mid }
    }
    let ti = 0.5 * (lo + hi);
    let tt = (ti.sin() / n).asin();
    let mut m = Manual::default();
    let top = m.object(
        &[quad_triangle(DVec3::ZERO, DVec3::X, DVec3::Y, 8.0)],
        None,
        Surface::Glass(n as f32),
    );
    let bottom = m.object(
        &[quad_triangle(-d * DVec3::Z, DVec3::X, DVec3::Y, 8.0)],
        None,
        Surface::Glass(n as f32),
    );
    let p = DVec3::new(x_total, 0.0, -d - g);
    let floor = m.object(
        &[quad_triangle(p, DVec3::X, DVec3::Y, 0.5)],
        None,
        Surface::Diffuse,
    );
    let eye = DVec3::new(0.0, 0.0, h);
    let x1 = DVec3::new(h * ti.tan(), 0.0, 0.0);
    let x2 = x1 + DVec3::new(d * tt.tan(), 0.0, -d);
    let cam = camera(eye, x1);
    let record = PathRecord {
        film: cam.project(x1).expect("visible").as_vec2(),
        vertices: vec![
            m.vertex(top, 0, x1, Some(Lobe::SpecularTransmission), n as f32),
            m.vertex(
                bottom,
                0,
                x2,
                Some(Lobe::SpecularTransmission),
                (1.0 / n) as f32,
            ),
            m.vertex(floor, 0, p, None, 1.0),
        ],
        ..PathRecord::default()
    };
    let scene = m.scene(cam.clone());
    let mut table = ParamTable::new(&scene);
    table.add("o1.translate.z").expect("valid key");
    let path = solved(&record, &scene, &table, PathKind::ChainToSurface);
    let motion = table.motion(&table.values());
    let Node::Surface { anchor, .. } = path.nodes[1] else {
        panic!("x1 is a surface")
    };
    let x1_solved = anchor.eval(motion.object(anchor.object), [0.0, 0.0]).x;
    // The camera ray through x1 misses P by the slab's lateral offset.
    let lateral = (p - eye).cross((x1_solved - eye).normalize()).length();
    let expected = d * (ti - tt).sin() / tt.cos();
    assert!(
        (lateral - expected).abs() < 1e-10,
        "{lateral} vs {expected}"
    );
    // Raising the bottom face by δ: thickness d − δ, depth below it g + δ.
    let dti = -(ti.tan() - tt.tan())
        / ((h + g) / ti.cos().powi(2) + d / tt.cos().powi(2) * ti.cos() / (n * tt.cos()));
    let dx1 = DVec3::X * h / ti.cos().powi(2) * dti;
    assert_close(
        columns(&path, &table)[0],
        pixel_motion(&cam, x1_solved, dx1),
        1e-8,
    );
}

#[test]
fn a_point_lights_shadow_of_a_point_occluder_moves_by_similar_triangles() {
    let mut m = Manual::default();
    let plane = m.object(
        &[quad_triangle(DVec3::ZERO, DVec3::X, DVec3::Y, 8.0)],
        None,
        Surface::Diffuse,
    );
    let o = DVec3::new(0.125, -0.25, 0.75);
    let occluder = m.object(
        &[quad_triangle(
            o,
            DVec3::X,
            DVec3::new(0.0, 1.0, 0.25),
            0.125,
        )],
        None,
        Surface::Diffuse,
    );
    let l = DVec3::new(0.375, 0.25, 2.0);
    m.lights.push(PointLight {
        name: "lamp".into(),
        position: l,
        intensity: Vec3::ONE,
    });
    let t = l.z / (l.z - o.z);
    let s = l + (o - l) * t;
    let cam = camera(DVec3::new(0.0, -2.0, 3.0), s);
    let record = PathRecord {
        film: cam.project(s).expect("visible").as_vec2(),
        vertices: vec![m.vertex(plane, 0, s, Some(Lobe::DiffuseReflection), 1.0)],
        connections: vec![ConnectionRecord {
            vertex: 0,
            light: LightPoint::Point { index: 0 },
            light_position: l.as_vec3(),
            light_normal: Vec3::ZERO,
            contribution: Vec3::ZERO,
            unoccluded: Vec3::ONE,
            occluder: Some(OccluderRecord {
                at: m.at(occluder, 0, o),
                p: o.as_vec3(),
            }),
            dropped: None,
        }],
        ..PathRecord::default()
    };
    let scene = m.scene(cam.clone());
    let mut table = ParamTable::new(&scene);
    for key in [
        "o1.translate.x",
        "o1.translate.y",
        "o1.translate.z",
        "lamp.translate.x",
    ] {
        table.add(key).expect("valid key");
    }
    let path = solved(&record, &scene, &table, PathKind::Shadow);
    let dz = ((o - l) * l.z / (l.z - o.z).powi(2)) * DVec3::new(1.0, 1.0, 0.0);
    let expected = [DVec3::X * t, DVec3::Y * t, dz, DVec3::X * (1.0 - t)];
    let cols = columns(&path, &table);
    assert_eq!(cols.len(), expected.len(), "one column per parameter");
    for (col, ds) in cols.into_iter().zip(expected) {
        assert_close(col, pixel_motion(&cam, s, ds), 1e-9);
    }
}
