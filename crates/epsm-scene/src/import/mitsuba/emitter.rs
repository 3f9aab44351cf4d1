//! Top-level Mitsuba emitters → point lights and the background (`area`
//! emitters live in shapes, see [`shape`](super::shape)).
//!
//! | Mitsuba | epsm | parameters (default) |
//! |---|---|---|
//! | `point` | point light | `position` (a point) or `to_world` (its translation), `intensity` (1, W/sr) |
//! | `constant` | constant background | `radiance` (1) |
//! | `envmap` | environment map | `filename` (`.exr` or `.png`), `scale` (1), `to_world`: a rotation about `+y` only |
//!
//! Mitsuba's lat-long mapping is epsm's (`u = atan2(x, −z)/2π + ½`, `v = acos y / π`),
//! so a map loads unchanged; a `to_world` rotation by θ about `+y` becomes
//! `rotate_y = −θ`. At most one background emitter.
//!
//! ```xml
//! <emitter type="point" id="bulb">
//!     <point name="position" x="0" y="3" z="1"/>
//!     <rgb name="intensity" value="1.5"/>
//! </emitter>
//! ```

use std::sync::Arc;

use glam::DVec3;

use super::parse::{Element, finish};
use super::transform::transform;
use crate::error::{FieldError, Result};
use crate::fields::Fields;
use crate::load::build::{ImageCache, image};
use epsm_render::lights::{Background, EnvMap, PointLight};

/// What one top-level emitter becomes.
pub(crate) enum Emitter {
    /// A point light.
    Point(PointLight),
    /// The background.
    Background(Background),
}

/// The emitter of element `el`; `name` names a point light.
pub(crate) fn emitter(
    el: &Element,
    name: String,
    images: &mut ImageCache,
    ctx: &Fields,
    warnings: &mut Vec<FieldError>,
) -> Result<Emitter> {
    let field = |key: &str| format!("{}.{key}", el.path);
    let out = match el.kind(ctx)? {
        "point" => {
            let position = match (el.point(ctx, "position")?, el.prop("to_world")) {
                (Some(_), Some(_)) => {
                    return Err(ctx.err(
                        &field("to_world"),
                        "give either position or to_world, not both",
                    ));
                }
                (Some(p), None) => p,
                (None, Some(t)) => transform(t, ctx)?.translation,
                (None, None) => DVec3::ZERO,
            };
            let intensity = el.rgb(ctx, "intensity")?.unwrap_or([1.0; 3]);
            let intensity = ctx.color(&field("intensity"), intensity, f64::INFINITY)?;
            Emitter::Point(PointLight {
                name,
                position,
                intensity,
            })
        }
        "constant" => {
            let radiance = el.rgb(ctx, "radiance")?.unwrap_or([1.0; 3]);
            Emitter::Background(Background::Constant(ctx.color(
                &field("radiance"),
                radiance,
                f64::INFINITY,
            )?))
        }
        "envmap" => {
            let file = el
                .string(ctx, "filename")?
                .ok_or_else(|| ctx.err(&field("filename"), "required"))?;
            let scale = el.float(ctx, "scale")?.unwrap_or(1.0);
            let scale = ctx.within(&field("scale"), scale, 0.0, f64::MAX, "a value >= 0")?;
            let rotate_y = match el.prop("to_world") {
                Some(t) => y_rotation(&transform(t, ctx)?).ok_or_else(|| {
                    ctx.err(
                        &field("to_world"),
                        "only rotations about +y are supported for envmap",
                    )
                })?,
                None => 0.0,
            };
            let img = image(&field("filename"), file, f32::INFINITY, ctx, images)?;
            let map = EnvMap::new((*img).clone(), scale as f32, rotate_y as f32);
            Emitter::Background(Background::EnvMap(Arc::new(map)))
        }
        "area" => return Err(ctx.err(&field("type"), "area emitters must be nested in a <shape>")),
        other => {
            let msg = format!(
                "unsupported emitter type \"{other}\" (supported: area, point, constant, envmap)"
            );
            return Err(ctx.err(&field("type"), msg));
        }
    };
    finish(el, ctx, &[], warnings)?;
    Ok(out)
}

/// epsm's `rotate_y` (radians) for a Mitsuba `to_world` that rotates by θ
/// about `+y`: `−θ`; `None` for any other map.
fn y_rotation(m: &glam::DAffine3) -> Option<f64> {
    let r = m.matrix3;
    let theta = (-r.x_axis.z).atan2(r.x_axis.x);
    let expected = glam::DMat3::from_rotation_y(theta);
    let close = (r - expected)
        .to_cols_array()
        .iter()
        .all(|d| d.abs() < 1e-9);
    (close && m.translation == DVec3::ZERO).then_some(-theta)
}
