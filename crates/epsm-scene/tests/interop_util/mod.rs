//! Writes glTF 2.0 files for tests: meshes packed into one binary buffer,
//! nodes, materials, a camera and `KHR_lights_punctual` lights, as JSON text
//! beside a `.bin` file.

use std::path::{Path, PathBuf};

use epsm_render::scene::Mesh;
use serde_json::{Value, json};

/// A glTF document under construction.
#[derive(Default)]
pub struct Gltf {
    /// The binary buffer.
    pub bin: Vec<u8>,
    /// `bufferViews` entries.
    pub views: Vec<Value>,
    /// `accessors` entries.
    pub accessors: Vec<Value>,
    /// `meshes` entries.
    pub meshes: Vec<Value>,
    /// `materials` entries.
    pub materials: Vec<Value>,
    /// `nodes` entries (all roots of the scene unless `roots` is set).
    pub nodes: Vec<Value>,
    /// `cameras` entries.
    pub cameras: Vec<Value>,
    /// `KHR_lights_punctual` lights.
    pub lights: Vec<Value>,
    /// Root nodes; `None` means every node.
    pub roots: Option<Vec<usize>>,
}

impl Gltf {
    /// Appends `bytes` as a buffer view and an accessor; returns the accessor index.
    fn accessor(&mut self, bytes: &[u8], count: usize, component: u32, kind: &str) -> usize {
        let offset = self.bin.len();
        self.bin.extend(bytes);
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
        self.views
            .push(json!({"buffer": 0, "byteOffset": offset, "byteLength": bytes.len()}));
        self.accessors.push(json!({
            "bufferView": self.views.len() - 1, "componentType": component, "count": count, "type": kind
        }));
        self.accessors.len() - 1
    }

    /// Adds `mesh` (positions, normals when present, u32 indices) with
    /// `material`; returns the mesh index.
    pub fn mesh(&mut self, mesh: &Mesh, material: usize) -> usize {
        let floats = |v: &[glam::Vec3]| -> Vec<u8> {
            v.iter()
                .flat_map(|p| p.to_array())
                .flat_map(f32::to_le_bytes)
                .collect()
        };
        let n = mesh.positions.len();
        let (lo, hi) = mesh.positions.iter().fold(
            (glam::Vec3::INFINITY, glam::Vec3::NEG_INFINITY),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let position = self.accessor(&floats(&mesh.positions), n, 5126, "VEC3");
        self.accessors[position]["min"] = json!(lo.to_array());
        self.accessors[position]["max"] = json!(hi.to_array());
        let mut attributes = json!({"POSITION": position});
        if !mesh.normals.is_empty() {
            attributes["NORMAL"] = json!(self.accessor(&floats(&mesh.normals), n, 5126, "VEC3"));
        }
        let indices: Vec<u8> = mesh
            .indices
            .iter()
            .flatten()
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let indices = self.accessor(&indices, 3 * mesh.indices.len(), 5125, "SCALAR");
        self.meshes.push(json!({"primitives": [
            {"attributes": attributes, "indices": indices, "material": material}
        ]}));
        self.meshes.len() - 1
    }

    /// Writes `NAME.gltf` and `NAME.bin` into `dir`; returns the `.gltf` path.
    pub fn write(&self, dir: &Path, name: &str) -> PathBuf {
        let bin_name = format!("{name}.bin");
        std::fs::write(dir.join(&bin_name), &self.bin).expect("write bin");
        let roots = self
            .roots
            .clone()
            .unwrap_or_else(|| (0..self.nodes.len()).collect());
        let mut doc = json!({
            "asset": {"version": "2.0"},
            "scene": 0,
            "scenes": [{"nodes": roots}],
            "nodes": self.nodes,
            "meshes": self.meshes,
            "materials": self.materials,
            "buffers": [{"uri": bin_name, "byteLength": self.bin.len()}],
            "bufferViews": self.views,
            "accessors": self.accessors,
        });
        if !self.cameras.is_empty() {
            doc["cameras"] = json!(self.cameras);
        }
        if !self.lights.is_empty() {
            doc["extensionsUsed"] = json!(["KHR_lights_punctual"]);
            doc["extensions"] = json!({"KHR_lights_punctual": {"lights": self.lights}});
        }
        let path = dir.join(format!("{name}.gltf"));
        std::fs::write(&path, serde_json::to_string_pretty(&doc).expect("json"))
            .expect("write gltf");
        path
    }
}

/// A column-major glTF `matrix` of an affine map.
pub fn matrix(m: glam::DAffine3) -> Value {
    json!(glam::DMat4::from(m).as_mat4().to_cols_array())
}
