//! Mitsuba shapes → meshes placed in the world, with an optional `area`
//! emitter. The built-in shapes share Mitsuba's conventions, so they are
//! epsm's [`shapes`]; mesh files load through [`load_mesh`] (validated).
//!
//! | Mitsuba | mesh | parameters (default) |
//! |---|---|---|
//! | `obj`, `ply` | the file | `filename` (required, relative to the XML file), `face_normals` (false: drop vertex normals) |
//! | `rectangle` | `[-1, 1]²` in `z = 0`, facing `+z` | — |
//! | `cube` | `[-1, 1]³` | — |
//! | `sphere` | the exact sphere ([`Surface::Sphere`]); with an emitter or `flip_normals`, which exact spheres do not have, an icosphere of [`SPHERE_LEVELS`] levels | `center` (0), `radius` (1) |
//! | `disk` | unit disk in `z = 0`, [`DEFAULT_DISK_SEGMENTS`](shapes::DEFAULT_DISK_SEGMENTS) segments | — |
//! | all | | `to_world` (identity), `flip_normals` (false) |
//! | `<emitter type="area">` | `Object.emission` | `radiance` (1) |
//!
//! `flip_tex_coords` is skipped with a warning (textures are not imported).
//!
//! ```xml
//! <shape type="sphere" id="ball">
//!     <point name="center" x="0" y="1" z="0"/>
//!     <float name="radius" value="0.5"/>
//!     <ref id="white"/>
//! </shape>
//! ```

use std::collections::HashMap;
use std::sync::Arc;

use glam::{DAffine3, DVec3, Vec3};

use super::parse::{Element, finish};
use super::transform::transform;
use crate::desc::ShapeKind;
use crate::error::{FieldError, Result};
use crate::fields::Fields;
use crate::import::load_mesh;
use crate::load::named::NamedFile;
use crate::load::object::flipped;
use crate::shapes;
use epsm_render::scene::{Mesh, Surface};

/// Icosphere levels of a Mitsuba `sphere` that emits or is flipped
/// (Mitsuba's spheres are exact; 5120 triangles keep the silhouette within
/// 0.3 % of the radius).
pub const SPHERE_LEVELS: u32 = 4;

/// A placed shape, before its material is attached.
pub(crate) struct Shape {
    /// Object-space mesh (shared between shapes of the same source).
    pub mesh: Arc<Mesh>,
    /// Object → world.
    pub world_from_object: DAffine3,
    /// Radiance of an `area` emitter.
    pub emission: Option<Vec3>,
    /// The mesh, or the exact sphere (the mesh then empty).
    pub surface: Surface,
}

/// Where a mesh comes from, with the flags that change it: the cache key.
#[derive(Clone, PartialEq, Eq, Hash)]
enum Source {
    Builtin(ShapeKind),
    File(NamedFile, bool),
}

/// Builds shapes, reading each mesh source once.
#[derive(Default)]
pub(crate) struct Shapes {
    meshes: HashMap<(Source, bool), Arc<Mesh>>,
}

impl Shapes {
    /// The mesh, placement and emission of `<shape>` element `el`.
    pub fn shape(
        &mut self,
        el: &Element,
        ctx: &Fields,
        warnings: &mut Vec<FieldError>,
    ) -> Result<Shape> {
        let field = |key: &str| format!("{}.{key}", el.path);
        let mut placement = DAffine3::IDENTITY;
        let mut skippable: &[&str] = &[];
        let source = match el.kind(ctx)? {
            kind @ ("obj" | "ply") => {
                skippable = &["flip_tex_coords"];
                let name = el
                    .string(ctx, "filename")?
                    .ok_or_else(|| ctx.err(&field("filename"), "required"))?;
                let path = ctx.resolve(name);
                let ext = path
                    .extension()
                    .and_then(|e| e.to_str())
                    .map(str::to_ascii_lowercase);
                if ext.as_deref() != Some(kind) {
                    return Err(ctx.err(
                        &field("filename"),
                        format!("expected a .{kind} file, found \"{name}\""),
                    ));
                }
                let file = NamedFile::new(path, &field("filename"), ctx)?;
                Source::File(file, el.boolean(ctx, "face_normals")?.unwrap_or(false))
            }
            "rectangle" => Source::Builtin(ShapeKind::Rectangle),
            "cube" => Source::Builtin(ShapeKind::Cube),
            "disk" => Source::Builtin(ShapeKind::Disk),
            "sphere" => {
                let center = el.point(ctx, "center")?.unwrap_or(DVec3::ZERO);
                let radius = el.float(ctx, "radius")?.unwrap_or(1.0);
                if radius <= 0.0 {
                    return Err(ctx.err(
                        &field("radius"),
                        format!("expected a value > 0, found {radius}"),
                    ));
                }
                placement =
                    DAffine3::from_translation(center) * DAffine3::from_scale(DVec3::splat(radius));
                Source::Builtin(ShapeKind::Sphere)
            }
            other => {
                let msg = format!(
                    "unsupported shape type \"{other}\" (supported: obj, ply, rectangle, cube, sphere, disk)"
                );
                return Err(ctx.err(&field("type"), msg));
            }
        };
        let flip = el.boolean(ctx, "flip_normals")?.unwrap_or(false);
        let to_world = match el.prop("to_world") {
            Some(t) => transform(t, ctx)?,
            None => DAffine3::IDENTITY,
        };
        let emitters: Vec<&Element> = el.tagged("emitter").collect();
        let emission = match emitters.as_slice() {
            [] => None,
            [e] => Some(area(e, ctx, warnings)?),
            _ => return Err(ctx.err(&el.path, "expected at most one <emitter>")),
        };
        finish(el, ctx, skippable, warnings)?;
        let exact = source == Source::Builtin(ShapeKind::Sphere) && !flip && emission.is_none();
        let (mesh, surface) = if exact {
            (Arc::default(), Surface::Sphere)
        } else {
            (
                self.mesh(source, flip, &field("filename"), ctx)?,
                Surface::Mesh,
            )
        };
        Ok(Shape {
            mesh,
            world_from_object: to_world * placement,
            emission,
            surface,
        })
    }

    /// The mesh of `source`, flipped when asked, from the cache when possible.
    fn mesh(&mut self, source: Source, flip: bool, field: &str, ctx: &Fields) -> Result<Arc<Mesh>> {
        if let Some(mesh) = self.meshes.get(&(source.clone(), flip)) {
            return Ok(mesh.clone());
        }
        let mesh = match &source {
            _ if flip => flipped(&*self.mesh(source.clone(), false, field, ctx)?),
            Source::Builtin(ShapeKind::Sphere) => {
                shapes::build(ShapeKind::Sphere, Some(SPHERE_LEVELS))
            }
            Source::Builtin(kind) => shapes::build(*kind, None),
            Source::File(file, face_normals) => {
                let mut mesh = load_mesh(&file.path).map_err(|e| ctx.nested(field, &e))?;
                if *face_normals {
                    mesh.normals.clear();
                }
                mesh
            }
        };
        let mesh = Arc::new(mesh);
        self.meshes.insert((source, flip), mesh.clone());
        Ok(mesh)
    }
}

/// The radiance of an `<emitter type="area">` nested in a shape.
fn area(el: &Element, ctx: &Fields, warnings: &mut Vec<FieldError>) -> Result<Vec3> {
    let kind = el.kind(ctx)?;
    if kind != "area" {
        let msg = format!("a shape's emitter must be of type area, found \"{kind}\"");
        return Err(ctx.err(&format!("{}.type", el.path), msg));
    }
    let radiance = el.rgb(ctx, "radiance")?.unwrap_or([1.0; 3]);
    let radiance = ctx.color(&format!("{}.radiance", el.path), radiance, f64::INFINITY)?;
    finish(el, ctx, &[], warnings)?;
    Ok(radiance)
}
