//! A pinhole camera.

use glam::{Mat4, Vec3, Vec4};

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

    /// World to camera space as OpenEXR's `worldToCamera` defines it:
    /// left-handed, origin at the eye, x right, y up, z the viewing
    /// direction (for column vectors; the EXR stores its transpose, Imath's
    /// row-vector form, which has the same 16 floats as this matrix's columns).
    #[must_use]
    pub fn world_to_camera(&self) -> Mat4 {
        let (r, u, f) = (self.right, self.up, self.forward);
        Mat4::from_cols(
            Vec4::new(r.x, u.x, f.x, 0.0),
            Vec4::new(r.y, u.y, f.y, 0.0),
            Vec4::new(r.z, u.z, f.z, 0.0),
            Vec4::new(-r.dot(self.eye), -u.dot(self.eye), -f.dot(self.eye), 1.0),
        )
    }

    /// World to normalised device coordinates, as OpenEXR's standard
    /// attribute `worldToNDC` defines them (RenderMan's NDC): after the
    /// division by w (= the camera-space depth z), (x, y) = (0, 0) at the
    /// display window's upper-left corner and (1, 1) at its lower-right (y
    /// down, as the image's rows), and z = 1 - 1/z, a depth that grows with
    /// distance (its near plane at 1 scene unit). Column vectors; the EXR
    /// stores the transpose (see [`Camera::world_to_camera`]).
    #[must_use]
    pub fn world_to_ndc(&self) -> Mat4 {
        let aspect = self.width as f32 / self.height as f32;
        // Screen coordinates s in [-1, 1] (y up) become 0.5 + 0.5 s in x
        // and 0.5 - 0.5 s in y; the 0.5 offsets are multiplied by w = z.
        let projection = Mat4::from_cols(
            Vec4::new(0.5 / (self.tan_half_fov_y * aspect), 0.0, 0.0, 0.0),
            Vec4::new(0.0, -0.5 / self.tan_half_fov_y, 0.0, 0.0),
            Vec4::new(0.5, 0.5, 1.0, 1.0),
            Vec4::new(0.0, 0.0, -1.0, 0.0),
        );
        projection * self.world_to_camera()
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
    #[test]
    fn world_to_camera_and_ndc_map_the_view_as_openexr_defines_them() {
        let camera = super::Camera::new(
            glam::Vec3::new(1.0, 2.0, 3.0),
            glam::Vec3::new(1.0, 2.0, -7.0),
            glam::Vec3::Y,
            90.0,
            200,
            100,
        );
        let c = camera.world_to_camera();
        // The eye is the origin; the look-at point is 10 units along +z.
        assert!(c.transform_point3(glam::Vec3::new(1.0, 2.0, 3.0)).length() < 1e-5);
        assert!(
            (c.transform_point3(glam::Vec3::new(1.0, 2.0, -7.0)) - glam::Vec3::new(0.0, 0.0, 10.0)).length() < 1e-5
        );
        // A film position (x, y) in pixels lands at NDC (x / width, y /
        // height): (0, 0) upper left, (1, 1) lower right.
        for (x, y) in [(200.0, 0.0), (0.0, 0.0), (0.0, 100.0), (50.0, 75.0)] {
            let ray = camera.ray(x, y);
            let p = camera.world_to_ndc().project_point3(ray.origin + 5.0 * ray.direction);
            assert!((p.x - x / 200.0).abs() < 1e-5 && (p.y - y / 100.0).abs() < 1e-5, "({x}, {y}): {p}");
        }
    }

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
