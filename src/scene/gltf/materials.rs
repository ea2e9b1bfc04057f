//! A glTF material as the renderer's: the metallic-roughness BRDF's
//! factors and textures (base colour, metallic-roughness, normal),
//! KHR_materials_specular, emission (KHR_materials_emissive_strength), alpha
//! modes, and each texture's sampler and KHR_texture_transform
//! (docs/design.md §5.3; docs/scene-format.md tabulates the mapping).

use glam::{Affine2, Mat2, Vec2, Vec3, Vec4};
use gltf::texture::{MagFilter, WrappingMode};

use super::Importer;
use crate::scene::image::{Encoding, RgbImage};
use crate::scene::material::{
    Albedo, Clearcoat, Cutout, Material, NormalMap, PbrMaterial, Sheen, TextureRef, Transmission, DEFAULT_IOR,
};
use crate::scene::texels::Texels;
use crate::scene::texture::{Filter, Texture, Wrap};
use crate::scene::SceneError;

/// KHR_materials_specular's factor and colour, and the textures that
/// multiply them.
struct Specular {
    factor: f32,
    colour: Vec3,
    texture: Option<TextureRef>,
    colour_texture: Option<TextureRef>,
}

impl Importer<'_, '_> {
    /// The scene's material for a glTF material, made once.
    pub(super) fn material(&mut self, m: gltf::Material<'_>) -> Result<usize, SceneError> {
        if let Some(&index) = self.materials.get(&m.index()) {
            return Ok(index);
        }
        let location = m.index().map_or("materials (default)".to_string(), |i| format!("materials[{i}]"));
        let pbr = m.pbr_metallic_roughness();
        let base = Vec4::from_array(pbr.base_color_factor());
        let metallic = pbr.metallic_factor();
        let roughness = pbr.roughness_factor();
        for (name, value) in
            [("baseColorFactor", base.min_element()), ("metallicFactor", metallic), ("roughnessFactor", roughness)]
        {
            let max = if name == "baseColorFactor" { base.max_element() } else { value };
            if !(value.is_finite() && max.is_finite() && value >= 0.0 && max <= 1.0) {
                return Err(self.error(format!("{location}.pbrMetallicRoughness.{name}"), "must be between 0 and 1"));
            }
        }
        let base_rgb = base.truncate();
        let Specular {
            factor: specular,
            colour: specular_colour,
            texture: specular_texture,
            colour_texture: specular_colour_texture,
        } = self.specular(&m, &location)?;
        let mut coverage = None;
        let albedo = match pbr.base_color_texture() {
            None => Albedo::Constant(base_rgb),
            Some(info) => {
                let at = format!("{location}.pbrMetallicRoughness.baseColorTexture");
                match self.texture(Slot::of(&info), &at, Encoding::Srgb, |t, _| t * base_rgb)? {
                    Some((texture, image)) => {
                        coverage = image.alpha.is_some().then_some((image, texture.transform));
                        Albedo::Texture(texture)
                    }
                    None => Albedo::Constant(base_rgb),
                }
            }
        };
        let metallic_roughness = match pbr.metallic_roughness_texture() {
            None => None,
            Some(info) => {
                let at = format!("{location}.pbrMetallicRoughness.metallicRoughnessTexture");
                self.texture(Slot::of(&info), &at, Encoding::Linear, |t, _| t)?.map(|(t, _)| t)
            }
        };
        let normal_map = match m.normal_texture() {
            None => None,
            Some(info) => {
                let at = format!("{location}.normalTexture");
                if !info.scale().is_finite() {
                    return Err(self.error(format!("{at}.scale"), "must be finite"));
                }
                let slot =
                    Slot::of_normal(&info).map_err(|e| self.error(format!("{at}.extensions.{e}"), "is malformed"))?;
                self.texture(slot, &at, Encoding::Linear, |t, _| t)?.map(|(t, _)| NormalMap {
                    texture: t.texture,
                    transform: t.transform,
                    scale: info.scale(),
                    set: t.set,
                })
            }
        };
        let cutout = self.cutout(&m, &location, coverage, base.w)?;
        let (emission, emissive_texture) = self.emission(&m, &location)?;
        let (ior, transmission) = self.transmission(&m, &location)?;
        let clearcoat = self.clearcoat(&m, &location)?;
        let sheen = self.sheen(&m, &location)?;
        // KHR_materials_volume: "doubleSided has no effect on volume
        // boundaries": a refracted ray meets the solid's inside.
        let solid = transmission.as_ref().is_some_and(|t| !t.thin_walled);
        let index = self.parts.scene.materials.len();
        let name = m.name().map_or_else(|| location.clone(), str::to_string);
        self.parts.scene.materials.push(Material {
            emission,
            emissive_texture,
            emits_both_sides: m.double_sided(),
            cutout,
            pbr: Some(PbrMaterial {
                metallic,
                roughness,
                specular,
                specular_colour,
                metallic_roughness,
                specular_texture,
                specular_colour_texture,
                normal_map,
                ior,
                transmission,
                clearcoat,
                sheen,
            }),
            unlit: m.unlit(),
            culls_back_faces: !m.double_sided() && !solid,
            ..Material::diffuse(name, albedo)
        });
        self.materials.insert(m.index(), index);
        Ok(index)
    }

    /// KHR_materials_specular's factor, colour and their textures (1,
    /// white and none without the extension): the dielectric's reflectance
    /// at normal incidence is 0.04 (IOR 1.5) times the colour, times the
    /// factor.
    fn specular(&mut self, m: &gltf::Material<'_>, location: &str) -> Result<Specular, SceneError> {
        let (specular, specular_colour) = m
            .specular()
            .map_or((1.0, Vec3::ONE), |s| (s.specular_factor(), Vec3::from_array(s.specular_color_factor())));
        if !(specular.is_finite()
            && specular_colour.is_finite()
            && specular >= 0.0
            && specular_colour.min_element() >= 0.0)
        {
            return Err(self.error(format!("{location}.extensions.KHR_materials_specular"), "must be finite and >= 0"));
        }
        let at = format!("{location}.extensions.KHR_materials_specular");
        // The extension's schema caps the factor at 1: above it the
        // diffuse weight 1 - max(F) would be negative.
        let specular = if specular > 1.0 {
            self.warn(&format!("{at}.specularFactor"), &format!("{specular} clamped to 1, the extension's maximum"));
            1.0
        } else {
            specular
        };
        let specular_texture = match m.specular().and_then(|s| s.specular_texture()) {
            None => None,
            // The factor is the texture's alpha channel (linear).
            Some(info) => self
                .texture(Slot::of(&info), &format!("{at}.specularTexture"), Encoding::Linear, |_, a| Vec3::splat(a))?
                .map(|(t, _)| t),
        };
        let specular_colour_texture = match m.specular().and_then(|s| s.specular_color_texture()) {
            None => None,
            Some(info) => {
                let at = format!("{at}.specularColorTexture");
                self.texture(Slot::of(&info), &at, Encoding::Srgb, |t, _| t)?.map(|(t, _)| t)
            }
        };
        Ok(Specular {
            factor: specular,
            colour: specular_colour,
            texture: specular_texture,
            colour_texture: specular_colour_texture,
        })
    }

    /// The cut-out of glTF's alphaMode (MASK at its cutoff; BLEND a partial
    /// coverage, docs/design.md §5.9): the base colour texture's alpha (if
    /// it has one, `coverage`, with its transform) times the base colour
    /// factor's `alpha_factor`; None where nothing is cut out.
    fn cutout(
        &mut self,
        m: &gltf::Material<'_>,
        location: &str,
        coverage: Option<(std::rc::Rc<RgbImage>, Affine2)>,
        alpha_factor: f32,
    ) -> Result<Option<Cutout>, SceneError> {
        // Some(cutoff) for a mask, Some(None) for partial coverage.
        let cutoff = match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => return Ok(None),
            gltf::material::AlphaMode::Mask => Some(m.alpha_cutoff().unwrap_or(0.5)),
            gltf::material::AlphaMode::Blend => None,
        };
        if cutoff.is_some_and(|c| !c.is_finite()) {
            return Err(self.error(format!("{location}.alphaCutoff"), "must be finite"));
        }
        // The image's alpha times the factor's, made only for a mask.
        let (alpha, width, height, transform) = match coverage {
            Some((image, transform)) => {
                let a = image.alpha.as_ref().expect("an image with alpha");
                let texels = image.width * image.height;
                ((0..texels).map(|k| a.get(k) * alpha_factor).collect(), image.width, image.height, transform)
            }
            None => (vec![alpha_factor], 1, 1, Affine2::IDENTITY),
        };
        // Only a mask that removes something costs Embree a filter call.
        let removes = |a: f32| cutoff.map_or(a < 1.0, |cutoff| a < cutoff);
        Ok(alpha.iter().any(|&a| removes(a)).then_some(Cutout {
            alpha,
            width: width as u32,
            height: height as u32,
            transform,
            cutoff,
        }))
    }

    /// KHR_materials_ior's index of refraction (1.5 without it), and
    /// KHR_materials_transmission's factor and texture with
    /// KHR_materials_volume's thickness and attenuation (docs/design.md
    /// §5.8). A rough transmitting surface's transmission is as rough as
    /// its reflection (Walter et al. 2007's BTDF); the thickness texture is
    /// not read: the geometry is the volume, as in a path tracer, and only
    /// whether the thickness factor is 0 (thin-walled) matters.
    fn transmission(
        &mut self,
        m: &gltf::Material<'_>,
        location: &str,
    ) -> Result<(f32, Option<Transmission>), SceneError> {
        let ior = m.ior().unwrap_or(DEFAULT_IOR);
        let at = format!("{location}.extensions.KHR_materials_ior.ior");
        // The extension allows 0 besides [1, inf) (reflectance 1, for
        // specular-glossiness materials).
        if !(ior.is_finite() && (ior == 0.0 || ior >= 1.0)) {
            return Err(self.error(at, format!("must be 0 or at least 1, got {ior}")));
        }
        let Some(t) = m.transmission() else { return Ok((ior, None)) };
        let at = format!("{location}.extensions.KHR_materials_transmission");
        let factor = t.transmission_factor();
        if !(factor.is_finite() && (0.0..=1.0).contains(&factor)) {
            return Err(
                self.error(format!("{at}.transmissionFactor"), format!("must be between 0 and 1, got {factor}"))
            );
        }
        let texture = match t.transmission_texture() {
            None => None,
            // The factor is the texture's red channel (linear).
            Some(info) => self
                .texture(Slot::of(&info), &format!("{at}.transmissionTexture"), Encoding::Linear, |t, _| {
                    Vec3::splat(t.x)
                })?
                .map(|(t, _)| t),
        };
        if factor == 0.0 && texture.is_none() {
            return Ok((ior, None));
        }
        let mut transmission = Transmission { texture, ..Transmission::thin(factor) };
        if let Some(volume) = m.volume() {
            let at = format!("{location}.extensions.KHR_materials_volume");
            let (thickness, distance) = (volume.thickness_factor(), volume.attenuation_distance());
            let colour = Vec3::from_array(volume.attenuation_color());
            if !(thickness.is_finite() && thickness >= 0.0) {
                return Err(self.error(format!("{at}.thicknessFactor"), format!("must be >= 0, got {thickness}")));
            }
            if distance.is_nan() || distance <= 0.0 {
                return Err(self.error(format!("{at}.attenuationDistance"), format!("must be > 0, got {distance}")));
            }
            if !(colour.is_finite() && colour.min_element() >= 0.0 && colour.max_element() <= 1.0) {
                return Err(self.error(format!("{at}.attenuationColor"), "must be between 0 and 1"));
            }
            // ior 0 bends nothing: its solid is drawn as a thin wall.
            transmission.thin_walled = thickness == 0.0 || ior < 1.0;
            transmission.attenuation_colour = colour;
            transmission.attenuation_distance = distance;
        }
        Ok((ior, Some(transmission)))
    }

    /// KHR_materials_clearcoat's layer (docs/design.md §5.10), None without
    /// the extension or at a factor of 0: its factors, their textures and
    /// its own normal texture (without one the coat is smooth over a
    /// normal-mapped base, as the extension says).
    fn clearcoat(&mut self, m: &gltf::Material<'_>, location: &str) -> Result<Option<Clearcoat>, SceneError> {
        const NAME: &str = "KHR_materials_clearcoat";
        let Some(json) = m.extension_value(NAME) else { return Ok(None) };
        let at = format!("{location}.extensions.{NAME}");
        let factor = self.unit_factor(json, &at, "clearcoatFactor", 0.0)?;
        let roughness = self.unit_factor(json, &at, "clearcoatRoughnessFactor", 0.0)?;
        // The factors are the textures' red and green channels (linear).
        let texture =
            self.extension_texture(json, &at, "clearcoatTexture", Encoding::Linear, |t, _| Vec3::splat(t.x))?;
        let roughness_texture =
            self.extension_texture(json, &at, "clearcoatRoughnessTexture", Encoding::Linear, |t, _| Vec3::splat(t.y))?;
        let normal_map = match json.get("clearcoatNormalTexture") {
            None => None,
            Some(info) => {
                let field = format!("{at}.clearcoatNormalTexture.scale");
                let scale = match info.get("scale") {
                    None => 1.0,
                    Some(v) => match v.as_f64().filter(|s| s.is_finite()) {
                        Some(s) => s as f32,
                        None => return Err(self.error(field, "must be a finite number")),
                    },
                };
                self.extension_texture(json, &at, "clearcoatNormalTexture", Encoding::Linear, |t, _| t)?
                    .map(|t| NormalMap { texture: t.texture, transform: t.transform, scale, set: t.set })
            }
        };
        if factor == 0.0 {
            return Ok(None);
        }
        Ok(Some(Clearcoat { factor, texture, roughness, roughness_texture, normal_map }))
    }

    /// KHR_materials_sheen's layer (docs/design.md §5.10), None without the
    /// extension or with a black colour factor (the extension: "the whole
    /// sheen layer is disabled").
    fn sheen(&mut self, m: &gltf::Material<'_>, location: &str) -> Result<Option<Sheen>, SceneError> {
        const NAME: &str = "KHR_materials_sheen";
        let Some(json) = m.extension_value(NAME) else { return Ok(None) };
        let at = format!("{location}.extensions.{NAME}");
        let colour = match json.get("sheenColorFactor") {
            None => Vec3::ZERO,
            Some(value) => match serde_json::from_value::<[f32; 3]>(value.clone()) {
                Ok(c) if c.iter().all(|c| (0.0..=1.0).contains(c)) => Vec3::from_array(c),
                _ => return Err(self.error(format!("{at}.sheenColorFactor"), "must be three numbers between 0 and 1")),
            },
        };
        let roughness = self.unit_factor(json, &at, "sheenRoughnessFactor", 0.0)?;
        let colour_texture = self.extension_texture(json, &at, "sheenColorTexture", Encoding::Srgb, |t, _| t)?;
        // The roughness is the texture's alpha channel (linear).
        let roughness_texture =
            self.extension_texture(json, &at, "sheenRoughnessTexture", Encoding::Linear, |_, a| Vec3::splat(a))?;
        if colour == Vec3::ZERO {
            return Ok(None);
        }
        Ok(Some(Sheen { colour, colour_texture, roughness, roughness_texture }))
    }

    /// A factor between 0 and 1 of an extension's JSON (`default` where
    /// absent), or an error naming the field.
    fn unit_factor(&self, json: &serde_json::Value, at: &str, field: &str, default: f32) -> Result<f32, SceneError> {
        match json.get(field) {
            None => Ok(default),
            Some(value) => match value.as_f64() {
                Some(x) if (0.0..=1.0).contains(&x) => Ok(x as f32),
                _ => Err(self.error(format!("{at}.{field}"), format!("must be a number between 0 and 1, got {value}"))),
            },
        }
    }

    /// A texture info of an extension's JSON (`index`, `texCoord`, and its
    /// KHR_texture_transform), read as [`Importer::texture`] reads the
    /// core's; None where absent or unreadable (warned).
    fn extension_texture(
        &mut self,
        json: &serde_json::Value,
        at: &str,
        field: &str,
        encoding: Encoding,
        map: impl Fn(Vec3, f32) -> Vec3,
    ) -> Result<Option<TextureRef>, SceneError> {
        let Some(info) = json.get(field) else { return Ok(None) };
        let at = format!("{at}.{field}");
        let index = info.get("index").and_then(serde_json::Value::as_u64);
        let texture = index.and_then(|i| self.doc.textures().nth(usize::try_from(i).ok()?));
        let Some(texture) = texture else {
            return Err(self.error(format!("{at}.index"), "must name one of the file's textures"));
        };
        let tex_coord = match info.get("texCoord") {
            None => 0,
            Some(value) => match value.as_u64().and_then(|t| u32::try_from(t).ok()) {
                Some(t) => t,
                None => return Err(self.error(format!("{at}.texCoord"), "must be a non-negative integer")),
            },
        };
        const KHR: &str = "KHR_texture_transform";
        let transform = match info.get("extensions").and_then(|e| e.get(KHR)) {
            None => None,
            Some(value) => {
                let t: gltf::json::extensions::texture::TextureTransform = serde_json::from_value(value.clone())
                    .map_err(|_| self.error(format!("{at}.extensions.{KHR}"), "is malformed"))?;
                Some(KhrTextureTransform::from(&t))
            }
        };
        let slot = Slot { texture, tex_coord, transform };
        Ok(self.texture(slot, &at, encoding, map)?.map(|(t, _)| t))
    }

    /// The emitted radiance (emissiveFactor x KHR_materials_emissive_strength,
    /// W/(m^2 sr)) and the emissive texture multiplying it.
    pub(super) fn emission(
        &mut self,
        m: &gltf::Material<'_>,
        location: &str,
    ) -> Result<(Vec3, Option<TextureRef>), SceneError> {
        let strength = m.emissive_strength().unwrap_or(1.0);
        let emission = Vec3::from_array(m.emissive_factor()) * strength;
        if !emission.is_finite() || emission.min_element() < 0.0 {
            return Err(self.error(
                format!("{location}.emissiveFactor"),
                format!("emission must be finite and >= 0, got {emission}"),
            ));
        }
        let emissive_texture = match m.emissive_texture() {
            Some(info) if emission != Vec3::ZERO => {
                let at = format!("{location}.emissiveTexture");
                self.texture(Slot::of(&info), &at, Encoding::Srgb, |t, _| t)?.map(|(t, _)| t)
            }
            // A texture times a zero factor emits nothing: not read.
            _ => None,
        };
        Ok((emission, emissive_texture))
    }
    /// A texture of the file as the renderer's: its image decoded as
    /// `encoding` says and mapped texel by texel through `map` (colour and
    /// alpha, 1 where the image has none), read with its sampler's wrap
    /// modes and magnification filter, through the slot's texture
    /// coordinates and KHR_texture_transform. Returns the reference and the
    /// decoded image.
    pub(super) fn texture(
        &mut self,
        slot: Slot<'_>,
        at: &str,
        encoding: Encoding,
        map: impl Fn(Vec3, f32) -> Vec3,
    ) -> Result<Option<(TextureRef, std::rc::Rc<RgbImage>)>, SceneError> {
        // KHR_texture_transform's texCoord overrides the texture info's.
        let tex_coord = slot.transform.and_then(|t| t.tex_coord).unwrap_or(slot.tex_coord);
        let set = if tex_coord <= 1 {
            tex_coord as usize
        } else {
            self.warn(at, &format!("uses TEXCOORD_{tex_coord}: read with TEXCOORD_0 (sets 0 and 1 are read)"));
            0
        };
        let transform = uv_transform(slot.transform);
        if !(transform.matrix2.is_finite() && transform.translation.is_finite()) {
            return Err(self.error(format!("{at}.extensions.KHR_texture_transform"), "must be finite"));
        }
        let texture = slot.texture;
        // An image that cannot be read (a missing file) is drawn around, as
        // glTF viewers do: the factor alone.
        let image = match self.data.image(&texture.source(), at, encoding) {
            Ok(image) => image,
            Err(e) => {
                self.parts.scene.incomplete.push(format!("{e}: the factor alone is used"));
                return Ok(None);
            }
        };
        let sampler = texture.sampler();
        let wrap = |mode: WrappingMode| match mode {
            WrappingMode::Repeat => Wrap::Repeat,
            WrappingMode::ClampToEdge => Wrap::ClampToEdge,
            WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        };
        let filter = match sampler.mag_filter() {
            Some(MagFilter::Nearest) => Filter::Nearest,
            Some(MagFilter::Linear) | None => Filter::Linear,
        };
        // A map that keeps the image's codes (a factor of 1) keeps them
        // (docs/design.md §5.3, "Textures in memory").
        let alpha = |k: usize| image.alpha.as_ref().map_or(1.0, |a| a.get(k));
        let texels = Texels::collect(image.width * image.height, image.texels.encoding(), |k| {
            map(image.texels.get(k), alpha(k))
        });
        let texture = Texture::from_compact(image.width, image.height, texels)
            .with_sampler([wrap(sampler.wrap_s()), wrap(sampler.wrap_t())], filter);
        self.parts.scene.textures.push(texture);
        Ok(Some((TextureRef { texture: self.parts.scene.textures.len() - 1, transform, set }, image)))
    }
}

/// The map from a mesh's glTF uv to `Texture::lookup`'s: KHR_texture_transform
/// (translation x rotation x scale, as the extension defines it), then v
/// flipped (glTF's v = 0 is the image's top row, the lookup's its bottom).
pub(super) fn uv_transform(transform: Option<KhrTextureTransform>) -> Affine2 {
    let flip = Affine2::from_mat2_translation(Mat2::from_diagonal(Vec2::new(1.0, -1.0)), Vec2::new(0.0, 1.0));
    let Some(t) = transform else { return flip };
    let (sin, cos) = t.rotation.sin_cos();
    let rotation = Mat2::from_cols(Vec2::new(cos, -sin), Vec2::new(sin, cos));
    let khr = Affine2::from_mat2_translation(
        rotation * Mat2::from_diagonal(Vec2::from_array(t.scale)),
        Vec2::from_array(t.offset),
    );
    flip * khr
}

/// KHR_texture_transform's fields (the extension's defaults where absent).
#[derive(Debug, Clone, Copy)]
pub(super) struct KhrTextureTransform {
    offset: [f32; 2],
    rotation: f32,
    scale: [f32; 2],
    tex_coord: Option<u32>,
}

impl KhrTextureTransform {
    #[cfg(test)]
    pub(super) fn new(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> Self {
        Self { offset, rotation, scale, tex_coord: None }
    }
}

impl From<&gltf::json::extensions::texture::TextureTransform> for KhrTextureTransform {
    fn from(t: &gltf::json::extensions::texture::TextureTransform) -> Self {
        Self { offset: t.offset.0, rotation: t.rotation.0, scale: t.scale.0, tex_coord: t.tex_coord }
    }
}

/// Where a material reads a texture: the texture, its `texCoord`, and its
/// KHR_texture_transform.
pub(super) struct Slot<'a> {
    texture: gltf::Texture<'a>,
    tex_coord: u32,
    transform: Option<KhrTextureTransform>,
}

impl<'a> Slot<'a> {
    fn of(info: &gltf::texture::Info<'a>) -> Self {
        let transform = info.texture_transform().map(|t| KhrTextureTransform {
            offset: t.offset(),
            rotation: t.rotation(),
            scale: t.scale(),
            tex_coord: t.tex_coord(),
        });
        Self { texture: info.texture(), tex_coord: info.tex_coord(), transform }
    }

    /// A normal texture's slot: the `gltf` crate models no transform on
    /// it, so the extension's JSON is read here. Err names the extension
    /// when its JSON is malformed.
    fn of_normal(info: &gltf::material::NormalTexture<'a>) -> Result<Self, &'static str> {
        const KHR: &str = "KHR_texture_transform";
        let transform = match info.extension_value(KHR) {
            None => None,
            Some(value) => {
                let t: gltf::json::extensions::texture::TextureTransform =
                    serde_json::from_value(value.clone()).map_err(|_| KHR)?;
                Some(KhrTextureTransform::from(&t))
            }
        };
        Ok(Self { texture: info.texture(), tex_coord: info.tex_coord(), transform })
    }
}
