//! The light table: every emitter of a scene with power-proportional selection
//! (pbrt-v4 `PowerLightSampler`), and the per-light sampling it dispatches to.
//!
//! Selection index layout: area emitters (in object order), then point lights
//! (in scene order), then the background. Area lights pick a triangle with the
//! remapped selection number and a point with `u`; the background uses `u`.

use glam::{DVec3, Vec2, Vec3};

use super::area::{AreaEmitter, in_front, solid_angle_pdf};
use super::distribution::Distribution1D;
use super::{Background, LightPoint, LightSample, PointLight};
use crate::scene::{Object, ObjectId};

/// Precomputed selection and sampling tables for every emitter of a scene.
#[derive(Clone, Debug)]
pub struct LightTable {
    /// Emissive objects.
    pub(super) area: Vec<AreaEmitter>,
    /// For each object, its index in `area`.
    pub(super) emitter_of_object: Vec<Option<u32>>,
    /// Point lights.
    pub(super) points: Vec<PointLight>,
    /// The background.
    pub(super) background: Background,
    /// Selection ∝ power over `area ++ points ++ [background]`; `None` when
    /// nothing emits.
    pub(super) selection: Option<Distribution1D>,
    /// The gather tables of the sixteen-lane functions.
    #[cfg(target_arch = "x86_64")]
    pub(super) wide: super::wide::Tables,
}

impl Default for LightTable {
    fn default() -> Self {
        Self {
            area: Vec::new(),
            emitter_of_object: Vec::new(),
            points: Vec::new(),
            background: Background::Constant(Vec3::ZERO),
            selection: None,
            #[cfg(target_arch = "x86_64")]
            wide: Default::default(),
        }
    }
}

impl LightTable {
    /// Builds the tables: world-space emissive triangles and power-proportional
    /// selection. `bounds` (world bounds of the scene geometry) only sizes the
    /// background's power estimate.
    pub fn build(
        objects: &[Object],
        point_lights: &[PointLight],
        background: &Background,
        bounds: Option<(DVec3, DVec3)>,
    ) -> Self {
        let mut area = Vec::new();
        let mut emitter_of_object = vec![None; objects.len()];
        for (id, object) in objects.iter().enumerate() {
            if let Some(emission) = object.emission {
                emitter_of_object[id] = Some(area.len() as u32);
                area.push(AreaEmitter::new(id as ObjectId, object, emission));
            }
        }
        let powers: Vec<f64> = area
            .iter()
            .map(AreaEmitter::power)
            .chain(point_lights.iter().map(PointLight::power))
            .chain(std::iter::once(background.power(bounds)))
            .collect();
        let table = Self {
            area,
            emitter_of_object,
            points: point_lights.to_vec(),
            background: background.clone(),
            selection: Distribution1D::new(&powers),
            #[cfg(target_arch = "x86_64")]
            wide: Default::default(),
        };
        #[cfg(target_arch = "x86_64")]
        let table = Self {
            wide: super::wide::Tables::new(&table),
            ..table
        };
        table
    }

    /// Whether the scene has no emitter of non-zero power.
    pub fn is_empty(&self) -> bool {
        self.selection.is_none()
    }

    /// The background's selection index.
    pub(super) fn background_index(&self) -> usize {
        self.area.len() + self.points.len()
    }

    fn select_pmf(&self, index: usize) -> f64 {
        self.selection.as_ref().map_or(0.0, |s| s.pmf(index))
    }

    /// Samples a light point as seen from `p`. `None` when there is no light
    /// or the sample carries no energy (e.g. `p` behind an area light).
    /// Always inlined (see `tracer::render_tile_avx2`).
    #[inline(always)]
    pub fn sample(&self, p: Vec3, u_select: f32, u: Vec2) -> Option<LightSample> {
        let pick = self.selection.as_ref()?.sample_discrete(u_select as f64);
        let n_area = self.area.len();
        if let Some(emitter) = self.area.get(pick.index) {
            let y = emitter.sample(pick.u_remapped, u)?;
            let d = y.position - p;
            if !in_front(d, y.normal) {
                return None;
            }
            let pdf_area = (pick.pmf * emitter.pdf_area()) as f32;
            let pdf = solid_angle_pdf(pdf_area, d, y.normal);
            if pdf <= 0.0 {
                return None;
            }
            let dist = d.length();
            return Some(LightSample {
                wo: d / dist,
                dist,
                position: y.position,
                normal: y.normal,
                radiance: emitter.emission,
                pdf,
                delta: false,
                source: LightPoint::Area {
                    object: emitter.object,
                    triangle: y.triangle,
                    b1: y.b1,
                    b2: y.b2,
                },
            });
        }
        if let Some(light) = self.points.get(pick.index - n_area) {
            let c = light.connect(p)?;
            return Some(LightSample {
                wo: c.wo,
                dist: c.dist,
                position: light.position.as_vec3(),
                normal: Vec3::ZERO,
                radiance: c.radiance,
                pdf: pick.pmf as f32,
                delta: true,
                source: LightPoint::Point {
                    index: (pick.index - n_area) as u32,
                },
            });
        }
        let s = self.background.sample(u)?;
        Some(LightSample {
            wo: s.dir,
            dist: f32::INFINITY,
            position: s.dir,
            normal: Vec3::ZERO,
            radiance: self.background.eval(s.dir),
            pdf: (pick.pmf * s.pdf as f64) as f32,
            delta: false,
            source: LightPoint::Background,
        })
    }

    /// Solid-angle pdf (selection included) that `sample` from `p` returns the
    /// point `y` on triangle `triangle` of emissive object `object` with unit
    /// normal `n` (`|cos|` is used, so either orientation of `n` works). Zero
    /// for non-emitters and when `p` is behind the emitting face.
    pub fn pdf_area(&self, object: ObjectId, triangle: u32, p: Vec3, y: Vec3, n: Vec3) -> f32 {
        let Some(&Some(index)) = self.emitter_of_object.get(object as usize) else {
            return 0.0;
        };
        let d = y - p;
        if !in_front(d, self.area[index as usize].normal(triangle)) {
            return 0.0;
        }
        solid_angle_pdf(self.selected_pdf_area(index as usize), d, n)
    }

    /// The area density (m⁻²) of sampling a point of area emitter `index`,
    /// its selection included, as [`Self::pdf_area`] uses it.
    pub(super) fn selected_pdf_area(&self, index: usize) -> f32 {
        (self.select_pmf(index) * self.area[index].pdf_area()) as f32
    }

    /// Solid-angle pdf (selection included) of sampling background direction `dir`.
    pub fn pdf_background(&self, dir: Vec3) -> f32 {
        let p_select = self.select_pmf(self.background_index());
        if p_select == 0.0 {
            return 0.0;
        }
        (p_select * self.background.pdf(dir) as f64) as f32
    }

    /// Probability that `sample` selects point light `index`.
    pub fn pdf_point(&self, index: u32) -> f32 {
        self.select_pmf(self.area.len() + index as usize) as f32
    }
}
