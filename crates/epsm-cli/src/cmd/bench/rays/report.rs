//! What `epsm bench rays` reports: per ray set and thread count the rays per
//! second and per CPU-second and the fraction of hits, beside the build, the
//! top-level update and the acceleration structure's size; printed as text or
//! as one JSON object.

use serde::Serialize;

/// Throughput of one ray set on one thread count.
#[derive(Serialize)]
pub(super) struct Throughput {
    pub threads: usize,
    /// The ray set.
    pub rays: &'static str,
    /// Rays in the set.
    pub count: usize,
    pub query: &'static str,
    pub mrays_per_s: f64,
    /// Rays per CPU-second of the process (Linux only): the rate per busy
    /// core, insensitive to other processes taking the cores.
    pub mrays_per_cpu_s: Option<f64>,
    pub hit_fraction: f64,
    /// With `--scene`: the same rays through the batch walks
    /// (`Accel::closest_hits`, `Accel::occluded_rays`), else absent.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub batched_mrays_per_s: Option<f64>,
    /// The batch walks' rays per CPU-second (with `--scene`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub batched_mrays_per_cpu_s: Option<f64>,
    /// The batch walks' fraction of hits (with `--scene`; the scalar one
    /// but for ties, see `Accel::closest_hits`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub batched_hit_fraction: Option<f64>,
}

/// Everything measured.
#[derive(Serialize)]
pub(super) struct Report {
    /// The scene file whose rays were walked (`--scene`), else absent.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scene: Option<String>,
    /// Samples per pixel of the logged render (`--scene`), else absent.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spp: Option<u32>,
    pub triangles: usize,
    /// Exact spheres (`shape = "sphere"` with `exact = true`).
    pub spheres: usize,
    pub instances: usize,
    pub build_seconds: f64,
    /// Moving one instance and updating the top level (the sphere only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tlas_update_seconds: Option<f64>,
    pub accel_bytes: usize,
    /// Whether the batch walks ran sixteen rays at a time (the CPU has
    /// AVX-512; with `--scene`, else absent).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub batched_wide: Option<bool>,
    pub throughput: Vec<Throughput>,
}

/// Prints `report` as text, or as one JSON object with `json`.
pub(super) fn print(report: &Report, json: bool) -> anyhow::Result<()> {
    if json {
        println!("{}", serde_json::to_string(report)?);
        return Ok(());
    }
    if let (Some(scene), Some(spp)) = (&report.scene, report.spp) {
        println!("{scene}: the rays of a render at {spp} spp");
    }
    let update = report
        .tlas_update_seconds
        .map(|s| format!(", TLAS update {:.1} µs", s * 1e6))
        .unwrap_or_default();
    println!(
        "{} triangles, {} exact sphere(s), {} instances: build {:.1} ms{update}, {:.1} MB",
        report.triangles,
        report.spheres,
        report.instances,
        report.build_seconds * 1e3,
        report.accel_bytes as f64 / 1e6
    );
    if let Some(wide) = report.batched_wide {
        let how = if wide {
            "16 rays at a time (AVX-512)"
        } else {
            "one at a time (no AVX-512)"
        };
        println!("batched: the same rays through Accel::closest_hits / occluded_rays, {how}");
    }
    for t in &report.throughput {
        let batched = t
            .batched_mrays_per_s
            .map(|b| {
                format!(
                    "; batched {:6.2} Mrays/s, {:6.2} Mrays/CPU-s ({:.0}% hit)",
                    b,
                    t.batched_mrays_per_cpu_s.unwrap_or(f64::NAN),
                    t.batched_hit_fraction.unwrap_or(f64::NAN) * 100.0
                )
            })
            .unwrap_or_default();
        println!(
            "{} thread(s) {:>10} {:>8}: {:6.2} Mrays/s, {:6.2} Mrays/CPU-s ({:.0}% hit, {} rays){batched}",
            t.threads,
            t.rays,
            t.query,
            t.mrays_per_s,
            t.mrays_per_cpu_s.unwrap_or(f64::NAN),
            t.hit_fraction * 100.0,
            t.count
        );
    }
    Ok(())
}
