//! `epsm bench`: performance measurements printed as text or JSON.

/// The benchmarks.
#[derive(clap::Subcommand, Debug)]
pub enum BenchCommand {
    /// Path-tracing throughput on scene files.
    Render(super::bench_render::RenderBenchArgs),
    /// Adjoint manifold solves per second by path type and length.
    Manifold(super::bench_manifold::ManifoldBenchArgs),
    /// BVH build and update time and closest-hit / occlusion rays per second
    /// on a bumpy sphere (coherent and incoherent rays, 1 and all threads).
    Rays(super::bench_rays::RaysBenchArgs),
    /// Optimal-transport matching of two synthetic RGBXY images (coloured
    /// blobs on a noisy background): seconds, loss, marginal error, memory.
    Ot(super::bench_ot::OtBenchArgs),
}

/// Runs one benchmark.
pub fn run(cmd: &BenchCommand) -> anyhow::Result<()> {
    match cmd {
        BenchCommand::Render(a) => super::bench_render::run(a),
        BenchCommand::Manifold(a) => super::bench_manifold::run(a),
        BenchCommand::Rays(a) => super::bench_rays::run(a),
        BenchCommand::Ot(a) => super::bench_ot::run(a),
    }
}
