//! Subcommands of the `epsm` binary.

pub mod bench_ot;
