//! Problem files (TOML text) that tests of more than one crate run.

/// The settings of the tiny optimization problem over the shared tiny scene
/// (`tests/data/tiny-box.toml` at the workspace root: a grey box on a floor
/// under an area light, seen from above at 32²): a target rendered at 16
/// samples per pixel, exact OT matched at 32², ten Adam iterations of rate
/// 0.1 without decay, and 2 samples per pixel per pass. A test prepends the
/// `scene_file` key and adds `[[parameters]]` tables.
pub const TINY_SETTINGS: &str = r#"
[target]
spp = 16

[loss]
kind = "ot_exact"
match_resolution = [32, 32]

[optimizer]
iterations = 10
lr = 0.1
decay = 1.0

[render]
spp_primal = 2
spp_grad = 2
"#;
