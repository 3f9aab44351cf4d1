//! Building one differentiable path from a record: its nodes (anchored in
//! `f64` on the meshes and exact spheres, never on the `f32` record positions), the
//! parameters it touches, and one constraint per unknown vertex with the
//! constants (`m`, `c`) measured at the base configuration so that
//! `C(0, θ₀) = 0` holds for them exactly.

use epsm_render::Scene;
use epsm_render::lights::LightPoint;
use epsm_render::materials::{Bsdf, Lobe, VertexKind};
use epsm_render::record::{ConnectionRecord, PathRecord, TrianglePoint, VertexRecord};
use glam::Vec3;

use super::{DiffPath, End, Node, PathKind};
use crate::constraints::{Constraint, ConstraintKind, na};
use crate::drops::DropReason;
use crate::frame::BaseFrame;
use crate::motion::Motion;
use crate::vertex::Anchor;

fn surface(
    scene: &Scene,
    motion: &Motion,
    at: &TrianglePoint,
    unknown: Option<usize>,
) -> Result<Node, DropReason> {
    let anchor = Anchor::at_point(scene, motion, at).ok_or(DropReason::DegenerateTriangle)?;
    Ok(Node::Surface { anchor, unknown })
}

fn light(scene: &Scene, motion: &Motion, c: &ConnectionRecord) -> Result<Node, DropReason> {
    match c.light {
        LightPoint::Area {
            object,
            triangle,
            b1,
            b2,
        } => surface(
            scene,
            motion,
            &TrianglePoint {
                object,
                triangle,
                b1,
                b2,
            },
            None,
        ),
        LightPoint::Point { index } => Ok(Node::PointLight(index as usize)),
        LightPoint::Background => Err(DropReason::NotDifferentiable),
    }
}

/// The relative IOR of a refraction in `f64`: the record's `f32` value
/// snapped to the material's `ior` or `1/ior`, whichever it rounds from.
fn exact_eta(scene: &Scene, at: &TrianglePoint, recorded: f32) -> f64 {
    let material = scene
        .objects()
        .get(at.object as usize)
        .and_then(|o| scene.materials().get(o.material as usize));
    let recorded = f64::from(recorded);
    match material.map(|m| &m.bsdf) {
        Some(Bsdf::Dielectric(d)) => {
            let ior = f64::from(d.ior);
            if (recorded - ior).abs() <= (recorded - 1.0 / ior).abs() {
                ior
            } else {
                1.0 / ior
            }
        }
        _ => recorded,
    }
}

/// Builds one path: `verts` are its unknown vertices (all but the first
/// diffuse one are S; for a shadow, just D), `end` the fixed end.
pub(super) fn build(
    kind: PathKind,
    record: &PathRecord,
    scene: &Scene,
    motion: &Motion,
    verts: &[&VertexRecord],
    end: Option<End<'_>>,
    contribution: Vec3,
) -> Result<Option<DiffPath>, DropReason> {
    // Nodes: camera, then the pixel vertex (fixed for primary paths), ...
    let mut nodes = vec![Node::Camera];
    if kind == PathKind::Primary {
        let first = record
            .vertices
            .first()
            .ok_or(DropReason::NotDifferentiable)?;
        nodes.push(surface(scene, motion, &first.at, None)?);
    }
    for (q, x) in verts.iter().enumerate() {
        nodes.push(surface(scene, motion, &x.at, Some(q))?);
    }
    if kind == PathKind::Shadow
        && let Some(End::Light(c)) = &end
    {
        let o = c.occluder.ok_or(DropReason::NotDifferentiable)?;
        nodes.push(surface(scene, motion, &o.at, None)?);
    }
    match &end {
        Some(End::Vertex(x)) => nodes.push(surface(scene, motion, &x.at, None)?),
        Some(End::Light(c)) => nodes.push(light(scene, motion, c)?),
        None => {}
    }
    let mut params: Vec<usize> = motion.camera.grads.iter().map(|g| g.param).collect();
    for node in &nodes {
        match node {
            Node::Surface { anchor, .. } => {
                params.extend(motion.object(anchor.object).grads.iter().map(|g| g.param))
            }
            Node::PointLight(i) => params.extend(motion.lights[*i].grads.iter().map(|g| g.param)),
            Node::Camera => {}
        }
    }
    params.sort_unstable();
    params.dedup();
    if params.is_empty() {
        return Ok(None);
    }
    let mut path = DiffPath {
        kind,
        pixel: record.pixel,
        film: record.film.as_dvec2(),
        contribution,
        nodes,
        constraints: Vec::new(),
        params,
    };
    let state = crate::constraints::assembly::evaluate(&path, motion, &[]);
    for (q, vert) in verts.iter().enumerate() {
        let x = q + 1;
        let (a, b) = if kind == PathKind::Shadow {
            (x + 1, x + 2)
        } else {
            (x - 1, x + 1)
        };
        let s = &state.nodes;
        let n = s[x].n;
        let frame = BaseFrame::new(n);
        let wo = (s[b].x - s[x].x).normalize();
        let wi = (s[a].x - s[x].x).normalize();
        let first_caustic = kind == PathKind::Caustic && q == 0;
        let ck = match (kind, vert.kind, vert.lobe) {
            (PathKind::Shadow, ..) => ConstraintKind::Collinear,
            _ if first_caustic => ConstraintKind::FixedDirection {
                c: frame.project(&na(n), &na(wo)),
            },
            (_, VertexKind::Glossy, _) => ConstraintKind::Glossy {
                m: frame.project(&na(n), &na((wi + wo).normalize())),
            },
            (_, _, Some(Lobe::SpecularTransmission)) => ConstraintKind::Specular {
                eta: exact_eta(scene, &vert.at, vert.eta),
                transmit: true,
            },
            (_, _, Some(Lobe::SpecularReflection)) => ConstraintKind::Specular {
                eta: 1.0,
                transmit: false,
            },
            _ => return Err(DropReason::LobeMismatch),
        };
        path.constraints.push(Constraint {
            kind: ck,
            frame,
            nodes: [a, x, b],
        });
    }
    Ok(Some(path))
}
