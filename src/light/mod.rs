//! Light types. Each type gets its own light tree ([LC05] sec. 4.1,
//! ../shared/LIGHTCUTS.md section 2); a scene builds trees only for the types it has.

use glam::Vec3;

/// An omni-directional point light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OmniLight {
    /// Metres.
    pub position: Vec3,
    /// Radiant intensity per RGB channel, W/sr.
    pub intensity: Vec3,
}

/// Every light of a scene, by type.
#[derive(Debug, Clone, Default)]
pub struct Lights {
    pub omni: Vec<OmniLight>,
}

impl Lights {
    #[must_use]
    pub fn len(&self) -> usize {
        self.omni.len()
    }

    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The scalar a light's RGB value is compared on: Rec. 709 luminance. Used
/// for representative selection probabilities and for cut error bounds.
#[must_use]
pub fn luminance(rgb: Vec3) -> f32 {
    0.2126 * rgb.x + 0.7152 * rgb.y + 0.0722 * rgb.z
}
