//! Colour derivatives of geometric parameters and of `ior` against central
//! differences of the path contribution at fixed sampled coordinates (no
//! re-tracing, so visibility cannot change): every vertex keeps its local
//! coordinates on its object, or, for the vertex a pixel sees with the L2
//! convention, stays on the pixel's camera ray. The reference below
//! re-evaluates each term's factors from scratch (the scene's placed
//! meshes, `Material::eval`, plain products), one parameter kind per test.

mod colour_reference;

use colour_reference::{records, scene, term_values, terms};
use epsm_core::ParamTable;
use epsm_core::colour::{ColourModel, PrimaryMotion};
use epsm_core::drops::DropCounts;
use epsm_render::Scene;
use epsm_render::materials::fresnel::fresnel_dielectric;
use epsm_render::materials::{Bsdf, Lobe, VertexKind};
use epsm_render::record::PathRecord;
use glam::Vec3;

/// Analytic `dc/dθ` of parameter `key` against the central difference of
/// the reference, summed over records and channels per record.
fn check(key: &str, h: f64, primary: PrimaryMotion) {
    let mut scene = scene();
    let mut table = ParamTable::new(&scene);
    let k = table.add(key).expect("valid key");
    let base = table.values()[k];
    let recs = records(&scene);
    let motion = table.motion(&table.values());
    let model = ColourModel::new(&table, &scene, Some(primary));
    let on_ray = primary == PrimaryMotion::OnCameraRay;
    let mut at = |v: f64, scene: &mut Scene| {
        table.set_value(k, v);
        table.apply(scene);
        recs.iter()
            .map(|r| terms(scene, r, on_ray))
            .collect::<Vec<_>>()
    };
    let t0 = at(base, &mut scene);
    let steps = [h, 0.5 * h].map(|h| (at(base + h, &mut scene), at(base - h, &mut scene)));
    at(base, &mut scene);
    let (mut err, mut total, mut moved, mut kept, mut chains) =
        (0.0f64, 0.0f64, 0usize, 0usize, 0usize);
    let mut skipped = DropCounts::default();
    for (i, r) in recs.iter().enumerate() {
        if !on_ray && r.vertices.iter().any(|v| v.kind == VertexKind::Specular) {
            continue;
        }
        let vals = term_values(r);
        for (tp, tm) in &steps {
            let lens = [t0[i].len(), tp[i].len(), tm[i].len()];
            assert_eq!(
                lens,
                [vals.len(); 3],
                "record {i}: terms at θ₀, θ₀ + h, θ₀ − h"
            );
        }
        let fd = |(tp, tm): &(Vec<Vec<Vec3>>, Vec<Vec<Vec3>>), h: f64| -> f64 {
            vals.iter()
                .zip(&t0[i])
                .zip(tp[i].iter().zip(&tm[i]))
                .filter(|((c, f0), _)| **c != Vec3::ZERO && f0.min_element() > 0.0)
                .map(|((c, f0), (fp, fm))| {
                    f64::from((*c * (*fp - *fm) / *f0).element_sum()) / (2.0 * h)
                })
                .sum()
        };
        let (fd, fd_half) = (fd(&steps[0], h), fd(&steps[1], 0.5 * h));
        if fd == 0.0 {
            continue;
        }
        moved += 1;
        // Near contact (a short segment, a grazing cosine) the central
        // difference itself has not converged: skip those paths.
        if (fd - fd_half).abs() > 1e-2 * fd.abs() {
            continue;
        }
        kept += 1;
        let before = skipped.total();
        let a: f64 = model
            .gradient(r, &scene, &motion, &mut skipped)
            .iter()
            .filter(|e| e.0 == k)
            .map(|e| f64::from(e.1.element_sum()))
            .sum();
        if skipped.total() > before {
            continue;
        }
        chains += usize::from(r.vertices.iter().any(|v| v.kind == VertexKind::Specular));
        err += (a - fd_half).abs();
        total += fd_half.abs();
    }
    eprintln!(
        "{key} {primary:?}: {moved} paths change, {kept} with converged differences \
         ({chains} through mirrors or glass), {} left out, Σ|fd| {total:.3e}, Σ|err| {err:.3e}",
        skipped.total()
    );
    assert!(
        moved > 10 && 10 * kept >= 9 * moved,
        "{key}: too few paths change"
    );
    assert!(
        err <= 2e-3 * total,
        "{key}: Σ|analytic − fd| {err:.3e} vs Σ|fd| {total:.3e}"
    );
    assert!(
        20 * skipped.total() as usize <= kept,
        "{key}: {} paths left out",
        skipped.total()
    );
}

#[test]
fn object_translation() {
    check("box.translate.x", 1e-3, PrimaryMotion::Attached);
    check("ball.translate.z", 1e-3, PrimaryMotion::OnCameraRay);
}

#[test]
fn object_rotation() {
    check("box.rotate.y", 0.05, PrimaryMotion::Attached);
    check("box.rotate.x", 0.05, PrimaryMotion::OnCameraRay);
    check("panel.rotate.y", 0.05, PrimaryMotion::OnCameraRay);
}

#[test]
fn object_scale() {
    check("ball.scale", 1e-3, PrimaryMotion::Attached);
    check("box.scale", 1e-3, PrimaryMotion::OnCameraRay);
}

#[test]
fn emitter_rotation_and_translation() {
    check("lamp.rotate.x", 0.05, PrimaryMotion::Attached);
    check("lamp.translate.y", 1e-3, PrimaryMotion::OnCameraRay);
}

/// With the L2 convention, vertices after a mirror or a glass interface
/// stay on the scattered ray.
#[test]
fn mirror_and_glass_chains() {
    check("mirror.rotate.y", 0.05, PrimaryMotion::OnCameraRay);
    check("glass.translate.x", 1e-3, PrimaryMotion::OnCameraRay);
    check("ball.translate.x", 1e-3, PrimaryMotion::OnCameraRay);
}

#[test]
fn point_light_translation() {
    check("bulb.translate.x", 1e-3, PrimaryMotion::Attached);
}

#[test]
fn camera_pose() {
    check("camera.yaw", 0.05, PrimaryMotion::OnCameraRay);
    check("camera.pitch", 0.05, PrimaryMotion::OnCameraRay);
    check("camera.translate.z", 1e-3, PrimaryMotion::OnCameraRay);
    // The pixel-attached vertices' terms are `f32`: at a 1e-3 step about one
    // path in ten has a difference still limited by rounding.
    check("camera.translate.x", 4e-3, PrimaryMotion::Attached);
}

/// `ior`: the weight of each dielectric lobe over its fixed choice
/// probability, `F` or `(1 − F)/η²`, at fixed directions.
#[test]
fn dielectric_ior() {
    let scene = scene();
    let mut table = ParamTable::new(&scene);
    let k = table.add("glass.ior").expect("valid key");
    let recs = records(&scene);
    let motion = table.motion(&table.values());
    let model = ColourModel::new(&table, &scene, None);
    // ln of the weight of dielectric vertex `i` of `r` at `ior`.
    let ln_weight = |r: &PathRecord, i: usize, ior: f32| -> f32 {
        let v = &r.vertices[i];
        let prev = if i == 0 {
            scene.camera().origin_f32()
        } else {
            r.vertices[i - 1].p
        };
        let c = v.ns.dot((prev - v.p).normalize());
        let eta = if c >= 0.0 { ior } else { 1.0 / ior };
        let f = fresnel_dielectric(c.abs(), eta);
        let w = if v.lobe == Some(Lobe::SpecularTransmission) {
            (1.0 - f) / (eta * eta)
        } else {
            f
        };
        w.ln()
    };
    let h = 1e-3;
    let (mut err, mut total, mut n) = (0.0f64, 0.0f64, 0);
    let mut skipped = DropCounts::default();
    for r in &recs {
        let mut fd = 0.0f64;
        for (i, v) in r.vertices.iter().enumerate() {
            let material = scene.objects()[v.at.object as usize].material;
            let glass = matches!(
                scene.materials()[material as usize].bsdf,
                Bsdf::Dielectric(_)
            );
            if !glass || v.lobe.is_none() {
                continue;
            }
            // Radiance carried after vertex i.
            let after = r.escaped
                + r.vertices[i + 1..]
                    .iter()
                    .map(|v| v.contribution)
                    .sum::<Vec3>();
            let rate = (ln_weight(r, i, 1.5 + h) - ln_weight(r, i, 1.5 - h)) / (2.0 * h);
            fd += f64::from(after.element_sum() * rate);
        }
        if fd == 0.0 {
            continue;
        }
        let a: f64 = model
            .gradient(r, &scene, &motion, &mut skipped)
            .iter()
            .filter(|e| e.0 == k)
            .map(|e| f64::from(e.1.element_sum()))
            .sum();
        err += (a - fd).abs();
        total += fd.abs();
        n += 1;
    }
    eprintln!("glass.ior: {n} paths, Σ|fd| {total:.3e}, Σ|err| {err:.3e}");
    assert!(n > 5 && total > 0.0);
    assert!(
        err <= 1e-2 * total,
        "Σ|analytic − fd| {err:.3e} vs Σ|fd| {total:.3e}"
    );
}

#[test]
fn non_finite_material_terms_are_dropped_and_counted() {
    let scene = scene();
    let mut table = ParamTable::new(&scene);
    table.add("box.albedo.r").expect("valid key");
    let motion = table.motion(&table.values());
    let model = ColourModel::new(&table, &scene, None);
    let mut skipped = DropCounts::default();
    let mut entries = Vec::new();
    for mut r in records(&scene) {
        r.escaped = Vec3::NAN;
        r.vertices
            .iter_mut()
            .for_each(|v| v.contribution = Vec3::NAN);
        entries.extend(model.gradient(&r, &scene, &motion, &mut skipped));
    }
    assert!(entries.iter().all(|(_, d)| d.is_finite()));
    assert!(skipped.get(epsm_core::DropReason::NonFinite) > 0);
}
