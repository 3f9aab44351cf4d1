//! The caustic receiver's constraint against the alternative "the last chain
//! segment toward the light keeps its world direction" (docs/design.md §5.3).
//!
//! Measured on camera → D (plane) → S (flat mirror) → L (emitter), both
//! variants re-solved onto `C = 0` and differentiated in forward mode:
//! - moving the light or the receiver along its normal: identical `dp/dθ`
//!   (a fixed specular chain maps the direction at its receiver end one to
//!   one onto the direction at its light end, so fixing either is the same);
//! - rotating the receiver: different (the receiver constraint turns the
//!   incoming direction with the receiver's frame; the segment variant does not);
//! - rotating the mirror: different (the receiver constraint keeps the
//!   direction arriving at D, the segment variant the one leaving L).
//!   We keep the receiver constraint: it describes what a caustic on a moving
//!   receiver does (the pattern rides with the surface).

use epsm_render::lights::Background;
use epsm_render::materials::{Bsdf, Conductor, Diffuse, Lobe, Material, Texture, VertexKind};
use epsm_render::record::{PathRecord, TrianglePoint, VertexRecord};
use epsm_render::scene::{Mesh, Object, RenderSettings, SceneParts, Surface};
use epsm_render::{Camera, Scene};
use glam::{DAffine3, DVec3, Vec3};
use std::sync::Arc;

use super::{Constraint, ConstraintKind};
use crate::frame::BaseFrame;
use crate::newton::{NewtonSettings, project};
use crate::paths::{PathKind, classify};
use crate::{ParamTable, SolveSettings, solve_forward};

/// A one-triangle object in the plane through `c` with normal `n`, `c` at
/// barycentrics (1/4, 1/4).
fn object(c: DVec3, n: DVec3, id: u32, emission: Option<Vec3>) -> Object {
    let (u, v) = epsm_render::frame::basis_f64(n);
    let positions = [c - u - v, c + 3.0 * u - v, c - u + 3.0 * v]
        .map(|p| p.as_vec3())
        .to_vec();
    Object {
        name: format!("o{id}"),
        mesh: Arc::new(Mesh {
            positions,
            normals: Vec::new(),
            uvs: Vec::new(),
            indices: vec![[0, 1, 2]],
        }),
        world_from_object: DAffine3::IDENTITY,
        material: id,
        emission,
        surface: Surface::Mesh,
    }
}

fn vertex(id: u32, p: DVec3, kind: VertexKind, lobe: Lobe) -> VertexRecord {
    VertexRecord {
        at: TrianglePoint {
            object: id,
            triangle: 0,
            b1: 0.25,
            b2: 0.25,
        },
        p: p.as_vec3(),
        ng: Vec3::Z,
        ns: Vec3::Z,
        kind,
        lobe: Some(lobe),
        eta: 1.0,
        m: Vec3::Z,
        throughput: Vec3::ONE,
        contribution: Vec3::ONE,
    }
}

#[test]
fn receiver_and_segment_constraints_agree_unless_the_receiver_rotates_or_the_chain_moves() {
    let (d, s, l) = (
        DVec3::ZERO,
        DVec3::new(0.5, 0.0, 1.0),
        DVec3::new(1.5, 0.25, 1.5),
    );
    let mirror_n = ((d - s).normalize() + (l - s).normalize()).normalize();
    let diffuse = |name: &str| Material {
        name: name.into(),
        bsdf: Bsdf::Diffuse(Diffuse {
            albedo: Texture::Constant(Vec3::ONE),
        }),
        two_sided: true,
    };
    let mirror = Material {
        name: "mirror".into(),
        bsdf: Bsdf::Conductor(Conductor { tint: Vec3::ONE }),
        two_sided: true,
    };
    let camera =
        Camera::look_at(DVec3::new(-1.0, 0.5, 2.0), d, DVec3::Y, 40.0, 64, 64).expect("camera");
    let film = camera.project(d).expect("visible").as_vec2();
    let scene = Scene::new(SceneParts {
        camera,
        materials: vec![diffuse("floor"), mirror, diffuse("lamp")],
        objects: vec![
            object(d, DVec3::Z, 0, None),
            object(s, mirror_n, 1, None),
            object(l, (s - l).normalize(), 2, Some(Vec3::ONE)),
        ],
        point_lights: Vec::new(),
        background: Background::Constant(Vec3::ZERO),
        settings: RenderSettings::default(),
        source: None,
    })
    .expect("scene");
    let record = PathRecord {
        film,
        vertices: vec![
            vertex(0, d, VertexKind::Diffuse, Lobe::DiffuseReflection),
            vertex(1, s, VertexKind::Specular, Lobe::SpecularReflection),
            vertex(2, l, VertexKind::Diffuse, Lobe::DiffuseReflection),
        ],
        ..PathRecord::default()
    };
    let mut table = ParamTable::new(&scene);
    for key in [
        "o2.translate.x",
        "o0.translate.z",
        "o0.rotate.x",
        "o1.rotate.y",
    ] {
        table.add(key).expect("key");
    }
    let motion = table.motion(&table.values());
    let settings = SolveSettings::for_radius(1.0);
    let paths = classify(&record, &scene, &motion, &settings).paths;
    let receiver = paths
        .iter()
        .find(|p| p.kind == PathKind::Caustic)
        .expect("caustic");
    let mut segment = receiver.clone();
    segment.constraints[0] = Constraint {
        kind: ConstraintKind::Segment { c: [0.0, 0.0] },
        frame: BaseFrame::new((l - s).normalize()),
        nodes: [2, 1, 3],
    };
    let jac = |p| {
        let p = project(p, &motion, &settings, &NewtonSettings::default()).expect("re-solved");
        solve_forward(&p, &motion, &settings)
            .expect("solved")
            .columns
    };
    let (a, b) = (jac(receiver), jac(&segment));
    let rel = |i: usize| (a[i] - b[i]).length() / a[i].length().max(b[i].length());
    // Agreement up to the f32 rounding of the record the two variants start from.
    assert!(
        rel(0) < 1e-6 && rel(1) < 1e-6,
        "light move, receiver translation: {} {}",
        rel(0),
        rel(1)
    );
    assert!(
        rel(2) > 1e-2 && rel(3) > 1e-2,
        "receiver / mirror rotation: {} {}",
        rel(2),
        rel(3)
    );
}
