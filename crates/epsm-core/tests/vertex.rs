//! The tangent parameterisation agrees with the renderer's exact `f64`
//! surface points, and its `u`-derivatives with finite differences.

mod common;

use common::{End, Rng, Spec, Vertex, build};
use epsm_core::PathKind;
use epsm_core::vertex::Anchor;
use epsm_render::hit::surface_point_f64;

#[test]
fn anchors_match_render_surface_points_and_their_u_derivatives() {
    let mut rng = Rng::new(3);
    let mut checked = 0;
    while checked < 300 {
        let spec = Spec::new(
            PathKind::Caustic,
            vec![Vertex::Mirror, Vertex::Glass { ior: 1.5 }],
            End::Emitter,
        );
        let Some(s) = build(&spec, &mut rng) else {
            continue;
        };
        let motion = s.table.motion(&s.table.values());
        for v in &s.record.vertices {
            let (id, object) = (v.at.object, &s.scene.objects()[v.at.object as usize]);
            let (b1, b2) = (f64::from(v.at.b1), f64::from(v.at.b2));
            let om = motion.object(id);
            let anchor =
                Anchor::new(object, id, v.at.triangle, b1, b2, om).expect("regular triangle");
            let at = anchor.eval(om, [0.0, 0.0]);
            let sp = surface_point_f64(object, v.at.triangle, b1, b2);
            assert!(at.x.distance(sp.p) < 1e-12 * (1.0 + sp.p.length()));
            assert!(at.n.dot(sp.ns) > 1.0 - 1e-12, "{} vs {}", at.n, sp.ns);
            // Orthonormal in-plane tangents at θ₀; normals move as finite differences say.
            assert!(
                (at.dx_du[0].length() - 1.0).abs() < 1e-12
                    && at.dx_du[0].dot(at.dx_du[1]).abs() < 1e-12
            );
            let h = 1e-6;
            for k in 0..2 {
                let mut du = [0.0; 2];
                du[k] = h;
                let (p, m) = (anchor.eval(om, du), anchor.eval(om, du.map(|d| -d)));
                assert!(((p.x - m.x) / (2.0 * h) - at.dx_du[k]).length() < 1e-8);
                assert!(
                    ((p.n - m.n) / (2.0 * h) - at.dn_du[k]).length()
                        < 1e-6 * (1.0 + at.dn_du[k].length())
                );
            }
            checked += 1;
        }
    }
}
