//! Builds an optimization problem in code and runs it: recover where the
//! table of `scenes/layout.toml` stands from a target rendered at its true
//! place. Run: `cargo run --release -p epsm-core --example optimize`.

use epsm_core::{Optimization, ParamSpec, Problem};
use epsm_scene::load_parts;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let scene = load_parts(std::path::Path::new("scenes/layout.toml"))?;
    let params = vec![
        ParamSpec::new("table.translate.x", -0.5, 0.04).with_true(0.0),
        ParamSpec::new("table.translate.z", 0.4, 0.04).with_true(0.0),
    ];
    let mut problem = Problem::new(scene, params);
    problem.optimizer.iterations = 30;
    problem.loss.match_resolution = [48, 48];
    let mut opt = Optimization::new(problem)?;
    while !opt.is_done() {
        let row = opt.step()?;
        println!(
            "iteration {:2}: loss {:.3e}, θ = {:?}, parameter error {:.4}",
            row.iteration,
            row.loss,
            row.theta,
            row.param_error.unwrap_or(f64::NAN)
        );
    }
    let (g, _) = opt.gradient()?;
    println!(
        "final θ = {:?}, dL/dθ = {:?}, paths solved {}",
        opt.theta(),
        g.grad,
        g.stats.solved
    );
    Ok(())
}
