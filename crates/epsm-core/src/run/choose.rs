//! The run's automatic choices, made once when it starts: step sizes, the
//! colour-flow term, the decay, the matched render's samples, the hybrid
//! switch, the late phase and the judge of the best θ, each recorded with
//! its reason.

use std::collections::HashSet;

use epsm_render::scene::ObjectId;
use epsm_render::{Image, Scene};
use glam::Vec2;

use super::best::Judge;
use super::noise::{self, Noise};
use super::{View, latest_switch, stream_seed, window};
use crate::params::Target;
use crate::problem::Problem;
use crate::problem::auto::{self, Choice, is_camera, is_geometric};
use crate::schedule::{Method, Schedule};

/// Makes the run's automatic choices for `problem` (resolving its
/// `None` settings in place, recording each in `choices`): the step sizes,
/// the colour-flow term, the decay, the matched render's samples, the
/// hybrid switch and the late phase.
/// Returns the schedule and the judge of θ.
pub(super) fn choose(
    problem: &mut Problem,
    grad: &View,
    target_match: &Image,
    choices: &mut Vec<Choice>,
) -> (Schedule, Judge) {
    let targets: Vec<_> = grad.table.params().iter().map(|p| p.target).collect();
    let n = problem.optimizer.iterations;
    for (i, p) in problem.params.iter_mut().enumerate() {
        if let Some(step) = &p.step {
            p.lr = step.lr(n);
            let why = format!(
                "{}: {} x scale / {n} iterations, scale {} ({})",
                p.key,
                auto::CROSSING,
                step.scale,
                step.why
            );
            choices.push(Choice::new(
                format!("parameters[{i}].lr"),
                format!("{:.4}", p.lr),
                why,
            ));
        }
    }
    if problem.loss.flow.is_none() {
        let (on, why) = flow_rule(&targets, &grad.scene);
        problem.loss.flow = Some(on);
        choices.push(Choice::new("loss.flow", on.to_string(), why));
    }
    if problem.optimizer.beta2.is_none() {
        let material_only = !targets.iter().any(is_geometric);
        let b = auto::beta2(material_only);
        problem.optimizer.beta2 = Some(b);
        let why = if material_only {
            "every parameter is a material value: L2 throughout, whose gradient shrinks with \
             the error; a short second-moment memory keeps the late steps long"
        } else {
            "a long second-moment memory (geometric parameters)"
        };
        choices.push(Choice::new("optimizer.beta2", b.to_string(), why));
    }
    if problem.optimizer.decay.is_none() {
        let d = auto::decay(n);
        problem.optimizer.decay = Some(d);
        let why = format!(
            "the learning rate falls to 1/{} of its first value over {n} iterations",
            auto::FINAL_LR_DIVISOR
        );
        choices.push(Choice::new("optimizer.decay", format!("{d:.4}"), why));
    }
    let spp_grad = problem.passes.spp_grad;
    if problem.passes.spp_match.is_none() {
        let seed = problem.optimizer.seed;
        let seeds = [stream_seed(seed, 0, 0xA1), stream_seed(seed, 0, 0xA2)];
        let noise = Noise::measure(&grad.scene, target_match, seeds);
        let spp = noise.spp_match(spp_grad);
        problem.passes.spp_match = Some(spp);
        let why = format!(
            "noise of one sample {:.2e} against the target's signal {:.2e} (tone-mapped variances): \
             {:.0} spp keep the noise under {} % of the signal{}",
            noise.per_sample,
            noise.signal,
            noise.needed_spp(),
            noise::NOISE_FRACTION * 100.0,
            if spp == 0 {
                format!("; the gradient pass's {spp_grad} spp do")
            } else {
                format!(" (a power of two, at most {})", noise::MAX_SPP)
            }
        );
        choices.push(Choice::new("render.spp_match", spp.to_string(), why));
    }
    let o = &problem.optimizer;
    let kind = problem.loss.kind;
    let ot = o.method.uses_ot() && kind.is_ot();
    let schedule = match o.l2_fraction {
        Some(f) => Schedule::fixed(o.method, kind, n, f),
        None if ot && !targets.iter().any(is_geometric) => {
            let why = "every parameter is a material value: L2 throughout";
            choices.push(Choice::new("optimizer.l2_fraction", "1", why));
            Schedule::fixed(o.method, kind, n, 1.0)
        }
        None => {
            let (w, latest) = (window(n), latest_switch(n));
            if ot {
                let why = format!(
                    "switch from OT to L2 (Adam reset, the step size of half the iterations run) once the OT loss's moving average has not \
                     fallen by 1 % for {w} iterations, at the latest before iteration {latest}"
                );
                choices.push(Choice::new("optimizer.l2_fraction", "on plateau", why));
            }
            Schedule::on_plateau(o.method, kind, n, w, latest)
        }
    };
    if o.method != Method::Prdpt
        && let Some(late) = auto::late_samples(!targets.iter().any(is_geometric), n)
    {
        problem.passes.late = Some(late);
        let matched = problem
            .passes
            .spp_match
            .filter(|&s| s > 0)
            .unwrap_or(spp_grad);
        let why = format!(
            "every parameter is a material value: from iteration {} on the gradient pass takes \
             {} spp and the matched render {} spp, so that the noise of a few bright paths \
             scatters θ less near the optimum",
            late.from,
            spp_grad * late.factor,
            matched * late.factor,
        );
        choices.push(Choice::new(
            "render.late_samples",
            format!("{}x from iteration {}", late.factor, late.from),
            why,
        ));
    }
    let judge = Judge::new(n, problem.passes.spp_match.unwrap_or(0), spp_grad);
    let why = format!(
        "θ judged every {} iterations and at the end on two independent renders of {} spp in \
         all (the product of their tone-mapped differences from the target); the best is \
         reported and rendered",
        judge.every, judge.spp
    );
    choices.push(Choice::new("best", "judged", why));
    (schedule, judge)
}

/// The colour-flow term's automatic rule: on when the camera moves, or when
/// every geometric parameter moves an object that is not a light and that
/// camera rays through the match resolution's pixel centres see directly
/// (its pixels' content moves with it). Off when a light moves (its
/// shading changes rather than moves) or an object is seen only through
/// shadows, reflections or refractions, where the flow term's image
/// differences follow noise more than motion. Returns the choice and why.
fn flow_rule(targets: &[Target], scene: &Scene) -> (bool, String) {
    if targets.iter().any(is_camera) {
        return (
            true,
            "a camera parameter is optimized: the whole image moves".into(),
        );
    }
    let light = (
        false,
        "a light moves: its shading changes, not only moves".to_owned(),
    );
    let mut moving = Vec::new();
    for t in targets.iter().filter(|t| is_geometric(t)) {
        let (Target::Translate { object, .. }
        | Target::Rotate { object, .. }
        | Target::Scale { object }) = *t
        else {
            return light;
        };
        if scene
            .objects()
            .get(object as usize)
            .is_none_or(|o| o.emission.is_some())
        {
            return light;
        }
        moving.push(object);
    }
    if moving.is_empty() {
        return (false, "no geometric parameter".into());
    }
    let seen = directly_seen(scene);
    if moving.iter().any(|o| !seen.contains(o)) {
        return (
            false,
            "a moving object is not seen directly (only its shadows, reflections or \
             refractions)"
                .into(),
        );
    }
    (
        true,
        "every moving object is seen directly: its pixels' content moves with it".into(),
    )
}

/// The objects the camera ray through some pixel centre of `scene` hits
/// first.
fn directly_seen(scene: &Scene) -> HashSet<ObjectId> {
    let cam = scene.camera();
    let rays = cam.film_rays();
    let mut seen = HashSet::new();
    for y in 0..cam.height {
        for x in 0..cam.width {
            let ray = rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            if let Some(hit) = scene.accel().closest_hit(&ray) {
                seen.insert(hit.object);
            }
        }
    }
    seen
}
