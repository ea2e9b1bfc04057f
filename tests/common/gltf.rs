//! glTF 2.0 files written by the tests themselves: a small builder over the
//! JSON (serde_json) and one binary buffer, written as `.gltf` with the
//! buffer embedded (base64 data URI) or beside it (`.bin`), or as `.glb`.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use base64::Engine as _;
use serde_json::{json, Value};

pub struct GltfBuilder {
    pub json: Value,
    pub bin: Vec<u8>,
}

impl Default for GltfBuilder {
    fn default() -> Self {
        Self::new()
    }
}

impl GltfBuilder {
    pub fn new() -> Self {
        Self {
            json: json!({
                "asset": { "version": "2.0", "generator": "lightcuts tests" },
                "scene": 0,
                "scenes": [{ "nodes": [] }],
                "nodes": [], "meshes": [], "materials": [], "accessors": [], "bufferViews": [],
                "buffers": [],
            }),
            bin: Vec::new(),
        }
    }

    fn push(&mut self, key: &str, value: Value) -> usize {
        let array = self.json[key].as_array_mut().expect("an array");
        array.push(value);
        array.len() - 1
    }

    fn view(&mut self, bytes: &[u8]) -> usize {
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.push("bufferViews", json!({ "buffer": 0, "byteOffset": offset, "byteLength": bytes.len() }))
    }

    /// A FLOAT accessor of `kind` ("VEC2", "VEC3") over `data`.
    pub fn floats(&mut self, data: &[f32], kind: &str, components: usize) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes);
        let mut accessor =
            json!({ "bufferView": view, "componentType": 5126, "count": data.len() / components, "type": kind });
        if kind == "VEC3" && !data.is_empty() {
            let (mut min, mut max) = ([f32::MAX; 3], [f32::MIN; 3]);
            for p in data.chunks(3) {
                for k in 0..3 {
                    min[k] = min[k].min(p[k]);
                    max[k] = max[k].max(p[k]);
                }
            }
            accessor["min"] = json!(min);
            accessor["max"] = json!(max);
        }
        self.push("accessors", accessor)
    }

    /// An accessor of `count` elements of `kind` over raw little-endian
    /// `bytes` of `component_type` (5120 BYTE ... 5126 FLOAT).
    pub fn raw(&mut self, bytes: &[u8], component_type: u32, count: usize, kind: &str, normalized: bool) -> usize {
        let view = self.view(bytes);
        self.push(
            "accessors",
            json!({ "bufferView": view, "componentType": component_type, "count": count, "type": kind, "normalized": normalized }),
        )
    }

    /// A buffer view of `bytes`, for sparse accessors.
    pub fn bytes_view(&mut self, bytes: &[u8]) -> usize {
        self.view(bytes)
    }

    /// An UNSIGNED_INT index accessor.
    pub fn indices(&mut self, data: &[u32]) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes);
        self.push(
            "accessors",
            json!({ "bufferView": view, "componentType": 5125, "count": data.len(), "type": "SCALAR" }),
        )
    }

    /// A mesh of one primitive; returns its index.
    pub fn mesh(
        &mut self,
        positions: &[[f32; 3]],
        indices: Option<&[u32]>,
        normals: Option<&[[f32; 3]]>,
        uvs: Option<&[[f32; 2]]>,
        material: Option<usize>,
        mode: Option<u32>,
    ) -> usize {
        let flat: Vec<f32> = positions.iter().flatten().copied().collect();
        let mut attributes = json!({ "POSITION": self.floats(&flat, "VEC3", 3) });
        if let Some(n) = normals {
            let flat: Vec<f32> = n.iter().flatten().copied().collect();
            attributes["NORMAL"] = json!(self.floats(&flat, "VEC3", 3));
        }
        if let Some(t) = uvs {
            let flat: Vec<f32> = t.iter().flatten().copied().collect();
            attributes["TEXCOORD_0"] = json!(self.floats(&flat, "VEC2", 2));
        }
        let mut primitive = json!({ "attributes": attributes });
        if let Some(i) = indices {
            primitive["indices"] = json!(self.indices(i));
        }
        if let Some(m) = material {
            primitive["material"] = json!(m);
        }
        if let Some(m) = mode {
            primitive["mode"] = json!(m);
        }
        self.push("meshes", json!({ "primitives": [primitive] }))
    }

    /// A parallelogram corner, corner + u, corner + u + v, corner + v (front
    /// side: u x v), with uvs over [0, 1]^2.
    pub fn quad(&mut self, corner: [f32; 3], u: [f32; 3], v: [f32; 3], material: Option<usize>) -> usize {
        let at = |a: f32, b: f32| [0, 1, 2].map(|k| corner[k] + a * u[k] + b * v[k]);
        let positions = [at(0.0, 0.0), at(1.0, 0.0), at(1.0, 1.0), at(0.0, 1.0)];
        let uvs = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        self.mesh(&positions, Some(&[0, 1, 2, 0, 2, 3]), None, Some(&uvs), material, None)
    }

    /// A mesh given as its JSON; returns its index.
    pub fn push_mesh(&mut self, value: Value) -> usize {
        self.push("meshes", value)
    }

    /// An accessor given as its JSON; returns its index.
    pub fn push_accessor(&mut self, value: Value) -> usize {
        self.push("accessors", value)
    }

    pub fn material(&mut self, value: Value) -> usize {
        self.push("materials", value)
    }

    /// A node; `root` puts it in the scene's node list.
    pub fn node(&mut self, value: Value, root: bool) -> usize {
        let index = self.push("nodes", value);
        if root {
            self.json["scenes"][0]["nodes"].as_array_mut().unwrap().push(json!(index));
        }
        index
    }

    /// A KHR_lights_punctual light; returns its index.
    pub fn light(&mut self, value: Value) -> usize {
        self.use_extension("KHR_lights_punctual");
        let extensions = self.json.as_object_mut().unwrap().entry("extensions").or_insert(json!({}));
        let lights =
            extensions.as_object_mut().unwrap().entry("KHR_lights_punctual").or_insert(json!({ "lights": [] }))
                ["lights"]
                .as_array_mut()
                .unwrap();
        lights.push(value);
        lights.len() - 1
    }

    pub fn camera(&mut self, value: Value) -> usize {
        if self.json.get("cameras").is_none() {
            self.json["cameras"] = json!([]);
        }
        self.push("cameras", value)
    }

    /// An image (PNG bytes) in a buffer view, with a texture; returns the texture index.
    pub fn png_texture(&mut self, width: u32, height: u32, rgb: &[u8]) -> usize {
        self.png_texture_of(width, height, png::ColorType::Rgb, rgb)
    }

    /// An image of `color` texels (PNG bytes) in a buffer view, with a
    /// texture; returns the texture index.
    pub fn png_texture_of(&mut self, width: u32, height: u32, color: png::ColorType, bytes: &[u8]) -> usize {
        let rgb = bytes;
        let mut png = Vec::new();
        {
            let mut encoder = png::Encoder::new(&mut png, width, height);
            encoder.set_color(color);
            encoder.set_depth(png::BitDepth::Eight);
            encoder.write_header().unwrap().write_image_data(rgb).unwrap();
        }
        let view = self.view(&png);
        for key in ["images", "textures"] {
            if self.json.get(key).is_none() {
                self.json[key] = json!([]);
            }
        }
        let image = self.push("images", json!({ "bufferView": view, "mimeType": "image/png" }));
        self.push("textures", json!({ "source": image }))
    }

    pub fn use_extension(&mut self, name: &str) {
        let used = self.json.as_object_mut().unwrap().entry("extensionsUsed").or_insert(json!([]));
        if !used.as_array().unwrap().contains(&json!(name)) {
            used.as_array_mut().unwrap().push(json!(name));
        }
    }

    /// The JSON with the buffer at `uri`.
    fn with_buffer(&self, uri: Option<String>) -> Value {
        let mut json = self.json.clone();
        let mut buffer = json!({ "byteLength": self.bin.len() });
        if let Some(uri) = uri {
            buffer["uri"] = json!(uri);
        }
        json["buffers"] = json!([buffer]);
        json
    }

    /// A `.gltf` with its buffer embedded as a base64 data URI.
    pub fn embedded(&self) -> String {
        let data = base64::engine::general_purpose::STANDARD.encode(&self.bin);
        serde_json::to_string_pretty(&self.with_buffer(Some(format!("data:application/octet-stream;base64,{data}"))))
            .unwrap()
    }

    /// Writes `dir/name.gltf` and `dir/name.bin`; returns the `.gltf`'s path.
    pub fn write_separate(&self, dir: &Path, name: &str) -> PathBuf {
        std::fs::write(dir.join(format!("{name}.bin")), &self.bin).unwrap();
        let path = dir.join(format!("{name}.gltf"));
        std::fs::write(&path, serde_json::to_string_pretty(&self.with_buffer(Some(format!("{name}.bin")))).unwrap())
            .unwrap();
        path
    }

    /// A binary glTF: header, JSON chunk, BIN chunk.
    pub fn glb(&self) -> Vec<u8> {
        let mut json = serde_json::to_vec(&self.with_buffer(None)).unwrap();
        while json.len() % 4 != 0 {
            json.push(b' ');
        }
        let mut bin = self.bin.clone();
        while bin.len() % 4 != 0 {
            bin.push(0);
        }
        let total = 12 + 8 + json.len() + 8 + bin.len();
        let mut out = Vec::with_capacity(total);
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        out.extend_from_slice(&(json.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&json);
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
        out
    }
}

/// A diffuse material of albedo `rgb` (metallic 0, KHR_materials_specular 0).
pub fn diffuse(rgb: [f32; 3]) -> Value {
    json!({
        "pbrMetallicRoughness": { "baseColorFactor": [rgb[0], rgb[1], rgb[2], 1.0], "metallicFactor": 0.0 },
        "extensions": { "KHR_materials_specular": { "specularFactor": 0.0 } }
    })
}

/// A small scene: a grey floor (20 x 20 m at y = 0), a point light of 683 cd
/// (1 W/sr) at height 2, a perspective camera looking down at the floor
/// from height 6.
pub fn floor_and_point_light() -> GltfBuilder {
    let mut g = GltfBuilder::new();
    g.use_extension("KHR_materials_specular");
    let grey = g.material(diffuse([0.5, 0.5, 0.5]));
    let floor = g.quad([-10.0, 0.0, 10.0], [20.0, 0.0, 0.0], [0.0, 0.0, -20.0], Some(grey));
    g.node(json!({ "mesh": floor, "name": "floor" }), true);
    let light = g.light(json!({ "type": "point", "intensity": 683.0, "color": [1.0, 1.0, 1.0], "name": "bulb" }));
    g.node(
        json!({ "translation": [0.0, 2.0, 0.0], "extensions": { "KHR_lights_punctual": { "light": light } } }),
        true,
    );
    let camera = g.camera(json!({ "type": "perspective", "name": "top", "perspective": { "yfov": 0.6, "aspectRatio": 1.5, "znear": 0.1 } }));
    // -Z to -Y: a rotation of -90 degrees about x.
    let s = std::f32::consts::FRAC_1_SQRT_2;
    g.node(json!({ "camera": camera, "translation": [0.0, 6.0, 0.0], "rotation": [-s, 0.0, 0.0, s] }), true);
    g
}

/// A glTF pane facing the camera, of a base colour of white and the
/// material's `extensions`, in front of a red emitter (radiance 1) that
/// fills the view, in the dark. Smooth: `rough_pane_before_a_red_emitter`
/// of roughness 0.
pub fn pane_before_a_red_emitter(extensions: Value) -> GltfBuilder {
    rough_pane_before_a_red_emitter(extensions, 0.0)
}

/// The same pane of `roughness`.
pub fn rough_pane_before_a_red_emitter(extensions: Value, roughness: f32) -> GltfBuilder {
    let mut b = GltfBuilder::new();
    let material = b.material(json!({
        "pbrMetallicRoughness": { "baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0, "roughnessFactor": roughness },
        "extensions": extensions,
    }));
    let mesh = b.quad([-1.0, -1.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0], Some(material));
    b.node(json!({ "mesh": mesh }), true);
    let red = b.material(json!({
        "pbrMetallicRoughness": { "baseColorFactor": [0, 0, 0, 1] },
        "emissiveFactor": [1, 0, 0],
    }));
    let mesh = b.quad([-3.0, -3.0, -1.0], [6.0, 0.0, 0.0], [0.0, 6.0, 0.0], Some(red));
    b.node(json!({ "mesh": mesh }), true);
    let camera = b.camera(json!({ "type": "perspective", "perspective": { "yfov": 0.5, "znear": 0.01 } }));
    b.node(json!({ "camera": camera, "translation": [0.0, 0.0, 3.0] }), true);
    b
}
