//! Special files where a problem expects an input file (a symlink to
//! `/dev/zero`, a FIFO): the problem file itself, its target image, its
//! scene file and a checkpoint are refused at once with an error naming the
//! file (and the field), instead of being read forever or blocking.
#![cfg(unix)]

use std::path::{Path, PathBuf};

use epsm_core::{Optimization, load_problem};
use epsm_testkit::special::{each, refused};

/// The shipped layout scene, which the problems below drive.
fn layout() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes/layout.toml")
        .canonicalize()
        .expect("shipped scene")
}

/// A problem file `problem.toml` in `dir` with `scene_file` and `target`.
fn write_problem(dir: &Path, scene_file: &Path, target: &str) -> PathBuf {
    let path = dir.join("problem.toml");
    let text = format!(
        "scene_file = \"{}\"\n[[parameters]]\nkey = \"table.translate.x\"\ninitial = 0.5\ntrue = 0.0\n[target]\n{target}\n",
        scene_file.display()
    );
    std::fs::write(&path, text).expect("write problem");
    path
}

#[test]
fn a_problem_file_that_is_dev_zero_or_a_fifo_is_refused_naming_it() {
    each("problem.toml", |kind, _, path| {
        let msg = refused(move || load_problem(&path));
        assert!(
            msg.contains("problem.toml: not a regular file"),
            "{kind:?}: {msg}"
        );
    });
}

#[test]
fn a_target_image_that_is_dev_zero_or_a_fifo_is_refused_naming_the_field() {
    each("target.exr", |kind, dir, _| {
        let path = write_problem(dir, &layout(), "image = \"target.exr\"");
        let msg = refused(move || load_problem(&path));
        assert!(
            msg.contains("problem.toml")
                && msg.contains("target.image")
                && msg.contains("target.exr: not a regular file"),
            "{kind:?}: {msg}"
        );
    });
}

#[test]
fn a_scene_file_that_is_dev_zero_or_a_fifo_is_refused_naming_it() {
    each("scene.toml", |kind, dir, scene| {
        let path = write_problem(dir, &scene, "spp = 4");
        let msg = refused(move || load_problem(&path));
        assert!(
            msg.contains("scene.toml: not a regular file"),
            "{kind:?}: {msg}"
        );
    });
}

#[test]
fn a_checkpoint_that_is_dev_zero_or_a_fifo_is_refused_naming_it() {
    each("checkpoint.json", |kind, _, path| {
        let msg = refused(move || Optimization::load_checkpoint(&path));
        assert!(
            msg.contains("checkpoint.json: not a regular file"),
            "{kind:?}: {msg}"
        );
    });
}
