//! glTF 2.0 import (`.gltf` with external or embedded buffers, and `.glb`):
//! the default scene's meshes, materials, KHR_lights_punctual lights,
//! emissive meshes (as area lights) and cameras, mapped onto the renderer's
//! model as docs/scene-format.md tabulates. Buffers, images and accessors are
//! read by `io` rather than by the `gltf` crate's importer so that every
//! error names the file and the JSON location (`meshes[2].primitives[0].indices`).
//!
//! By job: `io` parses the file and reads its buffers, images and
//! accessors; `nodes` walks the scene's nodes (world transforms, cameras,
//! instancing, motion over the shutter with `animation`); `geometry` makes
//! a primitive's mesh (attributes, morph targets, skins, tangents);
//! `materials` its material and textures; `lights` its punctual lights.

mod animation;
mod geometry;
mod io;
mod lights;
mod materials;
mod nodes;

use std::collections::HashMap;

pub(crate) use geometry::{mikktspace_tangents, Tangents};
use std::path::Path;

use super::file::{GltfSpec, ImportedCamera};
use super::groups::GltfLightNames;
use super::{ImportParts, SceneError, MAX_EMITTER_SAMPLES};
use super::{MAX_IMPORT_INSTANCES as MAX_INSTANCES, MAX_IMPORT_TRIANGLES as MAX_TRIANGLES};

/// Extensions whose absence from the renderer changes nothing it draws
/// (when merely used) and which it implements; anything else listed in
/// `extensionsRequired` is refused by name.
const IMPLEMENTED: [&str; 12] = [
    "KHR_lights_punctual",
    "KHR_materials_clearcoat",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_sheen",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_unlit",
    "KHR_materials_volume",
    "KHR_mesh_quantization",
    "KHR_texture_transform",
    "EXT_mesh_gpu_instancing",
];

/// Extensions the renderer knows but does not implement, with what a
/// render of a file that uses them does instead (named once on stderr).
const IGNORED: [(&str, &str); 10] = [
    ("KHR_materials_iridescence", "no thin-film iridescence"),
    ("KHR_materials_anisotropy", "isotropic roughness"),
    ("KHR_materials_dispersion", "no dispersion"),
    ("KHR_materials_diffuse_transmission", "surfaces are opaque"),
    ("KHR_materials_variants", "the default material of each primitive"),
    ("KHR_materials_pbrSpecularGlossiness", "the material's pbrMetallicRoughness (or its defaults)"),
    ("KHR_texture_basisu", "each texture's PNG or JPEG source"),
    ("EXT_texture_webp", "each texture's PNG or JPEG source"),
    ("KHR_draco_mesh_compression", "each primitive's uncompressed attributes"),
    ("EXT_meshopt_compression", "each buffer view's uncompressed fallback"),
];

/// Deepest node hierarchy followed.
const MAX_DEPTH: usize = 1024;

/// Most joints a skin may have.
const MAX_JOINTS: usize = 1 << 16;

/// Where the imported parts go (`ImportParts`), and what only a glTF
/// import reports.
pub struct Parts<'a> {
    pub scene: ImportParts<'a>,
    /// The names each of the lights this import adds is known by (for the
    /// `[[gltf.groups]]` rules), one per light, in order.
    pub light_names: &'a mut Vec<GltfLightNames>,
    /// The animation played, and over which shutter, when one is.
    pub played: &'a mut Option<PlayedAnimation>,
}

/// The glTF animation a render plays: its name, and the shutter it is
/// sampled over (seconds of the file's timeline; open = close: the pose
/// at that instant).
#[derive(Debug, Clone, PartialEq)]
pub struct PlayedAnimation {
    pub name: String,
    pub shutter: [f32; 2],
}

/// Imports `spec.file` (relative to `base`) into `parts`; returns the chosen
/// camera when `want_camera` (the TOML gives none). With a `shutter`
/// (seconds, open <= close), the file's animation (`spec.animation`, else
/// its first) is sampled over it: what it moves, moves; at an instant (open
/// = close) everything is posed as the animation has it then. An
/// animation named without a shutter is checked and not played (a warning
/// says so).
pub fn import(
    scene_file: &Path,
    base: &Path,
    spec: &GltfSpec,
    want_camera: bool,
    shutter: Option<[f32; 2]>,
    parts: Parts<'_>,
) -> Result<Option<ImportedCamera>, SceneError> {
    let path = base.join(&spec.file);
    parts.scene.inputs.push(path.clone());
    let check = |ok: bool, field: &str, message: String| {
        if ok {
            Ok(())
        } else {
            Err(SceneError::new(scene_file, format!("gltf.{field}"), message))
        }
    };
    check(
        spec.lumens_per_watt.is_finite() && spec.lumens_per_watt > 0.0,
        "lumens_per_watt",
        format!("must be finite and > 0, got {}", spec.lumens_per_watt),
    )?;
    check(
        (1..=MAX_EMITTER_SAMPLES).contains(&spec.emitter_samples),
        "emitter_samples",
        format!("must be between 1 and {MAX_EMITTER_SAMPLES}, got {}", spec.emitter_samples),
    )?;
    let bytes = crate::util::file::read_regular(&path, crate::util::file::MAX_FILE_BYTES)
        .map_err(|e| SceneError::new(scene_file, "gltf.file", format!("cannot read '{}': {e}", path.display())))?;
    let gltf = io::parse(&path, &bytes)?;
    let data = io::Data::load(&path, &gltf.document, gltf.blob.as_deref())?;
    let animation = match (shutter, &spec.animation) {
        (None, None) => None,
        // A name is checked whether or not it is played.
        _ => animation::Animation::read(&path, &gltf.document, &data, spec.animation.as_deref())?,
    };
    let warn = |parts: &mut Parts<'_>, location: &str, message: String| {
        parts.scene.warnings.push(format!("{}: {location}: {message}", path.display()));
    };
    let mut parts = parts;
    if let (Some(animation), None) = (&animation, shutter) {
        let message = format!(
            "'{}' is not played: give a shutter (--shutter OPEN,CLOSE to blur over it, or T,T for the pose at T seconds)",
            animation.name
        );
        warn(&mut parts, "animations", message);
    }
    let animation = shutter.zip(animation);
    if let Some(([open, close], animation)) = &animation {
        if let Some([first, last]) = animation.key_range().filter(|[first, last]| *open < *first || *close > *last) {
            let message = format!(
                "the shutter {open},{close} s is not within animation '{}''s keys, {first} to {last} s (outside them it \
                 holds its first or last key): frames typed as seconds? Blender's exporter writes frame f at f / fps \
                 seconds (frame 6 at 24 fps is 0.25 s)",
                animation.name
            );
            warn(&mut parts, "animations", message);
        }
        *parts.played = Some(PlayedAnimation { name: animation.name.clone(), shutter: [*open, *close] });
    }
    let mut importer = Importer {
        file: &path,
        doc: &gltf.document,
        data,
        materials: HashMap::new(),
        spec,
        parts,
        skipped_primitives: 0,
        emitters: super::EmissiveMeshes::GLTF,
        triangles: 0,
        placements: Vec::new(),
        prototypes: HashMap::new(),
        punctual: 0,
        shutter: animation,
        still_moving: 0,
    };
    let camera = importer.import_scene(want_camera)?;
    // The buffer and image files, after the glTF file, in the order read.
    importer.parts.scene.inputs.append(&mut importer.data.inputs);
    Ok(camera)
}

struct Importer<'a, 'p> {
    file: &'a Path,
    doc: &'a gltf::Document,
    data: io::Data<'a>,
    /// The scene's material index of each glTF material (None: the default).
    materials: HashMap<Option<usize>, usize>,
    spec: &'a GltfSpec,
    parts: Parts<'p>,
    skipped_primitives: usize,
    emitters: super::EmissiveMeshes,
    /// Triangles imported so far (every copy counted, an instanced mesh once).
    triangles: usize,
    /// How many rigid, orientation-preserving placements each glTF mesh
    /// has (EXT_mesh_gpu_instancing's nodes count as many): a mesh placed
    /// twice or more is imported once and instanced.
    placements: Vec<usize>,
    /// The scene mesh of each instanced glTF primitive (mesh, primitive),
    /// in the mesh's own space; None for one imported as copies (emissive,
    /// or not triangles).
    prototypes: HashMap<(usize, usize), Option<usize>>,
    /// KHR_lights_punctual lights imported.
    punctual: usize,
    /// The shutter and the animation played over it.
    shutter: Option<([f32; 2], animation::Animation)>,
    /// Moving primitives drawn still (emissive, mirrored or skinned).
    still_moving: usize,
}

impl Importer<'_, '_> {
    fn error(&self, location: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError::new(self.file, location, message)
    }

    fn warn(&mut self, location: &str, message: &str) {
        self.parts.scene.warnings.push(format!("{}: {location}: {message}", self.file.display()));
    }

    /// Names, once each, the extensions the file uses but the renderer does
    /// not implement, with what the render does instead (a required one was
    /// refused in `io::parse`).
    fn name_ignored_extensions(&mut self) {
        let used: Vec<String> = self.doc.extensions_used().map(str::to_string).collect();
        for name in used {
            if IMPLEMENTED.contains(&name.as_str()) {
                continue;
            }
            let instead = IGNORED
                .iter()
                .find(|(n, _)| *n == name)
                .map_or("ignored: the render is what the file gives without it", |(_, instead)| instead);
            self.warn("extensionsUsed", &format!("{name} is not implemented: {instead}"));
        }
    }
}

#[cfg(test)]
mod tests;
