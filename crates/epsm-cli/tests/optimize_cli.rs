//! `epsm optimize` end to end on a tiny problem: the report files exist and
//! parse, and `--resume` continues from the checkpoint.

use std::path::{Path, PathBuf};
use std::process::Command;

fn epsm(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_epsm"))
        .args(args)
        .output()
        .expect("epsm runs")
}

/// Runs `epsm optimize` on `problem` (relative to this crate) into a fresh
/// temporary folder named after `name`; the run's output and the folder.
fn optimize_into(problem: &str, name: &str) -> (std::process::Output, PathBuf) {
    let dir = std::env::temp_dir().join(format!("epsm-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let problem = Path::new(env!("CARGO_MANIFEST_DIR")).join(problem);
    let run = epsm(&[
        "optimize",
        problem.to_str().expect("utf-8"),
        "--out",
        dir.to_str().expect("utf-8 path"),
    ]);
    (run, dir)
}

fn tiny() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/tiny.toml")
}

#[test]
fn optimize_writes_parseable_reports_and_resumes() {
    let dir = std::env::temp_dir().join(format!("epsm-optimize-cli-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = dir.to_str().expect("utf-8 path");
    let problem = tiny();
    let run = epsm(&["optimize", problem.to_str().expect("utf-8"), "--out", out]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    // The exact matcher: no unconverged-solve warning.
    assert!(!stderr.contains("warning:"), "{stderr}");
    for f in [
        "run.csv",
        "report.png",
        "checkpoint.json",
        "target.png",
        "target.exr",
        "initial.png",
        "initial.exr",
        "final.png",
        "final.exr",
    ] {
        assert!(dir.join(f).is_file(), "{f} missing");
    }
    let csv = std::fs::read_to_string(dir.join("run.csv")).expect("run.csv");
    let lines: Vec<&str> = csv.lines().collect();
    assert!(
        lines[0].starts_with(
            "iteration,wall_s,loss,image_rmse,param_error,judged_loss,box.translate.x,"
        )
    );
    assert_eq!(lines.len(), 4, "header and 3 rows");
    // The summary: the best θ beside the last, the tolerance and whether
    // it is solved (tiny.toml: tolerance 0.45, initial error 0.5).
    let summary = std::fs::read_to_string(dir.join("summary.csv")).expect("summary.csv");
    let summary: Vec<Vec<&str>> = summary.lines().map(|l| l.split(',').collect()).collect();
    assert_eq!(summary.len(), 2, "header and one row");
    let cell = |name: &str| {
        let i = summary[0].iter().position(|c| *c == name).expect(name);
        summary[1][i]
    };
    let best: f64 = cell("best_param_error").parse().expect("best error");
    let last: f64 = cell("last_param_error").parse().expect("last error");
    assert!(best <= 0.5 && last.is_finite(), "best {best}, last {last}");
    assert_eq!(cell("tolerance").parse::<f64>().ok(), Some(0.45));
    assert_eq!(cell("solved"), if best <= 0.45 { "yes" } else { "no" });
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(stdout.contains("solved: "), "{stdout}");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(stderr.contains("auto render.spp_match = "), "{stderr}");
    let columns = lines[0].split(',').count();
    for (i, line) in lines[1..].iter().enumerate() {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells.len(), columns);
        assert_eq!(cells[0].parse::<u32>().expect("iteration"), i as u32);
        for c in &cells[1..6] {
            let v: f64 = c.parse().expect("number");
            assert!(v.is_finite());
        }
    }
    let checkpoint: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("checkpoint.json")).expect("checkpoint"),
    )
    .expect("json");
    assert_eq!(checkpoint["iteration"], 3);

    let resumed = epsm(&[
        "optimize",
        problem.to_str().expect("utf-8"),
        "--resume",
        out,
        "--iterations",
        "5",
    ]);
    assert!(
        resumed.status.success(),
        "{}",
        String::from_utf8_lossy(&resumed.stderr)
    );
    let csv = std::fs::read_to_string(dir.join("run.csv")).expect("run.csv");
    assert_eq!(csv.lines().count(), 6, "rows 0..5 after resuming");

    let bad = epsm(&["optimize", "does-not-exist.toml"]);
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("does-not-exist.toml"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The matcher's guard counts reach `run.csv`: at blur 3e-4 on 16² points
/// some entropic solves stop above the marginal tolerance (iterations 0 and
/// 2 here), and each row counts them; standard error warns once, naming the
/// problem's blur and the ways out.
#[test]
fn run_reports_count_unconverged_entropic_solves() {
    let (run, dir) = optimize_into("tests/data/tiny-sinkhorn.toml", "guards");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert_eq!(stderr.matches("warning:").count(), 1, "{stderr}");
    for needle in [
        "warning: iteration 0: 1 entropic OT solve(s) stopped above the marginal tolerance",
        "[loss] blur = 0.0003 (",
        "tiny-sinkhorn.toml)",
        "kind = \"ot_exact\"",
        "ot_unconverged_solves",
    ] {
        assert!(stderr.contains(needle), "no `{needle}` in {stderr}");
    }
    let csv = std::fs::read_to_string(dir.join("run.csv")).expect("run.csv");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let column = |name: &str| {
        header
            .iter()
            .position(|c| *c == name)
            .unwrap_or_else(|| panic!("no {name} column in {header:?}"))
    };
    let (unconverged, stops) = (
        column("ot_unconverged_solves"),
        column("ot_auction_budget_stops"),
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let count = |row: &[&str], i: usize| row[i].parse::<u64>().expect("a count");
    let total: u64 = rows.iter().map(|r| count(r, unconverged)).sum();
    assert!(total >= 1, "no unconverged solve counted:\n{csv}");
    assert!(rows.iter().all(|r| count(r, stops) == 0), "{csv}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// README's main command, with the problem's automatic settings (no tuning
/// keys) and its seed: the best θ's light ends within 2 % of the box size
/// (0.04) of the truth, the caustic problem's tolerance (seeds 1–3
/// measured 0.016, 0.0025 and 0.0041).
#[test]
fn the_readmes_caustic_job_reaches_its_target() {
    let (run, dir) = optimize_into("../../scenes/problems/caustic.toml", "readme-job");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let error: f64 = stdout
        .split("parameter error ")
        .nth(1)
        .and_then(|rest| rest.split_whitespace().next())
        .and_then(|x| x.parse().ok())
        .unwrap_or_else(|| panic!("no parameter error in {stdout}"));
    assert!(error < 0.04, "parameter error {error}: {stdout}");
    assert!(dir.join("report.png").is_file() && dir.join("run.csv").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn compare_under_a_time_budget_stops_every_method_at_the_budget() {
    let dir = std::env::temp_dir().join(format!("epsm-compare-cli-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = dir.to_str().expect("utf-8 path");
    let problem = tiny();
    let problem = problem.to_str().expect("utf-8");
    // A budget far below one iteration's time: every method stops after its
    // first iteration although 50 were asked for.
    let run = epsm(&[
        "compare",
        problem,
        "--methods",
        "epsm,l2",
        "--out",
        out,
        "--iterations",
        "50",
        "--time-budget",
        "1e-9",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    for method in ["epsm", "l2"] {
        let csv = std::fs::read_to_string(dir.join(method).join("run.csv")).expect("run.csv");
        assert_eq!(csv.lines().count(), 2, "{method}: header and one row");
    }
    let table = std::fs::read_to_string(dir.join("compare.csv")).expect("compare.csv");
    let rows: Vec<&str> = table.lines().skip(1).collect();
    assert_eq!(rows.len(), 2);
    for row in rows {
        let cols: Vec<&str> = row.split(',').collect();
        assert_eq!(cols.len(), 14, "{row}");
        assert_eq!(cols[8], "1", "iterations column: {row}");
        let primal: f64 = cols[10].parse().expect("primal_s");
        assert!(primal > 0.0, "primal seconds per iteration: {row}");
    }
    assert!(dir.join("compare.png").is_file());

    let bad = epsm(&["optimize", problem, "--out", out, "--time-budget=-1"]);
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--time-budget"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn compare_rejects_a_bad_method_list_before_running_any() {
    let dir = std::env::temp_dir().join(format!("epsm-compare-bad-{}", std::process::id()));
    let problem = tiny();
    for (methods, expected) in [
        ("epsm,foo", "--method `foo`"),
        ("epsm,l2,epsm", "`epsm` is listed twice (entries 1 and 3)"),
    ] {
        let _ = std::fs::remove_dir_all(&dir);
        let run = epsm(&[
            "compare",
            problem.to_str().expect("utf-8"),
            "--methods",
            methods,
            "--out",
            dir.to_str().expect("utf-8 path"),
            "--iterations",
            "1",
        ]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(1), "{methods}: {stderr}");
        assert!(stderr.contains(expected), "{methods}: {stderr}");
        assert!(
            !dir.join("epsm").exists(),
            "{methods}: epsm ran before the bad list was noticed"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn resuming_from_a_folder_without_a_checkpoint_fails_and_creates_nothing() {
    let dir = std::env::temp_dir().join(format!("epsm-resume-missing-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let problem = tiny();
    let run = epsm(&[
        "optimize",
        problem.to_str().expect("utf-8"),
        "--resume",
        dir.to_str().expect("utf-8 path"),
    ]);
    assert_eq!(run.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&run.stderr).contains("checkpoint.json"));
    assert!(!dir.exists(), "the failed resume created {}", dir.display());
}

#[test]
fn counts_outside_their_range_are_errors_before_any_work() {
    let problem = tiny();
    let problem = problem.to_str().expect("utf-8");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/tiny-box.toml");
    let scene = scene.to_str().expect("utf-8");
    let dir = std::env::temp_dir().join(format!("epsm-grad-spp0-{}", std::process::id()));
    let out = dir.to_str().expect("utf-8 path");
    for (args, expected) in [
        (
            vec!["check", scene, "--samples", "4000000000"],
            "--samples must be in [1, 1048576], got 4000000000",
        ),
        (
            vec!["check", scene, "--samples", "0"],
            "--samples must be in [1, 1048576], got 0",
        ),
        (
            vec![
                "grad",
                problem,
                "--param",
                "box.translate.x",
                "--spp",
                "0",
                "--out",
                out,
            ],
            "--spp must be at least 1",
        ),
        (
            vec!["bench", "rays", "--triangles", "4000000000"],
            "--triangles must be in [20, 4194304], got 4000000000",
        ),
        (
            vec!["bench", "rays", "--rays", "4000000000000"],
            "--rays must be in [1, 33554432], got 4000000000000",
        ),
        (
            vec!["bench", "rays", "--scene", scene, "--spp", "0"],
            "--spp must be in [1, 4096], got 0",
        ),
        (
            vec!["bench", "ot", "--n", "4000000000"],
            "--n must be in [1, 4194304], got 4000000000",
        ),
        (
            vec!["bench", "render", scene, "--repeats", "0"],
            "--repeats must be at least 1",
        ),
        (
            vec!["bench", "manifold", scene, "--seconds", "nan"],
            "--seconds must be a positive number, got NaN",
        ),
    ] {
        let run = epsm(&args);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
    }
    assert!(!dir.exists(), "grad wrote {out} before rejecting --spp 0");
}

#[test]
fn bench_rays_on_a_scene_walks_the_rays_of_its_render() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/tiny-box.toml");
    let scene = scene.to_str().expect("utf-8");
    let run = epsm(&[
        "bench",
        "rays",
        "--scene",
        scene,
        "--spp",
        "2",
        "--threads",
        "1",
        "--repeat",
        "1",
        "--json",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&run.stdout).expect("one JSON object");
    assert_eq!(report["scene"], scene);
    assert_eq!(report["spp"], 2);
    assert!(report.get("tlas_update_seconds").is_none());
    let rows = report["throughput"].as_array().expect("throughput rows");
    let row = |name: &str| {
        rows.iter()
            .find(|r| r["rays"] == name)
            .unwrap_or_else(|| panic!("no {name} row in {report}"))
    };
    // 32 × 32 pixels at 2 spp: one camera ray per sample.
    assert_eq!(row("camera")["count"], 2048);
    assert_eq!(row("camera")["query"], "closest");
    assert_eq!(row("shadow")["query"], "occluded");
    for name in ["camera", "bounce", "shadow"] {
        let r = row(name);
        assert_eq!(r["threads"], 1);
        assert!(r["count"].as_u64().expect("count") > 0, "{r}");
        assert!(r["mrays_per_s"].as_f64().expect("rate") > 0.0, "{r}");
        let hit = r["hit_fraction"].as_f64().expect("hit fraction");
        assert!((0.0..=1.0).contains(&hit), "{r}");
    }
    // Seen from above, the floor and the box fill most of the view.
    assert!(
        row("camera")["hit_fraction"]
            .as_f64()
            .expect("hit fraction")
            > 0.9
    );
}

/// Whether the ray `o + t d` (`t ≥ 0`) crosses the triangle `v` (Möller–Trumbore, `f64`).
fn crosses(o: [f64; 3], d: [f64; 3], v: [[f64; 3]; 3]) -> bool {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let (e1, e2) = (sub(v[1], v[0]), sub(v[2], v[0]));
    let p = cross(d, e2);
    let det = dot(e1, p);
    if det.abs() < 1e-12 {
        return false;
    }
    let s = sub(o, v[0]);
    let u = dot(s, p) / det;
    let q = cross(s, e1);
    let w = dot(d, q) / det;
    u >= 0.0 && w >= 0.0 && u + w <= 1.0 && dot(e2, q) / det >= 0.0
}

#[test]
fn bench_rays_dumps_the_triangles_and_rays_it_walks() {
    let dir = std::env::temp_dir().join(format!("epsm-rays-dump-{}", std::process::id()));
    let run = epsm(&[
        "bench",
        "rays",
        "--triangles",
        "80",
        "--rays",
        "500",
        "--threads",
        "1",
        "--repeat",
        "1",
        "--json",
        "--dump",
        dir.to_str().expect("utf-8"),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&run.stdout).expect("one JSON object");
    let floats = |name: &str| -> Vec<f64> {
        let bytes = std::fs::read(dir.join(name)).expect(name);
        assert_eq!(bytes.len() % 4, 0, "{name}");
        bytes
            .chunks_exact(4)
            .map(|b| f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])))
            .collect()
    };
    let triangles = floats("triangles.f32");
    // Five instances of an 80-triangle sphere, nine floats each.
    assert_eq!(triangles.len(), 5 * 80 * 9);
    let triangles: Vec<[[f64; 3]; 3]> = triangles
        .chunks_exact(9)
        .map(|t| [[t[0], t[1], t[2]], [t[3], t[4], t[5]], [t[6], t[7], t[8]]])
        .collect();
    for name in ["coherent", "incoherent"] {
        let rays = floats(&format!("{name}.f32"));
        assert_eq!(rays.len(), 500 * 6, "{name}");
        // The dumped rays against the dumped triangles, by brute force, hit
        // as often as the benchmark's walks of its own.
        let hits = rays
            .chunks_exact(6)
            .filter(|r| {
                let (o, d) = ([r[0], r[1], r[2]], [r[3], r[4], r[5]]);
                triangles.iter().any(|&t| crosses(o, d, t))
            })
            .count();
        let walked = report["throughput"]
            .as_array()
            .expect("rows")
            .iter()
            .find(|t| t["rays"] == name && t["query"] == "closest")
            .and_then(|t| t["hit_fraction"].as_f64())
            .expect("hit fraction");
        assert!(hits > 0, "{name}: no ray hits");
        assert_eq!(hits as f64 / 500.0, walked, "{name}");
    }
    std::fs::remove_dir_all(&dir).expect("remove the dump");
}

#[test]
fn bench_ot_reports_the_exact_solvers_cold_starts() {
    // The default blobs pair (n = 4096, seed 0) is well inside the warm start's range.
    let run = epsm(&["bench", "ot", "--json"]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&run.stdout).expect("one JSON object");
    assert_eq!(report["solver"], "exact");
    assert_eq!(report["n"], 4096);
    assert_eq!(report["cold_starts"], 0, "{report}");
    let run = epsm(&["bench", "ot", "--n", "256"]);
    let line = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success() && line.contains(" cold_starts=0 "),
        "{line}"
    );
}

#[test]
fn bench_ot_reports_unconverged_entropic_solves() {
    let run = epsm(&[
        "bench", "ot", "--solver", "sinkhorn", "--n", "256", "--json",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&run.stdout).expect("one JSON object");
    assert_eq!(report["unconverged_solves"], 0, "{report}");
    assert!(
        report["marginal_error"].as_f64().is_some_and(|e| e <= 1e-3),
        "{report}"
    );
}

#[test]
fn a_missing_file_is_reported_once_with_its_cause() {
    let run = epsm(&["render", "/nonexistent/scene.toml"]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    assert_eq!(
        stderr.trim(),
        "error: /nonexistent/scene.toml: No such file or directory (os error 2)"
    );
}
