//! `epsm`: the command-line front end of the epsm differentiable renderer.
//!
//! Every command is documented in `docs/cli.md`; `epsm <command> --help`
//! prints the same flags.

mod cmd;
mod progress;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// epsm — a CPU, pure-Rust, physically based differentiable renderer
/// (extended path space manifolds + optimal-transport loss).
#[derive(Parser, Debug)]
#[command(name = "epsm", version, about, long_about = None, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a scene file to an EXR (linear) or PNG (sRGB) image.
    Render(cmd::render::RenderArgs),
    /// Optimize scene parameters to match a target (docs/problem-format.md).
    Optimize(cmd::optimize::OptimizeArgs),
    /// Run several methods on one problem and plot error against time.
    Compare(cmd::compare::CompareArgs),
    /// Write gradient images (motion field, dI/dθ, OT matching) of one parameter.
    Grad(cmd::grad::GradArgs),
    /// Match two images (EXR or PNG) by optimal transport: loss, solve
    /// statistics and a picture of the matching.
    Match(cmd::matching::MatchArgs),
    /// Validate manifold derivatives of traced paths against Newton re-solves.
    Check(cmd::check::CheckArgs),
    /// Measure performance (renderer, BVH, matching) and print the numbers.
    #[command(subcommand)]
    Bench(cmd::bench::BenchCommand),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Render(args) => cmd::render::run(args),
        Command::Optimize(args) => cmd::optimize::run(args),
        Command::Compare(args) => cmd::compare::run(args),
        Command::Grad(args) => cmd::grad::run(args),
        Command::Match(args) => cmd::matching::run(args),
        Command::Check(args) => cmd::check::run(args),
        Command::Bench(b) => cmd::bench::run(b),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {}", epsm_core::error_chain(err.as_ref()));
            ExitCode::FAILURE
        }
    }
}
