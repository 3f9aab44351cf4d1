//! glTF 2.0 meshes (`.gltf` with external or embedded buffers, and binary
//! `.glb`) through the `gltf` crate. Here glTF is a *mesh source*: every
//! triangle primitive of every mesh instanced by the default scene (or the
//! first scene) is flattened into one object-space mesh, with its node's
//! world transform applied (positions by the matrix, normals by its inverse
//! transpose, winding reversed under a mirroring transform). Cameras, lights
//! and materials are ignored (a whole glTF scene loads through
//! [`gltf_scene`](super::gltf_scene), which shares this file's reading). Texture coordinates (set 0) are flipped to
//! `v = 1 − v` so that `v = 0` is the bottom row, as
//! [`Image::lookup`](epsm_render::film::Image::lookup) expects. Normals and uvs are
//! kept when every primitive has them. Only the `TRIANGLES` mode is accepted.
//!
//! ```toml
//! [[objects]]
//! name = "statue"
//! mesh = "meshes/statue.glb"
//! material = "white"
//! ```

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use glam::{DAffine3, DMat4, Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};

use crate::error::{Error, FieldError, Result, shown};
use epsm_render::scene::Mesh;

/// Reads the glTF or GLB file at `path` into one mesh (not yet validated).
pub fn load(path: &Path) -> Result<Mesh> {
    let bytes = crate::input_file::read(path)?;
    let file = open(&bytes, path)?;
    let mut mesh = Mesh::default();
    for placed in walk(&file.doc, path)? {
        let Some(m) = placed.node.mesh() else {
            continue;
        };
        let world = DAffine3::from_mat4(placed.world);
        let linear = world.matrix3.as_mat3();
        let normal_from_object = linear.inverse().transpose();
        for prim in m.primitives() {
            let field = format!("meshes[{}].primitives[{}]", m.index(), prim.index());
            let mut part =
                primitive(&prim, &file.buffers).map_err(|msg| FieldError::new(path, field, msg))?;
            for p in &mut part.positions {
                *p = world.transform_point3(p.as_dvec3()).as_vec3();
            }
            for n in &mut part.normals {
                *n = (normal_from_object * *n).normalize_or_zero();
            }
            if linear.determinant() < 0.0 {
                part.indices.iter_mut().for_each(|t| t.swap(1, 2));
            }
            super::append(&mut mesh, part);
        }
    }
    Ok(mesh)
}

/// A parsed and validated glTF document with its buffers loaded.
pub(crate) struct File {
    /// The document.
    pub doc: gltf::Document,
    /// Buffer contents, by buffer index.
    pub buffers: Vec<gltf::buffer::Data>,
}

/// Parses `bytes` (JSON glTF or GLB) and loads its buffers (external ones
/// relative to `file`'s directory).
pub(crate) fn open(bytes: &[u8], file: &Path) -> Result<File> {
    let fail = |field: &str, msg: String| Error::from(FieldError::new(file, field, msg));
    // The gltf crate subtracts the header size from the declared GLB length unchecked.
    if let Some(len) = bytes.strip_prefix(b"glTF").and_then(|r| r.get(4..8)) {
        let declared = u32::from_le_bytes([len[0], len[1], len[2], len[3]]);
        if declared < 12 {
            return Err(fail("glb", format!("declared length {declared} < 12")));
        }
    }
    let malformed = |e: gltf::Error| fail("gltf", format!("malformed glTF: {e}"));
    let gltf = gltf::Gltf::from_slice_without_validation(bytes).map_err(malformed)?;
    let json = gltf.document.into_json();
    // The gltf-json validator indexes POSITION accessors before checking them (found by fuzzing).
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            if let Some(a) = prim
                .attributes
                .values()
                .find(|a| a.value() >= json.accessors.len())
            {
                let field = format!("meshes[{m}].primitives[{p}].attributes");
                return Err(fail(
                    &field,
                    format!("accessor {} does not exist", a.value()),
                ));
            }
        }
    }
    let doc = gltf::Document::from_json(json).map_err(malformed)?;
    let base = file.parent().unwrap_or(Path::new(""));
    let mut blob = gltf.blob;
    let buffers = doc
        .buffers()
        .map(|b| {
            buffer(&b, base, &mut blob).map_err(|msg| fail(&format!("buffers[{}]", b.index()), msg))
        })
        .collect::<Result<_>>()?;
    Ok(File { doc, buffers })
}

/// The bytes of buffer `b`: the GLB binary chunk, a `data:` URI, or the first
/// `byteLength` bytes of a regular file (a `file:` URI or a percent-encoded
/// path relative to `base`). The error says what is wrong with it.
fn buffer(
    b: &gltf::Buffer,
    base: &Path,
    blob: &mut Option<Vec<u8>>,
) -> Result<gltf::buffer::Data, String> {
    let data = match b.source() {
        gltf::buffer::Source::Bin => blob.take().ok_or("refers to a missing GLB binary chunk")?,
        gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
            gltf::buffer::Data::from_source(b.source(), None)
                .map_err(|e| format!("uri: malformed data URI: {e}"))?
                .0
        }
        gltf::buffer::Source::Uri(uri) => {
            let path = match uri
                .strip_prefix("file://")
                .or_else(|| uri.strip_prefix("file:"))
            {
                Some(path) => PathBuf::from(path),
                None if uri.contains(':') => {
                    return Err(format!("uri: unsupported scheme in \"{uri}\""));
                }
                None => base.join(
                    urlencoding::decode(uri)
                        .map_err(|e| format!("uri: \"{uri}\" does not decode to UTF-8: {e}"))?
                        .as_ref(),
                ),
            };
            crate::input_file::read_capped(&path, b.length() as u64)
                .map_err(|e| format!("uri: {e}"))?
        }
    };
    if data.len() < b.length() {
        return Err(format!(
            "byteLength is {} but the buffer holds {} bytes",
            b.length(),
            data.len()
        ));
    }
    Ok(gltf::buffer::Data(data))
}

/// A node of the scene with its world transform (object → world).
pub(crate) struct Placed<'a> {
    /// The node.
    pub node: gltf::Node<'a>,
    /// Product of the node's and its ancestors' local transforms.
    pub world: DMat4,
}

/// How far a node rotation's quaternion length may be from 1 (quaternions
/// written with a few digits still load).
const ROTATION_TOLERANCE: f64 = 1e-3;

/// The nodes of the default scene (or the first scene), depth-first in file
/// order. Errors for a missing scene, a node reached twice (a cycle or a
/// shared child: glTF nodes form a forest), a rotation that is not a unit
/// quaternion (within [`ROTATION_TOLERANCE`]) and a non-finite or singular
/// transform.
pub(crate) fn walk<'a>(doc: &'a gltf::Document, file: &Path) -> Result<Vec<Placed<'a>>> {
    let fail = |field: String, msg: &str| Error::from(FieldError::new(file, field, msg));
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| fail("scenes".into(), "the file has no scene"))?;
    let mut seen = HashSet::new();
    let mut out = Vec::new();
    let mut stack: Vec<(gltf::Node, DMat4)> = scene.nodes().map(|n| (n, DMat4::IDENTITY)).collect();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        let field = format!("nodes[{}]", node.index());
        if !seen.insert(node.index()) {
            let msg = "reached twice: node cycles and shared children are not allowed";
            return Err(fail(field, msg));
        }
        // glTF rotations are unit quaternions (glTF 2.0 §5.25); gltf's matrix
        // of any other would be a silent identity or a scaled rotation.
        let transform = node.transform();
        if let gltf::scene::Transform::Decomposed { rotation, .. } = &transform {
            let norm = rotation
                .map(f64::from)
                .iter()
                .map(|q| q * q)
                .sum::<f64>()
                .sqrt();
            if norm.is_nan() || (norm - 1.0).abs() > ROTATION_TOLERANCE {
                let msg = format!(
                    "expected a unit quaternion, found one of length {}",
                    shown(norm)
                );
                return Err(fail(format!("{field}.rotation"), &msg));
            }
        }
        let local = DMat4::from_cols_array_2d(&transform.matrix().map(|c| c.map(f64::from)));
        let world = parent * local;
        if !world.is_finite() || world.determinant() == 0.0 {
            return Err(fail(field, "non-finite or singular transform"));
        }
        let first_child = stack.len();
        stack.extend(node.children().map(|c| (c, world)));
        stack[first_child..].reverse();
        out.push(Placed { node, world });
    }
    Ok(out)
}

/// One triangle primitive in object space; errors are messages. Every
/// accessor is checked against its buffer before it is read. Normals are
/// normalized; texture coordinates (set 0) flipped to `v = 1 − v`.
pub(crate) fn primitive(
    prim: &gltf::Primitive,
    buffers: &[gltf::buffer::Data],
) -> Result<Mesh, String> {
    if prim.mode() != gltf::mesh::Mode::Triangles {
        return Err(format!(
            "primitive mode {:?} is not supported: only TRIANGLES",
            prim.mode()
        ));
    }
    let float = [DataType::F32];
    let position = prim
        .get(&gltf::Semantic::Positions)
        .ok_or("the primitive has no POSITION attribute")?;
    checked(&position, Dimensions::Vec3, &float, buffers)?;
    if let Some(a) = prim.get(&gltf::Semantic::Normals) {
        checked(&a, Dimensions::Vec3, &float, buffers)?;
    }
    if let Some(a) = prim.get(&gltf::Semantic::TexCoords(0)) {
        checked(
            &a,
            Dimensions::Vec2,
            &[DataType::F32, DataType::U8, DataType::U16],
            buffers,
        )?;
    }
    if let Some(a) = prim.indices() {
        checked(
            &a,
            Dimensions::Scalar,
            &[DataType::U8, DataType::U16, DataType::U32],
            buffers,
        )?;
    }
    let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let missing = || "accessor data out of bounds".to_owned();
    let positions: Vec<Vec3> = reader
        .read_positions()
        .ok_or_else(missing)?
        .map(Vec3::from)
        .collect();
    let normals = match reader.read_normals() {
        Some(it) => it
            .map(|n| {
                Vec3::from(n)
                    .try_normalize()
                    .ok_or("zero or non-finite normal")
            })
            .collect::<Result<Vec<_>, _>>()?,
        None => Vec::new(),
    };
    let uvs: Vec<Vec2> = match reader.read_tex_coords(0) {
        Some(t) => t.into_f32().map(|[u, v]| Vec2::new(u, 1.0 - v)).collect(),
        None => Vec::new(),
    };
    let flat: Vec<u32> = match reader.read_indices() {
        Some(i) => i.into_u32().collect(),
        None => (0..positions.len() as u32).collect(),
    };
    if !flat.len().is_multiple_of(3) {
        return Err(format!("{} indices do not form triangles", flat.len()));
    }
    let complete = |len: usize| len == positions.len();
    Ok(Mesh {
        normals: if complete(normals.len()) {
            normals
        } else {
            Vec::new()
        },
        uvs: if complete(uvs.len()) { uvs } else { Vec::new() },
        indices: flat.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
        positions,
    })
}

/// Checks that accessor `a` has the expected shape and lies inside its
/// buffer view and buffer (the gltf crate's reader assumes both).
fn checked(
    a: &gltf::Accessor,
    dims: Dimensions,
    types: &[DataType],
    buffers: &[gltf::buffer::Data],
) -> Result<(), String> {
    let i = a.index();
    if a.sparse().is_some() {
        return Err(format!(
            "accessors[{i}]: sparse accessors are not supported"
        ));
    }
    if a.dimensions() != dims || !types.contains(&a.data_type()) {
        return Err(format!(
            "accessors[{i}]: expected {dims:?} of {types:?}, found {:?} of {:?}",
            a.dimensions(),
            a.data_type()
        ));
    }
    let view = a.view().ok_or(format!("accessors[{i}]: no buffer view"))?;
    let size = a.size();
    let stride = view.stride().unwrap_or(size);
    let need = (a.count().checked_sub(1))
        .and_then(|n| n.checked_mul(stride))
        .and_then(|n| n.checked_add(a.offset() + size));
    let view_end = view.offset().checked_add(view.length());
    let buffer_len = buffers.get(view.buffer().index()).map_or(0, |d| d.0.len());
    match (need, view_end) {
        (None, _) => Err(format!(
            "accessors[{i}]: count {} is zero or too large",
            a.count()
        )),
        _ if stride < size => Err(format!(
            "accessors[{i}]: byteStride {stride} < element size {size}"
        )),
        (Some(n), _) if n > view.length() => Err(format!(
            "accessors[{i}]: {} items need {n} bytes but bufferViews[{}] holds {}",
            a.count(),
            view.index(),
            view.length()
        )),
        (_, end) if end.is_none_or(|e| e > buffer_len) => Err(format!(
            "bufferViews[{}] ends past its buffer ({buffer_len} bytes)",
            view.index()
        )),
        _ => Ok(()),
    }
}
