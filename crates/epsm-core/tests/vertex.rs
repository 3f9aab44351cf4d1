//! The tangent parameterisation agrees with the renderer's exact `f64`
//! surface points (triangles) or the placed ellipsoid (exact spheres), and
//! its `u`- and θ-derivatives with finite differences.

mod common;

use std::sync::Arc;

use common::builder::diffuse;
use common::{End, OBJECT_FIELDS, Rng, Spec, Vertex, build};
use epsm_core::vertex::{Anchor, VertexState};
use epsm_core::{ParamTable, PathKind};
use epsm_render::hit::surface_point_f64;
use epsm_render::lights::Background;
use epsm_render::scene::{Mesh, Object, RenderSettings, SceneParts, Surface};
use epsm_render::sphere::local_coords;
use epsm_render::{Camera, Scene};
use glam::{DAffine3, DMat3, DQuat, DVec3, Vec3};

#[test]
fn anchors_match_render_surface_points_and_their_u_derivatives() {
    let mut rng = Rng::new(3);
    let mut checked = 0;
    while checked < 300 {
        let spec = Spec::new(
            PathKind::Caustic,
            vec![Vertex::Mirror, Vertex::Glass { ior: 1.5 }],
            End::Emitter,
        );
        let Some(s) = build(&spec, &mut rng) else {
            continue;
        };
        let motion = s.table.motion(&s.table.values());
        for v in &s.record.vertices {
            let (id, object) = (v.at.object, &s.scene.objects()[v.at.object as usize]);
            let (b1, b2) = (f64::from(v.at.b1), f64::from(v.at.b2));
            let om = motion.object(id);
            let anchor =
                Anchor::new(object, id, v.at.triangle, b1, b2, om).expect("regular triangle");
            let at = anchor.eval(om, [0.0, 0.0]);
            let sp = surface_point_f64(object, v.at.triangle, b1, b2);
            assert!(at.x.distance(sp.p) < 1e-12 * (1.0 + sp.p.length()));
            assert!(at.n.dot(sp.ns) > 1.0 - 1e-12, "{} vs {}", at.n, sp.ns);
            // Orthonormal in-plane tangents at θ₀; normals move as finite differences say.
            assert!(
                (at.dx_du[0].length() - 1.0).abs() < 1e-12
                    && at.dx_du[0].dot(at.dx_du[1]).abs() < 1e-12
            );
            let h = 1e-6;
            for k in 0..2 {
                let mut du = [0.0; 2];
                du[k] = h;
                let (p, m) = (anchor.eval(om, du), anchor.eval(om, du.map(|d| -d)));
                assert!(((p.x - m.x) / (2.0 * h) - at.dx_du[k]).length() < 1e-8);
                assert!(
                    ((p.n - m.n) / (2.0 * h) - at.dn_du[k]).length()
                        < 1e-6 * (1.0 + at.dn_du[k].length())
                );
            }
            checked += 1;
        }
    }
}

/// One exact sphere `ball` placed by `m`.
fn sphere_scene(m: DAffine3) -> Scene {
    Scene::new(SceneParts {
        camera: Camera::look_at(DVec3::splat(8.0), DVec3::ZERO, DVec3::Y, 40.0, 16, 16)
            .expect("camera"),
        materials: vec![diffuse()],
        objects: vec![Object {
            name: "ball".into(),
            mesh: Arc::new(Mesh::default()),
            world_from_object: m,
            material: 0,
            emission: None,
            surface: Surface::Sphere,
        }],
        point_lights: Vec::new(),
        background: Background::Constant(Vec3::ZERO),
        settings: RenderSettings::default(),
        source: None,
    })
    .expect("a sphere scene")
}

/// Object-space directions: random, the poles and axes, and points just
/// off the octahedral seams (the equator between the halves, the folded
/// diagonals `x = 0`, `y = 0` of the lower half).
fn sphere_directions(rng: &mut Rng) -> Vec<DVec3> {
    let mut dirs: Vec<DVec3> = (0..40).map(|_| rng.unit()).collect();
    for e in [1e-9, -1e-9, 0.0] {
        dirs.extend([
            DVec3::new(0.6, -0.8, e),
            DVec3::new(e, 0.3, -1.0),
            DVec3::new(-0.5, e, -0.7),
            DVec3::new(e, e, 1.0),
            DVec3::new(e, e, -1.0),
            DVec3::new(1.0, e, e),
        ]);
    }
    dirs.into_iter().map(DVec3::normalize).collect()
}

fn assert_close(a: DVec3, b: DVec3, tol: f64, what: &str) {
    assert!((a - b).length() <= tol, "{what}: {a} vs {b}");
}

/// Anchors on exact spheres under non-uniform, possibly mirroring
/// placements: points on the placed ellipsoid with its outward normal,
/// orthonormal tangents at θ₀, `u`- and θ-derivatives that match central
/// differences, and shifts that compose.
#[test]
fn sphere_anchors_stay_on_the_ellipsoid_and_their_derivatives_match_differences() {
    let mut rng = Rng::new(11);
    let mut checked = 0;
    for _ in 0..12 {
        let rot = DQuat::from_axis_angle(rng.unit(), rng.range(0.0, 3.0));
        let mut scale = DVec3::new(
            rng.range(0.5, 2.0),
            rng.range(0.5, 2.0),
            rng.range(0.5, 2.0),
        );
        if rng.below(3) == 0 {
            scale.y = -scale.y;
        }
        let file = DAffine3::from_mat3_translation(
            DMat3::from_quat(rot) * DMat3::from_diagonal(scale),
            rng.dvec3(-2.0, 2.0),
        );
        let scene = sphere_scene(file);
        let object = &scene.objects()[0];
        let mut table = ParamTable::new(&scene);
        for key in OBJECT_FIELDS {
            table.add(&format!("ball.{key}")).expect("key");
        }
        // A configuration away from the file placement.
        for (i, p) in table.params().to_vec().iter().enumerate() {
            let step = if p.key.contains("rotate") { 20.0 } else { 0.3 };
            table.set_value(i, p.value + rng.range(-step, step));
        }
        let values = table.values();
        let motion = table.motion(&values);
        let om = motion.object(0);
        assert_eq!(Anchor::new(object, 0, 0, f64::NAN, 0.5, om), None);
        let centre = om.translation;
        let inv = om.linear.inverse();
        for d in sphere_directions(&mut rng) {
            let [b1, b2] = local_coords(d);
            let anchor = Anchor::new(object, 0, 7, b1, b2, om).expect("regular sphere point");
            let at = anchor.eval(om, [0.0; 2]);
            assert_close(inv * (at.x - centre), d, 1e-12, "the recorded point");
            assert!(
                (at.dx_du[0].length() - 1.0).abs() < 1e-12
                    && (at.dx_du[1].length() - 1.0).abs() < 1e-12
                    && at.dx_du[0].dot(at.dx_du[1]).abs() < 1e-12,
                "orthonormal tangents at θ₀: {:?}",
                at.dx_du
            );
            let check_state = |vs: &VertexState| {
                let p = inv * (vs.x - centre);
                assert!((p.length() - 1.0).abs() < 1e-12, "off the ellipsoid: |{p}|");
                assert_close(vs.n, (om.normal * p).normalize(), 1e-12, "normal");
                assert!(vs.n.dot(vs.x - centre) > 0.0, "inward normal");
                for t in vs.dx_du {
                    assert!(t.dot(vs.n).abs() < 1e-12 * t.length(), "tangent off plane");
                }
            };
            for _ in 0..3 {
                let u = [rng.range(-0.6, 0.6), rng.range(-0.6, 0.6)];
                let vs = anchor.eval(om, u);
                check_state(&vs);
                // Central differences in u.
                let h = 1e-6;
                for k in 0..2 {
                    let (mut up, mut um) = (u, u);
                    up[k] += h;
                    um[k] -= h;
                    let (p, m) = (anchor.eval(om, up), anchor.eval(om, um));
                    assert_close((p.x - m.x) / (2.0 * h), vs.dx_du[k], 1e-8, "dx/du");
                    assert_close(
                        (p.n - m.n) / (2.0 * h),
                        vs.dn_du[k],
                        1e-7 * (1.0 + vs.dn_du[k].length()),
                        "dn/du",
                    );
                }
                // Central differences in θ at fixed u, for each parameter.
                for g in &om.grads {
                    let [dx, dn] = Anchor::dtheta(&vs, g);
                    let h = if table.params()[g.param].key.contains("rotate") {
                        1e-4
                    } else {
                        1e-6
                    };
                    let at_value = |v: f64| {
                        let mut vals = values.clone();
                        vals[g.param] = v;
                        anchor.eval(table.motion(&vals).object(0), u)
                    };
                    let (p, m) = (at_value(values[g.param] + h), at_value(values[g.param] - h));
                    let key = &table.params()[g.param].key;
                    let tol = 1e-7 * (1.0 + dx.length() + dn.length());
                    assert_close((p.x - m.x) / (2.0 * h), dx, tol, key);
                    assert_close((p.n - m.n) / (2.0 * h), dn, tol, key);
                }
                // Shifting composes: the shifted anchor at u' is this one at u + u'.
                let u2 = [rng.range(-0.4, 0.4), rng.range(-0.4, 0.4)];
                let (a, b) = (
                    anchor.shifted(u).eval(om, u2),
                    anchor.eval(om, [u[0] + u2[0], u[1] + u2[1]]),
                );
                check_state(&a);
                assert_close(a.x, b.x, 1e-12, "shifted x");
                assert_close(a.n, b.n, 1e-12, "shifted n");
                for k in 0..2 {
                    assert_close(a.dx_du[k], b.dx_du[k], 1e-12, "shifted dx/du");
                    assert_close(a.dn_du[k], b.dn_du[k], 1e-12, "shifted dn/du");
                }
                checked += 1;
            }
        }
    }
    assert!(checked > 2000, "{checked}");
}

/// An exact sphere's default pivot is its centre (its mesh is empty: the
/// placement's translation), so rotating and scaling it keep the centre.
#[test]
fn a_sphere_rotates_and_scales_about_its_centre() {
    let file = DAffine3::from_mat3_translation(
        DMat3::from_diagonal(DVec3::new(1.0, 2.0, 0.5)),
        DVec3::new(1.0, -2.0, 3.0),
    );
    let mut table = ParamTable::new(&sphere_scene(file));
    for (key, v) in [
        ("ball.rotate.x", 30.0),
        ("ball.rotate.z", -50.0),
        ("ball.scale", 1.7),
    ] {
        let i = table.add(key).expect("key");
        table.set_value(i, v);
    }
    let motion = table.motion(&table.values());
    assert_close(
        motion.object(0).translation,
        file.translation,
        1e-12,
        "centre",
    );
}
