//! Size guard: the time and memory one solve is expected to take, from the number of points.
//!
//! A match too large for the machine should be refused before it runs for
//! minutes and takes gigabytes. [`Matcher::estimate`] gives the expected
//! cold solve of `n` points per cloud from power laws fitted to `epsm bench ot`
//! on the blobs pairs (2-core AVX2/AVX-512 machine, shared; the fits err on
//! the slow side, `docs/performance.md` has the measurements):
//!
//! | matcher    | seconds                    | bytes        |
//! |------------|----------------------------|--------------|
//! | `exact`    | 0.5 · (n / 4096)^1.85      | 4 KB · n     |
//! | `sinkhorn` | 0.5 · (n / 4096)^1.75      | 1.5 KB · n   |
//! | `sliced`   | 0.01 · (n / 4096)^1.1      | 0.2 KB · n   |
//!
//! (Measured: exact 4096 points 1.5 s, 17 MB; 16384 points 19 s, 62 MB; sinkhorn
//! 1.0 s, 8 MB and 11 s, 20 MB, on the machine loaded about 7 times over; a
//! 512² match in an optimization took over 60 s and 2.2 GB per iteration.)
//! [`Matcher::check_size`] refuses an estimate beyond [`MatchLimits`] with
//! [`OtError::MatchTooLarge`], naming the estimate and the limit. A warm
//! start ([`crate::MatchState`]) is faster than the estimate, never slower by design.

use crate::Matcher;
use crate::error::OtError;

/// The expected cost of one cold solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MatchEstimate {
    /// Points per cloud.
    pub n: usize,
    /// Expected wall-clock seconds.
    pub seconds: f64,
    /// Expected peak memory of the solve, bytes.
    pub bytes: f64,
}

/// The largest accepted estimate of one solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MatchLimits {
    /// Most seconds per solve.
    pub seconds: f64,
    /// Most bytes per solve.
    pub bytes: f64,
}

impl Default for MatchLimits {
    /// 120 s and 2 GiB: a 256² exact match (65 536 points, about 80 s and
    /// 0.3 GB) passes, a 512² one (about 1100 s) does not.
    fn default() -> Self {
        Self {
            seconds: 120.0,
            bytes: 2.0 * 1024.0 * 1024.0 * 1024.0,
        }
    }
}

impl Matcher {
    /// The expected cost of one cold solve of `n` points per cloud (see the module doc).
    pub fn estimate(&self, n: usize) -> MatchEstimate {
        let (seconds_4096, exponent, bytes_per_point) = match self {
            Self::Exact(_) => (0.5, 1.85, 4096.0),
            Self::Sinkhorn(_) => (0.5, 1.75, 1536.0),
            Self::Sliced(_) => (0.01, 1.1, 200.0),
        };
        let scale = n as f64 / 4096.0;
        MatchEstimate {
            n,
            seconds: seconds_4096 * scale.powf(exponent),
            bytes: bytes_per_point * n as f64,
        }
    }

    /// The estimate of `n` points, or [`OtError::MatchTooLarge`] when it exceeds `limits`.
    pub fn check_size(&self, n: usize, limits: &MatchLimits) -> Result<MatchEstimate, OtError> {
        let e = self.estimate(n);
        if e.seconds > limits.seconds || e.bytes > limits.bytes {
            return Err(OtError::MatchTooLarge {
                matcher: self.name(),
                n,
                seconds: e.seconds,
                bytes: e.bytes,
                max_seconds: limits.seconds,
                max_bytes: limits.bytes,
            });
        }
        Ok(e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_512_square_exact_match_is_refused_and_a_64_square_one_passes() {
        let limits = MatchLimits::default();
        let exact = Matcher::exact();
        let small = exact.check_size(64 * 64, &limits);
        assert!(
            matches!(small, Ok(e) if e.seconds < 1.0 && e.bytes < 1e8),
            "{small:?}"
        );
        assert!(exact.check_size(256 * 256, &limits).is_ok());
        let big = exact.check_size(512 * 512, &limits);
        let Err(OtError::MatchTooLarge {
            n,
            seconds,
            max_seconds,
            ..
        }) = big
        else {
            panic!("{big:?}");
        };
        assert_eq!(n, 512 * 512);
        assert!(seconds > 60.0 && max_seconds == 120.0);
        let text = exact
            .check_size(512 * 512, &limits)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(text.contains("262144") && text.contains("120"), "{text}");
        // The estimates grow with n, and memory alone can refuse.
        let tight = MatchLimits {
            seconds: f64::INFINITY,
            bytes: 1e6,
        };
        assert!(Matcher::sinkhorn().check_size(4096, &tight).is_err());
        assert!(
            Matcher::sliced().estimate(1 << 20).seconds
                > Matcher::sliced().estimate(1 << 10).seconds
        );
    }
}
