//! Light types. Each type gets its own light tree ([LC05] sec. 4.1,
//! ../shared/LIGHTCUTS.md section 2); a scene builds trees only for the types
//! it has. Every light reduces to a point light of one of three kinds.

use glam::Vec3;

pub mod emitters;

use crate::light_tree::{LightKind, TreeLight};

/// An omni-directional point light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OmniLight {
    /// Metres.
    pub position: Vec3,
    /// Radiant intensity per RGB channel, W/sr.
    pub intensity: Vec3,
}

/// A cosine-weighted point light (an area-light sample or a virtual point
/// light): it radiates intensity * max(0, cos phi) towards a direction at
/// angle phi from its normal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrientedLight {
    pub position: Vec3,
    /// Unit normal.
    pub normal: Vec3,
    /// Radiant intensity along the normal, W/sr.
    pub intensity: Vec3,
}

/// A light at infinity: irradiance `irradiance` (W/m^2 on a surface facing
/// it) arriving from unit `direction` (pointing *towards* the light).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectionalLight {
    pub direction: Vec3,
    pub irradiance: Vec3,
}

/// Every light of a scene, by type.
#[derive(Debug, Clone, Default)]
pub struct Lights {
    pub omni: Vec<OmniLight>,
    pub oriented: Vec<OrientedLight>,
    pub directional: Vec<DirectionalLight>,
}

impl Lights {
    #[must_use]
    pub fn len(&self) -> usize {
        self.omni.len() + self.oriented.len() + self.directional.len()
    }

    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of lights of one kind.
    #[must_use]
    pub fn count(&self, kind: LightKind) -> usize {
        match kind {
            LightKind::Omni => self.omni.len(),
            LightKind::Oriented => self.oriented.len(),
            LightKind::Directional => self.directional.len(),
        }
    }

    /// Calls `f(kind, position, normal, intensity)` for every light, omni
    /// then oriented then directional, each in order: `position` is the
    /// direction towards the light for a directional light, `normal` is zero
    /// unless oriented, and `intensity` is a directional light's irradiance.
    /// Three plain loops (the exact renderer's hot path; a chained iterator
    /// branches on every light).
    pub fn for_each(&self, mut f: impl FnMut(LightKind, Vec3, Vec3, Vec3)) {
        for l in &self.omni {
            f(LightKind::Omni, l.position, Vec3::ZERO, l.intensity);
        }
        for l in &self.oriented {
            f(LightKind::Oriented, l.position, l.normal, l.intensity);
        }
        for l in &self.directional {
            f(LightKind::Directional, l.direction, Vec3::ZERO, l.irradiance);
        }
    }

    /// The lights of one kind as tree leaves, in order.
    #[must_use]
    pub fn tree_lights(&self, kind: LightKind) -> Vec<TreeLight> {
        match kind {
            LightKind::Omni => self
                .omni
                .iter()
                .map(|l| TreeLight { position: l.position, normal: Vec3::ZERO, intensity: l.intensity })
                .collect(),
            LightKind::Oriented => self
                .oriented
                .iter()
                .map(|l| TreeLight { position: l.position, normal: l.normal, intensity: l.intensity })
                .collect(),
            LightKind::Directional => self
                .directional
                .iter()
                .map(|l| TreeLight { position: l.direction, normal: Vec3::ZERO, intensity: l.irradiance })
                .collect(),
        }
    }
}

/// The scalar a light's RGB value is compared on: Rec. 709 luminance. Used
/// for representative selection probabilities and for cut error bounds.
#[must_use]
pub fn luminance(rgb: Vec3) -> f32 {
    0.2126 * rgb.x + 0.7152 * rgb.y + 0.0722 * rgb.z
}

/// Luminance in f64.
#[must_use]
pub fn luminance64(rgb: glam::DVec3) -> f64 {
    0.2126 * rgb.x + 0.7152 * rgb.y + 0.0722 * rgb.z
}
