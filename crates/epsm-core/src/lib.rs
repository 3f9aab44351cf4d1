//! # epsm-core: extended path space manifold derivatives
//!
//! How the screen position `p` of a traced path's visible effect moves when
//! scene parameters θ change (Xing et al., "Extended Path Space Manifolds for
//! Physically Based Differentiable Rendering", SIGGRAPH Asia 2023; docs/design.md §5).
//! A recorded path ([`epsm_render::record::PathRecord`]) is classified into
//! differentiable paths ([`paths::classify`]); each gets geometric constraints
//! `C(u, θ) = 0` on its unknown vertices, and the implicit function theorem
//! gives `du/dθ = −A⁻¹B` with `A = ∂C/∂u`, `B = ∂C/∂θ`. [`solve::solve_adjoint`]
//! does one transposed solve per path for a loss gradient `g = ∂L/∂p`;
//! [`solve::solve_forward`] returns the full `dp/dθ`; [`newton`] re-solves
//! `C = 0` at perturbed θ and is the oracle both are checked against
//! ([`check`]).
//!
//! ## Conventions
//! - **Units**: lengths in scene units; parameter values in user units
//!   (translations in scene units, rotations in **degrees**, scale as a factor,
//!   colours and roughness in their own units). Derivatives are per user unit:
//!   `dp/dθ` is in pixels per scene unit, pixels per degree, and so on.
//! - **Pixels**: film coordinates of `epsm-render` (pixel `(0, 0)` top-left,
//!   `y` down), through [`epsm_render::Camera`]'s pinhole projection π.
//! - **Vertices**: a path is `x0` (the camera) `x1 … xn`. An *unknown* vertex
//!   lies on a triangle or an exact sphere and is addressed by tangent
//!   coordinates `u = (u1, u2)` in that triangle's plane, or in the sphere's
//!   gnomonic chart around the vertex ([`vertex`]): at the base configuration
//!   θ₀, `∂x/∂u` is orthonormal whatever the triangle's size or shape or the
//!   sphere's placement. A *fixed*
//!   vertex (the camera, the diffuse vertex ending a chain, light points,
//!   occluder points) is no unknown: it moves rigidly with its object.
//! - **Directions** follow `epsm-render`: at vertex `i`,
//!   `wi = normalize(x_{i−1} − x_i)`, `wo = normalize(x_{i+1} − x_i)`.
//! - **Frames**: each constrained vertex keeps the Duff frame `(s₀, t₀)` of its
//!   base shading normal `n₀` and transports it by the minimal rotation
//!   `n₀ → n` ([`frame`]); `[F·w]_xy = (s·w, t·w)`.
//! - **Constraints** (one 2-D constraint per unknown vertex, [`constraints`]):
//!   *half vector* `[F·(wi + η wo)]_xy = 0` at smooth specular vertices (η = 1
//!   for reflection, the record's relative IOR for refraction; unnormalised);
//!   *glossy* `[F·normalize(wi + wo)]_xy = m_xy` (the microfacet normal kept);
//!   *fixed direction* `[F·wo]_xy = c` at a caustic receiver (light keeps
//!   arriving from the same local direction); *collinear*
//!   `[F·(normalize(o − x) − normalize(y − x))]_xy = 0` at a shadow receiver
//!   (it stays on the line from the light point `y` through the occluder `o`).
//! - **Precision**: everything here is `f64`, recomputed from the meshes (or
//!   the exact spheres' octahedral coordinates) and transforms, never from
//!   the `f32` record positions.
//! - **Robustness** (docs/design.md §6): a path that cannot be differentiated reliably
//!   is dropped with a [`drops::DropReason`] and counted; nothing is clipped or
//!   scrubbed.
//! - **On the manifold**: [`classify`] projects each path onto `C = 0` (the
//!   `f32` record satisfies it to ~1e-7 only), so derivatives are taken at an
//!   exact solution.
//!
//! ## Use
//!
//! ```no_run
//! use epsm_core::{ParamTable, SolveSettings, classify, solve_adjoint};
//! use epsm_render::record::RecordLevel;
//! use epsm_scene::load::load_scene;
//! use epsm_render::tracer::{RenderOptions, render_recorded};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let scene = load_scene("scenes/mirror.toml".as_ref())?;
//! let mut table = ParamTable::new(&scene);
//! table.add("mirror.rotate.y")?;
//! // Once per iteration: placements and their derivatives at θ.
//! let motion = table.motion(&table.values());
//! let settings = SolveSettings::for_radius(scene.radius());
//! let opts = RenderOptions::from_scene(&scene);
//! let (_, records) = render_recorded(&scene, &opts, RecordLevel::Full, &|_| {});
//! let mut grad = vec![0.0; table.len()];
//! for record in &records {
//!     for path in classify(record, &scene, &motion, &settings).paths {
//!         let g_xy = glam::DVec2::new(1.0, 0.0); // ∂L/∂p at the path's pixel
//!         if let Ok(g) = solve_adjoint(&path, g_xy, &motion, &settings) {
//!             for (k, v) in g.entries {
//!                 grad[k] += v;
//!             }
//!         }
//!     }
//! }
//! # Ok(())
//! # }
//! ```

pub mod backprop;
pub mod check;
pub mod colour;
pub mod constraints;
pub mod drops;
pub mod error;
pub mod field;
pub mod frame;
pub mod inspect;
pub mod loss;
pub mod motion;
pub mod newton;
pub mod optim;
pub mod params;
pub mod paths;
pub mod pixel;
pub mod problem;
pub mod report;
pub mod run;
pub mod schedule;
pub mod solve;
#[cfg(test)]
mod testing;
pub mod vertex;

pub use drops::{DropCounts, DropReason, Dropped};
/// Scene loading (TOML, glTF 2.0, Mitsuba 3 XML) for front ends that reach
/// the renderer through this crate.
pub use epsm_scene::{load_parts, load_scene};
pub use error::{Error, Result, error_chain};
pub use motion::Motion;
pub use params::ParamTable;
pub use paths::{DiffPath, PathKind, classify};
pub use problem::{ParamSpec, Problem, load_problem, problem_from_str, problem_with_target};
pub use run::{Checkpoint, OptResult, Optimization, OptimizeError};
pub use schedule::Method;
pub use solve::{Gradient, PixelJacobian, SolveSettings, solve_adjoint, solve_forward};
