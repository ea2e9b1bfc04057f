//! Scenes written piece by piece as scene-file text (TOML): the unit
//! tests', the integration tests' and `lightcuts bench switch`'s scenes, so
//! that the usual floor, spheres and grids of lights are written once. The
//! text is what a user would write, and it goes through the same loader.

use std::path::Path;

use super::{Scene, SceneError};

/// A scene file being written: the film, the camera, then materials,
/// shapes and lights in the order they are added.
#[derive(Debug, Clone)]
pub struct SceneText {
    text: String,
}

/// `[x, y, z]` with each number written so that it reads back exactly.
fn array(v: [f64; 3]) -> String {
    format!("[{:?}, {:?}, {:?}]", v[0], v[1], v[2])
}

impl SceneText {
    /// A `width` x `height` film at one sample per pixel.
    #[must_use]
    pub fn new(width: u32, height: u32) -> Self {
        Self { text: format!("[film]\nwidth = {width}\nheight = {height}\n") }
    }

    /// Samples per pixel.
    #[must_use]
    pub fn spp(mut self, spp: u32) -> Self {
        self.text = self.text.replacen("[film]\n", &format!("[film]\nspp = {spp}\n"), 1);
        self
    }

    /// A pinhole camera at `eye` looking at `look_at`, +Y up.
    #[must_use]
    pub fn camera(self, eye: [f64; 3], look_at: [f64; 3], fov_y_degrees: f64) -> Self {
        self.raw(&format!("[camera]\neye = {}\nlook_at = {}\nfov_y = {fov_y_degrees:?}\n", array(eye), array(look_at)))
    }

    /// A material `name` with a diffuse `albedo` and more fields as TOML
    /// lines (`specular = [...]`, `exponent = 30`, `mirror = [...]`).
    #[must_use]
    pub fn material(self, name: &str, albedo: [f64; 3], more: &str) -> Self {
        self.raw(&format!("[materials.{name}]\nalbedo = {}\n{more}", array(albedo)))
    }

    /// A horizontal square floor at height `y`, `half` metres from the
    /// origin each way, facing up.
    #[must_use]
    pub fn floor(self, y: f64, half: f64, material: &str) -> Self {
        let text = format!(
            "[[shapes]]\ntype = \"quad\"\ncorner = {}\nu = {}\nv = {}\nmaterial = \"{material}\"\n",
            array([-half, y, half]),
            array([2.0 * half, 0.0, 0.0]),
            array([0.0, 0.0, -2.0 * half])
        );
        self.raw(&text)
    }

    /// A sphere.
    #[must_use]
    pub fn sphere(self, centre: [f64; 3], radius: f64, material: &str) -> Self {
        let text = format!(
            "[[shapes]]\ntype = \"sphere\"\ncenter = {}\nradius = {radius:?}\nmaterial = \"{material}\"\n",
            array(centre)
        );
        self.raw(&text)
    }

    /// An axis-aligned box.
    #[must_use]
    pub fn cuboid(self, min: [f64; 3], max: [f64; 3], material: &str) -> Self {
        let text = format!(
            "[[shapes]]\ntype = \"box\"\nmin = {}\nmax = {}\nmaterial = \"{material}\"\n",
            array(min),
            array(max)
        );
        self.raw(&text)
    }

    /// `count[0]` x `count[1]` point lights of `intensity` W/sr each over the
    /// parallelogram `corner` + s `u` + t `v`.
    #[must_use]
    pub fn grid(self, corner: [f64; 3], u: [f64; 3], v: [f64; 3], count: [u32; 2], intensity: [f64; 3]) -> Self {
        let text = format!(
            "[[lights]]\ntype = \"grid\"\ncorner = {}\nu = {}\nv = {}\ncount = [{}, {}]\nintensity = {}\n",
            array(corner),
            array(u),
            array(v),
            count[0],
            count[1],
            array(intensity)
        );
        self.raw(&text)
    }

    /// One point light.
    #[must_use]
    pub fn point(self, position: [f64; 3], intensity: [f64; 3]) -> Self {
        self.raw(&format!(
            "[[lights]]\ntype = \"point\"\nposition = {}\nintensity = {}\n",
            array(position),
            array(intensity)
        ))
    }

    /// Anything else, as scene-file text.
    #[must_use]
    pub fn raw(mut self, toml: &str) -> Self {
        self.text.push_str(toml);
        if !toml.ends_with('\n') {
            self.text.push('\n');
        }
        self
    }

    /// The scene file's text.
    #[must_use]
    pub fn toml(&self) -> String {
        self.text.clone()
    }

    /// The scene, loaded as if from a file at `path` (which need not exist:
    /// relative paths in the text resolve against its directory).
    pub fn load(&self, path: &Path) -> Result<Scene, SceneError> {
        let spec = toml::from_str(&self.text).map_err(|e| SceneError::new(path, "file", e.to_string()))?;
        Scene::from_spec(path, spec)
    }
}

impl std::fmt::Display for SceneText {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.text)
    }
}

/// The renderer's usual test scene: a 10 x 10 m grey floor, a glossy
/// sphere and a mirror sphere, under a `lights_per_side`² grid of point
/// lights on a 4 x 4 m square 3 m up, seen from above at an angle on a
/// 96 x 72 film.
#[must_use]
pub fn floor_spheres_grid(lights_per_side: u32) -> SceneText {
    SceneText::new(96, 72)
        .camera([0.0, 3.0, 6.0], [0.0, 0.5, 0.0], 45.0)
        .material("floor", [0.7, 0.7, 0.7], "")
        .material("shiny", [0.6, 0.2, 0.1], "specular = [0.3, 0.3, 0.3]\nexponent = 30\n")
        .material("mirror", [0.05, 0.05, 0.05], "mirror = [0.8, 0.8, 0.8]\n")
        .floor(0.0, 5.0, "floor")
        .sphere([-0.8, 0.7, 0.0], 0.7, "shiny")
        .sphere([0.9, 0.5, 0.4], 0.5, "mirror")
        .grid([-2.0, 3.0, -2.0], [4.0, 0.0, 0.0], [0.0, 0.0, 4.0], [lights_per_side; 2], [1.0, 0.9, 0.8])
}

#[cfg(test)]
mod tests {
    use std::fmt::Write as _;

    use super::*;

    #[test]
    fn the_text_loads_into_the_scene_it_describes() {
        let scene = floor_spheres_grid(4).spp(3).load(Path::new("t.toml")).unwrap();
        assert_eq!((scene.film.width, scene.film.height, scene.film.spp), (96, 72, 3));
        assert_eq!(scene.meshes.len(), 3);
        assert_eq!(scene.materials.len(), 3);
        assert_eq!(scene.light_count_bound(), 16);
        // Numbers read back exactly.
        assert!(SceneText::new(1, 1).toml().contains("width = 1"));
        assert_eq!(array([0.1, -2.0, 1e-30]), "[0.1, -2.0, 1e-30]");
        let mut text = String::new();
        write!(text, "{}", SceneText::new(2, 2)).unwrap();
        assert!(text.starts_with("[film]"));
    }
}
