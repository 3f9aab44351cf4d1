use epsm_ot::*;
fn main() {
    let (s, t) = synthetic::blobs_pair(4096, 8).unwrap();
    let st = SinkhornSettings {
        blur: 1.0,
        scaling: 0.5,
        truncation: 1e9,
        max_polish_iterations: 50,
        marginal_tolerance: 1e-12,
        ..Default::default()
    };
    let t0 = std::time::Instant::now();
    let r = sinkhorn::solve(&s, &t, &st).unwrap();
    let secs = t0.elapsed().as_secs_f64();
    println!(
        "secs {secs} pairs {} => {} Gpairs/s it {}",
        r.stats.pair_evaluations,
        r.stats.pair_evaluations as f64 / secs / 1e9,
        r.stats.iterations
    );
}
