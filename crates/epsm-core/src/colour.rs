//! Colour derivatives `dc/dθ` of recorded paths at fixed sampled directions
//! (DESIGN §5.6), for material and emitter parameters.
//!
//! A path sample's radiance is a sum of terms, each a product of the BSDF
//! values of the vertices before it and an emission. At fixed directions,
//! a parameter of vertex `i`'s material scales every term after `i` by
//! `∂ ln f_i/∂θ` (per channel): the terms carried by the path's continuation
//! (the later vertices' contributions and escaped radiance, direction
//! `wo = x_{i+1} − x_i`) and each next-event connection made at `i` (its own
//! `wo`). `∂ ln f/∂θ` comes from a central difference of
//! [`Material::eval`](epsm_render::materials::Material::eval) with the
//! material's parameter moved by `±h` (exact for the diffuse albedo, which
//! is linear). An emitter's `emission` scale `s` gives `∂c/∂s = c_e / s` for
//! every term `c_e` it emits (hit by BSDF sampling or reached by a
//! connection). Held fixed: the sampling pdfs and MIS weights (the
//! "detached sampling" convention of path-replay renderers).
//!
//! | parameter | derivative |
//! |---|---|
//! | `albedo.r/g/b` (diffuse) | exact |
//! | `alpha` (rough conductor) | central difference, `h = 1e-3·max(α, 1e-3)` |
//! | `emission` | exact |
//! | `ior`, geometric parameters | not covered here: they move content through `dp/dθ` |

use epsm_render::Scene;
use epsm_render::frame::Frame;
use epsm_render::lights::LightPoint;
use epsm_render::materials::{Bsdf, Material, Texture};
use epsm_render::record::PathRecord;
use glam::{Vec2, Vec3};

use crate::params::{ParamTable, Target};

/// One material parameter with the material moved to `θ ± h`.
#[derive(Clone, Debug)]
struct Probe {
    param: usize,
    /// `(θ + h) − max(θ − h, 0)`: the width of the central difference.
    width: f32,
    plus: Material,
    minus: Material,
}

/// The colour-derivative model of one θ: which materials and emitters carry
/// parameters, with their perturbed copies.
#[derive(Clone, Debug, Default)]
pub struct ColourModel {
    /// Per material id, its probes.
    materials: Vec<Vec<Probe>>,
    /// Per object id, `(param, current scale)` of its emission.
    emission: Vec<Option<(usize, f32)>>,
}

/// `material` with the value of `target` set to `value` (unchanged when the
/// target does not apply).
fn with_value(material: &Material, target: Target, value: f32) -> Material {
    let mut m = material.clone();
    match (&mut m.bsdf, target) {
        (Bsdf::Diffuse(d), Target::Albedo { channel, .. }) => {
            if let Texture::Constant(c) = &mut d.albedo {
                c[channel] = value;
            }
        }
        (Bsdf::RoughConductor(r), Target::Alpha { .. }) => r.alpha = value,
        _ => {}
    }
    m
}

impl ColourModel {
    /// The model of `scene` (already at θ) for the parameters of `table`.
    pub fn new(table: &ParamTable, scene: &Scene) -> Self {
        let mut materials = vec![Vec::new(); scene.materials().len()];
        let mut emission = vec![None; scene.objects().len()];
        for (param, p) in table.params().iter().enumerate() {
            let v = p.value as f32;
            match p.target {
                Target::Albedo { material, .. } | Target::Alpha { material } => {
                    let Some(m) = scene.materials().get(material as usize) else {
                        continue;
                    };
                    let h = if matches!(p.target, Target::Alpha { .. }) {
                        1e-3 * v.max(1e-3)
                    } else {
                        1e-3
                    };
                    let lo = (v - h).max(0.0);
                    materials[material as usize].push(Probe {
                        param,
                        width: v + h - lo,
                        plus: with_value(m, p.target, v + h),
                        minus: with_value(m, p.target, lo),
                    });
                }
                Target::Emission { object } => {
                    if let Some(e) = emission.get_mut(object as usize) {
                        *e = Some((param, v));
                    }
                }
                _ => {}
            }
        }
        Self {
            materials,
            emission,
        }
    }

    /// Whether any parameter changes colours through this model.
    pub fn is_empty(&self) -> bool {
        self.materials.iter().all(Vec::is_empty) && self.emission.iter().all(Option::is_none)
    }

    /// `dc/dθ` of one path sample as `(parameter, ∂c/∂θ per channel)`
    /// entries (a parameter may appear more than once; entries add up).
    pub fn gradient(&self, record: &PathRecord, scene: &Scene) -> Vec<(usize, Vec3)> {
        let mut out = Vec::new();
        if self.is_empty() {
            return out;
        }
        let v = &record.vertices;
        let eye = scene.camera().origin_f32();
        // Radiance carried past vertex i along the path's own continuation.
        let mut after = vec![record.escaped; v.len()];
        for i in (0..v.len().saturating_sub(1)).rev() {
            after[i] = after[i + 1] + v[i + 1].contribution;
        }
        let material_of = |object: u32| scene.objects().get(object as usize).map(|o| o.material);
        for (i, x) in v.iter().enumerate() {
            let conns = record.connections.iter().filter(|c| c.vertex as usize == i);
            // Emission of this vertex (its contribution less its connections).
            if let Some(Some((param, s))) = self.emission.get(x.at.object as usize)
                && *s > 0.0
            {
                let own = x.contribution - conns.clone().map(|c| c.contribution).sum::<Vec3>();
                out.push((*param, own / *s));
            }
            let Some(probes) =
                material_of(x.at.object).and_then(|m| self.materials.get(m as usize))
            else {
                continue;
            };
            if probes.is_empty() {
                continue;
            }
            let frame = Frame::from_normal(x.ns);
            let prev = if i == 0 { eye } else { v[i - 1].p };
            let wi = frame.to_local((prev - x.p).normalize_or_zero());
            let wo_next = v
                .get(i + 1)
                .map_or(Vec3::Z, |n| frame.to_local((n.p - x.p).normalize_or_zero()));
            for probe in probes {
                let mut d = ratio(probe, wi, wo_next) * after[i];
                for c in conns.clone() {
                    let dir = match c.light {
                        LightPoint::Background => c.light_position,
                        _ => (c.light_position - x.p).normalize_or_zero(),
                    };
                    d += ratio(probe, wi, frame.to_local(dir)) * c.contribution;
                }
                out.push((probe.param, d));
            }
        }
        for c in &record.connections {
            if let LightPoint::Area { object, .. } = c.light
                && let Some(Some((param, s))) = self.emission.get(object as usize)
                && *s > 0.0
            {
                out.push((*param, c.contribution / *s));
            }
        }
        out
    }
}

/// `∂ ln f/∂θ` per channel at fixed local directions (0 where `f = 0`).
fn ratio(probe: &Probe, wi: Vec3, wo: Vec3) -> Vec3 {
    let uv = Vec2::ZERO;
    let (fp, fm) = (probe.plus.eval(wi, wo, uv), probe.minus.eval(wi, wo, uv));
    let f = 0.5 * (fp + fm);
    let d = (fp - fm) / probe.width;
    Vec3::select(
        f.cmpgt(Vec3::splat(1e-20)),
        d / f.max(Vec3::splat(1e-20)),
        Vec3::ZERO,
    )
}
