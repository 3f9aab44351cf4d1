//! Stanford PLY meshes, read by a small bounds-checked parser: `ascii`,
//! `binary_little_endian` and `binary_big_endian` bodies, any scalar type.
//!
//! | element / property | use |
//! |---|---|
//! | `vertex`: `x y z` | positions (required) |
//! | `vertex`: `nx ny nz` | normals (kept when all three are present; normalized) |
//! | `vertex`: `u v`, `s t` or `texture_u texture_v` | uvs (`v = 0` is the bottom row, as in OBJ) |
//! | `face`: list `vertex_indices` (or `vertex_index`) | polygons of ≥ 3 vertices, fan-triangulated |
//! | anything else | read and skipped |
//!
//! Every count is checked against the bytes left before anything is
//! allocated, so a header declaring billions of elements is an error, not an
//! allocation failure. Errors name the header line or the element item.
//!
//! ```toml
//! [[objects]]
//! name = "bunny"
//! mesh = "meshes/bunny.ply"
//! material = "white"
//! ```

mod header;

use std::path::Path;

use glam::{Vec2, Vec3};

use self::header::{Element, Format, Scalar, header};
use crate::error::{Error, FieldError, Result};
use epsm_render::scene::Mesh;

/// Reads the PLY file at `path` into one mesh (not yet validated).
pub fn load(path: &Path) -> Result<Mesh> {
    parse(&crate::input_file::read(path)?, path)
}

/// Parses the bytes of a PLY file; `file` names it in errors.
pub fn parse(bytes: &[u8], file: &Path) -> Result<Mesh> {
    let err = |field: &str, line: Option<usize>, msg: String| {
        let e = FieldError::new(file, field, msg);
        Error::from(match line {
            Some(l) => e.at_line(l),
            None => e,
        })
    };
    let (header, body) = header(bytes).map_err(|(line, msg)| err("header", Some(line), msg))?;
    let mut reader = Reader::new(header.format, body);
    let mut mesh = Mesh::default();
    for element in &header.elements {
        read_element(element, &mut reader, &mut mesh)
            .map_err(|(field, msg)| err(&field, None, msg))?;
    }
    Ok(mesh)
}

/// Reads scalars from the body, in either encoding.
struct Reader<'a> {
    format: Format,
    data: &'a [u8],
}

impl<'a> Reader<'a> {
    fn new(format: Format, data: &'a [u8]) -> Self {
        Self { format, data }
    }

    /// The next scalar as `f64` (every PLY type converts exactly).
    fn next(&mut self, t: Scalar) -> Option<f64> {
        if self.format == Format::Ascii {
            let start = self.data.iter().position(|b| !b.is_ascii_whitespace())?;
            let rest = &self.data[start..];
            let len = rest
                .iter()
                .position(u8::is_ascii_whitespace)
                .unwrap_or(rest.len());
            let token = std::str::from_utf8(&rest[..len]).ok()?;
            self.data = &rest[len..];
            return token.parse().ok();
        }
        let n = t.size();
        let (raw, rest) = self.data.split_at_checked(n)?;
        self.data = rest;
        let mut b = [0u8; 8];
        b[..n].copy_from_slice(raw);
        if self.format == Format::Big {
            b[..n].reverse();
        }
        Some(match t {
            Scalar::I8 => f64::from(b[0] as i8),
            Scalar::U8 => f64::from(b[0]),
            Scalar::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
            Scalar::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
            Scalar::I32 => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::F64 => f64::from_le_bytes(b),
        })
    }

    /// Whether `count` items can still follow, each at least `bytes` long
    /// in binary or `values` values long in ASCII (a character and a
    /// separator per value).
    fn can_hold(&self, count: usize, bytes: usize, values: usize) -> bool {
        let per_item = if self.format == Format::Ascii {
            2 * values
        } else {
            bytes
        };
        count
            .checked_mul(per_item)
            .is_some_and(|n| n <= self.data.len() + 1)
    }
}

/// Reads one element's items into `mesh`; errors are `(field, message)`.
fn read_element(e: &Element, r: &mut Reader, mesh: &mut Mesh) -> Result<(), (String, String)> {
    let fail = |msg: String| (e.name.clone(), msg);
    let min_size = e
        .properties
        .iter()
        .map(|p| p.list_count.unwrap_or(p.value).size())
        .sum::<usize>();
    if !r.can_hold(e.count, min_size, e.properties.len()) {
        return Err(fail(format!(
            "declares {} items but the file is too short to hold them",
            e.count
        )));
    }
    if e.properties.is_empty() && e.name != "vertex" {
        // Items without properties occupy no bytes: nothing to read, however many.
        return Ok(());
    }
    let index = |name: &str| e.properties.iter().position(|p| p.name == name);
    let slots = |names: &[&str]| names.iter().map(|n| index(n)).collect::<Option<Vec<_>>>();
    let is_vertex = e.name == "vertex";
    let position = slots(&["x", "y", "z"]).filter(|_| is_vertex);
    if is_vertex && position.is_none() {
        return Err(fail("has no x, y, z properties".into()));
    }
    let normal = slots(&["nx", "ny", "nz"]).filter(|_| is_vertex);
    let uv = [["u", "v"], ["s", "t"], ["texture_u", "texture_v"]]
        .iter()
        .find_map(|names| slots(names))
        .filter(|_| is_vertex);
    let faces = (e.name == "face")
        .then(|| index("vertex_indices").or_else(|| index("vertex_index")))
        .flatten();
    let mut scalars = vec![0.0f64; e.properties.len()];
    let mut list = Vec::new();
    for item in 0..e.count {
        let truncated = || {
            (
                format!("{}[{item}]", e.name),
                "truncated or malformed".to_owned(),
            )
        };
        for (k, p) in e.properties.iter().enumerate() {
            let Some(count_type) = p.list_count else {
                scalars[k] = r.next(p.value).ok_or_else(truncated)?;
                continue;
            };
            let n = r.next(count_type).ok_or_else(truncated)?;
            let n = as_index(n).ok_or_else(truncated)? as usize;
            if !r.can_hold(n, p.value.size(), 1) {
                return Err(truncated());
            }
            list.clear();
            for _ in 0..n {
                list.push(r.next(p.value).ok_or_else(truncated)?);
            }
            if Some(k) == faces {
                let field = format!("{}[{item}]", e.name);
                triangulate(&list, mesh).map_err(|msg| (field, msg))?;
            }
        }
        let v3 = |s: &[usize]| {
            Vec3::new(
                scalars[s[0]] as f32,
                scalars[s[1]] as f32,
                scalars[s[2]] as f32,
            )
        };
        if let Some(s) = &position {
            mesh.positions.push(v3(s));
        }
        if let Some(s) = &normal {
            mesh.normals.push(v3(s).normalize_or_zero());
        }
        if let Some(s) = &uv {
            mesh.uvs
                .push(Vec2::new(scalars[s[0]] as f32, scalars[s[1]] as f32));
        }
    }
    Ok(())
}

/// A non-negative integer that fits a `u32`.
fn as_index(v: f64) -> Option<u32> {
    (v.fract() == 0.0 && (0.0..=f64::from(u32::MAX)).contains(&v)).then_some(v as u32)
}

/// Appends the fan triangulation of one polygon.
fn triangulate(polygon: &[f64], mesh: &mut Mesh) -> Result<(), String> {
    let indices = polygon
        .iter()
        .map(|&v| as_index(v).ok_or(format!("vertex index {v} is not a valid index")))
        .collect::<Result<Vec<u32>, String>>()?;
    if indices.len() < 3 {
        return Err(format!(
            "a face needs ≥ 3 vertices, found {}",
            indices.len()
        ));
    }
    for k in 1..indices.len() - 1 {
        mesh.indices.push([indices[0], indices[k], indices[k + 1]]);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const QUAD: &str = "ply\nformat ascii 1.0\ncomment a unit quad\nelement vertex 4\n\
        property float x\nproperty float y\nproperty float z\nproperty float nx\n\
        property float ny\nproperty float nz\nelement face 1\n\
        property list uchar int vertex_indices\nend_header\n\
        0 0 0 0 0 2\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n4 0 1 2 3\n";

    fn parse_str(text: &str) -> Result<Mesh> {
        parse(text.as_bytes(), Path::new("t.ply"))
    }

    #[test]
    fn ascii_quads_are_fan_triangulated_with_unit_normals() {
        let mesh = parse_str(QUAD).expect("valid PLY");
        assert_eq!(mesh.indices, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(mesh.positions[2], Vec3::new(1.0, 1.0, 0.0));
        assert!(mesh.normals.iter().all(|n| *n == Vec3::Z));
        assert!(mesh.uvs.is_empty());
    }

    #[test]
    fn binary_little_and_big_endian_read_like_ascii() {
        for (format, big) in [("binary_little_endian", false), ("binary_big_endian", true)] {
            let mut bytes = format!(
                "ply\nformat {format} 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                 property float z\nproperty uchar flags\nelement face 1\n\
                 property list uchar uint vertex_indices\nend_header\n"
            )
            .into_bytes();
            let f = |v: f32| {
                if big {
                    v.to_be_bytes()
                } else {
                    v.to_le_bytes()
                }
            };
            for p in [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 3.0, 0.0]] {
                p.into_iter().for_each(|v| bytes.extend(f(v)));
                bytes.push(7);
            }
            bytes.push(3);
            for i in [0u32, 1, 2] {
                bytes.extend(if big {
                    i.to_be_bytes()
                } else {
                    i.to_le_bytes()
                });
            }
            let mesh = parse(&bytes, Path::new("b.ply")).expect("valid binary PLY");
            assert_eq!(mesh.positions[2], Vec3::new(0.0, 3.0, 0.0), "{format}");
            assert_eq!(mesh.indices, vec![[0, 1, 2]], "{format}");
        }
    }

    #[test]
    fn huge_counts_and_truncation_are_errors_naming_the_element() {
        let huge = QUAD.replace("element vertex 4", "element vertex 4000000000");
        let msg = parse_str(&huge).expect_err("huge count").to_string();
        assert!(msg.contains("vertex") && msg.contains("too short"), "{msg}");
        let cut = &QUAD[..QUAD.len() - 6];
        let msg = parse_str(cut).expect_err("truncated").to_string();
        assert!(msg.contains("face[0]"), "{msg}");
        let msg = parse_str(&QUAD.replace("4 0 1 2 3", "2 0 1"))
            .expect_err("two-vertex face")
            .to_string();
        assert!(msg.contains("≥ 3"), "{msg}");
        let empty = QUAD.replace(
            "element face 1",
            "element nothing 4000000000\nelement face 1",
        );
        assert_eq!(
            parse_str(&empty)
                .expect("property-less elements are empty")
                .len(),
            2
        );
        let msg = parse_str(&QUAD.replace("property float y\n", "property flot y\n"))
            .expect_err("bad type")
            .to_string();
        assert!(
            msg.contains("t.ply:6") && msg.contains("unknown type"),
            "{msg}"
        );
    }
}
