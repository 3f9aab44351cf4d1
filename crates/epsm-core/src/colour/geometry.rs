//! Colour derivatives of a recorded path for geometric parameters (docs/design.md
//! §5.6, the interior term): how the path's radiance changes while its
//! vertices move with θ and visibility stays as recorded.
//!
//! Vertex motion comes from the motion model ([`crate::motion`] through
//! [`crate::vertex::Anchor`]): every surface vertex and area-light point keeps its local
//! coordinates on its object (area measure, `x = M(θ)·p_obj`, the shading
//! normal turning with `M`); the camera eye and point lights move with
//! their parameters. The vertex the pixel sees moves in one of two ways
//! ([`PrimaryMotion`]): attached to its object (with the OT loss, whose
//! screen-position gradient `g_xy·dp/dθ` carries its motion across the
//! film), or along the pixel's fixed camera ray (with L2, the conventional
//! renderer's interior term: the pixel keeps looking through the same film
//! point and sees another point of the moving surface).
//!
//! A term of the path (an emission hit by BSDF sampling, a next-event
//! connection, the escaped radiance) is a product of factors over fixed
//! sampling densities (pdfs and MIS weights detached); its derivative is
//! the term times the sum of the factors' `∂ ln/∂θ`:
//!
//! | factor | where | `∂ ln` |
//! |---|---|---|
//! | `f_j(wi, wo)·|cos_j,o|` ([`Material::eval`]) | every non-delta vertex `j` | diffuse: `∂ ln|n·wo|`; glossy: central difference along the motion |
//! | `|cos_{j+1}|/r²` | segment to a BSDF-sampled vertex or an area-light point | `∂ ln|n·w| − 2 ∂ ln r` |
//! | `1/r²` | connection to a point light | `−2 ∂ ln r` |
//! | `s²` (area) | a vertex or light point on an object of scale `s` | `2 ∂s/s` |
//!
//! Camera importance and emitted radiance (Lambertian emitters) are
//! constant; the escaped radiance leaves the last vertex along its recorded
//! world direction ([`PathRecord::escape_dir`]), so that vertex's factor
//! changes with its motion while the background it sees is held fixed, as
//! for a next-event connection to the background. Delta (specular)
//! vertices: with the camera-ray convention the vertex after a mirror or
//! glass interface stays on the scattered ray and the lobe's Fresnel
//! weight changes with `cos θi` (`chain.rs`); with the
//! attached convention their motion is the manifold's (carried by `dp/dθ`),
//! so terms past a delta vertex whose neighbourhood moves are left out for
//! that parameter and counted ([`DropReason::NotDifferentiable`]).

use epsm_render::Scene;
use epsm_render::materials::{Bsdf, Material};
use epsm_render::record::PathRecord;
use glam::{DVec3, Vec2, Vec3};

use crate::drops::{DropCounts, DropReason};
use crate::motion::Motion;

use super::chain;
use super::moving::{Dir, Moving, Placed, cos, toward};
use super::place::delta_lobe;

/// How the vertex a pixel sees moves with θ.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PrimaryMotion {
    /// With its object, at fixed local coordinates (its screen motion is
    /// differentiated separately, through `dp/dθ`).
    Attached,
    /// Along the pixel's fixed film position: the conventional renderer's
    /// camera ray.
    OnCameraRay,
}

/// `∂ ln(f(wi, wo)·|cos_o|)` per channel at a non-delta vertex. A glossy
/// channel that is zero on both sides of the difference step stays zero;
/// one that is zero on one side only (a direction crossing the horizon
/// within the step) has no log-derivative and fails with
/// [`DropReason::Grazing`].
fn bsdf_rate(material: &Material, m: &Moving, wi: &Dir, wo: &Dir) -> Result<Vec3, DropReason> {
    let (co, dco) = cos(m, wo);
    match &material.bsdf {
        Bsdf::RoughConductor(r) => {
            let (ci, dci) = cos(m, wi);
            let (cio, dcio) = (wi.w.dot(wo.w), wi.dw.dot(wo.w) + wi.w.dot(wo.dw));
            let speed = dci.abs().max(dco.abs()).max(dcio.abs());
            if speed == 0.0 {
                return Ok(Vec3::ZERO);
            }
            let h = 1e-3 * f64::from(r.alpha).max(1e-2) / speed;
            let at = |t: f64| {
                let [wi_l, wo_l] = local_pair(ci + t * dci, co + t * dco, cio + t * dcio);
                material.eval(wi_l, wo_l, Vec2::ZERO)
            };
            let (p, q) = (at(h), at(-h));
            let (p_on, q_on) = (p.cmpgt(Vec3::ZERO), q.cmpgt(Vec3::ZERO));
            if p_on != q_on {
                return Err(DropReason::Grazing);
            }
            let rate = (p.ln() - q.ln()) / (2.0 * h as f32);
            Ok(Vec3::select(p_on, rate, Vec3::ZERO))
        }
        _ => Ok(Vec3::splat((dco / co) as f32)),
    }
}

/// Local directions with `cos θi = ci`, `cos θo = co` and `wi·wo = cio`
/// (isotropic BSDFs depend on nothing else).
fn local_pair(ci: f64, co: f64, cio: f64) -> [Vec3; 2] {
    let si = (1.0 - ci * ci).max(0.0).sqrt();
    let a = if si > 1e-12 {
        (cio - ci * co) / si
    } else {
        0.0
    };
    let b = (1.0 - co * co - a * a).max(0.0).sqrt();
    [
        DVec3::new(si, 0.0, ci).as_vec3(),
        DVec3::new(a, b, co).as_vec3(),
    ]
}

/// The geometric colour derivatives of one record.
pub(super) struct Geometric<'a> {
    pub(super) scene: &'a Scene,
    pub(super) motion: &'a Motion,
    pub(super) primary: PrimaryMotion,
    /// `(param, scale value)` of every scale parameter.
    pub(super) scales: &'a [(usize, f64)],
    /// Per material id, the parameter that sets its dielectric IOR.
    pub(super) iors: &'a [Option<usize>],
}

impl Geometric<'_> {
    /// Adds `(param, ∂c/∂θ)` entries of `record` to `out`; counts the terms
    /// left out in `skipped`.
    pub(super) fn gradient(
        &self,
        record: &PathRecord,
        out: &mut Vec<(usize, Vec3)>,
        skipped: &mut DropCounts,
    ) {
        if !self.moves(record) {
            return;
        }
        let (nodes, lights) = match self.place(record) {
            Ok(placed) => placed,
            Err(reason) => {
                skipped.add(reason);
                return;
            }
        };
        let mut params: Vec<usize> = nodes
            .iter()
            .chain(lights.iter().flatten())
            .flat_map(|p| p.grads.iter().map(|g| g.0))
            .collect();
        params.sort_unstable();
        params.dedup();
        for k in params {
            self.one(record, &nodes, &lights, k, out, skipped);
        }
    }

    /// The derivative along parameter `k`, added to `out` unless it is
    /// dropped (counted in `skipped`).
    fn one(
        &self,
        record: &PathRecord,
        nodes: &[Placed],
        lights: &[Option<Placed>],
        k: usize,
        out: &mut Vec<(usize, Vec3)>,
        skipped: &mut DropCounts,
    ) {
        match self.derivative(record, nodes, lights, k, skipped) {
            Ok(sum) if !sum.is_finite() => skipped.add(DropReason::NonFinite),
            Ok(sum) if sum != Vec3::ZERO => out.push((k, sum)),
            Ok(_) => {}
            Err(reason) => skipped.add(reason),
        }
    }

    /// `∂c/∂θ_k` of the record; terms past a delta vertex that cannot be
    /// differentiated are left out and counted in `skipped`.
    fn derivative(
        &self,
        record: &PathRecord,
        nodes: &[Placed],
        lights: &[Option<Placed>],
        k: usize,
        skipped: &mut DropCounts,
    ) -> Result<Vec3, DropReason> {
        let v = &record.vertices;
        let m: Vec<Moving> = nodes.iter().map(|p| p.d(k)).collect();
        let material = |i: usize| {
            self.scene
                .objects()
                .get(v[i].at.object as usize)
                .and_then(|o| self.scene.materials().get(o.material as usize))
        };
        let mut sum = Vec3::ZERO;
        // `∂ ln` of the factors before vertex `j`'s own BSDF.
        let mut prefix = Vec3::ZERO;
        let mut valid = true;
        for j in 1..nodes.len() {
            let i = j - 1;
            let conns = || {
                record
                    .connections
                    .iter()
                    .zip(lights)
                    .filter(move |(c, _)| c.vertex as usize == i)
            };
            let chains = || {
                record
                    .chains
                    .iter()
                    .filter(move |c| c.connection.vertex as usize == i)
                    .map(|c| c.connection.contribution)
            };
            // Emission hit here.
            let own = v[i].contribution
                - conns().map(|(c, _)| c.contribution).sum::<Vec3>()
                - chains().sum::<Vec3>();
            let mat = material(i).ok_or(DropReason::DegenerateTriangle)?;
            let delta = delta_lobe(&v[i]);
            let on_rays = self.primary == PrimaryMotion::OnCameraRay;
            if delta.is_some()
                && !on_rays
                && m[j - 1..nodes.len().min(j + 2)].iter().any(|n| !n.still())
            {
                valid = false;
            }
            if !valid {
                let left = own
                    + conns().map(|(c, _)| c.contribution).sum::<Vec3>()
                    + chains().sum::<Vec3>();
                if left != Vec3::ZERO || j + 1 < nodes.len() || record.escaped != Vec3::ZERO {
                    skipped.add(DropReason::NotDifferentiable);
                }
                break;
            }
            sum += own * prefix;
            let (wi, _) = toward(&m[j], &m[j - 1]);
            // Next-event connections made here.
            for (c, light) in conns() {
                let rate = match light {
                    Some(l) => {
                        let y = l.d(k);
                        let (wo, dr) = toward(&m[j], &y);
                        let mut r = bsdf_rate(mat, &m[j], &wi, &wo)? - Vec3::splat(2.0 * dr as f32);
                        if l.n != DVec3::ZERO {
                            let (cl, dcl) = cos(&y, &wo);
                            r += Vec3::splat((dcl / cl + l.area_rate(k)) as f32);
                        }
                        r
                    }
                    None => {
                        let wo = Dir {
                            w: c.light_position.as_dvec3(),
                            dw: DVec3::ZERO,
                        };
                        bsdf_rate(mat, &m[j], &wi, &wo)?
                    }
                };
                sum += c.contribution * (prefix + rate);
            }
            // Connections through glass: the factors up to here are
            // differentiated, the chain's own (BSDF toward it, its
            // geometry) are not, and are counted.
            for c in chains() {
                sum += c * prefix;
                skipped.add(DropReason::NotDifferentiable);
            }
            // The segment to the next vertex: the lobe's weight at a delta
            // vertex (the next vertex lies on its ray), else the BSDF and
            // the area-measure geometry.
            match (m.get(j + 1), delta) {
                (_, Some(lobe)) => {
                    let (c, dc) = cos(&m[j], &wi);
                    let rate = chain::weight_rate(mat, lobe, v[i].eta, c, dc)?;
                    prefix += Vec3::splat(rate as f32);
                }
                (Some(next), None) => {
                    let (wo, dr) = toward(&m[j], next);
                    let (cn, dcn) = cos(next, &wo);
                    prefix += bsdf_rate(mat, &m[j], &wi, &wo)?
                        + Vec3::splat((dcn / cn - 2.0 * dr + nodes[j + 1].area_rate(k)) as f32);
                }
                // The escaped radiance leaves along its recorded world
                // direction (the background at infinity stays put).
                (None, None) if record.escaped != Vec3::ZERO => {
                    let wo = Dir {
                        w: record.escape_dir.as_dvec3(),
                        dw: DVec3::ZERO,
                    };
                    prefix += bsdf_rate(mat, &m[j], &wi, &wo)?;
                }
                (None, _) => {}
            }
        }
        if valid {
            sum += record.escaped * prefix;
        }
        Ok(sum)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use epsm_render::materials::rough_conductor::RoughConductor;

    fn metal() -> Material {
        Material {
            name: "metal".into(),
            bsdf: Bsdf::RoughConductor(RoughConductor {
                alpha: 0.1,
                tint: Vec3::new(0.9, 0.0, 0.5),
            }),
            two_sided: false,
        }
    }

    fn still_vertex() -> Moving {
        Moving {
            x: DVec3::ZERO,
            dx: DVec3::ZERO,
            n: DVec3::Z,
            dn: DVec3::ZERO,
        }
    }

    #[test]
    fn a_glossy_direction_crossing_the_horizon_within_the_step_is_dropped() {
        let wi = Dir {
            w: DVec3::new(-0.6, 0.0, 0.8),
            dw: DVec3::ZERO,
        };
        // Leaving 1e-6 above the horizon, sinking at unit rate: the
        // difference step (1e-4) crosses it.
        let z: f64 = 1e-6;
        let wo = Dir {
            w: DVec3::new((1.0 - z * z).sqrt(), 0.0, z),
            dw: DVec3::new(z, 0.0, -1.0),
        };
        assert_eq!(
            bsdf_rate(&metal(), &still_vertex(), &wi, &wo),
            Err(DropReason::Grazing)
        );
        // Well above the horizon: the zero-tint channel stays exactly zero.
        let wo = Dir {
            w: DVec3::new(0.6, 0.0, 0.8),
            dw: DVec3::new(0.8, 0.0, -0.6),
        };
        let rate = bsdf_rate(&metal(), &still_vertex(), &wi, &wo).expect("above the horizon");
        assert!(
            rate.x.is_finite() && rate.x != 0.0 && rate.y == 0.0,
            "{rate}"
        );
    }
}
