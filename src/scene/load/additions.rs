//! Light a render adds from the command line (`--environment`, `--sun`),
//! so that a glTF file without lights renders without a TOML scene. Added
//! lights join the group `default` of a scene with light groups.

use std::path::Path;

use glam::Vec3;

use crate::scene::groups::DEFAULT_GROUP;
use crate::scene::{
    Environment, EnvironmentMap, Indirect, LightSource, PathSettings, Scene, SceneError, VplSettings,
    DEFAULT_MAX_DEPTH, DEFAULT_VPL_PATHS, MOST_PATH_DEPTH,
};

/// Directional lights an added environment becomes.
pub const ADDED_ENVIRONMENT_SAMPLES: u32 = 1024;

/// An added sun's irradiance when the flag gives none, W/m^2.
pub const ADDED_SUN_IRRADIANCE: f32 = 3.0;

impl Scene {
    /// Adds `environment` (`R,G,B`, a constant radiance in W/(m^2 sr), or
    /// the path of a lat-long OpenEXR; it replaces the scene's own) and `sun`
    /// (azimuth and elevation in degrees, irradiance in W/m^2: the sun's
    /// direction is (sin az cos el, sin el, cos az cos el), azimuth from +Z
    /// towards +X, +Y up). Errors name the flag.
    pub fn add_lights(&mut self, environment: Option<&str>, sun: Option<[f32; 3]>) -> Result<(), SceneError> {
        if let Some(text) = environment {
            let map = match parse_rgb(text) {
                Some(rgb) if rgb.is_finite() && rgb.min_element() >= 0.0 => EnvironmentMap::Constant(rgb),
                Some(_) => {
                    return Err(SceneError::new(
                        &self.path,
                        "--environment",
                        format!("'{text}': R,G,B must be finite and >= 0"),
                    ))
                }
                None => {
                    let file = Path::new(text);
                    let map = EnvironmentMap::load_exr(file, 1.0).map_err(|e| {
                        SceneError::new(file, "--environment", format!("cannot use as an environment: {e}"))
                    })?;
                    self.inputs.push(file.to_path_buf());
                    map
                }
            };
            self.environment = Some(Environment { map, samples: ADDED_ENVIRONMENT_SAMPLES });
            self.additions.push(format!("--environment {text}"));
            self.groups.environment = self.default_group()?;
        }
        if let Some([azimuth, elevation, irradiance]) = sun {
            let bad = |m: &str| SceneError::new(&self.path, "--sun", m.to_string());
            if !(azimuth.is_finite()
                && (-90.0..=90.0).contains(&elevation)
                && irradiance.is_finite()
                && irradiance >= 0.0)
            {
                return Err(bad(
                    "AZIMUTH must be finite, ELEVATION between -90 and 90 degrees, IRRADIANCE finite and >= 0",
                ));
            }
            let (a, e) = (azimuth.to_radians(), elevation.to_radians());
            let direction = Vec3::new(a.sin() * e.cos(), e.sin(), a.cos() * e.cos());
            let group = self.default_group()?;
            self.lights.push(LightSource::Sun {
                direction,
                irradiance: Vec3::splat(irradiance),
                angular_radius_degrees: 0.0,
                samples: 1,
                seed: self.lights.len() as u64,
            });
            self.groups.of_light.push(group);
            self.additions.push(format!("--sun {azimuth},{elevation},{irradiance}"));
        }
        Ok(())
    }

    /// Sets the indirect light from the command line: `method` is `path`,
    /// `vpl` or `none` (the scene's own settings of that method are kept;
    /// otherwise `max_depth` 8 for paths, 10,000 one-bounce light paths for
    /// VPLs), and `max_depth` the path method's depth. Errors name the flag.
    pub fn set_indirect(&mut self, method: Option<&str>, max_depth: Option<u32>) -> Result<(), SceneError> {
        if let Some(method) = method {
            self.indirect = match (method, self.indirect) {
                ("none", _) => None,
                ("path", Some(Indirect::Path(settings))) => Some(Indirect::Path(settings)),
                ("path", _) => Some(Indirect::Path(PathSettings { max_depth: DEFAULT_MAX_DEPTH })),
                ("vpl", Some(Indirect::Vpl(settings))) => Some(Indirect::Vpl(settings)),
                ("vpl", _) => {
                    let (power, brightest) = &self.emitted_power;
                    if *power > super::lights::MAX_TOTAL_EMISSION {
                        let message = super::lights::vpl_power_message(*power);
                        return Err(SceneError::new(&self.path, "--indirect", format!("{brightest}: {message}")));
                    }
                    Some(Indirect::Vpl(VplSettings { paths: DEFAULT_VPL_PATHS, bounces: 1 }))
                }
                (other, _) => {
                    let message = format!("'{other}': must be path, vpl or none");
                    return Err(SceneError::new(&self.path, "--indirect", message));
                }
            };
            self.additions.push(format!("--indirect {method}"));
        }
        if let Some(depth) = max_depth {
            let bad = |m: String| SceneError::new(&self.path, "--max-depth", m);
            if !(1..=MOST_PATH_DEPTH).contains(&depth) {
                return Err(bad(format!("must be between 1 and {MOST_PATH_DEPTH}, got {depth}")));
            }
            let Some(Indirect::Path(settings)) = &mut self.indirect else {
                return Err(bad("is the path method's depth: add --indirect path".into()));
            };
            settings.max_depth = depth;
            self.additions.push(format!("--max-depth {depth}"));
        }
        Ok(())
    }

    /// The group `default`'s index (0 in a scene without groups), made if
    /// the scene's groups do not have it.
    fn default_group(&mut self) -> Result<usize, SceneError> {
        let names = &mut self.groups.names;
        if names.is_empty() {
            return Ok(0);
        }
        if let Some(i) = names.iter().position(|n| n == DEFAULT_GROUP) {
            return Ok(i);
        }
        if names.len() == crate::scene::groups::MAX_LIGHT_GROUPS {
            return Err(SceneError::new(&self.path, "--sun", "the scene has as many light groups as it can"));
        }
        names.push(DEFAULT_GROUP.to_string());
        Ok(names.len() - 1)
    }

    /// Whether the scene has any light (lights, emitters, an environment).
    #[must_use]
    pub fn has_light(&self) -> bool {
        !self.lights.is_empty() || self.environment.is_some()
    }
}

/// `R,G,B` as three numbers, or None when the text is not three numbers.
fn parse_rgb(text: &str) -> Option<Vec3> {
    let parts: Vec<f32> = text.split(',').map(|p| p.trim().parse().ok()).collect::<Option<_>>()?;
    (parts.len() == 3).then(|| Vec3::new(parts[0], parts[1], parts[2]))
}
