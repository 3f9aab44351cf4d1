//! Path records: what the differentiation side (`epsm-core`) needs to know
//! about a traced path, and nothing more.
//!
//! A caller picks a [`RecordLevel`] so that scenes pay only for what they
//! need. Recording observes the tracer: it never changes the random numbers
//! consumed or the radiance computed (the only extra work is a closest-hit
//! query on blocked shadow rays, to name the first occluder).
//!
//! A sample the tracer drops (its radiance was not finite: the image gets
//! zero for it) keeps a record that says so ([`PathRecord::dropped`]) and
//! holds nothing else: no vertices, connections or escaped radiance, and a
//! zero radiance, as the image has. Nothing of it can be mistaken for a
//! path to differentiate, and its consumers count the drop once.

use glam::{UVec2, Vec2, Vec3};

use crate::hit::Hit;
use crate::lights::LightPoint;
use crate::materials::{Lobe, VertexKind};
use crate::scene::ObjectId;

/// How much of each path to record.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum RecordLevel {
    /// The first surface vertex only (primary visibility: silhouettes, layout).
    Primary,
    /// Vertices up to and including the first diffuse vertex, and the
    /// next-event connections made at them (chains to surfaces and lights,
    /// shadows at the first diffuse vertex).
    FirstDiffuse,
    /// Every vertex and connection (caustics: camera → D → S⁺ → L).
    Full,
}

/// Where a point lies on a triangle of an object (on an exact sphere,
/// [`Surface::Sphere`](crate::scene::Surface): triangle 0 and the octahedral
/// coordinates of the object-space point, [`crate::sphere`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrianglePoint {
    /// The object.
    pub object: ObjectId,
    /// Triangle index within the object's mesh (0 on an exact sphere).
    pub triangle: u32,
    /// Barycentric `b1` (first octahedral coordinate on an exact sphere).
    pub b1: f32,
    /// Barycentric `b2` (second octahedral coordinate on an exact sphere).
    pub b2: f32,
}

impl From<&Hit> for TrianglePoint {
    /// Where `hit` lies.
    fn from(hit: &Hit) -> Self {
        Self {
            object: hit.object,
            triangle: hit.triangle,
            b1: hit.b1,
            b2: hit.b2,
        }
    }
}

/// One surface vertex of a path (`x1`, `x2`, …; the camera is `x0`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VertexRecord {
    /// Object, triangle and local coordinates.
    pub at: TrianglePoint,
    /// Position, world space.
    pub p: Vec3,
    /// Unit geometric normal, world space.
    pub ng: Vec3,
    /// Unit shading normal, world space.
    pub ns: Vec3,
    /// The kind of manifold vertex the material makes.
    pub kind: VertexKind,
    /// The lobe sampled to continue the path; `None` when the path ended here
    /// (absorbed, Russian roulette, max depth, or an emitter with no BSDF
    /// continuation recorded).
    pub lobe: Option<Lobe>,
    /// Relative IOR `η(wo side)/η(wi side)` of the sampled lobe (1 for reflection).
    pub eta: f32,
    /// Sampled microfacet normal, world space (the shading normal for smooth
    /// and diffuse lobes).
    pub m: Vec3,
    /// Path throughput arriving at this vertex (before its BSDF).
    pub throughput: Vec3,
    /// Radiance this vertex added to the pixel sample: its emission hit by
    /// BSDF sampling (MIS-weighted) and its next-event contributions.
    pub contribution: Vec3,
}

/// A next-event-estimation connection from a path vertex to a light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConnectionRecord {
    /// Index into [`PathRecord::vertices`] of the vertex that connected.
    pub vertex: u32,
    /// The light point.
    pub light: LightPoint,
    /// Light position, world space (for the background: the unit direction).
    pub light_position: Vec3,
    /// Light normal (zero for point lights and the background).
    pub light_normal: Vec3,
    /// The radiance the connection added (zero when blocked).
    pub contribution: Vec3,
    /// What the contribution would have been if the ray were unblocked: the
    /// shadow's strength (zero when `dropped`).
    pub unoccluded: Vec3,
    /// The first occluder when the shadow ray was blocked.
    pub occluder: Option<OccluderRecord>,
    /// Set when the tracer dropped the shadow's strength: the ray was
    /// blocked and `unoccluded` was NaN or infinite. The sample's radiance
    /// does not include that strength, so the sample stays; `unoccluded` is
    /// zero and the derivative side counts the shadow dropped by this
    /// reason where it would have used it.
    pub dropped: Option<SampleDrop>,
}

/// A manifold next-event connection: from a path vertex through dielectric
/// refractions to a point on an area light (`tracer` module `chain`).
#[derive(Clone, Debug, PartialEq)]
pub struct ChainRecord {
    /// The vertex that connected, the light point the chain reaches (its
    /// first-hit position and normal) and the radiance it added; never
    /// blocked, never dropped.
    pub connection: ConnectionRecord,
    /// The refracting vertices from the path vertex to the light, each with
    /// lobe [`Lobe::SpecularTransmission`] and its relative IOR.
    pub specular: Vec<VertexRecord>,
}

/// The first surface that blocked a shadow ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OccluderRecord {
    /// Object, triangle and local coordinates.
    pub at: TrianglePoint,
    /// Position, world space.
    pub p: Vec3,
}

/// Why the tracer dropped a pixel sample ([`PathRecord::dropped`]) or a
/// blocked connection's strength ([`ConnectionRecord::dropped`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SampleDrop {
    /// A sample's radiance was NaN or infinite (counted in
    /// [`TraceCounters::non_finite`](crate::tracer::TraceCounters::non_finite)),
    /// or a blocked connection's unoccluded strength was.
    NonFinite,
}

/// A recorded path for one pixel sample.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PathRecord {
    /// The pixel.
    pub pixel: UVec2,
    /// The sample index within the pixel.
    pub sample: u32,
    /// Film position of the camera ray (pixels).
    pub film: Vec2,
    /// Surface vertices in path order.
    pub vertices: Vec<VertexRecord>,
    /// Next-event connections.
    pub connections: Vec<ConnectionRecord>,
    /// Manifold next-event connections through refracting surfaces.
    pub chains: Vec<ChainRecord>,
    /// Radiance of rays that left the scene (background), MIS-weighted.
    pub escaped: Vec3,
    /// Unit world direction of the ray that left the scene and saw the
    /// background (the last vertex's sampled `wo`, or the camera ray when
    /// no surface was hit); zero when `escaped` is zero. The colour
    /// derivatives evaluate the last vertex's BSDF along it.
    pub escape_dir: Vec3,
    /// The sample's total radiance (what the image accumulates).
    pub radiance: Vec3,
    /// Set when the tracer dropped the sample; the record then holds only
    /// its pixel, sample and film position.
    pub dropped: Option<SampleDrop>,
}

impl PathRecord {
    /// Marks the sample dropped for `reason`: clears everything recorded
    /// but which sample it is, so its radiance is zero, as in the image.
    pub(crate) fn drop_sample(&mut self, reason: SampleDrop) {
        *self = PathRecord {
            pixel: self.pixel,
            sample: self.sample,
            film: self.film,
            dropped: Some(reason),
            ..PathRecord::default()
        };
    }

    /// Whether the path touches object `id` at a recorded vertex, light point
    /// or occluder.
    pub fn touches(&self, id: ObjectId) -> bool {
        let lit_by = |c: &ConnectionRecord| {
            matches!(c.light, LightPoint::Area { object, .. } if object == id)
                || c.occluder.is_some_and(|o| o.at.object == id)
        };
        self.vertices.iter().any(|v| v.at.object == id)
            || self.connections.iter().any(lit_by)
            || self
                .chains
                .iter()
                .any(|c| lit_by(&c.connection) || c.specular.iter().any(|v| v.at.object == id))
    }
}
