//! The `[materials]` section: diffuse albedo (constant or a PNG texture),
//! Phong specular and mirror layers.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{Affine2, Vec2, Vec3};

use super::Validator;
use crate::scene::file::SceneFile;
use crate::scene::texture::Texture;
use crate::scene::{image, Albedo, Material, SceneError};

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
                let image = image::read_srgb_png(&texture_path)
                    .map_err(|e| SceneError::new(&texture_path, field("texture"), e.to_string()))?;
                textures.push(Texture::from_image(image));
                Albedo::Texture { texture: textures.len() - 1, transform: Affine2::from_scale(scale) }
            }
        };
        let specular = v.unit_rgb(m.specular, &field("specular"))?;
        v.check(m.exponent.is_finite() && (0.0..=1e6).contains(&m.exponent), &field("exponent"), || {
            format!("must be between 0 and 1e6, got {}", m.exponent)
        })?;
        let mirror = v.unit_rgb(m.mirror, &field("mirror"))?;
        material_index.insert(name.clone(), materials.len());
        materials.push(Material {
            name: name.clone(),
            albedo,
            specular,
            exponent: m.exponent,
            mirror,
            emission: Vec3::ZERO,
            emits_both_sides: false,
            cutout: None,
            pbr: None,
        });
    }
    Ok((materials, material_index))
}
