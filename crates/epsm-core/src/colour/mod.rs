//! Colour derivatives `dc/dθ` of recorded paths (docs/design.md §5.6): how a path
//! sample's radiance changes with θ at fixed sampled random numbers.
//!
//! A path sample's radiance is a sum of terms (emission hit by BSDF
//! sampling, next-event connections, escaped radiance), each a product of
//! the factors before it; its derivative is the term times the sum of the
//! factors' `∂ ln/∂θ`. Sampling pdfs and MIS weights are held fixed (the
//! "detached sampling" convention of path-replay renderers).
//!
//! | parameter | derivative | where |
//! |---|---|---|
//! | `albedo.r/g/b` (diffuse) | exact | `material.rs` |
//! | `alpha` (rough conductor) | central difference | `material.rs` |
//! | `ior` (dielectric) | Fresnel weight, central difference (fixed directions); the refracted ray turns with it, moving the vertices after the interface (L2 iterations) | `material.rs`, [`geometry`] |
//! | `emission` | exact: `∂c/∂s = c_e/s` for every term `c_e` the emitter emits | here |
//! | translation, rotation, scale of objects and emitters; point lights; camera position, yaw, pitch | vertices move with θ: BSDF values, cosines, `1/r²`, area | [`geometry`] |
//!
//! Geometric terms are built only when the model is made with a
//! [`PrimaryMotion`]. The optimisation loop asks for them in L2 iterations
//! ([`PrimaryMotion::OnCameraRay`]): with OT, colour gradients point at
//! matched colours, and on the layout problem adding the geometric shading
//! terms ([`PrimaryMotion::Attached`]) slowed the translations and did not
//! stop the rotation's drift. Terms
//! that cannot be differentiated (a moving delta vertex: its motion is the
//! manifold's, carried by `dp/dθ`) are counted, never silently dropped.

mod chain;
pub mod geometry;
mod material;
mod moving;
mod place;

use epsm_render::Scene;
use epsm_render::frame::Frame;
use epsm_render::lights::LightPoint;
use epsm_render::materials::VertexKind;
use epsm_render::record::PathRecord;
use glam::Vec3;

use geometry::Geometric;
pub use geometry::PrimaryMotion;
use material::Probe;

use crate::drops::{DropCounts, DropReason};
use crate::motion::Motion;
use crate::params::{ParamTable, Target};

/// The colour-derivative model of one θ: which materials and emitters carry
/// parameters, with their perturbed copies, and whether geometric
/// parameters get colour terms.
#[derive(Clone, Debug, Default)]
pub struct ColourModel {
    /// Per material id, its probes.
    materials: Vec<Vec<Probe>>,
    /// Per object id, `(param, current scale)` of its emission.
    emission: Vec<Option<(usize, f32)>>,
    /// How the pixel's vertex moves, when geometric terms are wanted and
    /// some parameter moves geometry.
    primary: Option<PrimaryMotion>,
    /// `(param, value)` of every scale parameter.
    scales: Vec<(usize, f64)>,
    /// Per material id, the parameter that sets its dielectric IOR (the
    /// refracted rays turn with it: a geometric term).
    iors: Vec<Option<usize>>,
}

impl ColourModel {
    /// The model of `scene` (already at θ) for the parameters of `table`;
    /// `geometric` adds the terms of geometric parameters, with the pixel's
    /// vertex moving as given.
    pub fn new(table: &ParamTable, scene: &Scene, geometric: Option<PrimaryMotion>) -> Self {
        let mut materials = vec![Vec::new(); scene.materials().len()];
        let mut emission = vec![None; scene.objects().len()];
        let mut scales = Vec::new();
        let mut iors = vec![None; scene.materials().len()];
        for (param, p) in table.params().iter().enumerate() {
            let v = p.value as f32;
            if let Target::Ior { material } = p.target
                && let Some(slot) = iors.get_mut(material as usize)
            {
                *slot = Some(param);
            }
            match p.target {
                Target::Albedo { material, .. }
                | Target::Alpha { material }
                | Target::Ior { material } => {
                    if let Some(m) = scene.materials().get(material as usize) {
                        materials[material as usize].push(Probe::new(param, m, p.target, v));
                    }
                }
                Target::Emission { object } => {
                    if let Some(e) = emission.get_mut(object as usize) {
                        *e = Some((param, v));
                    }
                }
                Target::Scale { .. } => scales.push((param, p.value)),
                _ => {}
            }
        }
        let turns_rays = iors.iter().any(Option::is_some);
        Self {
            materials,
            emission,
            primary: geometric.filter(|_| crate::backprop::has_geometry(table) || turns_rays),
            scales,
            iors,
        }
    }

    /// Whether any parameter changes colours through this model.
    pub fn is_empty(&self) -> bool {
        self.materials.iter().all(Vec::is_empty)
            && self.emission.iter().all(Option::is_none)
            && self.primary.is_none()
    }

    /// `dc/dθ` of one path sample as `(parameter, ∂c/∂θ per channel)`
    /// entries (a parameter may appear more than once; entries add up).
    /// `motion` is the placement at θ; terms left out are counted in
    /// `skipped`. Material and emission terms with a non-finite value are
    /// dropped together and counted as [`DropReason::NonFinite`]. The record
    /// of a sample the tracer dropped ([`PathRecord::dropped`]) gives no
    /// terms and is not counted here: the gradient pass counts it once.
    pub fn gradient(
        &self,
        record: &PathRecord,
        scene: &Scene,
        motion: &Motion,
        skipped: &mut DropCounts,
    ) -> Vec<(usize, Vec3)> {
        let mut out = Vec::new();
        if self.is_empty() || record.dropped.is_some() {
            return out;
        }
        self.values(record, scene, &mut out, skipped);
        if out.iter().any(|(_, d)| !d.is_finite()) {
            out.clear();
            skipped.add(DropReason::NonFinite);
        }
        if let Some(primary) = self.primary {
            let geo = Geometric {
                scene,
                motion,
                primary,
                scales: &self.scales,
                iors: &self.iors,
            };
            geo.gradient(record, &mut out, skipped);
        }
        out
    }

    /// The material and emission terms; a delta lobe's term that cannot be
    /// differentiated is left out and counted in `skipped`.
    fn values(
        &self,
        record: &PathRecord,
        scene: &Scene,
        out: &mut Vec<(usize, Vec3)>,
        skipped: &mut DropCounts,
    ) {
        let v = &record.vertices;
        let eye = scene.camera().origin_f32();
        // Radiance carried past vertex i along the path's own continuation.
        let mut after = vec![record.escaped; v.len()];
        for i in (0..v.len().saturating_sub(1)).rev() {
            after[i] = after[i + 1] + v[i + 1].contribution;
        }
        let material_of = |object: u32| scene.objects().get(object as usize).map(|o| o.material);
        // Every connection, with where it leaves its vertex toward: a
        // connection through glass toward its first refraction (its IOR
        // terms are not modelled and are counted).
        let ends = || {
            let through_glass = record.chains.iter().map(|c| {
                let first = c
                    .specular
                    .first()
                    .map_or(c.connection.light_position, |s| s.p);
                (c.connection, Some(first))
            });
            record
                .connections
                .iter()
                .map(|c| (*c, None))
                .chain(through_glass)
        };
        for c in &record.chains {
            for s in &c.specular {
                if material_of(s.at.object)
                    .and_then(|m| self.materials.get(m as usize))
                    .is_some_and(|p| !p.is_empty())
                {
                    skipped.add(DropReason::NotDifferentiable);
                }
            }
        }
        for (i, x) in v.iter().enumerate() {
            let conns = ends().filter(|(c, _)| c.vertex as usize == i);
            // Emission of this vertex (its contribution less its connections).
            if let Some(Some((param, s))) = self.emission.get(x.at.object as usize)
                && *s > 0.0
            {
                let own = x.contribution - conns.clone().map(|(c, _)| c.contribution).sum::<Vec3>();
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
            if x.kind == VertexKind::Specular {
                if let Some(lobe) = x.lobe {
                    for probe in probes {
                        match probe.delta_ratio(wi, lobe) {
                            Ok(rate) => out.push((probe.param, rate * after[i])),
                            Err(reason) => skipped.add(reason),
                        }
                    }
                }
                continue;
            }
            // Toward the next vertex, or where the path left the scene
            // (zero, and no terms after, when it ended here).
            let wo_next = frame.to_local(
                v.get(i + 1)
                    .map_or(record.escape_dir, |n| (n.p - x.p).normalize_or_zero()),
            );
            for probe in probes {
                let mut d = probe.ratio(wi, wo_next) * after[i];
                for (c, toward) in conns.clone() {
                    let dir = match (c.light, toward) {
                        (_, Some(p)) => (p - x.p).normalize_or_zero(),
                        (LightPoint::Background, None) => c.light_position,
                        _ => (c.light_position - x.p).normalize_or_zero(),
                    };
                    d += probe.ratio(wi, frame.to_local(dir)) * c.contribution;
                }
                out.push((probe.param, d));
            }
        }
        for (c, _) in ends() {
            if let LightPoint::Area { object, .. } = c.light
                && let Some(Some((param, s))) = self.emission.get(object as usize)
                && *s > 0.0
            {
                out.push((*param, c.contribution / *s));
            }
        }
    }
}

/// A two-sided glass of IOR 1.5, for the submodules' tests.
#[cfg(test)]
fn glass() -> epsm_render::materials::Material {
    use epsm_render::materials::{Bsdf, Material, dielectric::Dielectric};
    Material {
        name: "glass".into(),
        bsdf: Bsdf::Dielectric(Dielectric { ior: 1.5 }),
        two_sided: true,
    }
}

/// `g′(x)` by Richardson-extrapolated central differences of steps `h` and
/// `h/2` (truncation error `O(h⁴)`), for the submodules' tests.
#[cfg(test)]
fn richardson(g: impl Fn(f64) -> f64, x: f64, h: f64) -> f64 {
    let central = |h: f64| (g(x + h) - g(x - h)) / (2.0 * h);
    (4.0 * central(0.5 * h) - central(h)) / 3.0
}
