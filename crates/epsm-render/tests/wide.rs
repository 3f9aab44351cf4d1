//! The wide tracer against the scalar one: every shipped scene's image is
//! the same, byte for byte, whatever the thread count.

use std::path::Path;

use epsm_render::Scene;
use epsm_render::tracer::{Kernel, RenderOptions, render_with};

fn scene(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name);
    epsm_render::scene::load::load_scene(&path).expect("shipped scene loads")
}

#[test]
fn shipped_scenes_render_the_same_images_wide_and_scalar() {
    if !Kernel::wide_available() {
        eprintln!("no AVX-512 on this CPU: the wide tracer is not used, nothing to compare");
        return;
    }
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .expect("scenes/")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".toml"))
        .collect();
    names.sort();
    assert!(names.len() >= 8, "{names:?}");
    for name in &names {
        let s = scene(name);
        let opts = RenderOptions {
            spp: 5,
            ..RenderOptions::from_scene(&s)
        };
        let scalar = render_with(&s, &opts, Kernel::Scalar, &|_| {});
        let wide = render_with(&s, &opts, Kernel::Fastest, &|_| {});
        let (a, b) = (&scalar.image, &wide.image);
        let mut differ = 0;
        for y in 0..a.height {
            for x in 0..a.width {
                let (p, q) = (a.get(x, y), b.get(x, y));
                if p.to_array().map(f32::to_bits) != q.to_array().map(f32::to_bits) {
                    if differ < 5 {
                        eprintln!("{name}: pixel ({x}, {y}) {p} scalar, {q} wide");
                    }
                    differ += 1;
                }
            }
        }
        assert_eq!(differ, 0, "{name}: {differ} pixels differ");
        assert_eq!(scalar.counters, wide.counters, "{name}");
    }
}
