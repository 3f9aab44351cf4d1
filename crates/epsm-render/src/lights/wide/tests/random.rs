//! Random light tables for the lane checks: scenes of up to 20 emitters
//! of up to 50 triangles (degenerate ones among them, dark emitters,
//! non-emitters between them), point lights, black, constant and
//! environment-map backgrounds; reference points about the emitters;
//! uniform numbers with their boundary values.

use std::sync::Arc;

use glam::{DAffine3, DMat3, DVec3, Vec3};

use super::super::super::{Background, EnvMap, LightTable, PointLight};
use crate::film::Image;
use crate::scene::{Mesh, Object, Surface};
use crate::simd::Mask16;
use epsm_testkit::Rng;

/// An emissive object of `1..=50` random triangles, about one in six
/// degenerate (a repeated vertex or three collinear ones), under a random
/// affine map (mirroring in about half); dark (zero emission) one time in five.
pub(super) fn emitter(rng: &mut Rng) -> Object {
    let triangles = if rng.below(3) == 0 {
        1 + rng.below(2)
    } else {
        1 + rng.below(50)
    };
    let mut positions = Vec::new();
    for _ in 0..triangles {
        let [a, b] = [
            rng.dvec3(-1.0, 1.0).as_vec3(),
            rng.dvec3(-1.0, 1.0).as_vec3(),
        ];
        let c = match rng.below(6) {
            0 => a,
            1 => a + (b - a) * 0.25,
            _ => rng.dvec3(-1.0, 1.0).as_vec3(),
        };
        positions.extend([a, b, c]);
    }
    let linear = DMat3::from_cols(
        rng.dvec3(-2.0, 2.0),
        rng.dvec3(-2.0, 2.0),
        rng.dvec3(-2.0, 2.0),
    );
    let emission = if rng.below(5) == 0 {
        Vec3::ZERO
    } else {
        rng.dvec3(0.0, 20.0).as_vec3()
    };
    Object {
        name: "emitter".into(),
        mesh: Arc::new(Mesh {
            indices: (0..triangles as u32)
                .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
                .collect(),
            positions,
            normals: Vec::new(),
            uvs: Vec::new(),
        }),
        world_from_object: DAffine3::from_mat3_translation(linear, rng.dvec3(-3.0, 3.0)),
        material: 0,
        emission: Some(emission),
        surface: Surface::Mesh,
    }
}

/// A random scene's light table: 1 to 20 emitters among non-emitters,
/// 0 to 3 point lights (some dark), and a black, constant or
/// environment-map background.
pub(super) fn random_table(rng: &mut Rng) -> LightTable {
    let emitters = if rng.below(2) == 0 {
        1 + rng.below(3)
    } else {
        1 + rng.below(20)
    };
    let mut objects = Vec::new();
    for _ in 0..emitters {
        let mut dark = emitter(rng);
        if rng.below(3) == 0 {
            dark.emission = None;
            objects.push(dark);
        }
        objects.push(emitter(rng));
    }
    let points: Vec<PointLight> = (0..rng.below(4))
        .map(|i| PointLight {
            name: format!("p{i}"),
            // The first light at an `f32` point, which `reference` may pick.
            position: if i == 0 {
                rng.dvec3(-3.0, 3.0).as_vec3().as_dvec3()
            } else {
                rng.dvec3(-3.0, 3.0)
            },
            intensity: if i == 1 {
                Vec3::ZERO
            } else {
                rng.dvec3(0.0, 5.0).as_vec3()
            },
        })
        .collect();
    let background = match rng.below(4) {
        0 => Background::Constant(Vec3::ZERO),
        1 => {
            let mut image = Image::new(12, 6);
            for pixel in &mut image.pixels {
                if rng.below(4) != 0 {
                    *pixel = rng.dvec3(0.0, 3.0).as_vec3();
                }
            }
            Background::EnvMap(Arc::new(EnvMap::new(image, 1.5, rng.f32() * 6.0)))
        }
        _ => Background::Constant(rng.dvec3(0.0, 2.0).as_vec3()),
    };
    let bounds = Some((DVec3::splat(-4.0), DVec3::splat(4.0)));
    LightTable::build(&objects, &points, &background, bounds)
}

/// A point of emitter triangle `(emitter, triangle)` at coordinates `(a, b)`
/// along its edges, moved `h` along its normal.
pub(super) fn emitter_point(
    table: &LightTable,
    emitter: usize,
    triangle: usize,
    [a, b, h]: [f32; 3],
) -> Vec3 {
    let t = &table.area[emitter].triangles()[triangle];
    t.p0 + a * t.e1 + b * t.e2 + h * t.normal
}

/// A reference point: anywhere, at a point light, on an emitter, in its
/// plane, or on either side of it (near and far).
pub(super) fn reference(table: &LightTable, rng: &mut Rng) -> Vec3 {
    let emitters = table.area.len();
    if !table.points.is_empty() && rng.below(8) == 0 {
        // At a point light (no connection when that is the first light).
        return table.points[rng.below(table.points.len())]
            .position
            .as_vec3();
    }
    if emitters == 0 || rng.below(4) == 0 {
        return rng.dvec3(-4.0, 4.0).as_vec3();
    }
    let e = rng.below(emitters);
    let triangles = table.area[e].triangles().len();
    let (t, a) = (rng.below(triangles), rng.f32());
    let b = rng.f32() * (1.0 - a);
    let h = [0.0, 1e-4, -1e-4, 0.3, -0.3, 2.0][rng.below(6)];
    match rng.below(4) {
        0 => emitter_point(table, e, t, [0.0, 0.0, 0.0]),
        1 => emitter_point(table, e, t, [a * 5.0 - 2.0, b * 5.0 - 2.0, 0.0]),
        _ => emitter_point(table, e, t, [a, b, h]),
    }
}

/// A uniform number, sometimes a boundary value (0, −0, ½, 1⁻, 1) or NaN.
pub(super) fn uniform(rng: &mut Rng) -> f32 {
    const SPECIAL: [f32; 7] = [
        0.0,
        -0.0,
        0.5,
        0.25,
        1.0 - f32::EPSILON / 2.0,
        1.0,
        f32::NAN,
    ];
    if rng.below(8) == 0 {
        SPECIAL[rng.below(SPECIAL.len())]
    } else {
        rng.f32()
    }
}

/// A lane mask: every lane, or random lanes.
pub(super) fn lanes(rng: &mut Rng) -> Mask16 {
    if rng.below(3) == 0 {
        Mask16::ALL
    } else {
        Mask16(rng.below(1 << 16) as u16)
    }
}
