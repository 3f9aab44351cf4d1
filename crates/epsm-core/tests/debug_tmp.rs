mod common;
use common::*;
use epsm_core::check::*;
use epsm_core::*;
#[test]
fn dbg() {
    let mut rng = Rng(4);
    let settings = CheckSettings::for_radius(1.0);
    let mut n = 0;
    while n < 400 {
        let len = 1 + rng.below(3);
        let chain: Vec<Vertex> = (0..len)
            .map(|_| match rng.below(3) {
                0 => Vertex::Mirror,
                1 => Vertex::Glass {
                    ior: rng.range(1.1, 2.4),
                },
                _ => Vertex::Glossy {
                    alpha: rng.range(0.02, 0.6),
                },
            })
            .collect();
        let spec = Spec::new(PathKind::ChainToSurface, chain.clone(), End::Surface);
        let Some(mut s) = build(&spec, &mut rng) else {
            continue;
        };
        random_params(&mut s.table, &s.objects, &s.lights, &mut rng);
        let motion = s.table.motion(&s.table.values());
        let c = classify(&s.record, &s.scene, &motion);
        for p in c
            .paths
            .iter()
            .filter(|p| p.kind == PathKind::ChainToSurface)
        {
            n += 1;
            let r = check_path(p, &s.table, &motion, &settings);
            match r {
                Ok(pc) if pc.rel_err > 1e-6 => {
                    let keys: Vec<_> = p
                        .params
                        .iter()
                        .map(|&i| s.table.params()[i].key.clone())
                        .collect();
                    let pp =
                        newton::project(p, &motion, &settings.solve, &settings.newton).unwrap();
                    let j = solve_forward(&pp, &motion, &settings.solve).unwrap();
                    for (k, &param) in j.params.iter().enumerate() {
                        let hs = [1e-2, 1e-3, 1e-4, 1e-5].map(|h| {
                            newton::central_difference(
                                &pp,
                                &s.table,
                                param,
                                h * newton::fd_step(&s.table.params()[param].target, 1.0) / 1e-3,
                                &settings.solve,
                                &settings.newton,
                            )
                            .map(|d| (d - j.columns[k]).length() / j.columns[k].length())
                        });
                        eprintln!(
                            "  {} an {:?} {:?}",
                            s.table.params()[param].key,
                            j.columns[k],
                            hs
                        );
                    }
                    eprintln!(
                        "BAD {:?} cond {:.1e} err {:.1e} {:?} {:?}",
                        chain,
                        pc.condition,
                        pc.rel_err,
                        keys,
                        s.record.vertices.iter().map(|v| v.eta).collect::<Vec<_>>()
                    );
                }
                Err(e) => {
                    let pr = newton::project(p, &motion, &settings.solve, &settings.newton);
                    eprintln!("DROP {:?} {:?} projection ok: {}", chain, e, pr.is_ok());
                    if let Err(_) = pr {
                        let r = newton::resolve(
                            p,
                            &motion,
                            &settings.solve,
                            &newton::NewtonSettings {
                                tolerance: 1e-13,
                                max_iterations: 50,
                            },
                        );
                        eprintln!("   {:?}", r);
                    }
                }
                _ => {}
            }
        }
    }
    panic!();
}
