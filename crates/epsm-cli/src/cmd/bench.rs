//! `epsm bench`: performance measurements printed as text or JSON.

/// The benchmarks.
#[derive(clap::Subcommand, Debug)]
pub enum BenchCommand {
    /// Path-tracing throughput on scene files.
    Render(super::bench_render::RenderBenchArgs),
    /// Adjoint manifold solves per second by path type and length.
    Manifold(super::bench_manifold::ManifoldBenchArgs),
}

/// Runs one benchmark.
pub fn run(cmd: &BenchCommand) -> anyhow::Result<()> {
    match cmd {
        BenchCommand::Render(a) => super::bench_render::run(a),
        BenchCommand::Manifold(a) => super::bench_manifold::run(a),
    }
}
