//! Mitsuba 3 XML scenes (a subset) as [`SceneParts`]. The file is parsed by
//! [`parse`] (with `<default>` / `$name` substitution), then each top-level
//! element is mapped: [`sensor`] (camera, film, sampler, integrator),
//! [`bsdf`] (materials), [`shape`] (objects, area emitters), [`emitter`]
//! (point lights, background), with transforms by [`transform`]. The full
//! mapping and the list of what is skipped with a warning is in
//! `docs/interop.md`; anything else is an error naming the element path,
//! the attribute and the line.
//!
//! | top-level element | becomes | names |
//! |---|---|---|
//! | `<sensor>` (the first) | camera, resolution, spp, seed | — |
//! | `<integrator type="path">` | `max_depth`, `rr_depth` | — |
//! | `<bsdf id>` | a material | its `id` |
//! | `<shape>` | an object | its `id`, else `shape<i>`; an inline BSDF is named `<object>_bsdf`, no BSDF is `default` (diffuse 0.5) |
//! | `<emitter>` | point light or background | its `id`, else `light<i>` |
//!
//! ```xml
//! <scene version="3.0.0">
//!     <bsdf type="diffuse" id="white"><rgb name="reflectance" value="0.75"/></bsdf>
//!     <shape type="rectangle" id="floor"><ref id="white"/></shape>
//! </scene>
//! ```

pub mod bsdf;
pub mod emitter;
pub mod parse;
pub mod props;
pub mod sensor;
pub mod shape;
pub mod transform;

use std::collections::HashMap;
use std::path::Path;

use glam::Vec3;

use self::bsdf::{Definitions, target};
use self::emitter::Emitter;
use self::parse::{Element, finish};
use crate::error::{FieldError, Result};
use crate::fields::Fields;
use crate::load::Loaded;
use crate::load::build::ImageCache;
use epsm_render::lights::Background;
use epsm_render::materials::{Bsdf, Diffuse, Material, Texture};
use epsm_render::scene::{Object, SceneParts};

/// Loads the Mitsuba XML scene at `path`.
pub fn load(path: &Path) -> Result<Loaded> {
    from_str(&crate::input_file::read_to_string(path)?, path)
}

/// Builds a scene from the text of a Mitsuba XML file; `file` names it in
/// errors and its directory resolves mesh and image files.
pub fn from_str(text: &str, file: &Path) -> Result<Loaded> {
    let doc = parse::parse(text, file)?;
    let ctx = Fields::new(file, &doc.locator, "");
    let root = &doc.root;
    let mut warnings = Vec::new();
    let sensors: Vec<&Element> = root.tagged("sensor").collect();
    let integrators: Vec<&Element> = root.tagged("integrator").collect();
    let Some(first) = sensors.first() else {
        return Err(ctx.err("scene", "no <sensor>: the scene needs a perspective camera"));
    };
    if let Some(extra) = sensors.get(1) {
        warnings.push(ctx.located(&extra.path, "only the first <sensor> is used"));
    }
    if let Some(extra) = integrators.get(1) {
        return Err(ctx.err(&extra.path, "expected at most one <integrator>"));
    }
    let (camera, settings) =
        sensor::sensor(first, integrators.first().copied(), &ctx, &mut warnings)?;

    let mut defs = Definitions::new();
    for b in root.tagged("bsdf") {
        let id = b
            .attr("id")
            .ok_or_else(|| ctx.err(&format!("{}.id", b.path), "a top-level <bsdf> needs an id"))?;
        // Ids are unique (`parse` rejects a repeated one).
        defs.insert(id, b);
    }
    let mut materials = Materials::default();
    let mut objects = Vec::new();
    let mut shapes = shape::Shapes::default();
    for (i, el) in root.tagged("shape").enumerate() {
        let name = el
            .attr("id")
            .map_or_else(|| format!("shape{i}"), str::to_owned);
        if objects.iter().any(|o: &Object| o.name == name) {
            return Err(ctx.err(
                &format!("{}.id", el.path),
                format!("duplicate shape id \"{name}\""),
            ));
        }
        let material = materials.of_shape(el, &name, &defs, &ctx, &mut warnings)?;
        let placed = shapes.shape(el, &ctx, &mut warnings)?;
        objects.push(Object {
            name,
            mesh: placed.mesh,
            world_from_object: placed.world_from_object,
            material,
            emission: placed.emission,
            surface: placed.surface,
        });
    }
    // Top-level BSDFs no shape uses still load (and are checked).
    for el in root.tagged("bsdf") {
        materials.named(
            el.attr("id").unwrap_or_default(),
            el,
            &defs,
            &ctx,
            &mut warnings,
        )?;
    }

    let mut images = ImageCache::new();
    let mut point_lights = Vec::new();
    let mut background: Option<Background> = None;
    for (i, el) in root.tagged("emitter").enumerate() {
        let name = el
            .attr("id")
            .map_or_else(|| format!("light{i}"), str::to_owned);
        match emitter::emitter(el, name, &mut images, &ctx, &mut warnings)? {
            Emitter::Point(light) => point_lights.push(light),
            Emitter::Background(_) if background.is_some() => {
                return Err(ctx.err(
                    &el.path,
                    "only one background emitter (constant or envmap) is supported",
                ));
            }
            Emitter::Background(b) => background = Some(b),
        }
    }
    finish(root, &ctx, &[], &mut warnings)?;
    if objects.is_empty() && point_lights.is_empty() {
        return Err(ctx.err(
            "scene",
            "scene has nothing to render: no shapes and no point emitters",
        ));
    }
    Ok(Loaded {
        parts: SceneParts {
            camera,
            materials: materials.list,
            objects,
            point_lights,
            background: background.unwrap_or(Background::Constant(Vec3::ZERO)),
            settings,
            source: Some(file.to_owned()),
        },
        warnings,
    })
}

/// Name of the material of shapes without a BSDF (Mitsuba's default: diffuse 0.5).
pub const DEFAULT: &str = "default";

/// Materials built so far, with the index of each top-level id.
#[derive(Default)]
struct Materials {
    list: Vec<Material>,
    by_id: HashMap<String, u32>,
}

impl Materials {
    /// The material index of `<shape>` `el` (named `object`): its `<ref>`,
    /// its inline `<bsdf>`, or Mitsuba's default diffuse.
    fn of_shape(
        &mut self,
        el: &Element,
        object: &str,
        defs: &Definitions,
        ctx: &Fields,
        warnings: &mut Vec<FieldError>,
    ) -> Result<u32> {
        let nested: Vec<&Element> = el.tagged("bsdf").chain(el.tagged("ref")).collect();
        match nested.as_slice() {
            [] => {
                if defs.contains_key(DEFAULT) {
                    let msg = format!("has no BSDF and the id \"{DEFAULT}\" names another one");
                    return Err(ctx.err(&el.path, msg));
                }
                let default = Material {
                    name: DEFAULT.to_owned(),
                    bsdf: Bsdf::Diffuse(Diffuse {
                        albedo: Texture::Constant(Vec3::splat(0.5)),
                    }),
                    two_sided: false,
                };
                self.add(DEFAULT, || Ok(default))
            }
            [b] if b.tag == "ref" => {
                let def = target(b, defs, &mut Vec::new(), ctx)?;
                let id = def.attr("id").unwrap_or_default();
                self.named(id, def, defs, ctx, warnings)
            }
            [b] => {
                let name = b
                    .attr("id")
                    .map_or_else(|| format!("{object}_bsdf"), str::to_owned);
                if self.by_id.contains_key(&name) || defs.contains_key(name.as_str()) {
                    return Err(ctx.err(&b.path, format!("duplicate BSDF name \"{name}\"")));
                }
                let material = bsdf::material(b, name.clone(), defs, ctx, warnings)?;
                self.add(&name, || Ok(material))
            }
            _ => Err(ctx.err(&el.path, "expected at most one <bsdf> or <ref>")),
        }
    }

    /// The index of top-level BSDF `id` (element `el`), built on first use.
    fn named(
        &mut self,
        id: &str,
        el: &Element,
        defs: &Definitions,
        ctx: &Fields,
        warnings: &mut Vec<FieldError>,
    ) -> Result<u32> {
        self.add(id, || {
            bsdf::material(el, id.to_owned(), defs, ctx, warnings)
        })
    }

    /// The index of the material called `name`, built by `make` on first use.
    fn add(&mut self, name: &str, make: impl FnOnce() -> Result<Material>) -> Result<u32> {
        if let Some(&i) = self.by_id.get(name) {
            return Ok(i);
        }
        self.list.push(make()?);
        let i = self.list.len() as u32 - 1;
        self.by_id.insert(name.to_owned(), i);
        Ok(i)
    }
}
