//! Test support shared by the tests of the epsm crates (a dev-dependency
//! only; never part of a library's public surface):
//! - [`Rng`]: a seeded, portable random stream (PCG64-MCG from `rand_pcg`)
//!   with the few geometric draws the tests use;
//! - [`corpus`]: the runner that checks every file of a malformed-input
//!   corpus is rejected with an error naming the file and the field;
//! - [`scenes`] and [`problems`]: scene and problem files for tests of more
//!   than one crate;
//! - [`special`]: special files (a symlink to `/dev/zero`, a FIFO) where a
//!   loader expects an input file, and a check that it refuses them in time.

pub mod corpus;
pub mod problems;
mod rng;
pub mod scenes;
pub mod special;

pub use rng::Rng;
