//! Differentiable path types and the classification of recorded paths
//! (docs/design.md §5.4).
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
//!
//! The record's `f32` vertices satisfy the specular constraints only to
//! ~1e-7, and on sensitive chains (refraction through a tessellated glass
//! sphere) derivatives taken there differed from those on the manifold by
//! up to 28% in our measurements. So `classify` projects every path with
//! unknowns onto `C = 0` at θ₀ (Newton from the record, usually one step;
//! [`crate::newton::NewtonSettings::projection`]); a path whose projection
//! fails is counted by reason.

mod build;

use epsm_render::Scene;
use epsm_render::materials::VertexKind;
use epsm_render::record::{ConnectionRecord, PathRecord, VertexRecord};
use glam::{DVec2, UVec2, Vec3};

use crate::constraints::Constraint;
use crate::drops::{DropCounts, DropReason, Dropped};
use crate::motion::Motion;
use crate::newton::{NewtonSettings, project};
use crate::solve::SolveSettings;
use crate::vertex::Anchor;
use build::build;

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
    /// A point on a triangle or an exact sphere; `unknown` is its column
    /// block when it is solved for.
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
enum End<'a> {
    Vertex(&'a VertexRecord),
    Light(ConnectionRecord),
}

/// Classifies a record into differentiable paths, with vertex tangents built
/// in `motion` (the current θ, which becomes θ₀ for these paths), each
/// projected onto its manifold (the guards of `settings` apply). The record
/// of a sample the tracer dropped yields no path and is counted once, by
/// its reason ([`PathRecord::dropped`]); so is a shadow whose strength it
/// dropped ([`ConnectionRecord::dropped`]).
pub fn classify(
    record: &PathRecord,
    scene: &Scene,
    motion: &Motion,
    settings: &SolveSettings,
) -> Classified {
    let mut out = Classified::default();
    if let Some(d) = record.dropped {
        out.skipped.add(d.into());
        return out;
    }
    let v = &record.vertices;
    if v.is_empty() {
        return out;
    }
    let push = |kind,
                verts: &[&VertexRecord],
                end: Option<End<'_>>,
                contribution,
                out: &mut Classified| match build(
        kind,
        record,
        scene,
        motion,
        verts,
        end,
        contribution,
    ) {
        Ok(Some(p)) if p.unknowns() == 0 => out.paths.push(p),
        Ok(Some(p)) => match project(&p, motion, settings, &NewtonSettings::projection()) {
            Ok(p) => out.paths.push(p),
            Err(Dropped(r)) => out.skipped.add(r),
        },
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
        let chain: Vec<&VertexRecord> = v[..k].iter().collect();
        if let Some(d) = first_diffuse {
            let kind = if emissive(d) {
                PathKind::ChainToLight
            } else {
                PathKind::ChainToSurface
            };
            let c = record.radiance - v[..k].iter().map(|x| x.contribution).sum::<Vec3>();
            tracked += c;
            push(kind, &chain, Some(End::Vertex(&v[d])), c, &mut out);
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
        let verts: Vec<&VertexRecord> = v[..m].iter().collect();
        if m > 1 && m < v.len() && emissive(m) {
            // The light's emission: its vertex's contribution less the
            // next-event estimates made there.
            let emitted = v[m].contribution
                - record
                    .connections
                    .iter()
                    .filter(|c| c.vertex as usize == m)
                    .map(|c| c.contribution)
                    .sum::<Vec3>();
            tracked += emitted;
            push(
                PathKind::Caustic,
                &verts,
                Some(End::Vertex(&v[m])),
                emitted,
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
        // Connections from D through glass to a light.
        for chain in record.chains.iter().filter(|c| c.connection.vertex == 0) {
            let verts: Vec<&VertexRecord> = std::iter::once(&v[0])
                .chain(chain.specular.iter())
                .collect();
            tracked += chain.connection.contribution;
            push(
                PathKind::Caustic,
                &verts,
                Some(End::Light(chain.connection)),
                chain.connection.contribution,
                &mut out,
            );
        }
        // Shadows at D (one whose strength the tracer dropped is counted).
        for conn in record
            .connections
            .iter()
            .filter(|c| c.vertex == 0 && c.occluder.is_some())
        {
            match conn.dropped {
                Some(d) => out.skipped.add(d.into()),
                None => push(
                    PathKind::Shadow,
                    &[&v[0]],
                    Some(End::Light(*conn)),
                    conn.unoccluded,
                    &mut out,
                ),
            }
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
