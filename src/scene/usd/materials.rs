//! Materials: a `Material` prim's `outputs:surface` network read as
//! `UsdPreviewSurface` onto glTF's metallic-roughness model (the mapping
//! is docs/scene-format.md's, "USD"): its inputs as values or as
//! `UsdUVTexture` channels (file, wrap modes, scale, bias,
//! `sourceColorSpace`), their texture coordinates from a
//! `UsdPrimvarReader_float2` through an optional `UsdTransform2d`. A
//! texture's scale, bias and channel are applied to its texels once, at
//! import. An unsupported surface (MaterialX, MDL, RenderMan) falls back to
//! the material's universal `outputs:surface` when it has one, otherwise to
//! a grey default with a warning naming it.

use std::collections::HashMap;

use glam::{Affine2, DVec4, Vec3};

use super::geometry::Located;
use super::schema::Reader;
use super::stage::{Asset, Stage};
use crate::scene::image::{self, Encoding, RgbImage};
use crate::scene::material::{Albedo, Clearcoat, Cutout, Material, NormalMap, PbrMaterial, TextureRef};
use crate::scene::texels::{Coverage, Texels};
use crate::scene::texture::{Filter, Texture, Wrap};

/// Largest texture file read (256 MiB).
const MAX_TEXTURE_BYTES: u64 = 256 << 20;

/// The grey of a surface without a usable material (UsdPreviewSurface's
/// own diffuseColor fallback).
pub(super) const DEFAULT_GREY: Vec3 = Vec3::splat(0.18);

/// A UsdUVTexture output: which channels it reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Channel {
    Rgb,
    R,
    G,
    B,
    A,
}

/// An input's source: a value, or a texture lookup.
#[derive(Debug, Clone)]
enum Source {
    Value(DVec4),
    Texture(TextureSource),
}

/// What a UsdUVTexture reads and how.
#[derive(Debug, Clone)]
struct TextureSource {
    shader: String,
    /// Where the file is: resolved against the layer that authored it.
    file: String,
    /// The file as authored, for messages.
    authored: String,
    channel: Channel,
    wrap: [Wrap; 2],
    scale: DVec4,
    bias: DVec4,
    /// `sourceColorSpace`: "sRGB", "raw" or "auto".
    colour_space: String,
    /// The texture coordinates' primvar and the map from them to the lookup's.
    varname: String,
    transform: Affine2,
}

/// The key a baked texture is cached by.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
struct Baked {
    file: String,
    channels: Vec<(Channel, [u64; 2])>,
    wrap: [u8; 2],
    srgb: bool,
    normal: bool,
}

/// A material as imported, and the texture-coordinate primvar it reads.
pub(super) struct Imported {
    pub material: Material,
    pub varname: String,
    /// The primvar its diffuseColor reads (a `UsdPrimvarReader_float3`),
    /// and the reader's fallback where a mesh lacks it: the mesh's vertex
    /// colours, times a white base colour.
    pub colour_primvar: Option<(String, Vec3)>,
    /// The primvars its other inputs read through primvar readers (not
    /// given a value by the import), each with the note of what a gprim
    /// without a constant value of it gets instead (docs/design.md §6.8,
    /// "Primvar readers").
    pub primvars: Vec<(String, String)>,
}

/// Imports materials and their textures, each once.
pub(super) struct Materials<'s> {
    stage: &'s Stage,
    time: f64,
    textures: HashMap<Baked, usize>,
    /// Each texture file read, by where it is (sRGB-decoded copies keyed
    /// with a trailing NUL), or why it could not be.
    images: HashMap<String, Result<RgbImage, String>>,
    /// The files read since the last import.
    read: Vec<std::path::PathBuf>,
    /// What the materials lack (a texture that cannot be read, a shader
    /// this reader does not evaluate), since the last import.
    lacking: Vec<String>,
    /// Bound materials no layer defines.
    pub(super) undefined: Vec<String>,
    /// The values primvar readers read in the import under way: a gprim's
    /// constant primvars, by name (empty for the material all gprims share).
    constants: HashMap<String, DVec4>,
    /// The primvars read with no value in `constants` in the import under
    /// way, with the note of what is used instead.
    primvar_reads: Vec<(String, String)>,
}

impl<'s> Materials<'s> {
    pub(super) fn new(stage: &'s Stage, time: f64) -> Self {
        Self {
            stage,
            time,
            textures: HashMap::new(),
            images: HashMap::new(),
            read: Vec::new(),
            lacking: Vec::new(),
            undefined: Vec::new(),
            constants: HashMap::new(),
            primvar_reads: Vec::new(),
        }
    }

    /// What the imports so far lack (`Scene::incomplete`), taken.
    pub(super) fn take_lacking(&mut self) -> Vec<String> {
        std::mem::take(&mut self.lacking)
    }

    /// The material at `path` (a `Material` prim), with its textures added
    /// to `textures` and the files read to `inputs`; warnings for what it
    /// renders otherwise. Its primvar readers read `constants` (a gprim's
    /// constant primvars, by name; empty for the material all gprims share).
    pub(super) fn import(
        &mut self,
        path: &str,
        constants: HashMap<String, DVec4>,
        textures: &mut Vec<Texture>,
        inputs: &mut Vec<std::path::PathBuf>,
        warnings: &mut Vec<String>,
    ) -> Result<Imported, Located> {
        self.constants = constants;
        self.primvar_reads.clear();
        let imported = self.import_surface(path, textures, warnings);
        self.constants.clear();
        inputs.extend(self.read.drain(..).filter(|f| !inputs.contains(f)).collect::<Vec<_>>());
        imported
    }

    fn import_surface(
        &mut self,
        path: &str,
        textures: &mut Vec<Texture>,
        warnings: &mut Vec<String>,
    ) -> Result<Imported, Located> {
        let grey = || Imported {
            material: default_material(path),
            varname: "st".to_string(),
            colour_primvar: None,
            primvars: Vec::new(),
        };
        let info = self.stage.prim(path).map_err(|e| (path.to_string(), e))?;
        if info.type_name.is_empty() {
            // Nothing defines it: the layer that would is missing or not read.
            self.undefined.push(path.to_string());
            return Ok(grey());
        }
        if info.type_name != "Material" {
            warnings.push(format!("{path}: is bound as a material but is a '{}': grey", info.type_name));
            return Ok(grey());
        }
        let Some(shader) = self.surface_shader(path, warnings)? else {
            return Ok(grey());
        };
        let id = self.stage.token(&shader, "info:id", self.time).map_err(|e| (format!("{shader}.info:id"), e))?;
        if id.as_deref() != Some("UsdPreviewSurface") {
            warnings.push(format!(
                "{shader}: the surface shader '{}' is not UsdPreviewSurface, and the material has no \
                 UsdPreviewSurface outputs:surface: rendered grey",
                id.unwrap_or_default()
            ));
            return Ok(grey());
        }
        self.preview_surface(path, &shader, textures, warnings)
    }

    /// The shader behind the material's universal `outputs:surface` (or,
    /// without one, a warning naming the render contexts it has).
    fn surface_shader(&self, material: &str, warnings: &mut Vec<String>) -> Result<Option<String>, Located> {
        let sources = self
            .stage
            .connections(material, "outputs:surface")
            .map_err(|e| (format!("{material}.outputs:surface"), e))?;
        if let Some(source) = sources.first() {
            return Ok(Some(self.follow_to_shader(source)?));
        }
        let names = self.stage.property_names(material).map_err(|e| (material.to_string(), e))?;
        let others: Vec<&String> =
            names.iter().filter(|n| n.starts_with("outputs:") && n.ends_with(":surface")).collect();
        if others.is_empty() {
            warnings.push(format!("{material}: has no outputs:surface: rendered grey"));
        } else {
            warnings.push(format!(
                "{material}: only {} (no UsdPreviewSurface outputs:surface): rendered grey",
                others.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(", ")
            ));
        }
        Ok(None)
    }

    /// A connection source `/Path/Prim.outputs:name` followed through node
    /// graphs to the shader prim that computes it.
    fn follow_to_shader(&self, source: &str) -> Result<String, Located> {
        let mut source = source.to_string();
        for _ in 0..64 {
            let (prim, property) = split(&source);
            let info = self.stage.prim(prim).map_err(|e| (source.clone(), e))?;
            if info.type_name == "Shader" {
                return Ok(prim.to_string());
            }
            // A NodeGraph's (or Material's) output forwards its own connection.
            let next = self.stage.connections(prim, property).map_err(|e| (source.clone(), e))?;
            match next.first() {
                Some(n) => source = n.clone(),
                None => return Err((source.clone(), "connects to nothing that computes it".into())),
            }
        }
        Err((source, "the connections go round in a cycle".into()))
    }

    /// Input `name` of `shader`: its connection (followed through node
    /// graphs' interface inputs), its value, or the schema's fallback.
    /// Where the connection leads to what is not read (a texture file that
    /// is missing or unreadable, a UsdUVTexture without a file, a primvar
    /// reader, a shader this reader does not evaluate), a value instead:
    /// the texture's or reader's `inputs:fallback` when authored, else the
    /// input's own value, with a note of what is missing.
    fn input(&mut self, shader: &str, schema: &str, name: &str) -> Result<Source, Located> {
        Ok(self.input_reading(shader, schema, name, false)?.0)
    }

    /// [`Self::input`]; with `primvars`, a `UsdPrimvarReader_float3` it
    /// leads to is the primvar's name and the reader's fallback instead.
    fn input_reading(
        &mut self,
        shader: &str,
        schema: &str,
        name: &str,
        primvars: bool,
    ) -> Result<(Source, Option<(String, DVec4)>), Located> {
        let attribute = format!("inputs:{name}");
        let mut prim = shader.to_string();
        let mut property = attribute.clone();
        for _ in 0..64 {
            let sources = self.stage.connections(&prim, &property).map_err(|e| (format!("{prim}.{property}"), e))?;
            let Some(source) = sources.first() else {
                let value = if prim == shader {
                    self.value(shader, schema, &attribute)?
                } else {
                    self.value(&prim, "", &property)?
                };
                return Ok((
                    Source::Value(value.unwrap_or_else(|| {
                        // An interface input with no value: the shader's fallback.
                        self.value(shader, schema, &attribute).ok().flatten().unwrap_or(DVec4::ZERO)
                    })),
                    None,
                ));
            };
            let (source_prim, source_property) = split(source);
            let info = self.stage.prim(source_prim).map_err(|e| (source.clone(), e))?;
            if info.type_name == "Shader" {
                let (source_prim, source_property) = (source_prim.to_string(), source_property.to_string());
                return self.shader_source(shader, schema, name, &source_prim, &source_property, primvars);
            }
            prim = source_prim.to_string();
            property = source_property.to_string();
        }
        Err((format!("{shader}.{attribute}"), "the connections go round in a cycle".into()))
    }

    /// What shader `source` (its output `property`) gives input `name` of
    /// `shader` (see [`Self::input_reading`]).
    fn shader_source(
        &mut self,
        shader: &str,
        schema: &str,
        name: &str,
        source: &str,
        property: &str,
        primvars: bool,
    ) -> Result<(Source, Option<(String, DVec4)>), Located> {
        let id = self
            .stage
            .token(source, "info:id", self.time)
            .map_err(|e| (format!("{source}.info:id"), e))?
            .unwrap_or_default();
        let own = |this: &Self| -> Result<DVec4, Located> {
            Ok(this.value(shader, schema, &format!("inputs:{name}"))?.unwrap_or(DVec4::ZERO))
        };
        let fallback = |this: &Self| -> Result<Option<DVec4>, Located> { this.value(source, "", "inputs:fallback") };
        let instead = |this: &Self, fallback: Option<DVec4>| -> Result<(String, Source), Located> {
            Ok(match fallback {
                Some(f) => ("its inputs:fallback".to_string(), Source::Value(f)),
                None => (format!("{shader}.inputs:{name}'s own value"), Source::Value(own(this)?)),
            })
        };
        if id == "UsdUVTexture" {
            let texture = self.shader_output(source, property)?;
            let problem = if texture.file.is_empty() {
                Some("names no file".to_string())
            } else {
                self.load(&texture.file, &texture.authored).err()
            };
            let Some(problem) = problem else { return Ok((Source::Texture(texture), None)) };
            let channel = |v: DVec4| match texture.channel {
                Channel::Rgb => v,
                c => DVec4::splat(pick(v, c)),
            };
            let (what, value) = instead(self, fallback(self)?.map(channel))?;
            self.lacking.push(format!("{source}.inputs:file: {problem}: {what} is used"));
            return Ok((value, None));
        }
        if let Some(kind) = id.strip_prefix("UsdPrimvarReader_") {
            let varname = self.stage.token(source, "inputs:varname", self.time).ok().flatten().unwrap_or_default();
            let reader_fallback = fallback(self)?;
            // Any reader but float2 can feed a colour: a number as grey, a
            // float4's RGB (Stage::colours reads them so).
            if primvars
                && matches!(kind, "float" | "float3" | "float4" | "int" | "normal3f" | "point3f" | "vector3f")
                && !varname.is_empty()
            {
                // (A number's fallback reads as grey already: Self::value.)
                return Ok((Source::Value(DVec4::ONE), Some((varname, reader_fallback.unwrap_or(DVec4::ZERO)))));
            }
            // A gprim's constant value; else the reader's fallback, noted
            // for each gprim that gets it (docs/design.md §6.8).
            if let Some(&value) = self.constants.get(&varname) {
                return Ok((Source::Value(value), None));
            }
            let (what, value) = instead(self, reader_fallback.or(Some(DVec4::ZERO)))?;
            let note = format!(
                "{source}: a primvar ('{varname}') read into {shader}.inputs:{name} has no constant value on the \
                 gprim (one that varies over the surface is read only into diffuseColor): {what} is used"
            );
            if varname.is_empty() {
                self.lacking.push(note);
            } else {
                self.primvar_reads.push((varname, note));
            }
            return Ok((value, None));
        }
        let (what, value) = instead(self, None)?;
        self.lacking.push(format!("{source}: the shader '{id}' is not evaluated: {what} is used"));
        Ok((value, None))
    }

    /// An attribute's value as four numbers (a scalar in x, a colour in
    /// xyz), finite.
    fn value(&self, prim: &str, schema: &str, attribute: &str) -> Result<Option<DVec4>, Located> {
        let value = self.any_value(prim, schema, attribute)?;
        if value.is_some_and(|v| !v.is_finite()) {
            return Err((
                format!("{prim}.{attribute}"),
                format!("must be finite, got {:?}", value.unwrap_or_default()),
            ));
        }
        Ok(value)
    }

    fn any_value(&self, prim: &str, schema: &str, attribute: &str) -> Result<Option<DVec4>, Located> {
        let at = || format!("{prim}.{attribute}");
        let stage = self.stage;
        let t = self.time;
        if let Some(v) = stage.vec3(prim, attribute, t).ok().flatten() {
            return Ok(Some(v.extend(1.0)));
        }
        if let Some(v) = stage.vec4(prim, attribute, t).ok().flatten() {
            return Ok(Some(v));
        }
        if let Some(v) = stage.number(prim, attribute, t).map_err(|e| (at(), e))? {
            return Ok(Some(DVec4::new(v, v, v, 1.0)));
        }
        if schema.is_empty() {
            return Ok(None);
        }
        let read = Reader { stage, prim, schema, time: t };
        match super::schema::fallback(schema, attribute) {
            Some(super::schema::Fallback::Vec3(_)) => Ok(Some(read.vec3(attribute)?.extend(1.0))),
            Some(super::schema::Fallback::Number(_)) => {
                let v = read.number(attribute)?;
                Ok(Some(DVec4::new(v, v, v, 1.0)))
            }
            _ => Ok(None),
        }
    }

    /// A UsdUVTexture's output `property` (`outputs:rgb`, `outputs:r`...);
    /// its file's location empty where it names none.
    fn shader_output(&self, shader: &str, property: &str) -> Result<TextureSource, Located> {
        let at = |a: &str| format!("{shader}.{a}");
        let channel = match property {
            "outputs:rgb" => Channel::Rgb,
            "outputs:r" => Channel::R,
            "outputs:g" => Channel::G,
            "outputs:b" => Channel::B,
            "outputs:a" => Channel::A,
            other => return Err((at(other), "is not an output of UsdUVTexture (rgb, r, g, b, a)".into())),
        };
        let read = Reader { stage: self.stage, prim: shader, schema: "UsdUVTexture", time: self.time };
        let asset = self.stage.asset(shader, "inputs:file", self.time).map_err(|e| (at("inputs:file"), e))?;
        let (file, authored) = match asset {
            Some(a) if !a.authored.is_empty() => (a.location, a.authored),
            _ => (String::new(), String::new()),
        };
        let wrap = |name: &str| -> Result<Wrap, Located> {
            Ok(match read.token(name)?.as_str() {
                "repeat" => Wrap::Repeat,
                "mirror" => Wrap::MirroredRepeat,
                "clamp" => Wrap::ClampToEdge,
                // Without metadata in the file, USD's reading of useMetadata is black.
                "black" | "useMetadata" => Wrap::Black,
                other => {
                    return Err((at(name), format!("'{other}' is not a wrap mode (repeat, mirror, clamp, black)")))
                }
            })
        };
        let (varname, mut transform) = self.coordinates(shader)?;
        if authored.contains(UDIM) {
            // The tiles are read as one atlas of cols x rows tiles.
            let (cols, rows) = udim_grid(&udim_tiles(self.stage, &file, &authored));
            transform = Affine2::from_scale(glam::Vec2::new(1.0 / cols as f32, 1.0 / rows as f32)) * transform;
        }
        Ok(TextureSource {
            shader: shader.to_string(),
            file,
            authored,
            channel,
            wrap: [wrap("inputs:wrapS")?, wrap("inputs:wrapT")?],
            scale: read.vec4("inputs:scale")?,
            bias: read.vec4("inputs:bias")?,
            colour_space: read.token("inputs:sourceColorSpace")?,
            varname,
            transform,
        })
    }

    /// A texture's `inputs:st`: the primvar a UsdPrimvarReader_float2 reads
    /// and the UsdTransform2d between them, if any (scale, then rotation
    /// counter-clockwise in degrees, then translation).
    fn coordinates(&self, texture: &str) -> Result<(String, Affine2), Located> {
        let mut transform = Affine2::IDENTITY;
        let mut at = (texture.to_string(), "inputs:st".to_string());
        for _ in 0..64 {
            let sources = self.stage.connections(&at.0, &at.1).map_err(|e| (format!("{}.{}", at.0, at.1), e))?;
            let Some(source) = sources.first() else {
                // Unconnected: the primvar `st`, as Hydra reads it.
                return Ok(("st".to_string(), transform));
            };
            let (prim, property) = split(source);
            let info = self.stage.prim(prim).map_err(|e| (source.clone(), e))?;
            if info.type_name != "Shader" {
                at = (prim.to_string(), property.to_string());
                continue;
            }
            let id = self
                .stage
                .token(prim, "info:id", self.time)
                .map_err(|e| (format!("{prim}.info:id"), e))?
                .unwrap_or_default();
            match id.as_str() {
                "UsdPrimvarReader_float2" => {
                    let read = Reader { stage: self.stage, prim, schema: &id, time: self.time };
                    let name = read.token("inputs:varname")?;
                    let name = if name.is_empty() { "st".to_string() } else { name };
                    return Ok((name, transform));
                }
                "UsdTransform2d" => {
                    let read = Reader { stage: self.stage, prim, schema: &id, time: self.time };
                    let (scale, rotation, translation) =
                        (read.vec2("inputs:scale")?, read.number("inputs:rotation")?, read.vec2("inputs:translation")?);
                    let this = Affine2::from_scale_angle_translation(
                        scale.as_vec2(),
                        (rotation as f32).to_radians(),
                        translation.as_vec2(),
                    );
                    // Applied after what feeds it.
                    transform *= this;
                    at = (prim.to_string(), "inputs:in".to_string());
                }
                other => return Err((format!("{prim}.info:id"), format!("'{other}' cannot give texture coordinates"))),
            }
        }
        Err((texture.to_string(), "the texture coordinates' connections go round in a cycle".into()))
    }

    fn preview_surface(
        &mut self,
        material: &str,
        shader: &str,
        textures: &mut Vec<Texture>,
        warnings: &mut Vec<String>,
    ) -> Result<Imported, Located> {
        const SCHEMA: &str = "UsdPreviewSurface";
        let input = |this: &mut Self, name: &str| this.input(shader, SCHEMA, name);
        let mut varname: Option<String> = None;
        let note_varname = |source: &Source, varname: &mut Option<String>, warnings: &mut Vec<String>| {
            if let Source::Texture(t) = source {
                match varname {
                    None => *varname = Some(t.varname.clone()),
                    Some(v) if *v != t.varname => warnings.push(format!(
                        "{}: reads primvar '{}' where another texture reads '{v}': both read '{v}'",
                        t.shader, t.varname
                    )),
                    Some(_) => {}
                }
            }
        };
        // A primvar reader's colour varies over the surface as the mesh's
        // vertex colours, times a white base colour.
        let (diffuse, colour_primvar) = self.input_reading(shader, SCHEMA, "diffuseColor", true)?;
        note_varname(&diffuse, &mut varname, warnings);
        let albedo = match &diffuse {
            Source::Value(v) => Albedo::Constant(v.truncate().as_vec3().clamp(Vec3::ZERO, Vec3::ONE)),
            Source::Texture(t) => Albedo::Texture(self.texture(&[t], true, false, textures)?),
        };
        let specular_workflow = matches!(input(self, "useSpecularWorkflow")?, Source::Value(v) if v.x != 0.0);
        let metallic = input(self, "metallic")?;
        let roughness = input(self, "roughness")?;
        note_varname(&metallic, &mut varname, warnings);
        note_varname(&roughness, &mut varname, warnings);
        let mut pbr = preview_defaults();
        // Roughness and metallic as glTF holds them: factors times the
        // texture's G (roughness) and B (metallic).
        match (&roughness, &metallic) {
            (Source::Value(r), Source::Value(m)) => {
                pbr.roughness = r.x.clamp(0.0, 1.0) as f32;
                pbr.metallic = if specular_workflow { 0.0 } else { m.x.clamp(0.0, 1.0) as f32 };
            }
            _ => {
                pbr.roughness = 1.0;
                pbr.metallic = if specular_workflow { 0.0 } else { 1.0 };
                let texture = self.metallic_roughness(&roughness, &metallic, specular_workflow, textures)?;
                pbr.metallic_roughness = Some(texture);
            }
        }
        self.specular(shader, specular_workflow, &mut pbr, textures)?;
        let mut material = Material { pbr: None, ..Material::diffuse(material, albedo) };
        match input(self, "emissiveColor")? {
            Source::Value(v) => material.emission = v.truncate().as_vec3().max(Vec3::ZERO),
            Source::Texture(t) => {
                material.emission = Vec3::ONE;
                material.emissive_texture = Some(self.texture(&[&t], true, false, textures)?);
            }
        }
        if let Source::Texture(t) = input(self, "normal")? {
            let r = self.texture(&[&t], false, true, textures)?;
            pbr.normal_map = Some(NormalMap { texture: r.texture, transform: r.transform, scale: 1.0, set: 0 });
        }
        material.cutout = self.cutout(shader, textures, warnings)?;
        pbr.clearcoat = self.clearcoat(shader, textures)?;
        if matches!(input(self, "displacement")?, Source::Texture(_)) {
            warnings.push(format!("{shader}: displacement is not implemented"));
        }
        material.pbr = Some(pbr);
        Ok(Imported {
            material,
            varname: varname.unwrap_or_else(|| "st".to_string()),
            colour_primvar: colour_primvar.map(|(name, fallback)| (name, fallback.truncate().as_vec3())),
            primvars: std::mem::take(&mut self.primvar_reads),
        })
    }

    /// UsdPreviewSurface's clear coat (`clearcoat`, a white second
    /// specular lobe, and `clearcoatRoughness`), as KHR_materials_clearcoat's
    /// layer of IOR 1.5 (docs/design.md §5.10); None at a clearcoat of 0.
    fn clearcoat(&mut self, shader: &str, textures: &mut Vec<Texture>) -> Result<Option<Clearcoat>, Located> {
        let input = |this: &mut Self, name: &str| this.input(shader, "UsdPreviewSurface", name);
        let (factor, texture) = match input(self, "clearcoat")? {
            Source::Value(v) if v.x <= 0.0 => return Ok(None),
            Source::Value(v) => (v.x.min(1.0) as f32, None),
            Source::Texture(t) => (1.0, Some(self.texture(&[&t], false, false, textures)?)),
        };
        let (roughness, roughness_texture) = match input(self, "clearcoatRoughness")? {
            Source::Value(v) => (v.x.clamp(0.0, 1.0) as f32, None),
            Source::Texture(t) => (1.0, Some(self.texture(&[&t], false, false, textures)?)),
        };
        Ok(Some(Clearcoat { factor, texture, roughness, roughness_texture, normal_map: None }))
    }

    /// The specular layer: UsdPreviewSurface's specularColor as F0 in the
    /// specular workflow, its ior's F0 otherwise, and Blender's specular
    /// level where it writes one.
    fn specular(
        &mut self,
        shader: &str,
        specular_workflow: bool,
        pbr: &mut PbrMaterial,
        textures: &mut Vec<Texture>,
    ) -> Result<(), Located> {
        let input = |this: &mut Self, name: &str| this.input(shader, "UsdPreviewSurface", name);
        if specular_workflow {
            // F0 is specularColor: glTF's dielectric F0 is 0.04 x the
            // specular colour (KHR_materials_specular).
            match input(self, "specularColor")? {
                Source::Value(v) => pbr.specular_colour = (v.truncate().as_vec3() / 0.04).max(Vec3::ZERO),
                Source::Texture(t) => {
                    pbr.specular_colour = Vec3::splat(25.0);
                    pbr.specular_colour_texture = Some(self.texture(&[&t], true, false, textures)?);
                }
            }
        } else if let Source::Value(ior) = input(self, "ior")? {
            let ior = ior.x.max(1.0);
            let f0 = ((ior - 1.0) / (ior + 1.0)).powi(2);
            pbr.specular_colour = Vec3::splat((f0 / 0.04) as f32);
        }
        // Blender writes its Principled BSDF's "Specular IOR Level" (0.5 by
        // default) as `inputs:specular`, outside UsdPreviewSurface's
        // schema; its glTF exporter writes twice it as
        // KHR_materials_specular's factor, which this is read as.
        if let Some(level) = self
            .stage
            .number(shader, "inputs:specular", self.time)
            .map_err(|e| (format!("{shader}.inputs:specular"), e))?
        {
            pbr.specular = (2.0 * level).clamp(0.0, 1.0) as f32;
        }
        Ok(())
    }

    /// A cut-out from opacity below opacityThreshold (UsdPreviewSurface's
    /// "presence"); without a threshold, opacity is a partial coverage
    /// (docs/design.md §5.9), as Blender's importer and Storm read it.
    fn cutout(
        &mut self,
        shader: &str,
        textures: &mut Vec<Texture>,
        warnings: &mut Vec<String>,
    ) -> Result<Option<Cutout>, Located> {
        let input = |this: &mut Self, name: &str| this.input(shader, "UsdPreviewSurface", name);
        let mut cutout = None;
        let opacity = input(self, "opacity")?;
        let threshold = match input(self, "opacityThreshold")? {
            Source::Value(v) => v.x as f32,
            Source::Texture(t) => {
                warnings.push(format!("{}: a textured opacityThreshold is read as 0.5", t.shader));
                0.5
            }
        };
        match (&opacity, threshold > 0.0) {
            (Source::Texture(t), mask) => {
                let r = self.texture(&[t], false, false, textures)?;
                let texture = &textures[r.texture];
                let (width, height) = texture.size();
                let alpha = (0..width * height).map(|i| texture.texel_at(i).x).collect();
                cutout = Some(Cutout {
                    alpha,
                    width: width as u32,
                    height: height as u32,
                    transform: r.transform,
                    cutoff: mask.then_some(threshold),
                });
            }
            (Source::Value(v), true) if (v.x as f32) < threshold => {
                warnings.push(format!(
                    "{shader}: opacity {} is below its threshold {threshold}: the surface is drawn anyway",
                    v.x
                ));
            }
            (Source::Value(v), false) if v.x < 1.0 => {
                let alpha = vec![(v.x as f32).max(0.0)];
                cutout = Some(Cutout { alpha, width: 1, height: 1, transform: Affine2::IDENTITY, cutoff: None });
            }
            _ => {}
        }
        Ok(cutout)
    }

    /// A glTF metallic-roughness texture (G roughness, B metallic) from
    /// UsdPreviewSurface's two inputs, each a value or a texture channel;
    /// at the resolution of the (first) texture.
    fn metallic_roughness(
        &mut self,
        roughness: &Source,
        metallic: &Source,
        specular_workflow: bool,
        textures: &mut Vec<Texture>,
    ) -> Result<TextureRef, Located> {
        let sources: Vec<&TextureSource> = [roughness, metallic]
            .into_iter()
            .filter_map(|s| if let Source::Texture(t) = s { Some(t) } else { None })
            .collect();
        let first = sources[0];
        // One texture read through both channels: baked once.
        fn channel(s: &Source) -> Option<&TextureSource> {
            match s {
                Source::Texture(t) => Some(t),
                Source::Value(_) => None,
            }
        }
        let (r, m) = (channel(roughness), channel(metallic));
        let image = self.image(first)?;
        let (width, height) = (image.width, image.height);
        let sample = |this: &mut Self, t: &TextureSource| -> Result<Vec<f32>, Located> {
            let img = this.image(t)?;
            // Resampled to the first texture's size by the nearest texel.
            Ok((0..width * height)
                .map(|p| {
                    let (x, y) = (p % width, p / width);
                    let (sx, sy) = (x * img.width / width, y * img.height / height);
                    let k = sy * img.width + sx;
                    let v = channel_value(img, k, t.channel);
                    (f64::from(v) * pick(t.scale, t.channel) + pick(t.bias, t.channel)) as f32
                })
                .collect())
        };
        let constant = |s: &Source| match s {
            Source::Value(v) => v.x as f32,
            Source::Texture(_) => 0.0,
        };
        let rough = match r {
            Some(t) => sample(self, t)?,
            None => vec![constant(roughness); width * height],
        };
        let metal = match (m, specular_workflow) {
            (_, true) => vec![0.0; width * height],
            (Some(t), false) => sample(self, t)?,
            (None, false) => vec![constant(metallic); width * height],
        };
        // Channels of 8-bit data stay codes (docs/design.md §5.3).
        let texels = Texels::collect(width * height, Some(Encoding::Linear), |k| {
            Vec3::new(0.0, rough[k].clamp(0.0, 1.0), metal[k].clamp(0.0, 1.0))
        });
        textures.push(Texture::from_compact(width, height, texels).with_sampler(first.wrap, Filter::Linear));
        Ok(TextureRef { texture: textures.len() - 1, transform: first.transform, set: 0 })
    }

    /// The decoded image a texture reads (linear or sRGB-decoded as its
    /// colour space says for `srgb_role`), each file read once.
    fn image(&mut self, t: &TextureSource) -> Result<&RgbImage, Located> {
        self.image_as(t, false)
    }

    fn image_as(&mut self, t: &TextureSource, srgb: bool) -> Result<&RgbImage, Located> {
        let at = || format!("{}.inputs:file", t.shader);
        self.load(&t.file, &t.authored).map_err(|e| (at(), e))?;
        // Float images are scene-linear whatever the colour space says.
        if !srgb || self.images[&t.file].as_ref().is_ok_and(|image| image.scene_linear) {
            return self.images[&t.file].as_ref().map_err(|e| (at(), e.clone()));
        }
        // 8- and 16-bit values were read as value / max: decoding them
        // from sRGB texel by texel is what decoding the file as sRGB gives.
        let key = format!("{}\u{0}", t.file);
        if !self.images.contains_key(&key) {
            let decoded = self.images[&t.file]
                .as_ref()
                .map(|linear| RgbImage { texels: linear.texels.decoded_from_srgb(), ..linear.clone() });
            self.images.insert(key.clone(), decoded.map_err(Clone::clone));
        }
        self.images[&key].as_ref().map_err(|e| (at(), e.clone()))
    }

    /// Reads and decodes the texture file at `location` once (its values
    /// as stored, not yet decoded from sRGB); why it cannot be, else.
    fn load(&mut self, location: &str, authored: &str) -> Result<(), String> {
        if !self.images.contains_key(location) && authored.contains(UDIM) {
            let atlas = self.udim_atlas(location, authored);
            self.images.insert(location.to_string(), atlas);
        }
        if !self.images.contains_key(location) {
            let asset = Asset { authored: authored.to_string(), location: location.to_string() };
            let decoded = self.stage.asset_bytes(&asset, MAX_TEXTURE_BYTES).and_then(|(file, bytes)| {
                if !self.read.contains(&file) {
                    self.read.push(file);
                }
                image::decode_named(&bytes, authored, Encoding::Linear).map_err(|e| format!("'{authored}': {e}"))
            });
            self.images.insert(location.to_string(), decoded);
        }
        self.images[location].as_ref().map(drop).map_err(Clone::clone)
    }

    /// The tiles of a `<UDIM>` texture as one image (docs/design.md §5.3,
    /// "UDIM tiles"):
    /// tile 1001 + c + 10 r at column c, row r from the bottom, each tile
    /// at the first one's size (another size is resampled to it by the
    /// nearest texel), black where a tile of the grid is absent.
    fn udim_atlas(&mut self, location: &str, authored: &str) -> Result<RgbImage, String> {
        let tiles = udim_tiles(self.stage, location, authored);
        if tiles.is_empty() {
            let first = location.replace(UDIM, "1001");
            return Err(format!("no UDIM tile of '{authored}' was found (looked for {first} and the tiles after it)"));
        }
        let (cols, rows) = udim_grid(&tiles);
        // By (row, column): in tile order, so the first is the lowest tile.
        let mut images = std::collections::BTreeMap::new();
        for (c, r, tile) in tiles {
            self.load(&tile.location, &tile.authored)?;
            // The tile is kept only in the atlas.
            images.insert((r, c), self.images.remove(&tile.location).expect("loaded above")?);
        }
        let first = images.values().next().expect("at least one tile");
        let (w, h) = (first.width, first.height);
        let (width, height) = (cols * w, rows * h);
        // The tile and texel an atlas texel reads, None where no tile is.
        let source = |at: usize| -> Option<(&RgbImage, usize)> {
            let (x, y) = (at % width, at / width);
            let image = images.get(&(rows - 1 - y / h, x / w))?;
            let (x, y) = (x % w, y % h);
            Some((image, (y * image.height / h) * image.width + x * image.width / w))
        };
        // Codes where every tile is codes of one encoding (black is code 0
        // in both).
        let encodings: Vec<Option<Encoding>> = images.values().map(|i| i.texels.encoding()).collect();
        let codes_in = encodings.iter().all(|e| *e == encodings[0]).then_some(encodings[0]).flatten();
        let texels =
            Texels::collect(width * height, codes_in, |at| source(at).map_or(Vec3::ZERO, |(i, k)| i.texels.get(k)));
        let alpha = images.values().any(|i| i.alpha.is_some()).then(|| {
            let coverage = |at: usize| source(at).and_then(|(i, k)| Some(i.alpha.as_ref()?.get(k))).unwrap_or(1.0);
            let codes = images.values().all(|i| matches!(i.alpha, None | Some(Coverage::Codes(_))));
            if codes {
                Coverage::Codes((0..width * height).map(|at| (coverage(at) * 255.0).round() as u8).collect())
            } else {
                Coverage::Float((0..width * height).map(coverage).collect())
            }
        });
        Ok(RgbImage { width, height, texels, alpha, scene_linear: first.scene_linear })
    }

    /// A texture as a TextureRef: one source's channels with its scale and
    /// bias applied (a single channel read as grey), decoded from sRGB when
    /// it holds colour (`colour`) and its colour space says so or is
    /// `auto`; a `normal` map's values n in [-1, 1] stored as (n + 1) / 2,
    /// as the renderer's normal maps hold them.
    fn texture(
        &mut self,
        sources: &[&TextureSource],
        colour: bool,
        normal: bool,
        textures: &mut Vec<Texture>,
    ) -> Result<TextureRef, Located> {
        let t = sources[0];
        let srgb = match t.colour_space.as_str() {
            "sRGB" => true,
            "raw" => false,
            _ => colour && !normal,
        };
        let key = Baked {
            file: t.file.clone(),
            channels: vec![(t.channel, [hash4(t.scale), hash4(t.bias)])],
            wrap: t.wrap.map(|w| w as u8),
            srgb,
            normal,
        };
        if let Some(&index) = self.textures.get(&key) {
            return Ok(TextureRef { texture: index, transform: t.transform, set: 0 });
        }
        let image = self.image_as(t, srgb)?;
        // A texture that reads the image's codes as they are (scale 1,
        // bias 0) stays codes (docs/design.md §5.3).
        let texels = Texels::collect(image.width * image.height, image.texels.encoding(), |k| {
            let raw = match t.channel {
                Channel::Rgb => image.texels.get(k),
                c => Vec3::splat(channel_value(image, k, c)),
            };
            let v = raw.as_dvec3() * t.scale.truncate() + t.bias.truncate();
            let v = if normal { (v + 1.0) * 0.5 } else { v };
            v.as_vec3().max(Vec3::ZERO)
        });
        textures.push(Texture::from_compact(image.width, image.height, texels).with_sampler(t.wrap, Filter::Linear));
        let index = textures.len() - 1;
        self.textures.insert(key, index);
        Ok(TextureRef { texture: index, transform: t.transform, set: 0 })
    }
}

/// The token a texture's file name holds in place of its tile number.
const UDIM: &str = "<UDIM>";

/// The tiles of a `<UDIM>` texture that are there: tile 1001 + c + 10 r
/// (c and r from 0 to 9, the UDIM convention: 10 tiles a row along u) as
/// (c, r, its asset), resolved beside the same layer as the pattern.
fn udim_tiles(stage: &Stage, location: &str, authored: &str) -> Vec<(usize, usize, Asset)> {
    (0..100)
        .filter_map(|k| {
            let tile = (1001 + k).to_string();
            let asset = Asset { authored: authored.replace(UDIM, &tile), location: location.replace(UDIM, &tile) };
            stage.asset_exists(&asset).then_some((k % 10, k / 10, asset))
        })
        .collect()
}

/// The columns and rows of tiles an atlas of `tiles` spans (1 x 1 for none).
fn udim_grid(tiles: &[(usize, usize, Asset)]) -> (usize, usize) {
    tiles.iter().fold((1, 1), |(cols, rows), &(c, r, _)| (cols.max(c + 1), rows.max(r + 1)))
}

/// A texel's channel (alpha 1 where the image has none).
fn channel_value(image: &RgbImage, k: usize, channel: Channel) -> f32 {
    match channel {
        Channel::R | Channel::Rgb => image.texels.get(k).x,
        Channel::G => image.texels.get(k).y,
        Channel::B => image.texels.get(k).z,
        Channel::A => image.alpha.as_ref().map_or(1.0, |a| a.get(k)),
    }
}

/// The component of a scale or bias that applies to a single channel.
fn pick(v: DVec4, channel: Channel) -> f64 {
    match channel {
        Channel::R | Channel::Rgb => v.x,
        Channel::G => v.y,
        Channel::B => v.z,
        Channel::A => v.w,
    }
}

fn hash4(v: DVec4) -> u64 {
    v.to_array().iter().fold(0u64, |h, x| h.rotate_left(17) ^ x.to_bits())
}

/// `/Path/Prim.property` as (prim, property).
fn split(source: &str) -> (&str, &str) {
    match source.rfind('.') {
        Some(i) if !source[i..].contains('/') => (&source[..i], &source[i + 1..]),
        _ => (source, ""),
    }
}

/// The material of a surface with none bound, or whose material cannot be
/// read: UsdPreviewSurface's defaults (grey 0.18, roughness 0.5, dielectric).
pub(super) fn default_material(name: &str) -> Material {
    Material { pbr: Some(preview_defaults()), ..Material::diffuse(name, Albedo::Constant(DEFAULT_GREY)) }
}

/// UsdPreviewSurface's fallbacks as metallic-roughness parameters: a
/// dielectric (ior 1.5: F0 0.04) of roughness 0.5.
fn preview_defaults() -> PbrMaterial {
    PbrMaterial::untextured(0.0, 0.5)
}

/// A surface's display colour as its material's base colour (what
/// UsdGeom's `primvars:displayColor` means when no material is bound).
pub(super) fn display_material(name: &str, colour: Vec3) -> Material {
    let mut m = default_material(name);
    m.albedo = Albedo::Constant(colour.clamp(Vec3::ZERO, Vec3::ONE));
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;

    #[test]
    fn a_connection_source_splits_at_its_last_dot() {
        assert_eq!(split("/M/Tex.outputs:rgb"), ("/M/Tex", "outputs:rgb"));
        assert_eq!(split("/M.v2/Tex.outputs:r"), ("/M.v2/Tex", "outputs:r"));
    }

    #[test]
    fn a_transform2d_scales_then_turns_then_moves() {
        let m = Affine2::from_scale_angle_translation(Vec2::new(2.0, 1.0), 90f32.to_radians(), Vec2::new(0.5, 0.0));
        // (1, 0) -> scaled (2, 0) -> turned (0, 2) -> moved (0.5, 2).
        let p = m.transform_point2(Vec2::new(1.0, 0.0));
        assert!((p - Vec2::new(0.5, 2.0)).length() < 1e-6, "{p}");
    }
}
