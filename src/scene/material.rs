//! Materials: diffuse (constant or textured albedo) plus Phong specular, plus
//! a perfect mirror layer: [LC05]'s model; or glTF's metallic-roughness
//! material (`shading::pbr`), whose base colour is the albedo
//! (docs/design.md §5.3; their bounds over a cluster, docs/design.md §8.3).

use std::f32::consts::PI;

use glam::{Affine2, Vec2, Vec3};

use super::texture::Texture;

#[derive(Debug, Clone)]
pub enum Albedo {
    Constant(Vec3),
    Texture(TextureRef),
}

/// A shading point's texture coordinates: sets 0 and 1 (glTF's
/// `TEXCOORD_0` and `TEXCOORD_1`; set 1 is set 0 where a mesh has one set),
/// and how each changes from one pixel to the next along the film's x and
/// y (pbrt-v4's dudx, dvdx, dudy, dvdy), which choose the MIP level
/// (docs/design.md §5.3, "MIP maps"): zero where the point is not seen
/// through a pixel, which reads the image itself.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TexCoords {
    pub uv: [Vec2; 2],
    pub duv_dx: [Vec2; 2],
    pub duv_dy: [Vec2; 2],
}

impl TexCoords {
    /// Coordinates `uv` (sets 0 and 1) of no footprint.
    #[must_use]
    pub fn at(uv: [Vec2; 2]) -> Self {
        Self { uv, ..Self::default() }
    }

    /// The same coordinates without their footprint: what reads the image
    /// itself, as light sampling does (emission, docs/design.md §5.3).
    #[must_use]
    pub fn unfiltered(&self) -> Self {
        Self::at(self.uv)
    }
}

/// A texture a material reads: an index into `Scene::textures`, the map
/// from the mesh's uv to the texture's (repeats, glTF's v axis and
/// KHR_texture_transform) and which texture coordinates it reads (glTF's
/// `texCoord`: 0 or 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TextureRef {
    pub texture: usize,
    pub transform: Affine2,
    pub set: usize,
}

impl TextureRef {
    /// The texture's value at a point of texture coordinates `uvs`,
    /// filtered over their footprint (the transform's linear part carries
    /// the footprint into the texture's coordinates).
    #[must_use]
    pub fn lookup(&self, uvs: &TexCoords, textures: &[Texture]) -> Vec3 {
        let set = self.set.min(1);
        let uv = self.transform.transform_point2(uvs.uv[set]);
        let linear = self.transform.matrix2;
        textures[self.texture].filtered(uv, linear * uvs.duv_dx[set], linear * uvs.duv_dy[set])
    }
}

#[derive(Debug, Clone)]
pub struct Material {
    pub name: String,
    pub albedo: Albedo,
    /// Phong k_s.
    pub specular: Vec3,
    /// Phong exponent n.
    pub exponent: f32,
    /// Perfect mirror reflectance.
    pub mirror: Vec3,
    /// Emitted radiance from the front side, W/(m^2 sr) (area-light
    /// emitters); times `emissive_texture` where there is one.
    pub emission: Vec3,
    /// glTF's `emissiveTexture` (sRGB decoded to linear): the emitted
    /// radiance at a point is `emission` times its texel (docs/design.md
    /// §6.1, textured emitters).
    pub emissive_texture: Option<TextureRef>,
    /// Whether `emission` leaves the back side too (glTF's double-sided
    /// emissive materials, as Cycles renders them).
    pub emits_both_sides: bool,
    /// Where the surface is cut out (glTF's alphaMode MASK): rays pass
    /// through where the coverage is below the cutoff; or partially there
    /// (BLEND): rays pass with probability 1 - coverage.
    pub cutout: Option<Cutout>,
    /// glTF's metallic-roughness BRDF instead of diffuse + Phong: `albedo`
    /// is its base colour, and `specular`, `exponent` and `mirror` are 0.
    pub pbr: Option<PbrMaterial>,
    /// glTF's KHR_materials_unlit: the camera (and mirrors) see the base
    /// colour as radiance, W/(m^2 sr); it reflects no light, and lights
    /// nothing unless `emission` is also set.
    pub unlit: bool,
    /// glTF's `doubleSided: false`: camera rays (and mirror rays) pass
    /// through the back of its triangles; shadow rays do not.
    pub culls_back_faces: bool,
}

/// The metallic-roughness parameters of a material (glTF 2.0's
/// `pbrMetallicRoughness` and KHR_materials_specular).
#[derive(Debug, Clone)]
pub struct PbrMaterial {
    pub metallic: f32,
    pub roughness: f32,
    /// KHR_materials_specular's factor and colour (1 and white without it).
    pub specular: f32,
    pub specular_colour: Vec3,
    /// glTF's `metallicRoughnessTexture` (linear; G roughness, B metallic,
    /// multiplying the factors).
    pub metallic_roughness: Option<TextureRef>,
    /// KHR_materials_specular's `specularTexture`: its alpha channel
    /// (linear) multiplies `specular`; the texture holds that alpha in all
    /// three channels.
    pub specular_texture: Option<TextureRef>,
    /// KHR_materials_specular's `specularColorTexture` (sRGB decoded to
    /// linear), multiplying `specular_colour`.
    pub specular_colour_texture: Option<TextureRef>,
    /// glTF's `normalTexture`: tangent-space normals perturbing the
    /// shading normal, where the mesh has tangents.
    pub normal_map: Option<NormalMap>,
    /// KHR_materials_ior's index of refraction of the dielectric (1.5
    /// without it): its reflectance at normal incidence, and how a
    /// transmitted ray bends.
    pub ior: f32,
    /// KHR_materials_transmission (with KHR_materials_volume): None for an
    /// opaque surface.
    pub transmission: Option<Transmission>,
    /// KHR_materials_clearcoat (UsdPreviewSurface's `clearcoat`): None
    /// without a coat.
    pub clearcoat: Option<Clearcoat>,
    /// KHR_materials_sheen: None without a sheen.
    pub sheen: Option<Sheen>,
}

/// A clear coat over the base (KHR_materials_clearcoat; docs/design.md
/// §5.10): a GGX layer of IOR 1.5 whose Fresnel weight at the view takes
/// that share of the base away.
#[derive(Debug, Clone)]
pub struct Clearcoat {
    /// `clearcoatFactor`, 0 to 1, times `clearcoatTexture`'s red channel
    /// (linear; the texture holds it in all three channels).
    pub factor: f32,
    pub texture: Option<TextureRef>,
    /// `clearcoatRoughnessFactor`, 0 to 1, times
    /// `clearcoatRoughnessTexture`'s green channel (in all three).
    pub roughness: f32,
    pub roughness_texture: Option<TextureRef>,
    /// `clearcoatNormalTexture`: the coat's own normal map. Without one
    /// the coat is smooth over a normal-mapped base: its normal is the
    /// interpolated one, as the extension says.
    pub normal_map: Option<NormalMap>,
}

/// A sheen over the base (KHR_materials_sheen; docs/design.md §5.10):
/// the Charlie microfibre lobe, the base scaled by what it leaves.
#[derive(Debug, Clone)]
pub struct Sheen {
    /// `sheenColorFactor` times `sheenColorTexture` (sRGB decoded).
    pub colour: Vec3,
    pub colour_texture: Option<TextureRef>,
    /// `sheenRoughnessFactor` times `sheenRoughnessTexture`'s alpha
    /// channel (linear; in all three).
    pub roughness: f32,
    pub roughness_texture: Option<TextureRef>,
}

/// How a metallic-roughness dielectric lets light through
/// (KHR_materials_transmission and KHR_materials_volume; docs/design.md
/// §5.8): the transmitted fraction of its base takes the place of that
/// fraction of its diffuse lobe, and is traced as a delta bounce.
#[derive(Debug, Clone)]
pub struct Transmission {
    /// `transmissionFactor`, 0 to 1.
    pub factor: f32,
    /// `transmissionTexture` (linear), its red channel multiplying the
    /// factor; the texture holds it in all three channels.
    pub texture: Option<TextureRef>,
    /// A thin wall (KHR_materials_volume absent, or its thickness 0): a
    /// ray passes straight through, as the extension defines. Otherwise
    /// the mesh bounds a solid: rays refract entering and leaving it, by
    /// `PbrMaterial::ior`.
    pub thin_walled: bool,
    /// Beer-Lambert absorption inside a solid: white light keeps
    /// `attenuation_colour` after `attenuation_distance` metres
    /// (infinite: none).
    pub attenuation_colour: Vec3,
    pub attenuation_distance: f32,
}

impl Transmission {
    /// A thin wall that transmits `factor` of the base, untextured.
    #[must_use]
    pub fn thin(factor: f32) -> Self {
        Self {
            factor,
            texture: None,
            thin_walled: true,
            attenuation_colour: Vec3::ONE,
            attenuation_distance: f32::INFINITY,
        }
    }

    /// The fraction of light that keeps going after `distance` metres
    /// inside the solid, per channel: attenuation_colour ^ (distance /
    /// attenuation_distance) (KHR_materials_volume's Beer-Lambert law).
    #[must_use]
    pub fn interior_transmittance(&self, distance: f32) -> Vec3 {
        if self.thin_walled || !self.attenuation_distance.is_finite() {
            return Vec3::ONE;
        }
        let exponent = distance / self.attenuation_distance;
        Vec3::from_array(self.attenuation_colour.to_array().map(|c| if c > 0.0 { c.powf(exponent) } else { 0.0 }))
    }
}

impl PbrMaterial {
    /// glTF's defaults: metallic and roughness `metallic`, `roughness`,
    /// no texture, KHR_materials_specular's factor and colour 1 and white,
    /// IOR 1.5, opaque.
    #[must_use]
    pub fn untextured(metallic: f32, roughness: f32) -> Self {
        Self {
            metallic,
            roughness,
            specular: 1.0,
            specular_colour: Vec3::ONE,
            metallic_roughness: None,
            specular_texture: None,
            specular_colour_texture: None,
            normal_map: None,
            ior: DEFAULT_IOR,
            transmission: None,
            clearcoat: None,
            sheen: None,
        }
    }
}

/// glTF's index of refraction without KHR_materials_ior.
pub const DEFAULT_IOR: f32 = 1.5;

/// A tangent-space normal texture (linear; x, y, z = 2 texel - 1, +X along
/// increasing u, +Y up the image, +Z out of the surface), its x and y
/// scaled by `scale` (glTF's `normalTexture.scale`).
#[derive(Debug, Clone)]
pub struct NormalMap {
    /// An index into `Scene::textures`, and the map from the mesh's uv to
    /// the texture's.
    pub texture: usize,
    pub transform: Affine2,
    pub scale: f32,
    /// Which texture coordinates it reads.
    pub set: usize,
}

/// Coverage texels and the cutoff below which a surface is absent, or none:
/// partial coverage (docs/design.md §5.9).
#[derive(Debug, Clone)]
pub struct Cutout {
    /// `width * height` coverages, row 0 at the top.
    pub alpha: Vec<f32>,
    pub width: u32,
    pub height: u32,
    /// From the mesh's uv to the lookup's, as [`Albedo::Texture`]'s.
    pub transform: Affine2,
    pub cutoff: Option<f32>,
}

impl Material {
    /// A diffuse material of `albedo` alone: no Phong, mirror or emission
    /// layer, no cut-out, not metallic-roughness. Other materials are this
    /// with fields replaced (`Material { pbr, ..Material::diffuse(..) }`).
    #[must_use]
    pub fn diffuse(name: impl Into<String>, albedo: Albedo) -> Self {
        Self {
            name: name.into(),
            albedo,
            specular: Vec3::ZERO,
            exponent: 0.0,
            mirror: Vec3::ZERO,
            emission: Vec3::ZERO,
            emissive_texture: None,
            emits_both_sides: false,
            cutout: None,
            pbr: None,
            unlit: false,
            culls_back_faces: false,
        }
    }

    /// Diffuse albedo k_d at a surface point.
    #[must_use]
    pub fn albedo_at(&self, uvs: &TexCoords, textures: &[Texture]) -> Vec3 {
        match &self.albedo {
            Albedo::Constant(c) => *c,
            Albedo::Texture(t) => t.lookup(uvs, textures),
        }
    }

    /// Emitted radiance from the front side at a point of texture
    /// coordinates `uvs`, W/(m^2 sr).
    #[must_use]
    pub fn emission_at(&self, uvs: &TexCoords, textures: &[Texture]) -> Vec3 {
        match &self.emissive_texture {
            None => self.emission,
            // Unfiltered, as light sampling reads it: a path that hits an
            // emitter and one that samples it must see the same radiance.
            Some(t) => self.emission * t.lookup(&uvs.unfiltered(), textures),
        }
    }

    #[must_use]
    pub fn has_specular(&self) -> bool {
        self.specular != Vec3::ZERO
    }

    #[must_use]
    pub fn has_mirror(&self) -> bool {
        self.mirror != Vec3::ZERO
    }

    /// Whether the surface bounds a transmitting solid (not a thin wall):
    /// rays refract into it and meet its surface again from inside.
    #[must_use]
    pub fn bounds_a_solid(&self) -> bool {
        self.pbr.as_ref().and_then(|p| p.transmission.as_ref()).is_some_and(|t| !t.thin_walled)
    }
}

/// The Phong lobe's normalisation, (n + 2) / (2 pi), so that k_s is the
/// lobe's directional-hemispherical reflectance at normal incidence.
#[must_use]
pub fn phong_normalisation(exponent: f32) -> f32 {
    (exponent + 2.0) / (2.0 * PI)
}

/// Mirror direction of `wo` about `n` (both unit, pointing away from the surface).
#[must_use]
pub fn reflect(wo: Vec3, n: Vec3) -> Vec3 {
    2.0 * n.dot(wo) * n - wo
}
