//! The camera: a pinhole, or a thin lens (docs/design.md §13.1).

use glam::{Mat4, Vec2, Vec3, Vec4};

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
    /// The thin lens: its radius (0: a pinhole) and the distance of the
    /// plane in focus along the view direction, scene units.
    lens_radius: f32,
    focus_distance: f32,
    /// What it was made from (the eye, the point looked at, the up
    /// vector asked for), for placing it at another time.
    look_at: Vec3,
    up_hint: Vec3,
    fov_y_degrees: f32,
    /// Where the eye and the point looked at are at the shutter's close,
    /// when the camera moves (docs/design.md §13.6).
    end: Option<(Vec3, Vec3)>,
    /// The time in the shutter (0 at its open, 1 at its close) this camera
    /// stands at ([`Camera::at`]); its rays carry it.
    time: f32,
    /// Whether the shutter stays open, so that camera samples spread over it.
    shutter_open: bool,
}

impl Camera {
    /// `look_at - eye` and `up` must not be parallel (checked by the scene loader).
    #[must_use]
    pub fn new(eye: Vec3, look_at: Vec3, up: Vec3, fov_y_degrees: f32, width: u32, height: u32) -> Self {
        let forward = (look_at - eye).normalize();
        let up_hint = up;
        let right = forward.cross(up).normalize();
        let up = right.cross(forward);
        let tan_half_fov_y = (fov_y_degrees.to_radians() * 0.5).tan();
        Self {
            eye,
            right,
            up,
            forward,
            tan_half_fov_y,
            width,
            height,
            lens_radius: 0.0,
            focus_distance: 1.0,
            look_at,
            up_hint,
            fov_y_degrees,
            end: None,
            time: 0.0,
            shutter_open: false,
        }
    }

    /// The same camera with its shutter open for a while: its samples are
    /// spread over the shutter, and what moves blurs.
    #[must_use]
    pub fn with_open_shutter(mut self) -> Self {
        self.shutter_open = true;
        self
    }

    /// Whether camera samples spread over the shutter.
    #[must_use]
    pub fn shutter_open(&self) -> bool {
        self.shutter_open
    }

    /// The same camera moving over the shutter: its eye and the point it
    /// looks at travel in straight lines to `eye_end` and `look_at_end`
    /// (at the close), the up vector and the lens staying as they are.
    /// Every position in between must keep the view direction non-zero
    /// and not along up (checked by the scene loader).
    #[must_use]
    pub fn with_motion(mut self, eye_end: Vec3, look_at_end: Vec3) -> Self {
        self.end = Some((eye_end, look_at_end));
        self
    }

    /// Whether the camera moves over the shutter.
    #[must_use]
    pub fn moves(&self) -> bool {
        self.end.is_some()
    }

    /// The camera where it is at `time` of the shutter (0 at its open, 1
    /// at its close): its rays are traced at that time.
    #[must_use]
    pub fn at(&self, time: f32) -> Self {
        let mut placed = match self.end {
            None => self.clone(),
            Some((eye_end, look_at_end)) => {
                let (eye, look_at) = (self.eye.lerp(eye_end, time), self.look_at.lerp(look_at_end, time));
                let moved = Self::new(eye, look_at, self.up_hint, self.fov_y_degrees, self.width, self.height);
                Self {
                    end: self.end,
                    shutter_open: self.shutter_open,
                    ..moved.with_lens(self.lens_radius, self.focus_distance)
                }
            }
        };
        placed.time = time;
        placed
    }

    /// The same camera with a thin lens of `lens_radius` (scene units; 0
    /// keeps the pinhole) focused on the plane `focus_distance` along the
    /// view direction (> 0; checked by the scene loader).
    #[must_use]
    pub fn with_lens(mut self, lens_radius: f32, focus_distance: f32) -> Self {
        self.lens_radius = lens_radius;
        self.focus_distance = focus_distance;
        self
    }

    /// Whether camera rays sample a lens (a thin lens of radius > 0).
    #[must_use]
    pub fn has_lens(&self) -> bool {
        self.lens_radius > 0.0
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
        let direction = self.pinhole_direction(x, y).normalize();
        Ray { origin: self.eye, direction, t_near: 0.0, t_far: f32::INFINITY, time: self.time }
    }

    /// The direction through film position (x, y) from the eye, with a
    /// forward component of exactly 1 (not unit length).
    fn pinhole_direction(&self, x: f32, y: f32) -> Vec3 {
        let aspect = self.width as f32 / self.height as f32;
        let sx = (2.0 * x / self.width as f32 - 1.0) * self.tan_half_fov_y * aspect;
        let sy = (1.0 - 2.0 * y / self.height as f32) * self.tan_half_fov_y;
        self.forward + sx * self.right + sy * self.up
    }

    /// How far apart the points neighbouring pixels see are, at `spp`
    /// samples a pixel (docs/design.md §5.3, "MIP maps").
    #[must_use]
    pub fn pixel_footprint(&self, spp: u32) -> PixelFootprint {
        PixelFootprint {
            eye: self.eye,
            eye_end: self.end.map(|(eye_end, _)| eye_end),
            right: self.right,
            // A pixel's step on the film, whose distance from the eye is 1.
            spread: 2.0 * self.tan_half_fov_y / self.height as f32,
            scale: (1.0 / (spp.max(1) as f32).sqrt()).max(0.125),
        }
    }

    /// The camera ray through film position (x, y) and the lens point
    /// `lens` of the unit disc (ignored by a pinhole). A thin lens
    /// (pbrt-v4's `PerspectiveCamera`, docs/design.md §13.1): the ray
    /// leaves the lens at eye + lens_radius (u right + v up) towards the
    /// point the pinhole ray meets on the plane in focus, so every lens
    /// point sees that plane's points at the same film position (sharp),
    /// and a point at depth z spreads over a circle of confusion whose
    /// radius on that plane's scale is lens_radius |z - focus| / z.
    #[must_use]
    pub fn lens_ray(&self, x: f32, y: f32, lens: Vec2) -> Ray {
        if !self.has_lens() {
            return self.ray(x, y);
        }
        let focus = self.eye + self.focus_distance * self.pinhole_direction(x, y);
        let origin = self.eye + self.lens_radius * (lens.x * self.right + lens.y * self.up);
        Ray { origin, direction: (focus - origin).normalize(), t_near: 0.0, t_far: f32::INFINITY, time: self.time }
    }
}

/// pbrt-v4's `CameraBase::Approximate_dp_dxy`: the rays through the
/// next pixel along the film's x and y, approximated as the ray from the
/// eye to a point turned by one pixel's angle (the one at the film's
/// centre), meet the plane tangent to a surface at some distance from the
/// point the pixel's ray meets. That distance, scaled by
/// max(1/8, 1/sqrt(spp)) (a pixel's samples share its area), is the
/// footprint texture filtering needs, at the camera's hits and, as pbrt-v4
/// approximates it, at a path's later ones. A lens's spread is not counted.
#[derive(Debug, Clone, Copy)]
pub struct PixelFootprint {
    eye: Vec3,
    /// Where the eye is at the shutter's close, when the camera moves.
    eye_end: Option<Vec3>,
    /// The film's x axis (unit).
    right: Vec3,
    /// tan of the angle between neighbouring pixels' rays at the film's centre.
    spread: f32,
    /// max(1/8, 1/sqrt(spp)).
    scale: f32,
}

/// A footprint's stand-in where the neighbouring ray misses the tangent
/// plane (a surface seen edge-on): far wider than any texture.
const EDGE_ON: f32 = 1e8;

impl PixelFootprint {
    /// The change of the point seen, scene units, from one pixel to the
    /// next along the film's x and y, at point `p` of a surface of normal
    /// `n` (either side) seen at `time` of the shutter.
    #[must_use]
    pub fn dp_dxy(&self, p: Vec3, n: Vec3, time: f32) -> [Vec3; 2] {
        let eye = self.eye_end.map_or(self.eye, |end| self.eye.lerp(end, time));
        let to_p = p - eye;
        let distance = to_p.length();
        if !(distance > 0.0 && distance.is_finite()) {
            return [Vec3::ZERO; 2];
        }
        let d = to_p / distance;
        // The film's axes made square to the direction to p.
        let x = (self.right - d * d.dot(self.right)).try_normalize().unwrap_or_else(|| d.any_orthonormal_vector());
        let y = d.cross(x);
        [x, y].map(|axis| {
            let direction = d + self.spread * axis;
            let t = n.dot(to_p) / n.dot(direction);
            let step = eye + t * direction - p;
            if t > 0.0 && step.is_finite() {
                self.scale * step
            } else {
                axis * EDGE_ON
            }
        })
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
    fn a_pixel_footprint_is_its_angle_times_the_distance_over_the_cosine() {
        let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, 200, 100);
        let angle = 2.0 * (30f32.to_radians()).tan() / 100.0;
        // A wall facing the camera 10 away: a pixel's angle times 10,
        // along the film's x and y; at 16 spp, a quarter of it.
        let [dx, dy] = camera.pixel_footprint(1).dp_dxy(Vec3::new(0.0, 0.0, -10.0), Vec3::Z, 0.0);
        assert!((dx - Vec3::X * 10.0 * angle).length() < 1e-6, "{dx}");
        assert!((dy.length() - 10.0 * angle).abs() < 1e-6 && dy.dot(dx).abs() < 1e-9, "{dy}");
        let [quarter, _] = camera.pixel_footprint(16).dp_dxy(Vec3::new(0.0, 0.0, -10.0), Vec3::Z, 0.0);
        assert!((quarter - dx / 4.0).length() < 1e-7);
        // A floor 1 below the eye, seen 10 away: across the view a pixel's
        // angle times the distance; along it, where the ray turned down by
        // atan(angle) meets the floor (nearly d² angle / height, the
        // grazing stretch).
        let p = Vec3::new(0.0, -1.0, -10.0);
        let [across, along] = camera.pixel_footprint(1).dp_dxy(p, Vec3::Y, 0.0);
        assert!((across.length() - p.length() * angle).abs() < 1e-5, "{across}");
        let below = (0.1f32).atan() + angle.atan();
        let expected = 10.0 - 1.0 / below.tan();
        assert!((along.length() / expected - 1.0).abs() < 1e-4, "{along} against {expected}");
        assert!(along.length() > 0.8 * p.length_squared() * angle);
        // Edge-on, or at the eye: no footprint to speak of.
        let [edge, _] = camera.pixel_footprint(1).dp_dxy(Vec3::new(0.0, 0.0, -10.0), Vec3::Y, 0.0);
        assert!(edge.length() >= 1e7);
        assert_eq!(camera.pixel_footprint(1).dp_dxy(Vec3::ZERO, Vec3::Y, 0.0), [Vec3::ZERO; 2]);
    }

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

#[cfg(test)]
mod lens_tests {
    use super::*;
    use crate::util::sampling::{concentric_disc, hammersley};

    /// Where `ray` crosses the plane at depth `z` along -Z.
    fn at_depth(ray: &Ray, z: f32) -> Vec3 {
        ray.origin + ray.direction * ((-z - ray.origin.z) / ray.direction.z)
    }

    fn lens_points() -> impl Iterator<Item = Vec2> {
        (0..256).map(|i| Vec2::from(concentric_disc(hammersley(i, 256, [0.3, 0.7]))))
    }

    #[test]
    fn a_point_on_the_plane_in_focus_stays_sharp() {
        let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 40.0, 320, 240).with_lens(0.25, 7.0);
        for (x, y) in [(160.0, 120.0), (3.5, 200.25), (319.0, 0.0)] {
            let pinhole = at_depth(&camera.ray(x, y), 7.0);
            for lens in lens_points() {
                let ray = camera.lens_ray(x, y, lens);
                assert!((ray.direction.length() - 1.0).abs() < 1e-5);
                let p = at_depth(&ray, 7.0);
                assert!((p - pinhole).length() < 2e-5 * 7.0, "({x}, {y}) lens {lens}: {p} vs {pinhole}");
            }
        }
    }

    #[test]
    fn the_circle_of_confusion_has_the_thin_lens_radius() {
        // A point at depth z is seen, over the lens, from film positions
        // whose points on the plane in focus span a disc of radius
        // R |z - f| / z; equivalently the rays through one film position
        // cross depth z over a disc of radius R |z - f| / f about the
        // pinhole ray.
        let (radius, focus) = (0.1, 4.0);
        let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 30.0, 200, 200).with_lens(radius, focus);
        for z in [1.0f32, 2.0, 8.0, 40.0] {
            let centre = at_depth(&camera.ray(100.0, 100.0), z);
            let spread = lens_points()
                .map(|lens| (at_depth(&camera.lens_ray(100.0, 100.0, lens), z) - centre).length())
                .fold(0.0f32, f32::max);
            let expected = radius * (z - focus).abs() / focus;
            // The 256 lens points reach within 3% of the disc's rim.
            assert!(spread <= expected * 1.0001 && spread >= 0.97 * expected, "z {z}: {spread} vs {expected}");
        }
        // A pinhole ignores the lens point.
        let pinhole = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 30.0, 200, 200);
        assert!(!pinhole.has_lens());
        let a = pinhole.lens_ray(10.0, 20.0, Vec2::new(0.9, -0.3));
        assert_eq!(a.origin, Vec3::ZERO);
        assert_eq!(a.direction, pinhole.ray(10.0, 20.0).direction);
    }
}
