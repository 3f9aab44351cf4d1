//! `[[objects]]`: meshes (built-in or from files, each file loaded once per
//! scene and shared), transforms (`world_from_object = translate · rotate[n−1]
//! · … · rotate[0] · scale`), material references and emission.

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use glam::{DAffine3, DMat3, DQuat, DVec3};

use super::named::NamedFile;
use crate::desc::{ObjectDesc, ScaleDesc, ShapeKind};
use crate::error::Result;
use crate::fields::Fields;
use epsm_render::materials::Material;
use epsm_render::scene::{Mesh, Object, Surface};

use crate::{import, shapes};

/// Where a mesh comes from; with the flip flag, the key of the mesh cache.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
enum Source {
    /// A built-in shape with its checked subdivisions.
    Shape(ShapeKind, Option<u32>),
    /// A mesh file.
    File(NamedFile),
}

/// Builds objects, sharing meshes between objects that use the same source.
pub struct Objects<'a> {
    ctx: &'a Fields<'a>,
    meshes: HashMap<(Source, bool), Arc<Mesh>>,
}

impl<'a> Objects<'a> {
    /// An empty builder for the file of `ctx`.
    pub fn new(ctx: &'a Fields<'a>) -> Self {
        Self {
            ctx,
            meshes: HashMap::new(),
        }
    }

    /// All objects of the file; `materials` resolves material names.
    pub fn build(mut self, descs: &[ObjectDesc], materials: &[Material]) -> Result<Vec<Object>> {
        let mut names = HashSet::new();
        let mut objects = Vec::with_capacity(descs.len());
        for (i, d) in descs.iter().enumerate() {
            let field = format!("objects[{i}]");
            let name_field = format!("{field}.name");
            self.ctx
                .unique_name(&name_field, &d.name, &mut names, "object")?;
            objects.push(self.object(&field, d, materials)?);
        }
        Ok(objects)
    }

    /// One object, its name already checked.
    fn object(&mut self, field: &str, d: &ObjectDesc, materials: &[Material]) -> Result<Object> {
        let ctx = self.ctx;
        let material = materials
            .iter()
            .position(|m| m.name == d.material)
            .ok_or_else(|| {
                let known: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
                let known = if known.is_empty() {
                    "none".to_owned()
                } else {
                    known.join(", ")
                };
                let msg = format!("unknown material \"{}\" (defined: {known})", d.material);
                ctx.err(&format!("{field}.material"), msg)
            })?;
        let emission = d
            .emission
            .map(|e| ctx.color(&format!("{field}.emission"), e, f64::INFINITY))
            .transpose()?;
        let (mesh, surface) = if d.exact {
            self.exact_sphere(field, d)?;
            (Arc::default(), Surface::Sphere)
        } else {
            let source = self.source(field, d)?;
            (self.mesh(field, source, d.flip_normals)?, Surface::Mesh)
        };
        Ok(Object {
            name: d.name.clone(),
            mesh,
            world_from_object: self.transform(field, d)?,
            material: material as u32,
            emission,
            surface,
        })
    }

    /// Checks that `exact = true` names a sphere with nothing it excludes.
    fn exact_sphere(&self, field: &str, d: &ObjectDesc) -> Result<()> {
        let excluded = [
            (
                d.shape != Some(ShapeKind::Sphere),
                "exact",
                "applies to shape = \"sphere\" only",
            ),
            (
                d.mesh.is_some(),
                "mesh",
                "give either shape or mesh, not both",
            ),
            (
                d.subdivisions.is_some(),
                "subdivisions",
                "an exact sphere has no subdivisions",
            ),
            (
                d.flip_normals,
                "flip_normals",
                "not supported on an exact sphere",
            ),
            (
                d.emission.is_some(),
                "emission",
                "an exact sphere cannot emit (use a tessellated sphere)",
            ),
        ];
        match excluded.into_iter().find(|e| e.0) {
            Some((_, key, message)) => Err(self.ctx.err(&format!("{field}.{key}"), message)),
            None => Ok(()),
        }
    }

    /// Checks `shape` / `mesh` / `subdivisions` and names the mesh source.
    fn source(&self, field: &str, d: &ObjectDesc) -> Result<Source> {
        let ctx = self.ctx;
        let sub_field = format!("{field}.subdivisions");
        let no_subdivisions = |what: &str| match d.subdivisions {
            Some(_) => Err(ctx.err(&sub_field, format!("does not apply to {what}"))),
            None => Ok(()),
        };
        match (d.shape, &d.mesh) {
            (Some(_), Some(_)) => Err(ctx.err(
                &format!("{field}.shape"),
                "give either shape or mesh, not both",
            )),
            (None, None) => Err(ctx.err(&format!("{field}.shape"), "expected shape or mesh")),
            (None, Some(file)) => {
                no_subdivisions("mesh files")?;
                let path = ctx.resolve(file);
                Ok(Source::File(NamedFile::new(
                    path,
                    &format!("{field}.mesh"),
                    ctx,
                )?))
            }
            (Some(kind), None) => {
                let sub = match (kind, d.subdivisions) {
                    (ShapeKind::Sphere, Some(s)) => {
                        Some(ctx.count(&sub_field, s, 0, shapes::MAX_SPHERE_LEVELS)?)
                    }
                    (ShapeKind::Disk, Some(s)) => Some(ctx.count(
                        &sub_field,
                        s,
                        shapes::MIN_DISK_SEGMENTS,
                        shapes::MAX_DISK_SEGMENTS,
                    )?),
                    (ShapeKind::Rectangle | ShapeKind::Cube, _) => {
                        no_subdivisions("rectangle or cube")?;
                        None
                    }
                    (_, None) => None,
                };
                Ok(Source::Shape(kind, sub))
            }
        }
    }

    /// The (shared) mesh of `source`, flipped when asked.
    fn mesh(&mut self, field: &str, source: Source, flip: bool) -> Result<Arc<Mesh>> {
        if let Some(mesh) = self.meshes.get(&(source.clone(), flip)) {
            return Ok(mesh.clone());
        }
        let mesh = match (&source, flip) {
            (_, true) => Arc::new(flipped(self.mesh(field, source.clone(), false)?.as_ref())),
            (Source::Shape(kind, sub), false) => Arc::new(shapes::build(*kind, *sub)),
            (Source::File(file), false) => Arc::new(
                import::load_mesh(&file.path)
                    .map_err(|e| self.ctx.nested(&format!("{field}.mesh"), &e))?,
            ),
        };
        self.meshes.insert((source, flip), mesh.clone());
        Ok(mesh)
    }

    /// `world_from_object = translate · rotate[n−1] · … · rotate[0] · scale`.
    fn transform(&self, field: &str, d: &ObjectDesc) -> Result<DAffine3> {
        let ctx = self.ctx;
        let scale_field = format!("{field}.scale");
        let scale = match d.scale {
            None => DVec3::ONE,
            Some(ScaleDesc::Uniform(s)) => DVec3::splat(ctx.finite(&scale_field, s)?),
            Some(ScaleDesc::PerAxis(s)) => ctx.vec3(&scale_field, s)?,
        };
        if scale.cmpeq(DVec3::ZERO).any() {
            let msg = format!(
                "expected non-zero factors (the transform must be invertible), found {scale}"
            );
            return Err(ctx.err(&scale_field, msg));
        }
        let mut rotation = DMat3::IDENTITY;
        for (j, r) in d.rotate.iter().enumerate() {
            let axis_field = format!("{field}.rotate[{j}].axis");
            let axis = ctx.vec3(&axis_field, r.axis)?;
            let axis = axis
                .try_normalize()
                .ok_or_else(|| ctx.err(&axis_field, "expected a non-zero axis"))?;
            let angle = ctx.finite(&format!("{field}.rotate[{j}].angle"), r.angle)?;
            rotation =
                DMat3::from_quat(DQuat::from_axis_angle(axis, angle.to_radians())) * rotation;
        }
        let translate = ctx.vec3(
            &format!("{field}.translate"),
            d.translate.unwrap_or([0.0; 3]),
        )?;
        Ok(DAffine3::from_mat3_translation(
            rotation * DMat3::from_diagonal(scale),
            translate,
        ))
    }
}

/// `mesh` with reversed winding and negated normals.
pub(crate) fn flipped(mesh: &Mesh) -> Mesh {
    Mesh {
        positions: mesh.positions.clone(),
        normals: mesh.normals.iter().map(|n| -*n).collect(),
        uvs: mesh.uvs.clone(),
        indices: mesh.indices.iter().map(|&[a, b, c]| [a, c, b]).collect(),
    }
}
