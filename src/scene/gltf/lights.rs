//! KHR_lights_punctual's lights as the renderer's: photometric values over
//! the luminous efficacy (docs/design.md §6.5), placed by their nodes.

use std::f32::consts::FRAC_PI_4;

use glam::{Mat4, Vec3};
use gltf::json::extensions::scene::khr_lights_punctual::{Light as LightJson, Type as LightType};
use gltf::json::validation::Checked;

use super::Importer;
use crate::scene::file::DEFAULT_LUMENS_PER_WATT;
use crate::scene::groups::GltfLightNames;
use crate::scene::{LightSource, SceneError};

impl Importer<'_, '_> {
    /// KHR_lights_punctual light `index` placed by `world`: photometric
    /// values over `lumens_per_watt` (candela to W/sr, lux to W/m^2).
    pub(super) fn import_light(&mut self, index: usize, world: &Mat4, node_name: &str) -> Result<(), SceneError> {
        let location = format!("extensions.KHR_lights_punctual.lights[{index}]");
        let light: &LightJson = self
            .doc
            .as_json()
            .extensions
            .as_ref()
            .and_then(|e| e.khr_lights_punctual.as_ref())
            .and_then(|l| l.lights.get(index))
            .ok_or_else(|| self.error(&location, "a node refers to a light the file does not define"))?;
        let colour = Vec3::from_array(light.color);
        if !colour.is_finite() || colour.min_element() < 0.0 {
            return Err(self.error(format!("{location}.color"), format!("must be finite and >= 0, got {colour}")));
        }
        let value = light.intensity;
        if !value.is_finite() || !(0.0..=1e30).contains(&value) {
            return Err(self.error(format!("{location}.intensity"), format!("must be finite and >= 0, got {value}")));
        }
        let radiometric = colour * (value / self.spec.lumens_per_watt);
        let position = world.w_axis.truncate();
        // Lights shine along their node's -Z.
        let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        if light.range.is_some() {
            // Physical lights have no range; Cycles ignores it too.
            self.warn(&format!("{location}.range"), "ignored: the light falls off as 1/d^2 to any distance");
        }
        let kind = match &light.type_ {
            Checked::Valid(kind) => kind,
            Checked::Invalid => {
                return Err(self.error(format!("{location}.type"), "must be point, spot or directional"))
            }
        };
        let needs_direction = !matches!(kind, LightType::Point);
        if needs_direction && forward == Vec3::ZERO {
            return Err(self.error(&location, "the light's node has a degenerate (zero-scale) transform"));
        }
        let source = match kind {
            LightType::Point => LightSource::Point { position, intensity: radiometric },
            LightType::Spot => {
                let (inner, outer) =
                    light.spot.as_ref().map_or((0.0, FRAC_PI_4), |s| (s.inner_cone_angle, s.outer_cone_angle));
                if !(outer.is_finite() && outer > 0.0 && outer <= std::f32::consts::FRAC_PI_2) {
                    return Err(self.error(
                        format!("{location}.spot.outerConeAngle"),
                        format!("must be in (0, pi/2], got {outer}"),
                    ));
                }
                if !(inner.is_finite() && inner >= 0.0 && inner < outer) {
                    return Err(self.error(
                        format!("{location}.spot.innerConeAngle"),
                        format!("must be in [0, outerConeAngle), got {inner}"),
                    ));
                }
                LightSource::Spot {
                    position,
                    direction: forward,
                    intensity: radiometric,
                    inner_angle_degrees: inner.to_degrees(),
                    outer_angle_degrees: outer.to_degrees().min(90.0),
                }
            }
            LightType::Directional => LightSource::Sun {
                direction: -forward,
                irradiance: radiometric,
                angular_radius_degrees: 0.0,
                samples: 1,
                seed: 0x6c7f_0000 + index as u64,
            },
        };
        self.parts.scene.lights.push(source);
        self.punctual += 1;
        self.parts.light_names.push(GltfLightNames {
            light: light.name.clone(),
            node: Some(node_name.to_string()),
            material: None,
        });
        Ok(())
    }

    /// One line on stderr: how many punctual lights were converted, at
    /// which efficacy, and the viewers' convention's flag.
    pub(super) fn state_light_units(&mut self) {
        if self.punctual > 0 {
            let lpw = self.spec.lumens_per_watt;
            let convention = if lpw == DEFAULT_LUMENS_PER_WATT {
                format!(
                    "{lpw} lm/W, Blender's convention; a file made for glTF viewers (1 cd taken as 1 W/sr) needs \
                 --lumens-per-watt 1 or [gltf] lumens_per_watt = 1, {:.1} stops brighter",
                    lpw.log2()
                )
            } else {
                format!("{lpw} lm/W as asked ({DEFAULT_LUMENS_PER_WATT}, Blender's convention, is the default)")
            };
            let n = self.punctual;
            self.warn(
                "extensions.KHR_lights_punctual",
                &format!("{n} light(s) in candela and lux converted to W/sr and W/m^2 at {convention}"),
            );
        }
    }
}
