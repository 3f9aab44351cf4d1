//! The gradient pass of one iteration: the recorded trace at the match
//! resolution, the loss with its per-pixel gradients (beside an independent
//! render when the problem asks for one), and the backward pass to `dL/dθ`.

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
        if let Some(smoothing) = &self.smoothing {
            return Ok((self.smoothed_gradient(smoothing)?, Vec::new()));
        }
        let l2 = !self.schedule.loss_at(self.iteration).is_ot();
        // With the colour-flow term, an L2 iteration of the epsm method
        // differentiates like an OT one: the flow term supplies what the
        // pixel's colour gains as content (and its edges) moves across it,
        // so the pixel's vertex moves with its surface and every path's
        // screen motion counts.
        let flow = self.problem.loss.flow == Some(true);
        let flow_l2 = l2 && flow && self.problem.optimizer.method == Method::Epsm;
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
        let t0 = Instant::now();
        let opts = RenderOptions {
            spp,
            seed: self.seed(0),
            ..RenderOptions::from_scene(&self.grad.scene)
        };
        let loss_image = passes.loss_image(!l2);
        let ((out, records), independent) = self.maybe_join(
            || render_recorded(&self.grad.scene, &opts, level, &|_| {}),
            || match loss_image {
                LossImage::GradientPass => None,
                LossImage::Independent(spp) => {
                    Some(render_image(&self.grad.scene, spp, self.seed(2)))
                }
            },
        );
        let image = independent.unwrap_or_else(|| out.image.clone());
        let t1 = Instant::now();
        let kind = self.schedule.loss_at(self.iteration);
        let warm = &mut *self.warm.lock().unwrap_or_else(PoisonError::into_inner);
        let mut loss = evaluate(
            kind,
            &image,
            if kind.is_ot() {
                &self.target_ot
            } else {
                &self.target_match
            },
            self.problem.loss.lambda,
            Some(warm),
        )?;
        if flow && (kind.is_ot() || flow_l2) {
            add_flow(&image, &mut loss)?;
        }
        let t2 = Instant::now();
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
            trace: (t1 - t0).as_secs_f64(),
            matching: (t2 - t1).as_secs_f64(),
            solve: t2.elapsed().as_secs_f64(),
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
        ))
    }
}
