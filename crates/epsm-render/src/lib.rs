//! # epsm-render
//!
//! The forward half of epsm: the scene model, the two-level BVH, materials,
//! lights, the camera, a deterministic path tracer (rayon over tiles) and the
//! path records the differentiation side (`epsm-core`) consumes. This crate
//! knows nothing about derivatives of geometry, nor about files: scene files,
//! mesh and image formats are `epsm-scene`'s, which builds the [`Scene`] this
//! crate renders.
//!
//! On x86-64 CPUs with AVX-512 or AVX2 the tracer renders sixteen paths at
//! once, one per vector lane: the private module `simd` holds the lane types
//! (generic over an AVX-512, AVX2 or portable backend), and a
//! `wide` module beside each layer (sampler, BVH, materials, lights, tracer)
//! its sixteen-lane steps, each lane bit-identical to the scalar step (see
//! [`tracer`]).
//!
//! ## Conventions
//! - **Space**: right-handed world space, `+y` up by default (the camera's `up`
//!   decides). Lengths are in scene units (any unit, used consistently).
//! - **Angles**: degrees in scene files, radians in code.
//! - **Colour**: linear RGB, `f32`. Area-light and background values are
//!   radiance (W·sr⁻¹·m⁻²); point-light values are radiant intensity (W·sr⁻¹).
//!   PNG files (`epsm-scene`) are sRGB-encoded, EXR files linear.
//! - **Directions** at a vertex: `wi` points toward the previous vertex (the
//!   camera side) and `wo` toward the next vertex (the light side). Both are
//!   unit vectors pointing *away* from the surface. Light flows `wo → wi`.
//! - **Local frame**: BSDFs work in the shading frame ([`frame::Frame`]) where
//!   the shading normal is `+z`. Transforms are named `a_from_b`
//!   (`world_from_object` maps object-space points to world space).
//! - **BSDF evaluation** ([`materials::Material::eval`]) returns
//!   `f(wi, wo)·|cos θo|`, the cosine *included*; sampling returns the weight
//!   `f·|cos θo| / pdf`. Delta lobes (smooth conductor and dielectric) are only
//!   reachable by sampling.
//! - **Image plane**: pixel `(0, 0)` is the top-left corner, `x` grows to the
//!   right and `y` downwards; pixel `(i, j)` covers `[i, i+1) × [j, j+1)`, its
//!   centre is `(i + 0.5, j + 0.5)`.
//! - **Triangles**: local coordinates `(b1, b2)` on a triangle `(p0, p1, p2)`
//!   are barycentric: `p = (1 − b1 − b2)·p0 + b1·p1 + b2·p2`. Geometric normal
//!   `normalize((p1 − p0) × (p2 − p0))` (counter-clockwise front face).
//!   On an exact sphere ([`scene::Surface::Sphere`]) `(b1, b2)` are the
//!   octahedral coordinates of the object-space point ([`sphere`]) and the
//!   triangle index is 0.

pub mod bvh;
pub mod camera;
pub mod error;
pub mod film;
pub mod frame;
pub mod hit;
pub mod lights;
pub mod materials;
pub mod ray;
pub mod record;
pub mod sampler;
pub mod scene;
#[cfg(target_arch = "x86_64")]
mod simd;
pub mod sphere;
pub mod tracer;

pub use camera::Camera;
pub use error::{Error, Result};
pub use film::Image;
pub use frame::Frame;
pub use ray::Ray;
pub use scene::Scene;
