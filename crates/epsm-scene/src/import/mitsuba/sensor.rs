//! The `<sensor>` (with its `<film>` and `<sampler>`) and the `<integrator>`
//! → the camera and [`RenderSettings`].
//!
//! | Mitsuba | epsm | rule (Mitsuba default) |
//! |---|---|---|
//! | `sensor type="perspective"` | pinhole camera | other sensor types are errors |
//! | `fov`, `fov_axis` | vertical field of view | `fov` required; axis `x` (default), `y`, `diagonal`, `smaller`, `larger` converted through the film's aspect |
//! | sensor `to_world` | origin, view direction `+z`, up `+y` | identity; a mirroring transform is an error |
//! | `film` `width`, `height` | resolution | 768 × 576 |
//! | `sampler` `sample_count`, `seed` | `spp`, `seed` | 4, 0; the sampler type only changes the noise |
//! | `integrator type="path"` `max_depth` | `max_depth = max_depth − 1` (epsm counts scatterings, Mitsuba path segments) | −1 = unlimited → `MAX_DEPTH` |
//! | `integrator` `rr_depth` | `rr_depth` (same meaning) | 5 |
//!
//! A film's `<rfilter type="box"/>` is epsm's own pixel filter; other
//! reconstruction filters, `near_clip`, `far_clip` and film settings that
//! only affect the output file (`pixel_format`, `component_format`,
//! `file_format`) are skipped with a warning.
//!
//! ```xml
//! <sensor type="perspective">
//!     <float name="fov" value="40"/>
//!     <transform name="to_world"><lookat origin="0, 1, 4" target="0, 1, 0" up="0, 1, 0"/></transform>
//!     <film type="hdrfilm"><integer name="width" value="128"/><integer name="height" value="128"/></film>
//! </sensor>
//! ```

use glam::DAffine3;

use super::parse::{Element, finish};
use super::transform::transform;
use crate::error::{FieldError, Result};
use crate::fields::Fields;
use crate::load::build::{MAX_DEPTH, View, checked_camera};
use epsm_render::camera::Camera;
use epsm_render::scene::RenderSettings;

/// The camera of `sensor` and the render settings of its sampler and `integrator`.
pub(crate) fn sensor(
    sensor: &Element,
    integrator: Option<&Element>,
    ctx: &Fields,
    warnings: &mut Vec<FieldError>,
) -> Result<(Camera, RenderSettings)> {
    let field = |el: &Element, key: &str| format!("{}.{key}", el.path);
    if sensor.kind(ctx)? != "perspective" {
        let msg = "only perspective sensors are supported";
        return Err(ctx.err(&field(sensor, "type"), msg));
    }
    let films: Vec<&Element> = sensor.tagged("film").collect();
    let (w, h) = match films.as_slice() {
        [] => (768, 576),
        [film] => {
            let size = |key: &str, default: u32| -> Result<u32> {
                let v = film.integer(ctx, key)?.unwrap_or(i64::from(default));
                u32::try_from(v).map_err(|_| {
                    ctx.err(
                        &field(film, key),
                        format!("expected a positive integer, found {v}"),
                    )
                })
            };
            let size = (size("width", 768)?, size("height", 576)?);
            // A box filter is epsm's own (a sample counts for the pixel it
            // falls in, with weight one); any other is not used.
            for rfilter in film.tagged("rfilter") {
                let kind = rfilter.attr("type").unwrap_or_default();
                if kind != "box" || !rfilter.children.is_empty() {
                    let msg = format!(
                        "<rfilter type=\"{kind}\"> is skipped (epsm's pixels are box-filtered)"
                    );
                    warnings.push(ctx.located(&rfilter.path, msg));
                }
            }
            finish(
                film,
                ctx,
                &[
                    "pixel_format",
                    "component_format",
                    "file_format",
                    "sample_border",
                ],
                warnings,
            )?;
            size
        }
        _ => return Err(ctx.err(&sensor.path, "expected at most one <film>")),
    };
    // Mitsuba's defaults: 4 samples, a path integrator of unlimited depth, roulette from depth 5.
    let mut settings = RenderSettings {
        spp: 4,
        max_depth: MAX_DEPTH,
        rr_depth: 5,
        seed: 0,
        manifold_nee: true,
    };
    for sampler in sensor.tagged("sampler") {
        let count = |key: &str, lo: i64| -> Result<Option<u32>> {
            match sampler.integer(ctx, key)? {
                Some(v) => u32::try_from(v)
                    .ok()
                    .filter(|&v| i64::from(v) >= lo)
                    .map(Some)
                    .ok_or_else(|| {
                        ctx.err(
                            &field(sampler, key),
                            format!("expected an integer >= {lo}, found {v}"),
                        )
                    }),
                None => Ok(None),
            }
        };
        settings.spp = count("sample_count", 1)?.unwrap_or(settings.spp);
        settings.seed = count("seed", 0)?.unwrap_or(settings.seed);
        finish(sampler, ctx, &[], warnings)?;
    }
    if let Some(integrator) = integrator {
        depths(integrator, &mut settings, ctx, warnings)?;
    }
    let fov_field = field(sensor, "fov");
    if sensor.prop("focal_length").is_some() {
        return Err(ctx.err(&field(sensor, "focal_length"), "not supported: give fov"));
    }
    let fov = sensor
        .float(ctx, "fov")?
        .ok_or_else(|| ctx.err(&fov_field, "required"))?;
    let fov = ctx.within(&fov_field, fov, 1e-6, 180.0 - 1e-6, "degrees in (0, 180)")?;
    let (wf, hf) = (f64::from(w), f64::from(h));
    let axis = sensor.string(ctx, "fov_axis")?.unwrap_or("x");
    // tan(fov_y / 2) = tan(fov / 2) · h / (extent of the fov axis).
    let extent = match axis {
        "x" => wf,
        "y" => hf,
        "diagonal" => wf.hypot(hf),
        "smaller" => wf.min(hf),
        "larger" => wf.max(hf),
        other => {
            return Err(ctx.err(
                &field(sensor, "fov_axis"),
                format!("expected x, y, diagonal, smaller or larger, found \"{other}\""),
            ));
        }
    };
    let fov_y = 2.0 * ((0.5 * fov.to_radians()).tan() * hf / extent.max(1.0)).atan();
    let to_world = match sensor.prop("to_world") {
        Some(t) => transform(t, ctx)?,
        None => DAffine3::IDENTITY,
    };
    if to_world.matrix3.determinant() < 0.0 {
        let msg = "mirroring sensor transforms are not supported";
        return Err(ctx.err(&field(sensor, "to_world"), msg));
    }
    let view = View {
        origin: to_world.translation,
        target: to_world.translation + to_world.matrix3.z_axis,
        up: to_world.matrix3.y_axis,
        fov_y: fov_y.to_degrees(),
        resolution: [w, h],
    };
    finish(sensor, ctx, &["near_clip", "far_clip"], warnings)?;
    Ok((checked_camera(&view, &sensor.path, ctx)?, settings))
}

/// `max_depth` and `rr_depth` of a `path` integrator.
fn depths(
    el: &Element,
    settings: &mut RenderSettings,
    ctx: &Fields,
    warnings: &mut Vec<FieldError>,
) -> Result<()> {
    let kind = el.kind(ctx)?;
    if kind != "path" {
        let msg = format!("unsupported integrator \"{kind}\" (only path)");
        return Err(ctx.err(&format!("{}.type", el.path), msg));
    }
    let max_field = format!("{}.max_depth", el.path);
    settings.max_depth = match el.integer(ctx, "max_depth")? {
        None => settings.max_depth,
        Some(-1) => MAX_DEPTH,
        Some(m) if (2..=i64::from(MAX_DEPTH) + 1).contains(&m) => (m - 1) as u32,
        Some(m) => {
            let msg = format!(
                "expected -1 or an integer in [2, {}] (1 would show only emitters), found {m}",
                MAX_DEPTH + 1
            );
            return Err(ctx.err(&max_field, msg));
        }
    };
    if let Some(rr) = el.integer(ctx, "rr_depth")? {
        let rr = u32::try_from(rr).ok().filter(|&r| r >= 1);
        let msg = "expected an integer >= 1";
        settings.rr_depth = rr.ok_or_else(|| ctx.err(&format!("{}.rr_depth", el.path), msg))?;
    }
    finish(el, ctx, &[], warnings)
}
