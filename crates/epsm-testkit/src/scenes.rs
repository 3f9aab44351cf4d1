//! Scene files (TOML text) that tests of more than one crate render.

/// A camera 3 units straight above the origin looking down (`fov` 6°,
/// 16 × 16 pixels) at a diffuse floor (`floor`, albedo 0.5, 10 × 10 in the
/// plane y = 0), and a black diffuse material `black` for lamps. Lights
/// are appended.
pub const OVERHEAD_CAMERA: &str = r#"
[camera]
origin = [0, 3, 0]
target = [0, 0, 0]
up = [0, 0, -1]
fov = 6
resolution = [16, 16]
[materials.floor]
type = "diffuse"
albedo = [0.5, 0.5, 0.5]
[materials.black]
type = "diffuse"
albedo = [0, 0, 0]
[[objects]]
name = "floor"
shape = "rectangle"
material = "floor"
scale = 5
rotate = [{ axis = [1, 0, 0], angle = -90 }]
"#;

/// A point light `p` for [`OVERHEAD_CAMERA`]'s floor, so bright (`1e37`,
/// within `f32`) and so close to it that the radiance of the samples near
/// it overflows to infinity (the tracer drops them), while the samples
/// farther off stay finite.
pub const OVERFLOWING_LIGHT: &str = r#"
[[lights]]
type = "point"
name = "p"
position = [0.15, 0.01, 0]
intensity = [1e37, 1e37, 1e37]
"#;

/// A black wall for [`OVERFLOWING_LIGHT`] (`wall`, in the plane x = 0.1,
/// 0.02 high, across the view): it blocks the light from the floor left of
/// it, where the strength of those shadows (the radiance the blocked
/// connections would have added) overflows to infinity near the light.
pub const WALL_BESIDE_THE_LIGHT: &str = r#"
[[objects]]
name = "wall"
shape = "rectangle"
material = "black"
scale = [0.3, 0.02, 1]
rotate = [{ axis = [0, 1, 0], angle = 90 }]
translate = [0.1, 0, 0]
"#;
