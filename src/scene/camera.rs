//! A pinhole camera.

use glam::Vec3;

use crate::embree::Ray;

#[derive(Debug, Clone)]
pub struct Camera {
    pub eye: Vec3,
    /// Unit vectors: right, up (on the film) and forward.
    right: Vec3,
    up: Vec3,
    forward: Vec3,
    /// tan(fov_y / 2).
    tan_half_fov_y: f32,
    /// Full-frame size in pixels.
    pub width: u32,
    pub height: u32,
}

impl Camera {
    /// `look_at - eye` and `up` must not be parallel (checked by the scene loader).
    #[must_use]
    pub fn new(eye: Vec3, look_at: Vec3, up: Vec3, fov_y_degrees: f32, width: u32, height: u32) -> Self {
        let forward = (look_at - eye).normalize();
        let right = forward.cross(up).normalize();
        let up = right.cross(forward);
        Self { eye, right, up, forward, tan_half_fov_y: (fov_y_degrees.to_radians() * 0.5).tan(), width, height }
    }

    /// The primary ray through film position (x, y) in pixels of the full
    /// frame, (0, 0) at the top-left corner; the direction is unit length, so
    /// ray parameter t is the distance from the eye.
    #[must_use]
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let aspect = self.width as f32 / self.height as f32;
        let sx = (2.0 * x / self.width as f32 - 1.0) * self.tan_half_fov_y * aspect;
        let sy = (1.0 - 2.0 * y / self.height as f32) * self.tan_half_fov_y;
        let direction = (self.forward + sx * self.right + sy * self.up).normalize();
        Ray { origin: self.eye, direction, t_near: 0.0, t_far: f32::INFINITY }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_ray_looks_at_the_target_and_edges_span_the_fov() {
        let c = Camera::new(Vec3::ZERO, Vec3::new(0.0, 0.0, -5.0), Vec3::Y, 90.0, 200, 100);
        let centre = c.ray(100.0, 50.0);
        assert!((centre.direction - Vec3::NEG_Z).length() < 1e-6);
        let top = c.ray(100.0, 0.0).direction;
        assert!((top.y.atan2(-top.z).to_degrees() - 45.0).abs() < 1e-3);
        let right = c.ray(200.0, 50.0).direction;
        assert!(right.x > 0.0, "x grows to the right");
        assert!((right.x / -right.z - 2.0).abs() < 1e-5, "aspect 2 widens the horizontal fov");
    }
}
