//! Random path configurations built exactly (specular laws satisfied by
//! construction), with a scene, a record and a parameter table, for the
//! Newton and stress tests.
#![allow(dead_code)]

pub mod builder;
pub mod manual;
pub mod synth;

use epsm_core::check::{CheckReport, CheckSettings, check_path};
use epsm_core::{ParamTable, PathKind, classify};

#[allow(unused_imports)]
pub use epsm_core::params::OBJECT_FIELDS;
#[allow(unused_imports)]
pub use synth::{End, Rng, Spec, Synth, Vertex, build};

/// Classifies a synthetic configuration and checks its paths of `kind`;
/// paths dropped by `classify` (its projection) count as drops of `kind`
/// (a synthetic record holds one path of interest). Returns the paths
/// accounted for.
pub fn check_kind(
    s: &Synth,
    kind: PathKind,
    settings: &CheckSettings,
    report: &mut CheckReport,
) -> usize {
    let motion = s.table.motion(&s.table.values());
    let classified = classify(&s.record, &s.scene, &motion, &settings.solve);
    report
        .kinds
        .entry(kind)
        .or_default()
        .dropped
        .merge(&classified.skipped);
    let mut n = classified.skipped.total() as usize;
    for p in classified.paths.iter().filter(|p| p.kind == kind) {
        report.add(
            kind,
            check_path(p, &s.table, &motion, settings),
            settings.well_conditioned,
        );
        n += 1;
    }
    n
}

/// Adds random geometric parameters for every object on the path, the point
/// light and the camera.
pub fn random_params(
    table: &mut ParamTable,
    s_objects: &[String],
    lights: &[String],
    rng: &mut Rng,
) {
    for name in s_objects {
        let f = OBJECT_FIELDS[rng.below(OBJECT_FIELDS.len())];
        table.add(&format!("{name}.{f}")).expect("valid key");
    }
    for name in lights {
        let f = ["translate.x", "translate.y", "translate.z"][rng.below(3)];
        table.add(&format!("{name}.{f}")).expect("valid key");
    }
    const CAMERA: [&str; 5] = ["translate.x", "translate.y", "translate.z", "yaw", "pitch"];
    table
        .add(&format!("camera.{}", CAMERA[rng.below(CAMERA.len())]))
        .expect("valid key");
}
