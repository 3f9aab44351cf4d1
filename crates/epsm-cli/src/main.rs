//! The epsm command-line tool.

mod cmd;

use clap::{Parser, Subcommand};

/// epsm: differentiable rendering with extended path space manifolds.
#[derive(Parser)]
#[command(name = "epsm", version)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Benchmarks.
    Bench {
        #[command(subcommand)]
        what: Bench,
    },
}

#[derive(Subcommand)]
enum Bench {
    /// Ray tracing throughput of the BVH on a bumpy sphere.
    Rays(cmd::bench_rays::RaysBenchArgs),
}

fn main() -> anyhow::Result<()> {
    match Cli::parse().command {
        Command::Bench {
            what: Bench::Rays(args),
        } => cmd::bench_rays::run(&args),
    }
}
