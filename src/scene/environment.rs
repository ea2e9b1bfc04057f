//! The environment: radiance arriving from infinitely far away, constant or
//! from a latitude-longitude image. The scene looks it up (the background,
//! mirrors); `light::emitters` samples it into directional lights.
//!
//! Direction convention: +y is up; u = 0.5 + atan2(x, -z) / 2pi runs around
//! the horizon, v = acos(y) / pi from the zenith (top row) down.

use std::f32::consts::PI;
use std::path::Path;

use glam::Vec3;

use super::image::{read_radiance_exr, ImageError};

#[derive(Debug, Clone)]
pub enum EnvironmentMap {
    /// The same radiance from every direction, W/(m^2 sr).
    Constant(Vec3),
    /// A lat-long image of radiance (W/(m^2 sr)), times `scale`.
    LatLong { width: usize, height: usize, texels: Vec<Vec3>, scale: f32 },
}

/// The scene's environment: the map and how many directional lights it becomes.
#[derive(Debug, Clone)]
pub struct Environment {
    pub map: EnvironmentMap,
    pub samples: u32,
}

impl EnvironmentMap {
    /// Reads the R, G, B channels of a lat-long EXR.
    pub fn load_exr(path: &Path, scale: f32) -> Result<Self, ImageError> {
        let image = read_radiance_exr(path)?;
        Ok(Self::LatLong { width: image.width, height: image.height, texels: image.texels.into_floats(), scale })
    }

    /// The pixel (x, y) of a `width` x `height` lat-long map that unit
    /// direction `d` falls in.
    #[must_use]
    pub fn pixel_of(width: usize, height: usize, d: Vec3) -> (usize, usize) {
        let u = 0.5 + d.x.atan2(-d.z) / (2.0 * PI);
        let v = d.y.clamp(-1.0, 1.0).acos() / PI;
        ((u * width as f32) as usize % width.max(1), ((v * height as f32) as usize).min(height - 1))
    }

    /// The largest channel of the brightest radiance it holds, W/(m^2 sr).
    #[must_use]
    pub fn brightest(&self) -> f32 {
        match self {
            Self::Constant(c) => c.max_element(),
            Self::LatLong { texels, scale, .. } => texels.iter().map(|t| t.max_element()).fold(0.0, f32::max) * scale,
        }
    }

    /// Radiance arriving from unit direction `d` (W/(m^2 sr)).
    #[must_use]
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        match self {
            Self::Constant(c) => *c,
            Self::LatLong { width, height, texels, scale } => {
                let (x, y) = Self::pixel_of(*width, *height, d);
                texels[y * width + x] * *scale
            }
        }
    }
}
