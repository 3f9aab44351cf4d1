//! Mitsuba BSDFs → [`Material`]s. Values go through the TOML loader's
//! checks (reflectances in [0, 1], α in [1e-4, 1], IOR > 0).
//!
//! | Mitsuba | epsm | parameters (default) |
//! |---|---|---|
//! | `diffuse` | diffuse | `reflectance` (0.5) → albedo |
//! | `conductor` | conductor | `material` (`none`), `specular_reflectance` (1): tint = metal × reflectance |
//! | `roughconductor` | rough conductor | `distribution` = `ggx` (required: Mitsuba's default is Beckmann), `alpha` (0.1) or equal `alpha_u`/`alpha_v`, `material`, `specular_reflectance` |
//! | `dielectric` | dielectric | `int_ior` (`bk7`), `ext_ior` (`air`): ior = int / ext; numbers or names of [`IORS`] |
//! | `twosided` | the nested BSDF with `two_sided = true` | one nested `<bsdf>` or `<ref>` |
//!
//! Named metals map to their normal-incidence reflectance [`METALS`]
//! (linear RGB, Real-Time Rendering 4th ed., table 9.2); `none` is a perfect
//! reflector. `sample_visible` is skipped with a warning (it only changes
//! sampling). A `<ref id>` to an undefined or non-BSDF id, or a cycle of
//! references, is an error.
//!
//! ```xml
//! <bsdf type="roughconductor" id="gold">
//!     <string name="distribution" value="ggx"/>
//!     <float name="alpha" value="0.02"/>
//!     <string name="material" value="Au"/>
//! </bsdf>
//! ```

use std::collections::HashMap;

use super::parse::{Element, finish};
use crate::error::{FieldError, Result};
use crate::fields::Fields;
use epsm_render::materials::{
    Bsdf, Conductor, Dielectric, Diffuse, Material, RoughConductor, Texture,
};

/// Named metals: Mitsuba's `material` names → normal-incidence reflectance.
pub const METALS: [(&str, [f64; 3]); 8] = [
    ("none", [1.0, 1.0, 1.0]),
    ("Ag", [0.972, 0.960, 0.915]),
    ("Al", [0.913, 0.922, 0.924]),
    ("Au", [1.000, 0.782, 0.344]),
    ("Cr", [0.549, 0.556, 0.554]),
    ("Cu", [0.955, 0.638, 0.538]),
    ("Hg", [0.781, 0.780, 0.778]),
    ("Ni_palik", [0.660, 0.609, 0.526]),
];

/// Named indices of refraction (Mitsuba's table).
pub const IORS: [(&str, f64); 13] = [
    ("vacuum", 1.0),
    ("air", 1.000277),
    ("water", 1.333),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.575),
    ("diamond", 2.419),
];

/// Top-level `<bsdf id=…>` definitions by id.
pub(crate) type Definitions<'a> = HashMap<&'a str, &'a Element>;

/// The material of `el` (a `<bsdf>` or a `<ref>`), named `name`.
pub(crate) fn material(
    el: &Element,
    name: String,
    defs: &Definitions,
    ctx: &Fields,
    warnings: &mut Vec<FieldError>,
) -> Result<Material> {
    let mut stack = Vec::new();
    let (bsdf, two_sided) = resolve(el, defs, &mut stack, ctx, warnings)?;
    Ok(Material {
        name,
        two_sided: two_sided || matches!(bsdf, Bsdf::Dielectric(_)),
        bsdf,
    })
}

/// The `<bsdf>` a `<ref id>` names (or `el` itself), with the ids being
/// resolved on `stack` to catch cycles.
pub(crate) fn target<'a>(
    el: &'a Element,
    defs: &Definitions<'a>,
    stack: &mut Vec<String>,
    ctx: &Fields,
) -> Result<&'a Element> {
    if el.tag != "ref" {
        return Ok(el);
    }
    let id = el
        .attr("id")
        .ok_or_else(|| ctx.err(&format!("{}.id", el.path), "missing id attribute"))?;
    if stack.iter().any(|s| s == id) {
        let msg = format!("cyclic reference: {} → {id}", stack.join(" → "));
        return Err(ctx.err(&format!("{}.id", el.path), msg));
    }
    stack.push(id.to_owned());
    defs.get(id).copied().ok_or_else(|| {
        let msg = format!("reference to undefined BSDF id \"{id}\"");
        ctx.err(&format!("{}.id", el.path), msg)
    })
}

fn resolve(
    el: &Element,
    defs: &Definitions,
    stack: &mut Vec<String>,
    ctx: &Fields,
    warnings: &mut Vec<FieldError>,
) -> Result<(Bsdf, bool)> {
    let el = target(el, defs, stack, ctx)?;
    if el.tag != "bsdf" {
        return Err(ctx.err(&el.path, format!("expected <bsdf>, found <{}>", el.tag)));
    }
    if let Some(id) = el.attr("id").filter(|id| !stack.iter().any(|s| s == id)) {
        stack.push(id.to_owned());
    }
    let field = |key: &str| format!("{}.{key}", el.path);
    let kind = el.kind(ctx)?;
    let mut skippable: &[&str] = &[];
    let out = match kind {
        "diffuse" => {
            let albedo = el.rgb(ctx, "reflectance")?.unwrap_or([0.5; 3]);
            let albedo = ctx.color(&field("reflectance"), albedo, 1.0)?;
            (Bsdf::Diffuse(Diffuse { albedo: Texture::Constant(albedo) }), false)
        }
        "conductor" => (Bsdf::Conductor(Conductor { tint: tint(el, ctx)? }), false),
        "roughconductor" => {
            skippable = &["sample_visible"];
            match el.string(ctx, "distribution")? {
                Some("ggx") => {}
                Some(other) => return Err(ctx.err(&field("distribution"), format!("only ggx is supported, found \"{other}\""))),
                None => {
                    let msg = "missing: Mitsuba's default is beckmann, which epsm does not have; give <string name=\"distribution\" value=\"ggx\"/>";
                    return Err(ctx.err(&field("distribution"), msg));
                }
            }
            let alpha = match (el.float(ctx, "alpha")?, el.float(ctx, "alpha_u")?, el.float(ctx, "alpha_v")?) {
                (Some(a), None, None) => a,
                (None, None, None) => 0.1,
                (None, Some(u), Some(v)) if u == v => u,
                _ => return Err(ctx.err(&field("alpha"), "expected alpha, or equal alpha_u and alpha_v (anisotropy is not supported)")),
            };
            let alpha = ctx.alpha(&field("alpha"), alpha)?;
            (Bsdf::RoughConductor(RoughConductor { alpha, tint: tint(el, ctx)? }), false)
        }
        "dielectric" => {
            let int = ior(el, "int_ior", 1.5046, ctx)?;
            let ext = ior(el, "ext_ior", 1.000277, ctx)?;
            (Bsdf::Dielectric(Dielectric { ior: ctx.ior(&field("int_ior"), int / ext)? }), true)
        }
        "twosided" => {
            let nested: Vec<&Element> = el.tagged("bsdf").chain(el.tagged("ref")).collect();
            let &[inner] = nested.as_slice() else {
                let msg = "expected exactly one nested <bsdf> or <ref> (different front and back BSDFs are not supported)";
                return Err(ctx.err(&el.path, msg));
            };
            (resolve(inner, defs, stack, ctx, warnings)?.0, true)
        }
        other => return Err(ctx.err(&field("type"), format!("unsupported BSDF type \"{other}\" (supported: diffuse, conductor, roughconductor, dielectric, twosided)"))),
    };
    finish(el, ctx, skippable, warnings)?;
    Ok(out)
}

/// A conductor's tint: the named metal's reflectance × `specular_reflectance`.
fn tint(el: &Element, ctx: &Fields) -> Result<glam::Vec3> {
    let field = format!("{}.material", el.path);
    let metal = el.string(ctx, "material")?.unwrap_or("none");
    let Some((_, base)) = METALS.iter().find(|(n, _)| *n == metal) else {
        let known: Vec<&str> = METALS.iter().map(|(n, _)| *n).collect();
        return Err(ctx.err(
            &field,
            format!("unknown metal \"{metal}\" (known: {})", known.join(", ")),
        ));
    };
    let scale = el.rgb(ctx, "specular_reflectance")?.unwrap_or([1.0; 3]);
    let tint = [0, 1, 2].map(|i| base[i] * scale[i]);
    Ok(ctx.color(&format!("{}.specular_reflectance", el.path), tint, 1.0)?)
}

/// An index of refraction given as a number or a name of [`IORS`].
fn ior(el: &Element, key: &str, default: f64, ctx: &Fields) -> Result<f64> {
    let field = format!("{}.{key}", el.path);
    let Some(p) = el.prop(key) else {
        return Ok(default);
    };
    if p.tag == "string" {
        let name = el.string(ctx, key)?.unwrap_or_default();
        return IORS
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, v)| *v)
            .ok_or_else(|| {
                let known: Vec<&str> = IORS.iter().map(|(n, _)| *n).collect();
                ctx.err(
                    &field,
                    format!("unknown material \"{name}\" (known: {})", known.join(", ")),
                )
            });
    }
    let v = el.float(ctx, key)?.unwrap_or(default);
    Ok(f64::from(ctx.ior(&field, v)?))
}
