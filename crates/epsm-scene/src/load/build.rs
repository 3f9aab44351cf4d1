//! Turns a checked [`SceneDesc`] into [`SceneParts`]: camera, render
//! settings, background, materials and point lights here; objects in
//! [`object`](super::object).

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use glam::DVec3;

use super::named::NamedFile;
use super::object::Objects;
use crate::desc::{
    BackgroundDesc, CameraDesc, LightDesc, MaterialDesc, MaterialType, RenderDesc, SceneDesc,
};
use crate::error::{Error, Result};
use crate::fields::Fields;
use crate::image_io::{check_values, is_supported, read_image};
use epsm_render::camera::Camera;
use epsm_render::film::Image;
use epsm_render::lights::{Background, EnvMap, PointLight};
use epsm_render::materials::{
    Bsdf, Conductor, Dielectric, Diffuse, Material, RoughConductor, Texture,
};
use epsm_render::scene::{RenderSettings, SceneParts};

/// Largest accepted image side, pixels.
pub const MAX_RESOLUTION: u32 = 16384;
/// Largest accepted `max_depth`.
pub const MAX_DEPTH: u32 = 1024;

/// Images loaded so far (a texture used twice loads once).
pub type ImageCache = HashMap<NamedFile, Arc<Image>>;

/// Builds all parts of `desc`.
pub fn parts(desc: &SceneDesc, ctx: &Fields) -> Result<SceneParts> {
    let camera = camera(&desc.camera, ctx)?;
    let settings = render(&desc.render, ctx)?;
    let mut images = ImageCache::new();
    let background = match &desc.background {
        Some(b) => background(b, ctx, &mut images)?,
        None => Background::Constant(glam::Vec3::ZERO),
    };
    let mut materials = Vec::with_capacity(desc.materials.len());
    for (name, m) in &desc.materials {
        materials.push(material(name, m, ctx, &mut images)?);
    }
    let objects = Objects::new(ctx).build(&desc.objects, &materials)?;
    let mut names = HashSet::new();
    let mut point_lights = Vec::with_capacity(desc.lights.len());
    for (i, l) in desc.lights.iter().enumerate() {
        point_lights.push(light(&format!("lights[{i}]"), l, &mut names, ctx)?);
    }
    if objects.is_empty() && point_lights.is_empty() {
        return Err(ctx.err(
            "objects",
            "scene has nothing to render: no objects and no lights",
        ));
    }
    Ok(SceneParts {
        camera,
        materials,
        objects,
        point_lights,
        background,
        settings,
        source: Some(ctx.file.to_owned()),
    })
}

fn camera(c: &CameraDesc, ctx: &Fields) -> Result<Camera> {
    let view = View {
        origin: ctx.vec3("camera.origin", c.origin)?,
        target: ctx.vec3("camera.target", c.target)?,
        up: ctx.vec3("camera.up", c.up)?,
        fov_y: ctx.finite("camera.fov", c.fov)?,
        resolution: c.resolution,
    };
    checked_camera(&view, "camera", ctx)
}

/// A pinhole camera's placement before its checks (finite values).
#[derive(Clone, Copy, Debug)]
pub(crate) struct View {
    /// Eye position, world space.
    pub origin: DVec3,
    /// A point looked at.
    pub target: DVec3,
    /// Up hint.
    pub up: DVec3,
    /// Vertical field of view, degrees.
    pub fov_y: f64,
    /// `[width, height]`, pixels.
    pub resolution: [u32; 2],
}

/// The camera of `view`, checked (field of view in (0, 180), resolution in
/// range, a defined view direction, `up` not parallel to it); errors name
/// `{field}.fov`, `{field}.resolution[i]`, `{field}.target` or `{field}.up`.
pub(crate) fn checked_camera(view: &View, field: &str, ctx: &Fields) -> Result<Camera> {
    let fov = view.fov_y;
    if !(fov > 0.0 && fov < 180.0) {
        let msg = format!("expected degrees in (0, 180), found {fov}");
        return Err(ctx.err(&format!("{field}.fov"), msg));
    }
    let [w, h] = view.resolution;
    ctx.count(&format!("{field}.resolution[0]"), w, 1, MAX_RESOLUTION)?;
    ctx.count(&format!("{field}.resolution[1]"), h, 1, MAX_RESOLUTION)?;
    let (origin, target, up) = (view.origin, view.target, view.up);
    let forward = (target - origin).try_normalize().ok_or_else(|| {
        let msg = "equals the camera origin: the view direction is undefined";
        ctx.err(&format!("{field}.target"), msg)
    })?;
    let parallel = || {
        let msg = "is zero or parallel to the view direction";
        ctx.err(&format!("{field}.up"), msg)
    };
    if forward.cross(up).length() <= 1e-9 * up.length() {
        return Err(parallel());
    }
    Camera::look_at(origin, target, up, fov, w, h).ok_or_else(parallel)
}

fn render(r: &RenderDesc, ctx: &Fields) -> Result<RenderSettings> {
    Ok(RenderSettings {
        spp: ctx.count("render.spp", r.spp, 1, u32::MAX)?,
        max_depth: ctx.count("render.max_depth", r.max_depth, 1, MAX_DEPTH)?,
        rr_depth: ctx.count("render.rr_depth", r.rr_depth, 1, u32::MAX)?,
        seed: r.seed,
        manifold_nee: r.manifold_nee,
    })
}

/// Loads the image at `relative` (from field `field`) through the cache and
/// checks that every channel of every pixel is finite and in `[0, max]`.
pub(crate) fn image(
    field: &str,
    relative: &str,
    max: f32,
    ctx: &Fields,
    images: &mut ImageCache,
) -> Result<Arc<Image>> {
    let path = ctx.resolve(relative);
    if !is_supported(&path) {
        let msg = format!("expected a .png or .exr file, found \"{relative}\"");
        return Err(ctx.err(field, msg));
    }
    let file = NamedFile::new(path, field, ctx)?;
    let img = match images.get(&file) {
        Some(img) => img.clone(),
        None => {
            let img = Arc::new(read_image(&file.path).map_err(|e| ctx.nested(field, &e))?);
            images.insert(file.clone(), img.clone());
            img
        }
    };
    check_values(&file.path, &img, max).map_err(|e| ctx.nested(field, &e))?;
    Ok(img)
}

fn background(b: &BackgroundDesc, ctx: &Fields, images: &mut ImageCache) -> Result<Background> {
    match (&b.color, &b.envmap) {
        (Some(_), Some(_)) => Err(ctx.err("background", "give either color or envmap, not both")),
        (None, None) => Err(ctx.err("background", "expected color or envmap")),
        (Some(c), None) => {
            for (key, present) in [("scale", b.scale.is_some()), ("rotate", b.rotate.is_some())] {
                if present {
                    return Err(ctx.err(&format!("background.{key}"), "only applies to envmap"));
                }
            }
            Ok(Background::Constant(ctx.color(
                "background.color",
                *c,
                f64::INFINITY,
            )?))
        }
        (None, Some(file)) => {
            let image = image("background.envmap", file, f32::INFINITY, ctx, images)?;
            let scale = b.scale.unwrap_or(1.0);
            let scale = ctx.within("background.scale", scale, 0.0, f64::MAX, "a value >= 0")?;
            let rotate = ctx.finite("background.rotate", b.rotate.unwrap_or(0.0))?;
            Ok(Background::EnvMap(Arc::new(EnvMap::new(
                (*image).clone(),
                scale as f32,
                rotate.to_radians() as f32,
            ))))
        }
    }
}

fn material(
    name: &str,
    m: &MaterialDesc,
    ctx: &Fields,
    images: &mut ImageCache,
) -> Result<Material> {
    let field = format!("materials.{name}");
    if name.trim().is_empty() {
        return Err(ctx.err(&field, "material name must not be empty"));
    }
    let allowed: &[&str] = match m.kind {
        MaterialType::Diffuse => &["albedo", "texture", "two_sided"],
        MaterialType::Conductor => &["tint", "two_sided"],
        MaterialType::RoughConductor => &["alpha", "tint", "two_sided"],
        MaterialType::Dielectric => &["ior"],
    };
    let present = [
        ("albedo", m.albedo.is_some()),
        ("texture", m.texture.is_some()),
        ("tint", m.tint.is_some()),
        ("alpha", m.alpha.is_some()),
        ("ior", m.ior.is_some()),
        ("two_sided", m.two_sided.is_some()),
    ];
    if let Some((key, _)) = present.iter().find(|(k, p)| *p && !allowed.contains(k)) {
        let msg = format!(
            "not a parameter of type \"{}\" (expected one of: type, {})",
            m.kind.as_str(),
            allowed.join(", ")
        );
        return Err(ctx.err(&format!("{field}.{key}"), msg));
    }
    let unit = |key: &str, v: Option<[f64; 3]>, default: f64| {
        ctx.color(&format!("{field}.{key}"), v.unwrap_or([default; 3]), 1.0)
    };
    let bsdf = match m.kind {
        MaterialType::Diffuse => {
            let albedo = match (&m.albedo, &m.texture) {
                (Some(_), Some(_)) => {
                    return Err(ctx.err(&field, "give either albedo or texture, not both"));
                }
                (_, Some(t)) => {
                    Texture::Image(image(&format!("{field}.texture"), t, 1.0, ctx, images)?)
                }
                (a, None) => Texture::Constant(unit("albedo", *a, 0.5)?),
            };
            Bsdf::Diffuse(Diffuse { albedo })
        }
        MaterialType::Conductor => Bsdf::Conductor(Conductor {
            tint: unit("tint", m.tint, 1.0)?,
        }),
        MaterialType::RoughConductor => {
            let key = format!("{field}.alpha");
            let alpha = m
                .alpha
                .ok_or_else(|| ctx.err(&key, "required for rough_conductor"))?;
            Bsdf::RoughConductor(RoughConductor {
                alpha: ctx.alpha(&key, alpha)?,
                tint: unit("tint", m.tint, 1.0)?,
            })
        }
        MaterialType::Dielectric => Bsdf::Dielectric(Dielectric {
            ior: ctx.ior(&format!("{field}.ior"), m.ior.unwrap_or(1.5))?,
        }),
    };
    Ok(Material {
        name: name.to_owned(),
        two_sided: m.kind == MaterialType::Dielectric || m.two_sided.unwrap_or(false),
        bsdf,
    })
}

fn light<'n>(
    field: &str,
    l: &'n LightDesc,
    names: &mut HashSet<&'n str>,
    ctx: &Fields,
) -> Result<PointLight, Error> {
    ctx.unique_name(&format!("{field}.name"), &l.name, names, "light")?;
    Ok(PointLight {
        name: l.name.clone(),
        position: ctx.vec3(&format!("{field}.position"), l.position)?,
        intensity: ctx.color(&format!("{field}.intensity"), l.intensity, f64::INFINITY)?,
    })
}
