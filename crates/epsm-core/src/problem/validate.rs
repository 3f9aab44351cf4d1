//! Checks a parsed [`ProblemDesc`] field by field and builds the typed
//! [`Problem`], with located errors (file, line, dotted field).

use std::path::Path;

use epsm_ot::{MIN_BLUR, MatchLimits};
use epsm_render::{Image, Scene};
use epsm_scene::fields::{Fields, Locator};
use epsm_scene::{load::parts_from_desc, load_parts};

use super::auto::scale;
use super::desc::ProblemDesc;
use super::{LossSettings, OptimizerSettings, ParamSpec, Passes, Problem, ProblemError, Target};
use crate::loss::LossKind;
use crate::params::ParamTable;
use crate::schedule::Method;

/// Builds the problem of `d`, with `given` (linear RGB) as its target image
/// when the caller holds one in place of a `target.image` file.
pub(super) fn problem(
    d: &ProblemDesc,
    file: &Path,
    locator: &Locator,
    given: Option<Image>,
) -> Result<Problem, ProblemError> {
    let c = Fields::new(file, locator, "");
    let (scene, scene_field) = match (&d.scene_file, &d.scene) {
        (Some(path), None) => {
            let parts = load_parts(&c.resolve(path))
                .map_err(|e| c.located("scene_file", format!("cannot load `{path}`: {e}")))?;
            (parts, "scene_file")
        }
        (None, Some(desc)) => {
            // The embedded table's errors are located in this file already.
            let parts = parts_from_desc(desc, file, locator, "scene").map_err(|e| match e {
                epsm_scene::Error::Field(e) => e,
                other => c.located("scene", other.to_string()),
            })?;
            (parts, "scene")
        }
        _ => {
            return Err(c
                .located(
                    "scene_file",
                    "give exactly one of `scene_file` and a `[scene]` table",
                )
                .into());
        }
    };
    let probe = Scene::new(scene.clone()).map_err(|e| c.located(scene_field, e.to_string()))?;
    let table = ParamTable::new(&probe);
    if d.parameters.is_empty() {
        return Err(c
            .located("parameters", "expected at least one [[parameters]] entry")
            .into());
    }
    let lr = d
        .optimizer
        .lr
        .map(|v| c.check("optimizer.lr", v, v > 0.0, "a positive number"))
        .transpose()?;
    let diagonal = probe
        .accel()
        .world_bounds()
        .map_or(1.0, |(lo, hi)| (hi - lo).length());
    let mut params = Vec::with_capacity(d.parameters.len());
    for (i, p) in d.parameters.iter().enumerate() {
        let f = |name: &str| format!("parameters[{i}].{name}");
        if params.iter().any(|q: &ParamSpec| q.key == p.key) {
            return Err(c
                .located(&f("key"), format!("`{}` is listed twice", p.key))
                .into());
        }
        let param = table
            .resolve(&p.key)
            .map_err(|e| c.located(&f("key"), e.to_string()))?;
        let (domain, range) = param.target.domain();
        let within_domain = |v: f64| v >= domain[0] && v <= domain[1];
        let bounds = match p.bounds {
            Some([lo, hi]) => {
                c.finite(&f("bounds"), lo)?;
                c.check(
                    &f("bounds"),
                    hi,
                    hi > lo,
                    "an upper bound above the lower one",
                )?;
                for v in [lo, hi] {
                    c.check(&f("bounds"), v, within_domain(v), &range)?;
                }
                [lo, hi]
            }
            None => domain,
        };
        let what = match p.bounds {
            Some(_) => "a value within `bounds`",
            None => &range,
        };
        let inside = |v: f64| v >= bounds[0] && v <= bounds[1];
        let initial = p
            .initial
            .map(|v| c.check(&f("initial"), v, inside(v), what))
            .transpose()?;
        let true_value = p
            .true_value
            .map(|v| c.check(&f("true"), v, inside(v), what))
            .transpose()?;
        let explicit =
            p.lr.map(|v| c.check(&f("lr"), v, v > 0.0, "a positive number"))
                .transpose()?
                .or(lr);
        let step = explicit.is_none().then(|| {
            scale(
                &param.target,
                p.bounds,
                initial.unwrap_or(param.value),
                diagonal,
            )
        });
        let lr = match &step {
            Some(step) => step.lr(d.optimizer.iterations),
            None => explicit.unwrap_or_default(),
        };
        params.push(ParamSpec {
            key: p.key.clone(),
            initial,
            true_value,
            bounds,
            lr,
            step,
        });
    }
    let image = match (&d.target.image, given) {
        (Some(_), Some(_)) => {
            let msg = "the target is given as an image: leave `target.image` out";
            return Err(c.located("target.image", msg).into());
        }
        (None, Some(img)) => Some(
            epsm_scene::image_io::check_values(file, &img, f32::INFINITY)
                .map(|()| img)
                .map_err(|e| c.located("target.image", e.to_string()))?,
        ),
        (Some(path), None) => {
            let path = c.resolve(path);
            let img = epsm_scene::image_io::read_image(&path)
                .and_then(|img| {
                    epsm_scene::image_io::check_values(&path, &img, f32::INFINITY)?;
                    Ok(img)
                })
                .map_err(|e| c.located("target.image", e.to_string()))?;
            Some(img)
        }
        (None, None) => None,
    };
    let target = match image {
        Some(img) => {
            let cam = &scene.camera;
            if (img.width, img.height) != (cam.width, cam.height) {
                let msg = format!(
                    "image is {}x{} but the camera renders {}x{}",
                    img.width, img.height, cam.width, cam.height
                );
                return Err(c.located("target.image", msg).into());
            }
            Target::Image(img)
        }
        None => {
            if let Some(i) = params.iter().position(|p| p.true_value.is_none()) {
                let msg = "without `target.image` every parameter needs a `true` value";
                return Err(c.located(&format!("parameters[{i}]"), msg).into());
            }
            Target::Render {
                spp: c.count("target.spp", d.target.spp, 1, 1 << 16)?,
                seed: d.target.seed,
            }
        }
    };
    let l = &d.loss;
    let kind = match l.kind.as_str() {
        "ot_exact" => LossKind::OtExact,
        "ot_sinkhorn" => LossKind::OtSinkhorn {
            blur: c.check(
                "loss.blur",
                l.blur,
                l.blur >= MIN_BLUR,
                &format!("a number >= {MIN_BLUR:e}"),
            )?,
        },
        "l2" => LossKind::L2,
        other => {
            let msg = format!("unknown loss `{other}`; expected ot_exact, ot_sinkhorn or l2");
            return Err(c.located("loss.kind", msg).into());
        }
    };
    let [mw, mh] = l.match_resolution;
    c.count("loss.match_resolution", mw.min(mh), 4, 512)?;
    c.count("loss.match_resolution", mw.max(mh), 4, 512)?;
    if let Some(matcher) = kind.matcher() {
        let n = mw as usize * mh as usize;
        matcher
            .check_size(n, &MatchLimits::default())
            .map_err(|e| c.located("loss.match_resolution", e.to_string()))?;
    }
    let o = &d.optimizer;
    let tolerance = d
        .tolerance
        .map(|v| c.check("tolerance", v, v > 0.0, "a positive parameter error"))
        .transpose()?;
    let method = Method::parse(&o.method).ok_or_else(|| {
        c.located(
            "optimizer.method",
            format!(
                "unknown method `{}`; expected epsm, drot, l2 or prdpt",
                o.method
            ),
        )
    })?;
    let unit = |field: &str, v: f64, ok: bool, what: &str| c.check(field, v, ok, what);
    let optimizer = OptimizerSettings {
        method,
        iterations: c.count("optimizer.iterations", o.iterations, 1, 1_000_000)?,
        decay: o
            .decay
            .map(|v| {
                unit(
                    "optimizer.decay",
                    v,
                    v > 0.0 && v <= 1.0,
                    "a number in (0, 1]",
                )
            })
            .transpose()?,
        beta1: unit(
            "optimizer.beta1",
            o.beta1,
            (0.0..1.0).contains(&o.beta1),
            "a number in [0, 1)",
        )?,
        beta2: o
            .beta2
            .map(|v| {
                unit(
                    "optimizer.beta2",
                    v,
                    (0.0..1.0).contains(&v),
                    "a number in [0, 1)",
                )
            })
            .transpose()?,
        l2_fraction: o
            .l2_fraction
            .map(|v| {
                let ok = (0.0..=1.0).contains(&v);
                unit("optimizer.l2_fraction", v, ok, "a number in [0, 1]")
            })
            .transpose()?,
        stop: o.stop,
        seed: o.seed,
    };
    Ok(Problem {
        scene,
        params,
        target,
        loss: LossSettings {
            kind,
            lambda: c.check("loss.lambda", l.lambda, l.lambda > 0.0, "a positive number")?,
            match_resolution: [mw, mh],
            flow: l.flow,
        },
        optimizer,
        passes: Passes {
            spp_primal: c.count("render.spp_primal", d.render.spp_primal, 1, 1 << 16)?,
            spp_grad: c.count("render.spp_grad", d.render.spp_grad, 1, 1 << 16)?,
            spp_match: d
                .render
                .spp_match
                .map(|v| c.count("render.spp_match", v, 0, 1 << 16))
                .transpose()?,
            late: None,
        },
        out_dir: d.output.dir.clone().into(),
        checkpoint_every: d.output.checkpoint_every,
        tolerance,
    })
}
