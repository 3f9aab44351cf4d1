use epsm_ot::*;
fn main() {
    let (s, t) =
        synthetic::blobs_pair(std::env::args().nth(1).unwrap().parse().unwrap(), 8).unwrap();
    let ex = exact::solve(&s, &t, &ExactSettings::default())
        .unwrap()
        .loss;
    println!("exact {ex}");
    for (tr, jr) in [(30.0, 2.0)] {
        for cs in [32usize] {
            let st = SinkhornSettings {
                truncation: tr,
                jump_radii: jr,
                cluster_size: cs,
                ..Default::default()
            };
            let t0 = std::time::Instant::now();
            let r = sinkhorn::solve(&s, &t, &st).unwrap();
            println!("secs {}", t0.elapsed().as_secs_f64());
            if let Matching::Entropic(p) = &r.matching {
                println!(
                    "cs {cs}: loss {} tc {} me {} it {} pairs {}",
                    r.loss,
                    p.transport_cost,
                    p.marginal_error,
                    r.stats.iterations,
                    r.stats.pair_evaluations
                );
            }
        }
    }
}
