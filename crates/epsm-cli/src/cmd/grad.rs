//! `epsm grad`: gradient images of one parameter at the problem's initial θ,
//! at the match resolution (shown enlarged):
//! - `flow.png`: the motion field dp/dθ, colour-coded (hue = direction,
//!   brightness = magnitude) over the render, with sparse arrows;
//! - `dI.png`: dI/dθ as a signed heat map (red = brighter, blue = darker);
//! - `matching.png`: the current OT matching, lines from render pixels to
//!   their targets (subsampled);
//! - `render.png`, `target.png`.

use std::path::PathBuf;

use anyhow::Context;
use epsm_core::field::{image_derivative, motion_field};
use epsm_core::inspect::{
    Segment, fd_step, flow_colour, matching_lines, motion_arrows, normalized_luminance,
    signed_colour,
};
use epsm_core::load_problem;
use epsm_render::Image;
use epsm_scene::image_io::linear_to_srgb;

use plotters::prelude::*;

use super::plots::write_png;

/// Arguments of `epsm grad`.
#[derive(clap::Args, Debug)]
pub struct GradArgs {
    /// The problem file (TOML).
    pub problem: PathBuf,
    /// The parameter key.
    #[arg(long)]
    pub param: String,
    /// Output folder.
    #[arg(long, default_value = "grad")]
    pub out: PathBuf,
    /// Samples per pixel of the finite-difference renders for dI/dθ.
    #[arg(long, default_value_t = 16)]
    pub spp: u32,
}

/// An enlarged RGB8 canvas.
struct Canvas {
    w: u32,
    h: u32,
    scale: u32,
    rgb: Vec<u8>,
}

impl Canvas {
    fn new(src_w: u32, src_h: u32, colour: impl Fn(u32, u32) -> [f32; 3]) -> Self {
        let scale = (512 / src_w.max(src_h)).max(1);
        let (w, h) = (src_w * scale, src_h * scale);
        let mut rgb = vec![0u8; (w * h * 3) as usize];
        for y in 0..h {
            for x in 0..w {
                let c = colour(x / scale, y / scale);
                let i = ((y * w + x) * 3) as usize;
                for k in 0..3 {
                    rgb[i + k] = (c[k].clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
                }
            }
        }
        Self { w, h, scale, rgb }
    }

    fn lines(&mut self, lines: &[Segment], colour: RGBColor) -> anyhow::Result<()> {
        let (w, h, scale) = (self.w, self.h, self.scale as f32);
        let px = |p: glam::Vec2| ((p.x * scale) as i32, (p.y * scale) as i32);
        let root = BitMapBackend::with_buffer(&mut self.rgb, (w, h)).into_drawing_area();
        for Segment { from: a, to: b } in lines {
            let e = |e: DrawingAreaErrorKind<_>| anyhow::anyhow!("drawing: {e}");
            root.draw(&PathElement::new(
                vec![px(*a), px(*b)],
                colour.stroke_width(1),
            ))
            .map_err(e)?;
            root.draw(&Circle::new(px(*b), 2, colour.filled()))
                .map_err(e)?;
        }
        root.present().map_err(|e| anyhow::anyhow!("drawing: {e}"))
    }
}

fn srgb(img: &Image, x: u32, y: u32) -> [f32; 3] {
    let c = img.get(x, y);
    [
        linear_to_srgb(c.x),
        linear_to_srgb(c.y),
        linear_to_srgb(c.z),
    ]
}

/// Runs `epsm grad`.
pub fn run(args: &GradArgs) -> anyhow::Result<()> {
    anyhow::ensure!(args.spp >= 1, "--spp must be at least 1");
    let problem = load_problem(&args.problem)?;
    let param = problem
        .params
        .iter()
        .position(|p| p.key == args.param)
        .with_context(|| {
            let keys: Vec<&str> = problem.params.iter().map(|p| p.key.as_str()).collect();
            format!(
                "--param `{}` is not a parameter of the problem (it has {})",
                args.param,
                keys.join(", ")
            )
        })?;
    let mut opt = epsm_core::Optimization::new(problem)?;
    let (g, records) = opt.gradient()?;
    let (scene, table) = opt.match_view();
    let field = motion_field(scene, table, &records, param);
    let (w, h) = (g.image.width, g.image.height);
    let max = field.iter().map(|d| d.length()).fold(0.0, f64::max);
    let img = &g.image;
    let mut flow = Canvas::new(w, h, |x, y| {
        let (c, f) = (
            srgb(img, x, y),
            flow_colour(field[(y * w + x) as usize], max),
        );
        let blend = if f == [0.0; 3] { 0.0 } else { 0.7 };
        std::array::from_fn(|k| c[k] * (1.0 - blend) + f[k] * blend)
    });
    let arrows = motion_arrows(&field, w, h, (w.max(h) / 16).max(1));
    flow.lines(&arrows, WHITE)?;
    write_png(&args.out.join("flow.png"), flow.w, flow.h, &flow.rgb)?;

    let h_step = fd_step(&opt, param);
    let (scene, table) = opt.match_view_mut();
    let di = image_derivative(scene, table, param, h_step, args.spp);
    let lum = normalized_luminance(&di.pixels);
    let heat = Canvas::new(w, h, |x, y| signed_colour(lum[(y * w + x) as usize]));
    write_png(&args.out.join("dI.png"), heat.w, heat.h, &heat.rgb)?;

    let mut matching = Canvas::new(w, h, |x, y| srgb(img, x, y));
    matching.lines(&matching_lines(&g.loss, 7, 0.5), RGBColor(255, 220, 0))?;
    write_png(
        &args.out.join("matching.png"),
        matching.w,
        matching.h,
        &matching.rgb,
    )?;
    for (name, im) in [("render", img), ("target", opt.target())] {
        let c = Canvas::new(im.width, im.height, |x, y| srgb(im, x, y));
        write_png(&args.out.join(format!("{name}.png")), c.w, c.h, &c.rgb)?;
    }
    println!(
        "{}: {} at θ = {:.4}: max |dp/dθ| {:.3} px/unit, dL/dθ {:.4e} -> {}",
        args.problem.display(),
        args.param,
        opt.theta()[param],
        max,
        g.grad[param],
        args.out.display()
    );
    Ok(())
}
