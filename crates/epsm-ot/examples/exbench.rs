use epsm_ot::*;
fn main() {
    let n: usize = std::env::args().nth(1).unwrap().parse().unwrap();
    let (s, t) = synthetic::blobs_pair(n, 8).unwrap();
    let t0 = std::time::Instant::now();
    let k: usize = std::env::args().nth(2).unwrap().parse().unwrap();
    let blur: f64 = std::env::args().nth(3).unwrap().parse().unwrap();
    let mut st = ExactSettings::default();
    st.candidates = k;
    st.warm_start.blur = blur;
    let r = exact::solve(&s, &t, &st).unwrap();
    println!(
        "n {n} secs {} loss {} stats {:?}",
        t0.elapsed().as_secs_f64(),
        r.loss,
        r.stats
    );
}
