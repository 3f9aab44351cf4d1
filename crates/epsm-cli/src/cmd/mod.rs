//! Subcommands.

pub mod bench_rays;
