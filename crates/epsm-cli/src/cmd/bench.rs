//! `epsm bench`: performance measurements printed as text or JSON.

/// The benchmarks.
#[derive(clap::Subcommand, Debug)]
pub enum BenchCommand {
    /// Path-tracing throughput on scene files.
    Render(super::bench_render::RenderBenchArgs),
}

/// Runs one benchmark.
pub fn run(cmd: &BenchCommand) -> anyhow::Result<()> {
    match cmd {
        BenchCommand::Render(a) => super::bench_render::run(a),
    }
}
