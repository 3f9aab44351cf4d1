mod common;
use common::*;
use epsm_core::newton::*;
use epsm_core::*;
#[test]
fn dbg() {
    let mut rng = Rng(1);
    let mut shown = 0;
    while shown < 6 {
        let spec = Spec::new(PathKind::Caustic, vec![Vertex::Mirror], End::Emitter);
        let Some(mut s) = build(&spec, &mut rng) else {
            continue;
        };
        random_params(&mut s.table, &s.objects, &s.lights, &mut rng);
        let motion = s.table.motion(&s.table.values());
        let c = classify(&s.record, &s.scene, &motion);
        let st = SolveSettings::for_radius(1.0);
        for p in c.paths.iter().filter(|p| p.kind == PathKind::Primary) {
            let j = solve_forward(p, &motion, &st).unwrap();
            for (k, &param) in j.params.iter().enumerate() {
                let fd =
                    central_difference(p, &s.table, param, 1e-3, &st, &NewtonSettings::default())
                        .unwrap();
                eprintln!(
                    "{} an {:?} fd {:?}",
                    s.table.params()[param].key,
                    j.columns[k],
                    fd
                );
            }
            shown += 1;
        }
    }
    panic!();
}
