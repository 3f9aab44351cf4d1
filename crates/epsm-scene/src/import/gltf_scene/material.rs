//! glTF metallic-roughness materials → epsm materials (the mapping table
//! of [`gltf_scene`](super)), with the emission each gives its objects.
//!
//! | glTF | epsm |
//! |---|---|
//! | `transmissionFactor ≥ 0.5` | dielectric, `ior` of `KHR_materials_ior` (1.5) |
//! | `metallicFactor ≥ 0.5`, `roughnessFactor² <` [`SMOOTH_ALPHA`] | conductor, tint = base colour |
//! | `metallicFactor ≥ 0.5` | rough conductor, `α = roughnessFactor²` |
//! | otherwise | diffuse, albedo = base colour |
//! | `emissiveFactor × emissiveStrength` | `Object.emission` |
//!
//! ```json
//! {"pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.6, 0.3, 1], "metallicFactor": 1, "roughnessFactor": 0.3}}
//! ```

use glam::Vec3;

use super::Importer;
use crate::error::Result;
use epsm_render::materials::{
    Bsdf, Conductor, Dielectric, Diffuse, Material, RoughConductor, Texture,
};

/// GGX `α` below which a metal is a smooth conductor.
pub const SMOOTH_ALPHA: f64 = 1e-3;

/// The metallic-roughness parameters of one glTF material.
struct Pbr {
    name: String,
    base: [f64; 3],
    metallic: f64,
    roughness: f64,
    transmission: f64,
    ior: f64,
    emission: [f64; 3],
    double_sided: bool,
}

impl Importer<'_> {
    /// Maps glTF material `m` (its index is its position in `materials`).
    pub(super) fn material(&mut self, m: &gltf::Material) -> Result<()> {
        let i = self.materials.len();
        let pbr = m.pbr_metallic_roughness();
        let textures = [
            pbr.base_color_texture().is_some(),
            pbr.metallic_roughness_texture().is_some(),
            m.normal_texture().is_some(),
            m.emissive_texture().is_some(),
        ];
        if textures.contains(&true) {
            let msg = "textures are skipped: the constant factors are used";
            self.warn(&format!("materials[{i}]"), msg);
        }
        let [r, g, b, _] = pbr.base_color_factor().map(f64::from);
        let strength = f64::from(m.emissive_strength().unwrap_or(1.0));
        self.push(&Pbr {
            name: m
                .name()
                .map_or_else(|| format!("material{i}"), str::to_owned),
            base: [r, g, b],
            metallic: f64::from(pbr.metallic_factor()),
            roughness: f64::from(pbr.roughness_factor()),
            transmission: m
                .transmission()
                .map_or(0.0, |t| f64::from(t.transmission_factor())),
            ior: f64::from(m.ior().unwrap_or(1.5)),
            emission: m.emissive_factor().map(|e| f64::from(e) * strength),
            double_sided: m.double_sided(),
        })
    }

    /// Checks and appends one material (see the module table).
    fn push(&mut self, p: &Pbr) -> Result<()> {
        let ctx = self.ctx;
        let field = format!("materials[{}]", self.materials.len());
        let f = |key: &str| format!("{field}.{key}");
        if self.materials.iter().any(|m| m.name == p.name) {
            return Err(ctx.err(
                &f("name"),
                format!("duplicate material name \"{}\"", p.name),
            ));
        }
        let tint = ctx.color(&f("pbrMetallicRoughness.baseColorFactor"), p.base, 1.0)?;
        let metallic = ctx.within(
            &f("metallicFactor"),
            p.metallic,
            0.0,
            1.0,
            "a value in [0, 1]",
        )?;
        let roughness = ctx.within(
            &f("roughnessFactor"),
            p.roughness,
            0.0,
            1.0,
            "a value in [0, 1]",
        )?;
        let transmission = ctx.within(
            &f("transmissionFactor"),
            p.transmission,
            0.0,
            1.0,
            "a value in [0, 1]",
        )?;
        let alpha = roughness * roughness;
        let bsdf = if transmission >= 0.5 {
            Bsdf::Dielectric(Dielectric {
                ior: ctx.ior(&f("extensions.KHR_materials_ior.ior"), p.ior)?,
            })
        } else if metallic >= 0.5 && alpha < SMOOTH_ALPHA {
            Bsdf::Conductor(Conductor { tint })
        } else if metallic >= 0.5 {
            Bsdf::RoughConductor(RoughConductor {
                alpha: ctx.alpha(&f("roughnessFactor"), alpha)?,
                tint,
            })
        } else {
            Bsdf::Diffuse(Diffuse {
                albedo: Texture::Constant(tint),
            })
        };
        let emission = ctx.color(&f("emissiveFactor"), p.emission, f64::INFINITY)?;
        self.materials.push(Material {
            name: p.name.clone(),
            two_sided: p.double_sided || matches!(bsdf, Bsdf::Dielectric(_)),
            bsdf,
        });
        self.emission
            .push((emission != Vec3::ZERO).then_some(emission));
        Ok(())
    }

    /// The index of glTF's default material (white, metallic 1, roughness 1),
    /// appended on first use.
    pub(super) fn default_material(&mut self) -> Result<u32> {
        const NAME: &str = "gltf_default";
        if let Some(i) = self.materials.iter().position(|m| m.name == NAME) {
            return Ok(i as u32);
        }
        self.push(&Pbr {
            name: NAME.to_owned(),
            base: [1.0; 3],
            metallic: 1.0,
            roughness: 1.0,
            transmission: 0.0,
            ior: 1.5,
            emission: [0.0; 3],
            double_sided: false,
        })?;
        Ok(self.materials.len() as u32 - 1)
    }
}
