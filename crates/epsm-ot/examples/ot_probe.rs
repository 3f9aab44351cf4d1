//! Scratch probe (temporary): `ot_probe N sinkhorn|exact|exactsolver key=value...` on the blobs pair.
#![allow(clippy::unwrap_used, clippy::panic)]

use epsm_ot::{Matcher, Matching, SinkhornSettings, synthetic};
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let n: usize = a[1].parse().unwrap();
    let mode = a[2].as_str();
    let (s, t) = synthetic::blobs_pair(n, 0).unwrap();
    let mut st = SinkhornSettings::default();
    for kv in &a[3..] {
        let (k, v) = kv.split_once('=').unwrap();
        match k {
            "period" => st.coarse_period = v.parse().unwrap(),
            "msi" => st.max_scale_iterations = v.parse().unwrap(),
            "tol" => st.scale_tolerance = v.parse().unwrap(),
            "omega" => st.annealing_overrelaxation = v.parse().unwrap(),
            "jump" => st.jump_radii = v.parse().unwrap(),
            "cs" => st.cluster_size = v.parse().unwrap(),
            "scaling" => st.scaling = v.parse().unwrap(),
            "blur" => st.blur = v.parse().unwrap(),
            "and" => st.anderson_memory = v.parse().unwrap(),
            "trunc" => st.truncation = v.parse().unwrap(),
            _ => panic!("{k}"),
        }
    }
    st.exact_prices = mode == "exact";
    let m = if mode == "exactsolver" {
        Matcher::exact()
    } else {
        Matcher::Sinkhorn(st)
    };
    let t0 = std::time::Instant::now();
    let r = m.solve(&s, &t).unwrap();
    let secs = t0.elapsed().as_secs_f64();
    let (tc, me) = match &r.matching {
        Matching::Entropic(p) => (p.transport_cost, p.marginal_error),
        _ => (r.loss, 0.0),
    };
    println!(
        "n={n} mode={mode} {secs:.3}s loss={:.6} cost={tc:.6} marg={me:.2e} it={} pairs={:.3e} phases={:?}",
        r.loss,
        r.stats.iterations,
        r.stats.pair_evaluations as f64,
        r.stats
            .phases
            .iter()
            .map(|(k, v)| format!("{k}:{v:.3}"))
            .collect::<Vec<_>>()
    );
}
