//! The `[materials]` section: diffuse albedo (constant or a PNG texture),
//! Phong specular and mirror layers; or glTF's metallic-roughness BRDF
//! (`type = "pbr"`), its base colour the albedo.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{Affine2, Vec2, Vec3};

use super::Validator;
use crate::scene::file::{MaterialKind, MaterialSpec, SceneFile};
use crate::scene::image::{self, Encoding};
use crate::scene::material::{Clearcoat, PbrMaterial, Sheen, TextureRef, Transmission, DEFAULT_IOR};
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
            ("transmission", m.transmission.is_some()),
            ("ior", m.ior.is_some()),
            ("thin_walled", m.thin_walled),
            ("attenuation_colour", m.attenuation_colour.is_some()),
            ("attenuation_distance", m.attenuation_distance.is_some()),
            ("clearcoat", m.clearcoat.is_some()),
            ("clearcoat_roughness", m.clearcoat_roughness.is_some()),
            ("sheen_colour", m.sheen_colour.is_some()),
            ("sheen_roughness", m.sheen_roughness.is_some()),
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
    let (metallic, roughness) =
        (v.unit(m.metallic, 1.0, &field("metallic"))?, v.unit(m.roughness, 1.0, &field("roughness"))?);
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
    let ior = m.ior.unwrap_or(DEFAULT_IOR);
    v.check(ior.is_finite() && ior >= 1.0, &field("ior"), || format!("must be at least 1, got {ior}"))?;
    let transmission = transmission(v, m, field)?;
    let (clearcoat, sheen) = layers(v, m, field)?;
    Ok(PbrMaterial {
        metallic_roughness,
        ior,
        transmission,
        clearcoat,
        sheen,
        ..PbrMaterial::untextured(metallic, roughness)
    })
}

/// A `type = "pbr"` material's clear coat and sheen (docs/design.md
/// §5.10), each None unless its weight or colour is given and above 0;
/// a roughness without its layer refused.
fn layers(
    v: &Validator<'_>,
    m: &MaterialSpec,
    field: &impl Fn(&str) -> String,
) -> Result<(Option<Clearcoat>, Option<Sheen>), SceneError> {
    let factor = v.unit(m.clearcoat, 0.0, &field("clearcoat"))?;
    let roughness = v.unit(m.clearcoat_roughness, 0.0, &field("clearcoat_roughness"))?;
    v.check(factor > 0.0 || m.clearcoat_roughness.is_none(), &field("clearcoat_roughness"), || {
        "only a material with clearcoat above 0 has it".into()
    })?;
    let colour = match m.sheen_colour {
        Some(c) => v.unit_rgb(c, &field("sheen_colour"))?,
        None => Vec3::ZERO,
    };
    let sheen_roughness = v.unit(m.sheen_roughness, 0.0, &field("sheen_roughness"))?;
    v.check(colour != Vec3::ZERO || m.sheen_roughness.is_none(), &field("sheen_roughness"), || {
        "only a material with a sheen_colour above 0 has it".into()
    })?;
    let clearcoat = (factor > 0.0).then_some(Clearcoat {
        factor,
        texture: None,
        roughness,
        roughness_texture: None,
        normal_map: None,
    });
    let sheen = (colour != Vec3::ZERO).then_some(Sheen {
        colour,
        colour_texture: None,
        roughness: sheen_roughness,
        roughness_texture: None,
    });
    Ok((clearcoat, sheen))
}

/// A `type = "pbr"` material's transmission (docs/design.md §5.8): None
/// unless `transmission` is given and above 0; the thin wall's and the
/// solid's attenuation fields checked.
fn transmission(
    v: &Validator<'_>,
    m: &MaterialSpec,
    field: &impl Fn(&str) -> String,
) -> Result<Option<Transmission>, SceneError> {
    let factor = v.unit(m.transmission, 0.0, &field("transmission"))?;
    let attenuation = m.attenuation_colour.is_some() || m.attenuation_distance.is_some();
    for (name, given) in [("thin_walled", m.thin_walled), ("attenuation_colour", attenuation)] {
        v.check(factor > 0.0 || !given, &field(name), || "only a material with transmission above 0 has it".into())?;
    }
    if factor == 0.0 {
        return Ok(None);
    }
    v.check(!(m.thin_walled && attenuation), &field("attenuation_colour"), || {
        "a thin wall has no inside to absorb in".into()
    })?;
    let colour = match m.attenuation_colour {
        Some(c) => v.unit_rgb(c, &field("attenuation_colour"))?,
        None => Vec3::ONE,
    };
    let distance = m.attenuation_distance.unwrap_or(f32::INFINITY);
    v.check(distance > 0.0, &field("attenuation_distance"), || format!("must be > 0, got {distance}"))?;
    Ok(Some(Transmission {
        thin_walled: m.thin_walled,
        attenuation_colour: colour,
        attenuation_distance: distance,
        ..Transmission::thin(factor)
    }))
}
