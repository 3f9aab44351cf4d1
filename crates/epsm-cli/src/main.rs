//! The `epsm` command-line tool (minimal wiring: `epsm bench ot`).

mod cmd;

use clap::{Parser, Subcommand};

/// epsm: differentiable rendering with RGBXY derivatives and optimal transport.
#[derive(Debug, Parser)]
#[command(name = "epsm", version)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Benchmarks.
    #[command(subcommand)]
    Bench(Bench),
}

#[derive(Debug, Subcommand)]
enum Bench {
    /// Time one optimal-transport solve on the synthetic blobs pair.
    Ot(cmd::bench_ot::OtBenchArgs),
}

fn main() -> anyhow::Result<()> {
    match Cli::parse().command {
        Command::Bench(Bench::Ot(args)) => cmd::bench_ot::run(&args),
    }
}
