//! Placement derivatives against central differences.

use crate::ParamTable;
use crate::testing::scene;

#[test]
fn placement_derivatives_match_central_differences_and_zero_is_the_file_placement() {
    let scene = scene();
    let mut table = ParamTable::new(&scene);
    let keys = [
        "box.translate.y",
        "box.rotate.x",
        "box.rotate.y",
        "box.rotate.z",
        "box.scale",
        "lamp.translate.z",
        "camera.translate.x",
        "camera.yaw",
        "camera.pitch",
    ];
    for key in keys {
        table.add(key).expect("valid key");
    }
    let base = table.motion(&table.values());
    assert!(
        base.objects[0]
            .affine()
            .abs_diff_eq(scene.objects()[0].world_from_object, 1e-14)
    );
    let v: Vec<f64> = (0..keys.len())
        .map(|i| if i == 4 { 1.1 } else { 0.3 + 0.1 * i as f64 })
        .collect();
    let m = table.motion(&v);
    let h = 1e-6;
    for (i, key) in keys.iter().enumerate() {
        let (mut plus, mut minus) = (v.clone(), v.clone());
        plus[i] += h;
        minus[i] -= h;
        let (mp, mm) = (table.motion(&plus), table.motion(&minus));
        let fd = |a: f64, b: f64| (a - b) / (2.0 * h);
        if let Some(g) = m.objects[0].grads.iter().find(|g| g.param == i) {
            let dl = (mp.objects[0].linear - mm.objects[0].linear) * (0.5 / h);
            let dn = (mp.objects[0].normal - mm.objects[0].normal) * (0.5 / h);
            let dt = (mp.objects[0].translation - mm.objects[0].translation) / (2.0 * h);
            assert!(
                g.linear.abs_diff_eq(dl, 1e-7) && g.normal.abs_diff_eq(dn, 1e-7),
                "{key}"
            );
            assert!(g.translation.abs_diff_eq(dt, 1e-7), "{key}");
        } else if let Some(g) = m.camera.grads.iter().find(|g| g.param == i) {
            for (a, (p, q)) in [
                (
                    g.pose.origin,
                    (mp.camera.pose.origin, mm.camera.pose.origin),
                ),
                (
                    g.pose.forward,
                    (mp.camera.pose.forward, mm.camera.pose.forward),
                ),
                (g.pose.up, (mp.camera.pose.up, mm.camera.pose.up)),
            ] {
                assert!(
                    (0..3).all(|k| (a[k] - fd(p[k], q[k])).abs() < 1e-7),
                    "{key}"
                );
            }
        } else {
            let g = m.lights[0]
                .grads
                .iter()
                .find(|g| g.param == i)
                .expect("light param");
            assert!(g.dx.abs_diff_eq(
                (mp.lights[0].position - mm.lights[0].position) / (2.0 * h),
                1e-9
            ));
        }
    }
}
