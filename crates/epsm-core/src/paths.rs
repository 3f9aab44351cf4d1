//! Differentiable path types and the classification of recorded paths
//! (DESIGN §5.4).
//!
//! | kind | pattern | unknowns | constraints |
//! |---|---|---|---|
//! | [`PathKind::Primary`] | camera → x1 | none | — |
//! | [`PathKind::ChainToSurface`] | camera → S⁺ → D | the S | half vector per S |
//! | [`PathKind::ChainToLight`] | camera → S⁺ → L | the S | half vector per S |
//! | [`PathKind::Caustic`] | camera → D → S⁺ → L | D and the S | fixed direction at D, half vector per S |
//! | [`PathKind::Shadow`] | camera → D ⇢ o ⇢ L | D | collinear at D |
//!
//! L is an emissive surface hit by BSDF sampling, or the light point of an
//! unblocked next-event connection made at the last S (which is then glossy);
//! an S chain whose next vertex is emissive is a chain to a light. Camera
//! parameters apply to every kind. Paths that touch no parameter are not
//! returned; paths ending at the background are counted as
//! [`DropReason::NotDifferentiable`].

use epsm_render::Scene;
use epsm_render::lights::LightPoint;
use epsm_render::materials::{Bsdf, Lobe, VertexKind};
use epsm_render::record::{ConnectionRecord, PathRecord, TrianglePoint};
use glam::{DVec2, UVec2, Vec3};

use crate::constraints::{Constraint, ConstraintKind};
use crate::drops::{DropCounts, DropReason};
use crate::frame::BaseFrame;
use crate::motion::Motion;
use crate::vertex::Anchor;

/// The kind of a differentiable path.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PathKind {
    /// camera → x1: the surface seen directly.
    Primary,
    /// camera → S⁺ → D: a surface seen in mirrors or through glass.
    ChainToSurface,
    /// camera → S⁺ → L: a highlight, or a light seen in a mirror.
    ChainToLight,
    /// camera → D → S⁺ → L: a caustic.
    Caustic,
    /// camera → D ⇢ occluder ⇢ L: a shadow.
    Shadow,
}

impl PathKind {
    /// Every kind, in report order.
    pub const ALL: [PathKind; 5] = [
        PathKind::Primary,
        PathKind::ChainToSurface,
        PathKind::ChainToLight,
        PathKind::Caustic,
        PathKind::Shadow,
    ];

    /// A snake-case name for reports.
    pub fn name(self) -> &'static str {
        match self {
            PathKind::Primary => "primary",
            PathKind::ChainToSurface => "chain_to_surface",
            PathKind::ChainToLight => "chain_to_light",
            PathKind::Caustic => "caustic",
            PathKind::Shadow => "shadow",
        }
    }
}

/// One vertex of a differentiable path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Node {
    /// The camera's eye `x0`.
    Camera,
    /// A point on a triangle; `unknown` is its column block when it is solved for.
    Surface {
        /// Where it lies.
        anchor: Anchor,
        /// Column block index in `A`, `None` for a fixed point.
        unknown: Option<usize>,
    },
    /// A point light (index in the scene's point lights).
    PointLight(usize),
}

/// A path ready to differentiate: nodes (`nodes[1]` is the vertex the pixel
/// sees), one constraint per unknown node, and the parameters it touches.
#[derive(Clone, Debug, PartialEq)]
pub struct DiffPath {
    /// Its kind.
    pub kind: PathKind,
    /// The pixel of the record.
    pub pixel: UVec2,
    /// Film position of the camera ray (pixels).
    pub film: DVec2,
    /// The radiance the tracked effect carries. The primary path carries what
    /// the record's other non-shadow paths do not, so those add up to the
    /// record's radiance; a shadow carries the radiance its occluder removes.
    pub contribution: Vec3,
    /// The vertices.
    pub nodes: Vec<Node>,
    /// Constraint `r` owns unknown `r` (rows and columns `2r, 2r + 1`).
    pub constraints: Vec<Constraint>,
    /// Global indices of the parameters the path touches, ascending.
    pub params: Vec<usize>,
}

impl DiffPath {
    /// Number of unknown vertices.
    pub fn unknowns(&self) -> usize {
        self.constraints.len()
    }
}

/// The differentiable paths of a record, and what was skipped.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Classified {
    /// Paths touching at least one parameter.
    pub paths: Vec<DiffPath>,
    /// Paths that could not be built, by reason.
    pub skipped: DropCounts,
}

/// How a path ends.
enum End {
    Vertex(usize),
    Light(ConnectionRecord),
}

/// Classifies a record into differentiable paths, with vertex tangents built
/// in `motion` (the current θ, which becomes θ₀ for these paths).
pub fn classify(record: &PathRecord, scene: &Scene, motion: &Motion) -> Classified {
    let mut out = Classified::default();
    let v = &record.vertices;
    if v.is_empty() {
        return out;
    }
    let push =
        |kind, verts: &[usize], end: Option<End>, contribution, out: &mut Classified| match build(
            kind,
            record,
            scene,
            motion,
            verts,
            end,
            contribution,
        ) {
            Ok(Some(p)) => out.paths.push(p),
            Ok(None) => {}
            Err(r) => out.skipped.add(r),
        };
    let emissive = |i: usize| {
        scene
            .objects()
            .get(v[i].at.object as usize)
            .is_some_and(|o| o.emission.is_some())
    };
    let first_diffuse = v.iter().position(|x| x.kind == VertexKind::Diffuse);
    let mut tracked = Vec3::ZERO;

    // Chains from the camera: S vertices v[0..k], then D (or L) at v[k].
    let k = first_diffuse.unwrap_or(v.len());
    if k > 0 {
        let chain: Vec<usize> = (0..k).collect();
        if let Some(d) = first_diffuse {
            let kind = if emissive(d) {
                PathKind::ChainToLight
            } else {
                PathKind::ChainToSurface
            };
            let c = record.radiance - v[..k].iter().map(|x| x.contribution).sum::<Vec3>();
            tracked += c;
            push(kind, &chain, Some(End::Vertex(d)), c, &mut out);
        } else if record.escaped != Vec3::ZERO {
            out.skipped.add(DropReason::NotDifferentiable);
        }
        for conn in connections(record, |j| j < k) {
            tracked += conn.contribution;
            push(
                PathKind::ChainToLight,
                &chain[..=conn.vertex as usize],
                Some(End::Light(*conn)),
                conn.contribution,
                &mut out,
            );
        }
    }

    // Caustics: D = v[0], S vertices v[1..m], L at v[m] or a connection.
    if first_diffuse == Some(0) {
        let m = v[1..]
            .iter()
            .position(|x| x.kind == VertexKind::Diffuse)
            .map_or(v.len(), |i| i + 1);
        let verts: Vec<usize> = (0..m).collect();
        if m > 1 && m < v.len() && emissive(m) {
            tracked += v[m].contribution;
            push(
                PathKind::Caustic,
                &verts,
                Some(End::Vertex(m)),
                v[m].contribution,
                &mut out,
            );
        }
        for conn in connections(record, |j| j >= 1 && j < m) {
            tracked += conn.contribution;
            push(
                PathKind::Caustic,
                &verts[..=conn.vertex as usize],
                Some(End::Light(*conn)),
                conn.contribution,
                &mut out,
            );
        }
        // Shadows at D.
        for conn in record
            .connections
            .iter()
            .filter(|c| c.vertex == 0 && c.occluder.is_some())
        {
            push(
                PathKind::Shadow,
                &[0],
                Some(End::Light(*conn)),
                conn.unoccluded,
                &mut out,
            );
        }
    }
    push(
        PathKind::Primary,
        &[],
        None,
        record.radiance - tracked,
        &mut out,
    );
    out
}

/// Unblocked connections made at glossy vertices whose index passes `at`.
fn connections(
    record: &PathRecord,
    at: impl Fn(usize) -> bool,
) -> impl Iterator<Item = &ConnectionRecord> {
    record.connections.iter().filter(move |c| {
        let j = c.vertex as usize;
        at(j)
            && c.occluder.is_none()
            && record
                .vertices
                .get(j)
                .is_some_and(|x| x.kind == VertexKind::Glossy)
    })
}

fn surface(
    scene: &Scene,
    motion: &Motion,
    at: &TrianglePoint,
    unknown: Option<usize>,
) -> Result<Node, DropReason> {
    let object = scene
        .objects()
        .get(at.object as usize)
        .ok_or(DropReason::DegenerateTriangle)?;
    let anchor = Anchor::new(
        object,
        at.object,
        at.triangle,
        f64::from(at.b1),
        f64::from(at.b2),
        motion.object(at.object),
    )
    .ok_or(DropReason::DegenerateTriangle)?;
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

/// Builds one path: `verts` are the record's unknown vertices (all but the
/// first diffuse one are S; for a shadow, just D), `end` the fixed end.
fn build(
    kind: PathKind,
    record: &PathRecord,
    scene: &Scene,
    motion: &Motion,
    verts: &[usize],
    end: Option<End>,
    contribution: Vec3,
) -> Result<Option<DiffPath>, DropReason> {
    let v = &record.vertices;
    // Nodes: camera, then the pixel vertex (fixed for primary paths), ...
    let mut nodes = vec![Node::Camera];
    if kind == PathKind::Primary {
        nodes.push(surface(scene, motion, &v[0].at, None)?);
    }
    for (q, &i) in verts.iter().enumerate() {
        nodes.push(surface(scene, motion, &v[i].at, Some(q))?);
    }
    if kind == PathKind::Shadow
        && let Some(End::Light(c)) = &end
    {
        let o = c.occluder.ok_or(DropReason::NotDifferentiable)?;
        nodes.push(surface(scene, motion, &o.at, None)?);
    }
    match &end {
        Some(End::Vertex(i)) => nodes.push(surface(scene, motion, &v[*i].at, None)?),
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
    let state = crate::solve::evaluate(&path, motion, &[]);
    for (q, &i) in verts.iter().enumerate() {
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
        let ck = match (kind, v[i].kind, v[i].lobe) {
            (PathKind::Shadow, ..) => ConstraintKind::Collinear,
            _ if first_caustic => ConstraintKind::FixedDirection {
                c: frame.project(&crate::constraints::na(n), &crate::constraints::na(wo)),
            },
            (_, VertexKind::Glossy, _) => ConstraintKind::Glossy {
                m: frame.project(
                    &crate::constraints::na(n),
                    &crate::constraints::na((wi + wo).normalize()),
                ),
            },
            (_, _, Some(Lobe::SpecularTransmission)) => ConstraintKind::Specular {
                eta: exact_eta(scene, &v[i].at, v[i].eta),
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
