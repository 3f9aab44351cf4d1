//! A caustic fold (docs/design.md §6): a concave mirror images the camera onto the
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
//!
//! The same mirror also lights D (a caustic, the emitter at distance d1 on
//! the mirrored ray); D keeps its direction towards the mirror, so the
//! bundle through D is parallel and the folds are at `1/d1 = 2/(R cos θ)`
//! and `1/d1 = 2 cos θ/R`.
//!
//! The exact sphere of radius R tangent to z = 0 at the origin (seen from
//! inside) has the same position, normal and curvature there, so the same
//! folds: the second variant of each test mirrors on it.

mod common;

use common::manual::{Manual, Surface, quad_triangle};
use epsm_core::check::{CheckReport, CheckSettings, check_path};
use epsm_core::{DropReason, Dropped, ParamTable, PathKind, classify, solve_adjoint};
use epsm_render::Camera;
use epsm_render::materials::Lobe;
use epsm_render::record::PathRecord;
use glam::{DAffine3, DMat3, DVec2, DVec3, Vec3};

/// Checks the mirror path of `kind` with its far end at distance `d1`:
/// the camera for `ChainToSurface`; for `Caustic`, a small emitter facing
/// the mirror, with D seen from above. Returns the adjoint outcome and adds
/// the check to `report`. With `sphere` the mirror is the exact sphere.
fn mirror_path(
    kind: PathKind,
    d1: f64,
    sphere: bool,
    report: &mut CheckReport,
) -> Result<Vec<f64>, Dropped> {
    let r = 1.0;
    let mut m = Manual::default();
    let mirror = if sphere {
        // Object point +y at the origin (octahedral (0, 1), exact in f32).
        let turn = DMat3::from_cols(DVec3::X, -DVec3::Z, DVec3::Y);
        let place = DAffine3::from_mat3_translation(turn * r, DVec3::Z * r);
        m.sphere(place, Surface::Mirror)
    } else {
        let tri = quad_triangle(DVec3::ZERO, DVec3::X, DVec3::Y, 1.0);
        let normals = tri.map(|q| DVec3::Z - q / r);
        m.object(&[tri], Some(&[normals]), Surface::Mirror)
    };
    let d = DVec3::new(-0.5, 0.0, 0.75);
    let seen = m.object(
        &[quad_triangle(d, DVec3::X, DVec3::Y, 0.25)],
        None,
        Surface::Diffuse,
    );
    let far = DVec3::new(-d.x, 0.0, d.z).normalize() * d1;
    let (cam, vertices) = if kind == PathKind::Caustic {
        let e = far.normalize();
        let light = m.object(
            &[quad_triangle(far, DVec3::Y, DVec3::Y.cross(e), 0.01)],
            None,
            Surface::Diffuse,
        );
        m.objects[light as usize].emission = Some(Vec3::ONE);
        let cam = Camera::look_at(d + DVec3::new(0.25, 0.0, 2.0), d, DVec3::Y, 40.0, 64, 64)
            .expect("valid camera");
        let vertices = vec![
            m.vertex(seen, 0, d, Some(Lobe::DiffuseReflection), 1.0),
            m.vertex(mirror, 0, DVec3::ZERO, Some(Lobe::SpecularReflection), 1.0),
            m.vertex(light, 0, far, None, 1.0),
        ];
        (cam, vertices)
    } else {
        let cam = Camera::look_at(far, DVec3::ZERO, DVec3::Y, 40.0, 64, 64).expect("valid camera");
        let vertices = vec![
            m.vertex(mirror, 0, DVec3::ZERO, Some(Lobe::SpecularReflection), 1.0),
            m.vertex(seen, 0, d, None, 1.0),
        ];
        (cam, vertices)
    };
    let record = PathRecord {
        film: cam
            .project(vertices[0].p.as_dvec3())
            .expect("visible")
            .as_vec2(),
        vertices,
        ..PathRecord::default()
    };
    let scene = m.scene(cam);
    let mut table = ParamTable::new(&scene);
    // The sphere tilts about its point at the origin, as the triangle does
    // (its own pivot, its centre, would leave the surface in place).
    table.set_pivot(mirror, DVec3::ZERO);
    table.add("o1.translate.x").expect("valid key");
    table.add("o0.rotate.y").expect("valid key");
    let motion = table.motion(&table.values());
    let settings = CheckSettings::for_radius(1.0);
    // The record lies on the manifold (up to f32 rounding): classify's
    // projection keeps it.
    let classified = classify(&record, &scene, &motion, &settings.solve);
    let Some(path) = classified.paths.iter().find(|p| p.kind == kind) else {
        // Dropped while projecting the record (a caustic at its fold).
        let counted = &mut report.kinds.entry(kind).or_default().dropped;
        counted.merge(&classified.skipped);
        let (reason, _) = classified.skipped.nonzero().next().expect("a counted drop");
        return Err(Dropped(reason));
    };
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
    for kind in [PathKind::ChainToSurface, PathKind::Caustic] {
        fold_is_dropped_and_neighbourhood_validates(kind, false);
    }
}

#[test]
fn a_caustic_fold_on_an_exact_sphere_is_dropped_and_its_neighbourhood_validates() {
    for kind in [PathKind::ChainToSurface, PathKind::Caustic] {
        fold_is_dropped_and_neighbourhood_validates(kind, true);
    }
}

fn fold_is_dropped_and_neighbourhood_validates(kind: PathKind, sphere: bool) {
    let d = DVec3::new(-0.5, 0.0, 0.75);
    // A caustic's receiver keeps its direction towards the mirror: the
    // incoming bundle is parallel (1/d2 = 0 in the fold conditions).
    let inv_d2 = if kind == PathKind::Caustic {
        0.0
    } else {
        1.0 / d.length()
    };
    let cos = d.z / d.length();
    let tangential = 1.0 / (2.0 / cos - inv_d2);
    let sagittal = 1.0 / (2.0 * cos - inv_d2);
    let mut report = CheckReport::default();
    // The caustic's emitter is stored in f32, off the fold by rounding: on its
    // far side the record has no nearby solution (two merge and vanish), so
    // the projection in classify stalls, where A is singular too.
    for fold in [tangential, sagittal] {
        let outcome = mirror_path(kind, fold, sphere, &mut report);
        assert!(
            matches!(
                outcome,
                Err(Dropped(DropReason::Singular | DropReason::IllConditioned))
            ),
            "{kind:?} fold at d1 = {fold}: {outcome:?}"
        );
    }
    assert_eq!(report.kinds[&kind].dropped.total(), 2);
    // Near the fold: finite (large) gradients; well away: validated.
    for near in [tangential * (1.0 + 1e-5), sagittal * (1.0 - 1e-5)] {
        let g =
            mirror_path(kind, near, sphere, &mut report).expect("near the fold the path is kept");
        assert!(g.iter().all(|v| v.is_finite()), "{g:?}");
    }
    let mut away = CheckReport::default();
    mirror_path(kind, 0.5 * tangential, sphere, &mut away).expect("away from the fold");
    let a = &away.kinds[&kind];
    assert_eq!(a.errors.len(), 1);
    assert!(a.max_rel_err() <= 1e-6, "{}", a.max_rel_err());
}
