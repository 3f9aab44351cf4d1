//! The gradient pass of one iteration: the recorded trace at the match
//! resolution, the loss with its per-pixel gradients (of an independent
//! render when the problem asks for one, else of the trace's own image),
//! and the backward pass to `dL/dθ`.

use std::sync::PoisonError;
use std::time::Instant;

use epsm_render::Image;
use epsm_render::record::PathRecord;
use epsm_render::tracer::{RenderOptions, render_recorded};

use super::{OptResult, Optimization, render_image};
use crate::backprop::{PassInput, PassStats, backprop, record_level};
use crate::colour::{ColourModel, PrimaryMotion};
use crate::loss::{LossEval, add_flow, evaluate};
use crate::problem::LossImage;
use crate::report::Timings;
use crate::schedule::{Method, PathUse};

/// The gradient at the current θ and what produced it.
#[derive(Clone, Debug)]
pub struct GradientEval {
    /// `dL/dθ`, index order.
    pub grad: Vec<f64>,
    /// The loss at the match resolution, with its per-pixel gradients.
    pub loss: LossEval,
    /// The gradient-pass image (match resolution).
    pub image: Image,
    /// Path counts.
    pub stats: PassStats,
    /// Seconds of the trace, matching and solve parts.
    pub timings: Timings,
}

impl Optimization {
    /// `dL/dθ` at the current θ for the current iteration's loss and paths,
    /// and the records it used.
    /// With the `prdpt` method, the gradient of the smoothed L2 loss
    /// ([`prdpt`](super::prdpt)) and no records.
    pub fn gradient(&self) -> OptResult<(GradientEval, Vec<PathRecord>)> {
        let (g, records, ()) = self.gradient_beside(|| ())?;
        Ok((g, records))
    }

    /// [`Optimization::gradient`] with `beside` run at the same time (when
    /// overlap is on) where the cores would otherwise wait: the matching
    /// runs mostly on one thread, so `beside` and the recorded trace (which
    /// only the backward pass needs) run beside it.
    ///
    /// The order of the stages: the image the loss compares (the matched
    /// render when the loss takes an independent one, else the recorded
    /// trace), then the matching beside the rest (the recorded trace, if
    /// not yet run, and `beside`), then the backward pass. Every stream is
    /// seeded, so the results do not depend on the order.
    pub(super) fn gradient_beside<R: Send>(
        &self,
        beside: impl FnOnce() -> R + Send,
    ) -> OptResult<(GradientEval, Vec<PathRecord>, R)> {
        if let Some(smoothing) = &self.smoothing {
            let (g, r) = self.maybe_join(|| self.smoothed_gradient(smoothing), beside);
            return Ok((g?, Vec::new(), r));
        }
        let l2 = !self.schedule.loss_at(self.iteration).is_ot();
        // With the colour-flow term, an L2 iteration of the epsm method
        // differentiates like an OT one: the flow term supplies what the
        // pixel's colour gains as content (and its edges) moves across it,
        // so the pixel's vertex moves with its surface and every path's
        // screen motion counts.
        let flow = self.problem.loss.flow == Some(true);
        let flow_l2 = l2 && flow && self.problem.optimizer.method == Method::Epsm;
        let flow_term = flow && (!l2 || flow_l2);
        let use_ = if flow_l2 {
            PathUse::All
        } else {
            self.schedule.paths_at(self.iteration)
        };
        let colour = ColourModel::new(
            &self.grad.table,
            &self.grad.scene,
            (l2 && !flow_l2).then_some(PrimaryMotion::OnCameraRay),
        );
        let level = record_level(&self.grad.table, &self.grad.scene, &colour, use_);
        let passes = self.problem.passes.at(self.iteration);
        let spp = passes.spp_grad;
        let opts = RenderOptions {
            spp,
            seed: self.seed(0),
            ..RenderOptions::from_scene(&self.grad.scene)
        };
        let trace = || {
            let t0 = Instant::now();
            let traced = render_recorded(&self.grad.scene, &opts, level, &|_| {});
            (traced, t0.elapsed().as_secs_f64())
        };
        let ((out, records), trace_s, (loss, matching_s), side) = match passes.loss_image(!l2) {
            LossImage::Independent(spp_match) => {
                let t0 = Instant::now();
                let image = render_image(&self.grad.scene, spp_match, self.seed(2));
                let matched_s = t0.elapsed().as_secs_f64();
                let (loss, ((traced, trace_s), side)) = self.maybe_join(
                    || self.timed_loss(&image, flow_term),
                    || self.maybe_join(trace, beside),
                );
                (traced, matched_s + trace_s, loss, side)
            }
            LossImage::GradientPass => {
                let ((out, records), trace_s) = trace();
                let (loss, side) =
                    self.maybe_join(|| self.timed_loss(&out.image, flow_term), beside);
                ((out, records), trace_s, loss, side)
            }
        };
        let loss = loss?;
        let t0 = Instant::now();
        let input = PassInput {
            scene: &self.grad.scene,
            table: &self.grad.table,
            colour: &colour,
            loss: &loss,
            spp,
            use_,
        };
        let (grad, stats) = backprop(&input, &records);
        let timings = Timings {
            primal: 0.0,
            trace: trace_s,
            matching: matching_s,
            solve: t0.elapsed().as_secs_f64(),
        };
        Ok((
            GradientEval {
                grad,
                loss,
                image: out.image,
                stats,
                timings,
            },
            records,
            side,
        ))
    }

    /// The current iteration's loss of `image`, with the colour-flow term
    /// when `flow`, and its seconds.
    fn timed_loss(&self, image: &Image, flow: bool) -> (OptResult<LossEval>, f64) {
        let t0 = Instant::now();
        let kind = self.schedule.loss_at(self.iteration);
        let target = if kind.is_ot() {
            &self.target_ot
        } else {
            &self.target_match
        };
        let warm = &mut *self.warm.lock().unwrap_or_else(PoisonError::into_inner);
        let loss = evaluate(kind, image, target, self.problem.loss.lambda, Some(warm)).and_then(
            |mut loss| {
                if flow {
                    add_flow(image, &mut loss)?;
                }
                Ok(loss)
            },
        );
        (loss, t0.elapsed().as_secs_f64())
    }
}
