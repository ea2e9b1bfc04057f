//! The `[materials]` section: diffuse albedo (constant or a PNG texture),
//! Phong specular and mirror layers; or glTF's metallic-roughness BRDF
//! (`type = "pbr"`), its base colour the albedo.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{Affine2, Vec2, Vec3};

use super::Validator;
use crate::scene::file::{MaterialKind, MaterialSpec, SceneFile};
use crate::scene::image::{self, Encoding};
use crate::scene::material::{PbrMaterial, TextureRef};
use crate::scene::texture::Texture;
use crate::scene::{Albedo, Material, SceneError};

/// The materials, and each one's index by name.
pub(super) fn materials(
    v: &Validator<'_>,
    base: &Path,
    spec: &SceneFile,
    inputs: &mut Vec<PathBuf>,
    textures: &mut Vec<Texture>,
) -> Result<(Vec<Material>, HashMap<String, usize>), SceneError> {
    let mut materials = Vec::new();
    let mut material_index = HashMap::new();
    for (name, m) in &spec.materials {
        let field = |f: &str| format!("materials.{name}.{f}");
        let albedo = match (&m.albedo, &m.texture) {
            (Some(_), Some(_)) => {
                return Err(v.error(&field("texture"), "give either albedo or texture, not both"));
            }
            (None, None) => return Err(v.error(&field("albedo"), "missing: give albedo or texture")),
            (Some(a), None) => Albedo::Constant(v.unit_rgb(*a, &field("albedo"))?),
            (None, Some(t)) => {
                let scale = Vec2::from_array(m.texture_scale);
                v.check(scale.is_finite() && scale.min_element() > 0.0, &field("texture_scale"), || {
                    format!("must be finite and > 0, got {:?}", m.texture_scale)
                })?;
                let texture_path = base.join(t);
                inputs.push(texture_path.clone());
                let image = image::read_texture(&texture_path, Encoding::Srgb)
                    .map_err(|e| SceneError::new(&texture_path, field("texture"), e.to_string()))?;
                textures.push(Texture::from_image(image));
                Albedo::Texture(TextureRef {
                    texture: textures.len() - 1,
                    transform: Affine2::from_scale(scale),
                    set: 0,
                })
            }
        };
        if m.kind == MaterialKind::Pbr {
            let pbr = pbr(v, base, m, &field, inputs, textures)?;
            material_index.insert(name.clone(), materials.len());
            materials.push(Material { pbr: Some(pbr), ..Material::diffuse(name.clone(), albedo) });
            continue;
        }
        for (name, given) in [
            ("metallic", m.metallic.is_some()),
            ("roughness", m.roughness.is_some()),
            ("metallic_roughness_texture", m.metallic_roughness_texture.is_some()),
        ] {
            v.check(!given, &field(name), || "only a type = \"pbr\" material has it".to_string())?;
        }
        let specular = v.unit_rgb(m.specular, &field("specular"))?;
        v.check(m.exponent.is_finite() && (0.0..=1e6).contains(&m.exponent), &field("exponent"), || {
            format!("must be between 0 and 1e6, got {}", m.exponent)
        })?;
        let mirror = v.unit_rgb(m.mirror, &field("mirror"))?;
        material_index.insert(name.clone(), materials.len());
        materials.push(Material { specular, exponent: m.exponent, mirror, ..Material::diffuse(name.clone(), albedo) });
    }
    Ok((materials, material_index))
}

/// A `type = "pbr"` material's parameters: metallic and roughness (default
/// 1, glTF's), optionally a metallic-roughness texture; the Phong fields
/// refused.
fn pbr(
    v: &Validator<'_>,
    base: &Path,
    m: &MaterialSpec,
    field: &impl Fn(&str) -> String,
    inputs: &mut Vec<PathBuf>,
    textures: &mut Vec<Texture>,
) -> Result<PbrMaterial, SceneError> {
    for (name, given) in
        [("specular", m.specular != [0.0; 3]), ("exponent", m.exponent != 0.0), ("mirror", m.mirror != [0.0; 3])]
    {
        v.check(!given, &field(name), || "a type = \"pbr\" material has no Phong or mirror layer".to_string())?;
    }
    let unit = |value: Option<f32>, name: &str| -> Result<f32, SceneError> {
        let value = value.unwrap_or(1.0);
        v.check(value.is_finite() && (0.0..=1.0).contains(&value), &field(name), || {
            format!("must be between 0 and 1, got {value}")
        })?;
        Ok(value)
    };
    let (metallic, roughness) = (unit(m.metallic, "metallic")?, unit(m.roughness, "roughness")?);
    let metallic_roughness = match &m.metallic_roughness_texture {
        None => None,
        Some(t) => {
            let path = base.join(t);
            inputs.push(path.clone());
            let image = image::read_texture(&path, Encoding::Linear)
                .map_err(|e| SceneError::new(&path, field("metallic_roughness_texture"), e.to_string()))?;
            textures.push(Texture::from_image(image));
            Some(TextureRef {
                texture: textures.len() - 1,
                transform: Affine2::from_scale(Vec2::from_array(m.texture_scale)),
                set: 0,
            })
        }
    };
    Ok(PbrMaterial {
        metallic,
        roughness,
        specular: 1.0,
        specular_colour: Vec3::ONE,
        metallic_roughness,
        specular_texture: None,
        specular_colour_texture: None,
        normal_map: None,
    })
}
