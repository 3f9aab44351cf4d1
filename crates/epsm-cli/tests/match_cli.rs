//! `epsm match` end to end: an image matched to itself costs nothing, two
//! different renders cost something and give a picture, and a bad flag is
//! an error naming it.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn epsm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_epsm"))
        .args(args)
        .output()
        .expect("epsm runs")
}

fn scene(name: &str) -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    root.join(name).to_str().expect("utf-8").to_owned()
}

/// The value of the `key value` line `key` of `epsm match`'s output.
fn value(out: &Output, key: &str) -> f64 {
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text
        .lines()
        .find_map(|l| l.strip_prefix(&format!("{key} ")))
        .unwrap_or_else(|| panic!("no `{key}` line in {text}"));
    line.parse().expect("a number")
}

#[test]
fn match_prints_the_loss_and_draws_the_matching() {
    let dir: PathBuf = std::env::temp_dir().join(format!("epsm-match-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = |name: &str| dir.join(name).to_str().expect("utf-8").to_owned();
    for (file, name) in [("layout.exr", "layout.toml"), ("swap.exr", "swap.toml")] {
        let r = epsm(&["render", &scene(name), "--spp", "2", "-o", &path(file)]);
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    }
    let same = epsm(&[
        "match",
        &path("layout.exr"),
        &path("layout.exr"),
        "--resolution",
        "16",
        "16",
    ]);
    assert!(
        same.status.success(),
        "{}",
        String::from_utf8_lossy(&same.stderr)
    );
    assert_eq!(value(&same, "loss"), 0.0);

    let picture = path("matching.png");
    let args = [
        "--resolution",
        "24",
        "16",
        "--solver",
        "sinkhorn",
        "--blur",
        "0.05",
        "-o",
        &picture,
    ];
    let other = epsm(
        &[
            &["match", &path("layout.exr"), &path("swap.exr")],
            &args[..],
        ]
        .concat(),
    );
    assert!(
        other.status.success(),
        "{}",
        String::from_utf8_lossy(&other.stderr)
    );
    assert!(value(&other, "loss") > 1e-4);
    assert!(value(&other, "marginal_error") < 1e-3);
    assert!(Path::new(&picture).is_file());

    let bad = epsm(&[
        "match",
        &path("layout.exr"),
        &path("swap.exr"),
        "--solver",
        "pot",
    ]);
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("solver: unknown solver `pot`"));
    let _ = std::fs::remove_dir_all(&dir);
}
