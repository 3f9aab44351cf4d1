//! Why a path was not differentiated, and how often (docs/design.md §6).
//!
//! Nothing is clipped or scrubbed: a path whose derivative would be
//! unreliable is dropped with a reason, and the reasons are counted in every
//! report.

use std::fmt;

use epsm_render::record::SampleDrop;

/// Why a path was dropped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum DropReason {
    /// A zero (relative) pivot in the LU of `A`: the manifold is singular here
    /// (e.g. a caustic fold).
    Singular,
    /// The condition estimate `‖A‖₁‖A⁻¹‖₁` exceeds its bound.
    IllConditioned,
    /// `|cos|` below its bound at a specular or glossy vertex.
    Grazing,
    /// A path segment shorter than the scene-relative minimum.
    ShortSegment,
    /// A refraction vertex where Snell's law has no solution.
    TotalInternalReflection,
    /// The recorded lobe (reflection / refraction) disagrees with the geometry.
    LobeMismatch,
    /// A NaN or infinite value appeared.
    NonFinite,
    /// The pixel vertex is at or behind the camera's eye plane.
    BehindCamera,
    /// A vertex lies on a degenerate (zero-area) triangle (or an exact
    /// sphere with NaN coordinates or a singular placement).
    DegenerateTriangle,
    /// The path ends at the background (or another non-positional emitter):
    /// no position to differentiate.
    NotDifferentiable,
    /// A Newton re-solve did not converge (projecting a record onto its
    /// manifold in `classify`, or the oracle at a perturbed θ) while `A`
    /// at its last iterate passed the checks; when it did not, the drop is
    /// [`DropReason::Singular`] or [`DropReason::IllConditioned`] instead
    /// (a re-solve stalls at a fold, where the solutions merge and vanish).
    NewtonFailed,
}

impl DropReason {
    /// Every reason, in report order.
    pub const ALL: [DropReason; 11] = [
        DropReason::Singular,
        DropReason::IllConditioned,
        DropReason::Grazing,
        DropReason::ShortSegment,
        DropReason::TotalInternalReflection,
        DropReason::LobeMismatch,
        DropReason::NonFinite,
        DropReason::BehindCamera,
        DropReason::DegenerateTriangle,
        DropReason::NotDifferentiable,
        DropReason::NewtonFailed,
    ];

    /// A short snake-case name for reports.
    pub fn name(self) -> &'static str {
        match self {
            DropReason::Singular => "singular",
            DropReason::IllConditioned => "ill_conditioned",
            DropReason::Grazing => "grazing",
            DropReason::ShortSegment => "short_segment",
            DropReason::TotalInternalReflection => "total_internal_reflection",
            DropReason::LobeMismatch => "lobe_mismatch",
            DropReason::NonFinite => "non_finite",
            DropReason::BehindCamera => "behind_camera",
            DropReason::DegenerateTriangle => "degenerate_triangle",
            DropReason::NotDifferentiable => "not_differentiable",
            DropReason::NewtonFailed => "newton_failed",
        }
    }
}

impl From<SampleDrop> for DropReason {
    /// The reason a sample, or a shadow's strength, the tracer dropped is
    /// counted under.
    fn from(d: SampleDrop) -> Self {
        match d {
            SampleDrop::NonFinite => DropReason::NonFinite,
        }
    }
}

/// A path that was not differentiated, with the reason.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Dropped(pub DropReason);

impl fmt::Display for Dropped {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "path dropped: {}", self.0.name())
    }
}

impl std::error::Error for Dropped {}

impl From<DropReason> for Dropped {
    fn from(r: DropReason) -> Self {
        Dropped(r)
    }
}

/// Counts of dropped paths by reason.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DropCounts {
    counts: [u64; DropReason::ALL.len()],
}

impl DropCounts {
    /// Counts one drop.
    pub fn add(&mut self, reason: DropReason) {
        self.counts[reason as usize] += 1;
    }

    /// Adds every count of `other`.
    pub fn merge(&mut self, other: &DropCounts) {
        for (a, b) in self.counts.iter_mut().zip(other.counts) {
            *a += b;
        }
    }

    /// The count for `reason`.
    pub fn get(&self, reason: DropReason) -> u64 {
        self.counts[reason as usize]
    }

    /// All drops.
    pub fn total(&self) -> u64 {
        self.counts.iter().sum()
    }

    /// `(reason, count)` for every reason with a non-zero count.
    pub fn nonzero(&self) -> impl Iterator<Item = (DropReason, u64)> + '_ {
        DropReason::ALL
            .into_iter()
            .map(|r| (r, self.get(r)))
            .filter(|(_, c)| *c > 0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_add_merge_and_list_by_reason() {
        let mut a = DropCounts::default();
        a.add(DropReason::Singular);
        a.add(DropReason::Grazing);
        let mut b = DropCounts::default();
        b.add(DropReason::Grazing);
        b.merge(&a);
        assert_eq!(
            (
                b.get(DropReason::Grazing),
                b.get(DropReason::Singular),
                b.total()
            ),
            (2, 1, 3)
        );
        let listed: Vec<_> = b.nonzero().collect();
        assert_eq!(
            listed,
            vec![(DropReason::Singular, 1), (DropReason::Grazing, 2)]
        );
        assert!(
            DropReason::ALL
                .iter()
                .enumerate()
                .all(|(i, r)| *r as usize == i)
        );
    }
}
