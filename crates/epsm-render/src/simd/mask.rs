//! Lane masks: what every lane type's comparisons return and its selects
//! take, the same on every backend.

use std::ops::{BitAnd, BitOr, BitXor, Not};

use super::LANES;

/// One bit per lane: bit `i` set when lane `i` is selected. A plain `u16`,
/// so masks need no token and cost no vector register.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub(crate) struct Mask16(pub u16);

impl Mask16 {
    /// No lane.
    pub const NONE: Self = Self(0);
    /// Every lane.
    pub const ALL: Self = Self(u16::MAX);

    /// Lanes `0..n` (`n ≤ 16`).
    #[inline(always)]
    pub fn first(n: usize) -> Self {
        debug_assert!(n <= LANES);
        Self(((1u32 << n) - 1) as u16)
    }

    /// The lowest `n` lanes of `self` (all of them when it has fewer).
    #[inline(always)]
    pub fn first_of(self, n: u32) -> Self {
        let mut bits = self.0;
        let mut out = 0u16;
        for _ in 0..n.min(LANES as u32) {
            let lowest = bits & bits.wrapping_neg();
            out |= lowest;
            bits ^= lowest;
        }
        Self(out)
    }

    /// Whether any lane is set.
    #[inline(always)]
    pub fn any(self) -> bool {
        self.0 != 0
    }

    /// Whether every lane is set.
    #[inline(always)]
    pub fn all(self) -> bool {
        self.0 == u16::MAX
    }

    /// Whether lane `lane` is set.
    #[inline(always)]
    pub fn test(self, lane: usize) -> bool {
        self.0 >> (lane & (LANES - 1)) & 1 != 0
    }

    /// How many lanes are set.
    #[inline(always)]
    pub fn count(self) -> u32 {
        self.0.count_ones()
    }

    /// The lanes set, lowest first.
    #[inline(always)]
    pub fn lanes(self) -> impl Iterator<Item = usize> {
        let mut bits = self.0;
        std::iter::from_fn(move || {
            (bits != 0).then(|| {
                let lane = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                lane
            })
        })
    }

    /// Lanes of `self` not in `other`.
    #[inline(always)]
    pub fn and_not(self, other: Self) -> Self {
        Self(self.0 & !other.0)
    }

    /// Panics unless `len ≥ self.count()`: that a slice of `len` values
    /// holds enough for an expanding load into the lanes of `self` (the
    /// `expand_from` methods).
    #[inline(always)]
    pub(super) fn assert_expand_len(self, len: usize) {
        assert!(
            len >= self.count() as usize,
            "expanding load past the slice"
        );
    }
}

impl BitAnd for Mask16 {
    type Output = Self;
    #[inline(always)]
    fn bitand(self, o: Self) -> Self {
        Self(self.0 & o.0)
    }
}

impl BitOr for Mask16 {
    type Output = Self;
    #[inline(always)]
    fn bitor(self, o: Self) -> Self {
        Self(self.0 | o.0)
    }
}

impl BitXor for Mask16 {
    type Output = Self;
    #[inline(always)]
    fn bitxor(self, o: Self) -> Self {
        Self(self.0 ^ o.0)
    }
}

impl Not for Mask16 {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        Self(!self.0)
    }
}
