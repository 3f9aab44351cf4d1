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
//! | translation of an emitter or point light | next-event connections: `∂ ln(cos·cos/r²)/∂θ` at fixed light-sample coordinates |
//! | `ior`, other geometric parameters | not covered here: they move content through `dp/dθ` |

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
    /// Translations of emitters: `(param, ∂y/∂θ)` per emissive object id.
    area_moves: Vec<Vec<(usize, Vec3)>>,
    /// Translations of point lights: `(param, ∂y/∂θ)` per light index.
    point_moves: Vec<Vec<(usize, Vec3)>>,
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
    /// The model of `scene` (already at θ) for the parameters of `table`;
    /// `geometric` adds the terms of translated lights (used with the L2
    /// loss: with OT, colour gradients point at matched colours, and these
    /// broad shading terms would fight the screen-position gradients).
    pub fn new(table: &ParamTable, scene: &Scene, geometric: bool) -> Self {
        let mut materials = vec![Vec::new(); scene.materials().len()];
        let mut emission = vec![None; scene.objects().len()];
        let mut area_moves = vec![Vec::new(); scene.objects().len()];
        let mut point_moves = vec![Vec::new(); scene.point_lights().len()];
        let axis = |a: usize| Vec3::AXES[a.min(2)];
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
                Target::Translate { object, axis: a } if geometric => {
                    let emits = scene
                        .objects()
                        .get(object as usize)
                        .is_some_and(|o| o.emission.is_some());
                    if emits {
                        area_moves[object as usize].push((param, axis(a)));
                    }
                }
                Target::LightTranslate { light, axis: a } if geometric => {
                    if let Some(m) = point_moves.get_mut(light) {
                        m.push((param, axis(a)));
                    }
                }
                _ => {}
            }
        }
        Self {
            materials,
            emission,
            area_moves,
            point_moves,
        }
    }

    /// Whether any parameter changes colours through this model.
    pub fn is_empty(&self) -> bool {
        self.materials.iter().all(Vec::is_empty)
            && self.emission.iter().all(Option::is_none)
            && self.area_moves.iter().all(Vec::is_empty)
            && self.point_moves.iter().all(Vec::is_empty)
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
            let Some(x) = v.get(c.vertex as usize) else {
                continue;
            };
            let moves = match c.light {
                LightPoint::Area { object, .. } => self.area_moves.get(object as usize),
                LightPoint::Point { index } => self.point_moves.get(index as usize),
                LightPoint::Background => None,
            };
            for &(param, e) in moves.into_iter().flatten() {
                out.push((
                    param,
                    c.contribution
                        * moved_light_rate(x.p, x.ns, c.light_position, c.light_normal, e),
                ));
            }
        }
        out
    }
}

/// `∂ ln c/∂θ` of a next-event connection from `x` (shading normal `n`) to
/// a light point `y` (normal `n_l`, zero for point lights) translated at
/// rate `e = ∂y/∂θ`, at fixed light-sample coordinates: the connection
/// carries `cos_x · cos_l / r²` (area light; the area pdf is unchanged by a
/// translation) or `cos_x / r²` (point light), with `d = y − x`:
/// `(n·e)/(n·d) + (n_l·e)/(n_l·d) − 4(d·e)/r²`, or `(n·e)/(n·d) − 3(d·e)/r²`.
fn moved_light_rate(x: Vec3, n: Vec3, y: Vec3, n_l: Vec3, e: Vec3) -> f32 {
    let d = y - x;
    let r2 = d.length_squared();
    let (nd, nld) = (n.dot(d), n_l.dot(d));
    if r2 <= 0.0 || nd == 0.0 {
        return 0.0;
    }
    let mut rate = n.dot(e) / nd - 2.0 * d.dot(e) / r2;
    if n_l != Vec3::ZERO && nld != 0.0 {
        rate += n_l.dot(e) / nld - 2.0 * d.dot(e) / r2;
    } else {
        rate -= d.dot(e) / r2;
    }
    if rate.is_finite() { rate } else { 0.0 }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moved_light_rate_matches_a_finite_difference() {
        let (x, n) = (Vec3::new(0.1, 0.0, -0.2), Vec3::Y);
        let (y, n_l) = (Vec3::new(0.5, 2.0, 0.3), -Vec3::Y);
        let carried = |y: Vec3, area: bool| {
            let d = y - x;
            let r = d.length();
            let cos_l = if area { n_l.dot(-d) / r } else { 1.0 };
            n.dot(d) / r * cos_l / (r * r)
        };
        for (e, area) in [
            (Vec3::X, true),
            (Vec3::Z, true),
            (Vec3::X, false),
            (Vec3::Y, false),
        ] {
            let h = 1e-3;
            let fd = (carried(y + h * e, area).ln() - carried(y - h * e, area).ln()) / (2.0 * h);
            let rate = moved_light_rate(x, n, y, if area { n_l } else { Vec3::ZERO }, e);
            assert!(
                (rate - fd).abs() < 1e-3 * fd.abs().max(1e-2),
                "{e} {area}: {rate} vs {fd}"
            );
        }
    }
}
