//! A from-scratch evaluator of recorded path terms for the colour
//! derivative tests: the test scene, vertex placement on the placed meshes
//! (attached, on the camera ray, or on a mirror's or glass's scattered ray),
//! and each term's product of factors (`Material::eval`, cosines, `1/r²`,
//! area, delta weights; the escaped radiance along its recorded direction).
#![allow(dead_code)]

use std::path::Path;

use epsm_render::frame::Frame;
use epsm_render::lights::LightPoint;
use epsm_render::materials::fresnel::fresnel_dielectric;
use epsm_render::materials::{Bsdf, Lobe};
use epsm_render::record::{PathRecord, RecordLevel, TrianglePoint, VertexRecord};
use epsm_render::tracer::{RenderOptions, render_recorded};
use epsm_render::{Camera, Scene};
use epsm_scene::load::parts_from_str;
use glam::{DVec3, Vec2, Vec3};

/// A floor, a diffuse box, a smooth diffuse ball, a rough metal panel, a
/// glass ball, a mirror, an area light and a point light, under a dim sky.
pub const SCENE: &str = r#"
[camera]
origin = [0.3, 2.2, 3.6]
target = [0.0, 0.4, 0.0]
fov = 50.0
resolution = [20, 20]

[render]
spp = 4
max_depth = 4

[background]
color = [0.2, 0.2, 0.25]

[materials.floor]
type = "diffuse"
albedo = [0.6, 0.5, 0.4]

[materials.paint]
type = "diffuse"
albedo = [0.3, 0.6, 0.3]

[materials.metal]
type = "rough_conductor"
alpha = 0.3
tint = [0.9, 0.8, 0.7]

[materials.glass]
type = "dielectric"
ior = 1.5

[materials.mirror]
type = "conductor"
tint = [0.9, 0.9, 0.9]

[materials.lamp]
type = "diffuse"
albedo = [0.0, 0.0, 0.0]

[[objects]]
name = "floor"
shape = "rectangle"
material = "floor"
scale = 3.0
rotate = [{ axis = [1, 0, 0], angle = -90 }]

[[objects]]
name = "box"
shape = "cube"
material = "paint"
scale = 0.35
rotate = [{ axis = [0, 1, 0], angle = 25 }]
translate = [-0.2, 0.35, 0.0]

[[objects]]
name = "ball"
shape = "sphere"
material = "paint"
scale = 0.3
translate = [0.8, 0.3, 0.5]

[[objects]]
name = "panel"
shape = "rectangle"
material = "metal"
scale = 0.6
rotate = [{ axis = [0, 1, 0], angle = 20 }]
translate = [-0.6, 0.6, -1.0]

[[objects]]
name = "glass"
shape = "sphere"
material = "glass"
scale = 0.25
translate = [0.9, 0.25, -0.6]

[[objects]]
name = "mirror"
shape = "rectangle"
material = "mirror"
scale = 0.6
rotate = [{ axis = [0, 1, 0], angle = -35 }]
translate = [1.1, 0.7, -1.3]

[[objects]]
name = "lamp"
shape = "rectangle"
material = "lamp"
emission = [6.0, 6.0, 6.0]
scale = 0.5
rotate = [{ axis = [1, 0, 0], angle = 80 }]
translate = [0.3, 2.4, 0.3]

[[lights]]
name = "bulb"
type = "point"
position = [-1.0, 1.6, 1.2]
intensity = [1.5, 1.5, 1.5]
"#;

pub fn scene() -> Scene {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("colour.toml");
    Scene::new(parts_from_str(SCENE, &file).expect("scene parses")).expect("scene builds")
}

/// Position and unit shading normal of a triangle point, f64, from the
/// placed mesh.
pub fn place(scene: &Scene, at: &TrianglePoint) -> (DVec3, DVec3) {
    let o = &scene.objects()[at.object as usize];
    let (b1, b2) = (f64::from(at.b1), f64::from(at.b2));
    point(scene, at.object, at.triangle, b1, b2, o.world_from_object)
}

pub fn point(
    scene: &Scene,
    object: u32,
    tri: u32,
    b1: f64,
    b2: f64,
    m: glam::DAffine3,
) -> (DVec3, DVec3) {
    let mesh = &scene.objects()[object as usize].mesh;
    let idx = mesh.indices[tri as usize];
    let p = idx.map(|i| mesh.positions[i as usize].as_dvec3());
    let x = m.transform_point3(p[0] + (p[1] - p[0]) * b1 + (p[2] - p[0]) * b2);
    let n_obj = if mesh.normals.is_empty() {
        (p[1] - p[0]).cross(p[2] - p[0])
    } else {
        let n = idx.map(|i| mesh.normals[i as usize].as_dvec3());
        n[0] + (n[1] - n[0]) * b1 + (n[2] - n[0]) * b2
    };
    (x, (m.matrix3.inverse().transpose() * n_obj).normalize())
}

/// The point of `at`'s triangle (placed now) on the camera ray through `film`.
pub fn on_ray(scene: &Scene, at: &TrianglePoint, film: Vec2) -> (DVec3, DVec3) {
    let cam: &Camera = scene.camera();
    let th = (0.5 * cam.fov_y).tan();
    let (w, h) = (f64::from(cam.width), f64::from(cam.height));
    let sx = (2.0 * f64::from(film.x) / w - 1.0) * th * w / h;
    let sy = (1.0 - 2.0 * f64::from(film.y) / h) * th;
    hit(
        scene,
        at,
        cam.origin,
        cam.forward + cam.right * sx + cam.up * sy,
    )
}

/// The point of `at`'s triangle plane (placed now) on the ray `o + t d`.
pub fn hit(scene: &Scene, at: &TrianglePoint, o: DVec3, d: DVec3) -> (DVec3, DVec3) {
    let obj = &scene.objects()[at.object as usize];
    let m = obj.world_from_object;
    let idx = obj.mesh.indices[at.triangle as usize];
    let p = idx.map(|i| m.transform_point3(obj.mesh.positions[i as usize].as_dvec3()));
    // Möller–Trumbore in f64.
    let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
    let q = d.cross(e2);
    let det = e1.dot(q);
    let s = o - p[0];
    let b1 = s.dot(q) / det;
    let b2 = d.dot(s.cross(e1)) / det;
    point(scene, at.object, at.triangle, b1, b2, m)
}

/// Mirror reflection or Snell refraction (relative IOR `eta`) of the unit
/// `wi` (away from the surface) at unit normal `n`.
pub fn scatter(wi: DVec3, n: DVec3, eta: f64, transmit: bool) -> DVec3 {
    if !transmit {
        return 2.0 * n.dot(wi) * n - wi;
    }
    let n = if n.dot(wi) >= 0.0 { n } else { -n };
    let c = n.dot(wi);
    let ct = (1.0 - (1.0 - c * c) / (eta * eta)).sqrt();
    -wi / eta + (c / eta - ct) * n
}

/// The weight of a delta lobe over its choice probability at `x` (normal
/// `n`) for light arriving from `a`.
pub fn delta_weight(scene: &Scene, v: &VertexRecord, x: DVec3, n: DVec3, a: DVec3) -> f32 {
    let m = &scene.materials()[scene.objects()[v.at.object as usize].material as usize];
    let Bsdf::Dielectric(d) = &m.bsdf else {
        return 1.0;
    };
    let c = n.dot((a - x).normalize()) as f32;
    if v.lobe == Some(Lobe::SpecularTransmission) {
        1.0 - fresnel_dielectric(c.abs(), v.eta)
    } else {
        fresnel_dielectric(c.abs(), if c >= 0.0 { d.ior } else { 1.0 / d.ior })
    }
}

/// `f·|cos_o|` of the vertex material at `x` (normal `n`) from `a` to `b`.
pub fn eval(scene: &Scene, object: u32, x: DVec3, n: DVec3, a: DVec3, b_dir: DVec3) -> Vec3 {
    let m = &scene.materials()[scene.objects()[object as usize].material as usize];
    let f = Frame::from_normal(n.as_vec3());
    let wi = f.to_local((a - x).normalize().as_vec3());
    m.eval(wi, f.to_local(b_dir.as_vec3()), Vec2::ZERO)
}

/// Area scale of object `o`'s placement (uniform scale squared).
pub fn area(scene: &Scene, o: u32) -> f64 {
    scene.objects()[o as usize]
        .world_from_object
        .matrix3
        .determinant()
        .abs()
        .powf(2.0 / 3.0)
}

/// The factor products of every term of `record` in the scene as placed now.
pub fn terms(scene: &Scene, r: &PathRecord, on_camera_ray: bool) -> Vec<Vec3> {
    let v = &r.vertices;
    let mut x: Vec<(DVec3, DVec3)> = vec![(scene.camera().origin, DVec3::ZERO)];
    let delta = |i: usize| v[i].lobe.filter(|l| l.is_delta());
    for (i, vr) in v.iter().enumerate() {
        x.push(if i == 0 && on_camera_ray {
            on_ray(scene, &vr.at, r.film)
        } else if let (true, Some(lobe)) = (on_camera_ray, delta(i.saturating_sub(1))) {
            let (p, n) = x[i];
            let wi = (x[i - 1].0 - p).normalize();
            let d = scatter(wi, n, f64::from(v[i - 1].eta), lobe.is_transmission());
            hit(scene, &vr.at, p, d)
        } else {
            place(scene, &vr.at)
        });
    }
    let mut out = Vec::new();
    let mut prefix = Vec3::ONE;
    for j in 1..x.len() {
        let (p, n) = x[j];
        let obj = v[j - 1].at.object;
        out.push(prefix);
        for c in r.connections.iter().filter(|c| c.vertex as usize == j - 1) {
            let g = match c.light {
                LightPoint::Area {
                    object,
                    triangle,
                    b1,
                    b2,
                } => {
                    let (y, nl) = place(
                        scene,
                        &TrianglePoint {
                            object,
                            triangle,
                            b1,
                            b2,
                        },
                    );
                    let d = y - p;
                    let e = eval(scene, obj, p, n, x[j - 1].0, d.normalize());
                    e * (nl.dot(d).abs() / d.length().powi(3) * area(scene, object)) as f32
                }
                LightPoint::Point { index } => {
                    let d = scene.point_lights()[index as usize].position - p;
                    eval(scene, obj, p, n, x[j - 1].0, d.normalize()) / d.length_squared() as f32
                }
                LightPoint::Background => {
                    eval(scene, obj, p, n, x[j - 1].0, c.light_position.as_dvec3())
                }
            };
            out.push(prefix * g);
        }
        if delta(j - 1).is_some() {
            prefix *= delta_weight(scene, &v[j - 1], p, n, x[j - 1].0);
        } else if let Some(&(q, nq)) = x.get(j + 1) {
            let d = q - p;
            let e = eval(scene, obj, p, n, x[j - 1].0, d.normalize());
            let next = v[j].at.object;
            prefix *= e * (nq.dot(d).abs() / d.length().powi(3) * area(scene, next)) as f32;
        } else if r.escaped != Vec3::ZERO {
            // The escaped ray keeps its world direction.
            prefix *= eval(scene, obj, p, n, x[j - 1].0, r.escape_dir.as_dvec3());
        }
    }
    out.push(prefix);
    out
}

/// The record's term values, in [`terms`] order.
pub fn term_values(r: &PathRecord) -> Vec<Vec3> {
    let mut out = Vec::new();
    for (i, vr) in r.vertices.iter().enumerate() {
        let conns: Vec<Vec3> = r
            .connections
            .iter()
            .filter(|c| c.vertex as usize == i)
            .map(|c| c.contribution)
            .collect();
        out.push(vr.contribution - conns.iter().sum::<Vec3>());
        out.extend(conns);
    }
    out.push(r.escaped);
    out
}

pub fn records(scene: &Scene) -> Vec<PathRecord> {
    let opts = RenderOptions::from_scene(scene);
    render_recorded(scene, &opts, RecordLevel::Full, &|_| {}).1
}
