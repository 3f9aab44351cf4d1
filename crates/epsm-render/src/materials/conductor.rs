//! Smooth conductor: a perfect mirror whose reflectance is `tint` at every
//! angle (an artist-friendly stand-in for the complex Fresnel of metals).
//!
//! The lobe is a delta distribution: `sample` returns the mirror direction with
//! weight `tint` and discrete probability 1; `eval` and `pdf` are zero.
//!
//! | key | unit | default | range |
//! |---|---|---|---|
//! | `tint` | linear RGB | — | [0, 1] per channel |
//!
//! ```toml
//! [[materials]]
//! name = "mirror"
//! type = "conductor"
//! tint = [0.95, 0.95, 0.95]
//! ```

use glam::Vec3;

use super::{BsdfSample, Lobe};

/// Smooth conductor: a perfect mirror whose Fresnel reflectance is `tint`.
#[derive(Clone, Debug, PartialEq)]
pub struct Conductor {
    /// Reflectance per channel, in [0, 1].
    pub tint: Vec3,
}

impl Conductor {
    /// The mirror direction of `wi` (local, `wi.z > 0`).
    pub(super) fn sample(&self, wi: Vec3) -> Option<BsdfSample> {
        Some(BsdfSample {
            wo: Vec3::new(-wi.x, -wi.y, wi.z),
            weight: self.tint,
            pdf: 1.0,
            lobe: Lobe::SpecularReflection,
            eta: 1.0,
            m: Vec3::Z,
        })
    }
}
