//! A scene and its parameter table at one resolution: the optimization keeps
//! one at the scene resolution (primal renders) and one at the match
//! resolution (gradient passes and judged renders).

use epsm_render::Scene;

use super::OptResult;
use crate::params::ParamTable;
use crate::problem::Problem;

/// A scene and its parameter table (one per resolution).
#[derive(Clone, Debug)]
pub(super) struct View {
    /// The scene at this resolution.
    pub scene: Scene,
    /// Its parameter table.
    pub table: ParamTable,
}

impl View {
    /// The problem's scene at `width` × `height` pixels, with its
    /// parameters in the table and the objects they move made dynamic.
    pub fn new(problem: &Problem, width: u32, height: u32) -> OptResult<Self> {
        let mut parts = problem.scene.clone();
        parts.camera.width = width;
        parts.camera.height = height;
        let mut scene = Scene::new(parts)?;
        let mut table = ParamTable::new(&scene);
        for p in &problem.params {
            table.add(&p.key)?;
        }
        // Driven objects get their own BVH instances now, so moving them
        // rebuilds only the top level (not the static objects' BVH).
        scene.set_dynamic(&table.moving_objects());
        Ok(Self { scene, table })
    }

    /// Sets θ (user units, index order) and applies it to the scene.
    pub fn set(&mut self, theta: &[f64]) {
        for (k, v) in theta.iter().enumerate() {
            self.table.set_value(k, *v);
        }
        self.table.apply(&mut self.scene);
    }
}
