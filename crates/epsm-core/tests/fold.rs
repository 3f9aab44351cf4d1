//! A caustic fold (DESIGN §6): a concave mirror images the camera onto the
//! seen point (Coddington's equations), so `A` is singular. The path must be
//! dropped and counted, never give NaN or a huge gradient; the same mirror
//! away from the fold validates.
//!
//! The mirror is the plane z = 0 with the normal field of a sphere of radius
//! R (vertex normals `e_z − q/R`, exact in `f32`), seen at the origin. With
//! the seen point D at distance d2 and incidence angle θ, the camera at
//! distance d1 on the mirrored ray is at the tangential fold when
//! `1/d1 + 1/d2 = 2/(R cos θ)` and at the sagittal fold when
//! `1/d1 + 1/d2 = 2 cos θ/R`.

mod common;

use common::manual::{Manual, Surface, quad_triangle};
use epsm_core::check::{CheckReport, CheckSettings, check_path};
use epsm_core::{DropReason, Dropped, ParamTable, PathKind, classify, solve_adjoint};
use epsm_render::Camera;
use epsm_render::materials::Lobe;
use epsm_render::record::PathRecord;
use glam::{DVec2, DVec3};

/// Checks the mirror path with the camera at distance `d1`; returns the
/// adjoint outcome and adds the check to `report`.
fn mirror_path(d1: f64, report: &mut CheckReport) -> Result<Vec<f64>, Dropped> {
    let r = 1.0;
    let mut m = Manual::default();
    let tri = quad_triangle(DVec3::ZERO, DVec3::X, DVec3::Y, 1.0);
    let normals = tri.map(|q| DVec3::Z - q / r);
    let mirror = m.object(&[tri], Some(&[normals]), Surface::Mirror);
    let d = DVec3::new(-0.5, 0.0, 0.75);
    let seen = m.object(
        &[quad_triangle(d, DVec3::X, DVec3::Y, 0.25)],
        None,
        Surface::Diffuse,
    );
    let eye = DVec3::new(-d.x, 0.0, d.z).normalize() * d1;
    let cam = Camera::look_at(eye, DVec3::ZERO, DVec3::Y, 40.0, 64, 64).expect("valid camera");
    let record = PathRecord {
        film: cam.project(DVec3::ZERO).expect("visible").as_vec2(),
        vertices: vec![
            m.vertex(mirror, 0, DVec3::ZERO, Some(Lobe::SpecularReflection), 1.0),
            m.vertex(seen, 0, d, None, 1.0),
        ],
        ..PathRecord::default()
    };
    let scene = m.scene(cam);
    let mut table = ParamTable::new(&scene);
    table.add("o1.translate.x").expect("valid key");
    table.add("o0.rotate.y").expect("valid key");
    let motion = table.motion(&table.values());
    let settings = CheckSettings::for_radius(1.0);
    // The record lies exactly on the manifold: classify's projection keeps it.
    let paths = classify(&record, &scene, &motion, &settings.solve).paths;
    let path = paths
        .iter()
        .find(|p| p.kind == PathKind::ChainToSurface)
        .expect("mirror path");
    report.add(
        path.kind,
        check_path(path, &table, &motion, &settings),
        settings.well_conditioned,
    );
    solve_adjoint(path, DVec2::new(1.0, 0.5), &motion, &settings.solve)
        .map(|g| g.entries.iter().map(|e| e.1).collect())
}

#[test]
fn a_caustic_fold_is_dropped_and_counted_and_its_neighbourhood_validates() {
    let d = DVec3::new(-0.5, 0.0, 0.75);
    let (d2, cos) = (d.length(), d.z / d.length());
    let tangential = 1.0 / (2.0 / cos - 1.0 / d2);
    let sagittal = 1.0 / (2.0 * cos - 1.0 / d2);
    let mut report = CheckReport::default();
    for fold in [tangential, sagittal] {
        let outcome = mirror_path(fold, &mut report);
        assert!(
            matches!(
                outcome,
                Err(Dropped(DropReason::Singular | DropReason::IllConditioned))
            ),
            "fold at d1 = {fold}: {outcome:?}"
        );
    }
    let r = &report.kinds[&PathKind::ChainToSurface];
    assert_eq!(
        r.dropped.get(DropReason::Singular) + r.dropped.get(DropReason::IllConditioned),
        2
    );
    // Near the fold: finite (large) gradients; well away: validated.
    for near in [tangential * (1.0 + 1e-5), sagittal * (1.0 - 1e-5)] {
        let g = mirror_path(near, &mut report).expect("near the fold the path is kept");
        assert!(g.iter().all(|v| v.is_finite()), "{g:?}");
    }
    let mut away = CheckReport::default();
    mirror_path(0.5 * tangential, &mut away).expect("away from the fold");
    let a = &away.kinds[&PathKind::ChainToSurface];
    assert_eq!(a.errors.len(), 1);
    assert!(a.max_rel_err() <= 1e-6, "{}", a.max_rel_err());
}
