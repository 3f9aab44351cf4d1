//! The material test battery: every non-delta material gets
//! the same checks of `sample` against `eval` and `pdf`; delta materials get
//! their energy and direction checks.

use glam::{Vec2, Vec3};

use super::test_support::{
    Rng, assert_chi2, expected_counts, histogram, integrate_sphere, spherical,
};
use super::*;

fn material(bsdf: Bsdf, two_sided: bool) -> Material {
    Material {
        name: "m".into(),
        bsdf,
        two_sided,
    }
}

fn diffuse(albedo: Vec3) -> Bsdf {
    Bsdf::Diffuse(Diffuse {
        albedo: Texture::Constant(albedo),
    })
}

fn rough(alpha: f32, tint: Vec3) -> Bsdf {
    Bsdf::RoughConductor(RoughConductor { alpha, tint })
}

/// Every non-delta material of the battery, one- and two-sided.
fn non_delta_materials() -> Vec<(String, Material)> {
    let tint = Vec3::new(1.0, 0.8, 0.5);
    let mut out = Vec::new();
    for two_sided in [false, true] {
        out.push((
            format!("diffuse two_sided={two_sided}"),
            material(diffuse(Vec3::new(0.9, 0.5, 0.2)), two_sided),
        ));
        for alpha in [0.1, 0.3, 0.6, 1.0] {
            out.push((
                format!("ggx α={alpha} two_sided={two_sided}"),
                material(rough(alpha, tint), two_sided),
            ));
        }
    }
    out
}

/// Incident directions from grazing to normal, on the front (and back) side.
fn incident_directions(two_sided: bool) -> Vec<Vec3> {
    let mut out: Vec<Vec3> = [0.05f64, 0.3, 0.7, 1.0]
        .iter()
        .map(|&mu| spherical(mu.acos(), 0.4))
        .collect();
    if two_sided {
        out.push(spherical(2.2, 1.0));
    }
    out
}

fn rel_close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol * a.abs().max(b.abs()).max(1e-6)
}

#[test]
fn sampled_weight_equals_eval_over_pdf_and_pdf_matches() {
    let mut rng = Rng::new(1);
    for (name, m) in non_delta_materials() {
        for _ in 0..2000 {
            let wi = rng.sphere();
            let s = m.sample(wi, Vec2::ZERO, rng.f32(), rng.vec2());
            if wi.z < 0.0 && !m.two_sided {
                assert!(s.is_none(), "{name}: back face of a one-sided material");
                assert_eq!(m.eval(wi, rng.sphere(), Vec2::ZERO), Vec3::ZERO);
                continue;
            }
            let Some(s) = s else { continue };
            assert!(!s.lobe.is_delta() && (s.wo.length() - 1.0).abs() < 1e-4);
            assert!(
                s.wo.z * wi.z > 0.0,
                "{name}: reflection stays on the side of wi"
            );
            let pdf = m.pdf(wi, s.wo, Vec2::ZERO);
            let eval = m.eval(wi, s.wo, Vec2::ZERO);
            assert!(
                rel_close(pdf, s.pdf, 2e-3),
                "{name}: pdf {pdf} vs sampled {}",
                s.pdf
            );
            for c in 0..3 {
                assert!(
                    rel_close(eval[c] / s.pdf, s.weight[c], 2e-3),
                    "{name}: wi {wi} wo {} eval/pdf {} weight {}",
                    s.wo,
                    eval / s.pdf,
                    s.weight
                );
            }
            assert_eq!(s.eta, 1.0);
        }
    }
}

#[test]
fn pdf_integrates_to_the_probability_that_sampling_succeeds() {
    let mut rng = Rng::new(2);
    for (name, m) in non_delta_materials() {
        for wi in incident_directions(m.two_sided) {
            let integral = integrate_sphere(400, |wo| m.pdf(wi, wo, Vec2::ZERO) as f64);
            let n = 20_000;
            let ok = (0..n)
                .filter(|_| m.sample(wi, Vec2::ZERO, rng.f32(), rng.vec2()).is_some())
                .count() as f64
                / n as f64;
            let se = (ok * (1.0 - ok) / n as f64).sqrt();
            assert!(integral <= 1.0 + 3e-3, "{name} wi {wi}: ∫pdf = {integral}");
            assert!(
                (integral - ok).abs() <= 3.0 * se + 3e-3,
                "{name} wi {wi}: ∫pdf = {integral}, sampling succeeds with {ok}"
            );
            if let Bsdf::Diffuse(_) = m.bsdf {
                assert!((integral - 1.0).abs() < 1e-3, "{name}: no mass lost");
            }
        }
    }
}

#[test]
fn chi2_sampling_matches_pdf() {
    let mut rng = Rng::new(3);
    let n = 200_000;
    let materials = non_delta_materials();
    let tests = materials.len() * 3;
    for (name, m) in materials {
        for wi in [
            spherical(0.3, 0.0),
            spherical(1.3, 0.5),
            spherical(2.0, 1.0),
        ] {
            if wi.z < 0.0 && !m.two_sided {
                continue;
            }
            let observed = histogram(n, || {
                m.sample(wi, Vec2::ZERO, rng.f32(), rng.vec2())
                    .map(|s| s.wo)
            });
            let expected = expected_counts(n, 8, |wo| m.pdf(wi, wo, Vec2::ZERO) as f64);
            assert_chi2(&format!("{name} wi {wi}"), &observed, &expected, tests);
        }
    }
}

#[test]
fn eval_is_reciprocal() {
    let mut rng = Rng::new(4);
    for (name, m) in non_delta_materials() {
        for _ in 0..5000 {
            let (wi, wo) = (rng.sphere(), rng.sphere());
            let a = m.eval(wi, wo, Vec2::ZERO) / wo.z.abs();
            let b = m.eval(wo, wi, Vec2::ZERO) / wi.z.abs();
            for c in 0..3 {
                assert!(rel_close(a[c], b[c], 1e-3), "{name}: {wi} {wo}: {a} vs {b}");
            }
        }
    }
}

#[test]
fn white_diffuse_furnace_weight_is_one() {
    let mut rng = Rng::new(5);
    let m = material(diffuse(Vec3::ONE), false);
    let mut sum = 0.0f64;
    let n = 10_000;
    for _ in 0..n {
        let wi = spherical((rng.f32() as f64).acos(), 0.0);
        let s = m.sample(wi, Vec2::ZERO, rng.f32(), rng.vec2());
        sum += s.map_or(0.0, |s| s.weight.x as f64);
    }
    assert!(
        (sum / n as f64 - 1.0).abs() < 1e-6,
        "mean weight {}",
        sum / n as f64
    );
}

#[test]
fn back_face_of_two_sided_material_mirrors_the_front() {
    let m = material(rough(0.3, Vec3::ONE), true);
    let front = m
        .sample(
            Vec3::new(0.6, 0.0, 0.8),
            Vec2::ZERO,
            0.5,
            Vec2::new(0.3, 0.6),
        )
        .expect("front sample");
    let back = m
        .sample(
            Vec3::new(0.6, 0.0, -0.8),
            Vec2::ZERO,
            0.5,
            Vec2::new(0.3, 0.6),
        )
        .expect("back sample");
    assert_eq!(back.wo, Vec3::new(front.wo.x, front.wo.y, -front.wo.z));
    assert_eq!(back.m, Vec3::new(front.m.x, front.m.y, -front.m.z));
    assert_eq!(back.weight, front.weight);
    let one_sided = material(rough(0.3, Vec3::ONE), false);
    assert!(
        one_sided
            .sample(Vec3::new(0.6, 0.0, -0.8), Vec2::ZERO, 0.5, Vec2::ONE * 0.5)
            .is_none()
    );
    assert_eq!(
        one_sided.pdf(Vec3::new(0.6, 0.0, -0.8), -Vec3::Z, Vec2::ZERO),
        0.0
    );
}

#[test]
fn smooth_conductor_reflects_with_tint() {
    let tint = Vec3::new(0.9, 0.5, 0.1);
    let m = material(Bsdf::Conductor(Conductor { tint }), false);
    let wi = Vec3::new(0.48, 0.6, 0.64);
    let s = m
        .sample(wi, Vec2::ZERO, 0.3, Vec2::new(0.1, 0.2))
        .expect("mirror");
    assert_eq!(s.wo, Vec3::new(-0.48, -0.6, 0.64));
    assert_eq!(
        (s.weight, s.pdf, s.lobe),
        (tint, 1.0, Lobe::SpecularReflection)
    );
    assert!((wi + s.wo).normalize().distance(s.m) < 1e-6);
    assert_eq!(m.eval(wi, s.wo, Vec2::ZERO), Vec3::ZERO);
    assert_eq!(m.pdf(wi, s.wo, Vec2::ZERO), 0.0);
    assert!(m.is_delta() && m.vertex_kind() == VertexKind::Specular);
    assert!(
        m.sample(-wi, Vec2::ZERO, 0.3, Vec2::ZERO).is_none(),
        "one-sided"
    );
}

#[test]
fn diffuse_reads_its_albedo_texture_at_uv() {
    let mut image = crate::film::Image::new(2, 1);
    image.set(0, 0, Vec3::new(0.9, 0.1, 0.1));
    image.set(1, 0, Vec3::new(0.1, 0.1, 0.9));
    let albedo = Texture::Image(std::sync::Arc::new(image));
    let m = material(Bsdf::Diffuse(Diffuse { albedo }), false);
    let (wi, u) = (Vec3::Z, Vec2::new(0.4, 0.3));
    for (uv, texel) in [
        (Vec2::new(0.25, 0.5), Vec3::new(0.9, 0.1, 0.1)),
        (Vec2::new(0.75, 0.5), Vec3::new(0.1, 0.1, 0.9)),
    ] {
        let s = m.sample(wi, uv, 0.5, u).expect("diffuse sample");
        assert!(s.weight.distance(texel) < 1e-6);
        let f = m.eval(wi, s.wo, uv);
        assert!((f / s.pdf).distance(texel) < 1e-5);
    }
}

#[test]
fn zero_roughness_is_clamped_instead_of_producing_nan() {
    let m = material(rough(0.0, Vec3::ONE), false);
    let wi = Vec3::new(0.6, 0.0, 0.8);
    let s = m
        .sample(wi, Vec2::ZERO, 0.5, Vec2::new(0.2, 0.4))
        .expect("near-mirror sample");
    assert!(
        s.weight.is_finite()
            && s.pdf.is_finite()
            && s.wo.distance(Vec3::new(-0.6, 0.0, 0.8)) < 1e-2
    );
    assert!(m.eval(wi, s.wo, Vec2::ZERO).is_finite());
}

#[test]
fn material_local_directions_give_the_same_results_as_the_full_frame() {
    let mut rng = Rng::new(7);
    let mut all = non_delta_materials();
    all.push((
        "mirror".into(),
        material(Bsdf::Conductor(Conductor { tint: Vec3::ONE }), true),
    ));
    all.push((
        "glass".into(),
        material(Bsdf::Dielectric(Dielectric { ior: 1.5 }), false),
    ));
    for (name, m) in all {
        for _ in 0..500 {
            let frame = Frame::from_normal(rng.sphere());
            let (wi, wo) = (rng.sphere(), rng.sphere());
            let (wi_m, wo_m) = (m.to_local(&frame, wi), m.to_local(&frame, wo));
            let (wi_f, wo_f) = (frame.to_local(wi), frame.to_local(wo));
            let uv = rng.vec2();
            assert_eq!(m.eval(wi_m, wo_m, uv), m.eval(wi_f, wo_f, uv), "{name}");
            assert_eq!(m.pdf(wi_m, wo_m, uv), m.pdf(wi_f, wo_f, uv), "{name}");
            let (u_lobe, u) = (rng.f32(), rng.vec2());
            assert_eq!(
                m.sample(wi_m, uv, u_lobe, u),
                m.sample(wi_f, uv, u_lobe, u),
                "{name}"
            );
        }
    }
}
