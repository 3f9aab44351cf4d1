//! `epsm bench`: performance measurements printed as text or JSON, one
//! module per benchmark.

pub mod iteration;
pub mod manifold;
pub mod ot;
pub mod rays;
pub mod render;

/// The benchmarks.
#[derive(clap::Subcommand, Debug)]
pub enum BenchCommand {
    /// Path-tracing throughput on scene files.
    Render(render::RenderBenchArgs),
    /// Adjoint manifold solves per second by path type and length.
    Manifold(manifold::ManifoldBenchArgs),
    /// BVH build and update time and closest-hit / occlusion rays per second
    /// on a bumpy sphere (coherent and incoherent rays, 1 and all threads).
    Rays(rays::RaysBenchArgs),
    /// Optimal-transport matching of two synthetic RGBXY images (coloured
    /// blobs on a noisy background): seconds, loss, marginal error, memory.
    Ot(ot::OtBenchArgs),
    /// Seconds of one optimization iteration of a problem, split into its
    /// stages (primal render, trace, matching, solves), serial and
    /// overlapped.
    Iteration(iteration::IterationBenchArgs),
}

/// Runs one benchmark.
pub fn run(cmd: &BenchCommand) -> anyhow::Result<()> {
    match cmd {
        BenchCommand::Render(a) => render::run(a),
        BenchCommand::Manifold(a) => manifold::run(a),
        BenchCommand::Rays(a) => rays::run(a),
        BenchCommand::Ot(a) => ot::run(a),
        BenchCommand::Iteration(a) => iteration::run(a),
    }
}

/// CPU time used so far by all threads of this process, seconds (Linux:
/// the first field of each `/proc/self/task/*/schedstat`, nanoseconds).
fn cpu_seconds() -> Option<f64> {
    let mut total = 0u64;
    for task in std::fs::read_dir("/proc/self/task").ok()? {
        let stat = std::fs::read_to_string(task.ok()?.path().join("schedstat")).ok()?;
        total += stat.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    Some(total as f64 * 1e-9)
}
