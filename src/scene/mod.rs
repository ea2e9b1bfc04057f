//! Scenes: the file format (`file`), its validation into world-space meshes,
//! materials, light sources and the camera, and the images it names. Every
//! error names the file and the field path. Relative paths resolve against
//! the scene file's directory. The light sources are descriptions: the
//! `light` layer above turns them into the point lights the trees cluster.

pub mod builder;
pub mod camera;
pub mod environment;
pub mod error;
pub mod file;
pub mod gltf;
pub mod groups;
pub mod image;
pub(crate) mod load;
pub mod material;
pub mod mesh;
pub mod object;
pub mod subdivision;
pub mod texels;
pub mod texture;
pub mod usd;

use std::path::{Path, PathBuf};

use glam::Vec3;

pub use camera::{Camera, PixelFootprint};
pub use environment::{Environment, EnvironmentMap};
pub use error::SceneError;
pub use groups::LightGroups;
pub use load::additions::{ADDED_ENVIRONMENT_SAMPLES, ADDED_SUN_IRRADIANCE};
pub use load::LoadOptions;
pub use material::{Albedo, Material};
pub use mesh::Mesh;
pub use object::Object;
use texture::Texture;

/// Largest film accepted: 2^27 pixels (about 11600 x 11600). The renderer
/// keeps about 70 bytes per pixel, so this caps the image at about 9 GiB.
pub const MAX_PIXELS: u64 = 1 << 27;
/// The largest intensity (W/sr), radiance (W/(m^2 sr)) or irradiance
/// (W/m^2) one light source may have, per channel, an environment map's
/// texels included (glTF's importer has the same cap on its lights'
/// photometric values).
pub const MAX_EMISSION: f32 = 1e30;
/// The most samples per pixel a scene or the command line may ask for
/// (2^20): a million samples a pixel is past any converged render, and
/// keeps a pixel's sample count and its sample indices far inside `u32`.
pub const MAX_SPP: u32 = 1 << 20;
/// Largest coordinate magnitude a scene may use, metres. Embree rejects a
/// ray whose origin or direction has a component beyond 1.844e18
/// (`FLT_LARGE`; Debian builds it with assertions, which abort), and a
/// shadow ray's direction spans two points: 1e16 keeps a wide margin.
pub const MAX_COORDINATE: f32 = 1e16;
/// Most triangles one glTF or USD import may store (2^28): each copy
/// counted, an instanced mesh once.
pub const MAX_IMPORT_TRIANGLES: usize = 1 << 28;
/// Most instances one glTF or USD import may make (2^24; about 100 bytes
/// each, with Embree's).
pub const MAX_IMPORT_INSTANCES: usize = 1 << 24;
/// Largest number of lights a grid may generate (memory: ~28 bytes each).
pub const MAX_GRID_LIGHTS: u64 = 1 << 26;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
}

/// Where an importer (glTF or USD) puts what it reads: the scene's own
/// lists, which the TOML's parts and an earlier import may already fill
/// (indices are into these lists). Each importer adds what only it has.
pub struct ImportParts<'a> {
    pub meshes: &'a mut Vec<Mesh>,
    /// The objects that place the meshes an import keeps in their own
    /// space (instances, moving prims); every other mesh it adds is in
    /// world space, drawn as itself.
    pub instances: &'a mut Vec<Object>,
    pub materials: &'a mut Vec<Material>,
    pub textures: &'a mut Vec<Texture>,
    pub lights: &'a mut Vec<LightSource>,
    /// The files read, for the scene's inputs.
    pub inputs: &'a mut Vec<PathBuf>,
    pub warnings: &'a mut Vec<String>,
    /// What the file lacks or holds that is not drawn: `Scene::incomplete`.
    pub incomplete: &'a mut Vec<String>,
}

/// An importer's emissive meshes becoming area lights (docs/design.md
/// §6.1), the step the glTF and the USD importers share: each counts its
/// emitters and seeds the n-th one's drawn points from its own base, so
/// that a glTF and a USD file imported into one scene never draw the same
/// points.
#[derive(Debug)]
pub struct EmissiveMeshes {
    base: u64,
    count: u64,
}

impl EmissiveMeshes {
    /// The glTF importer's emitters (its seeds' base, kept as first chosen
    /// so that its images stay as they were).
    pub const GLTF: Self = Self { base: 0x617f_0000, count: 0 };
    /// The USD importer's emitters.
    pub const USD: Self = Self { base: 0x05d0_0000, count: 0 };

    /// The area light of the scene's mesh `mesh`, emitting `radiance`
    /// (W/(m^2 sr)) from the side its winding faces or from `both_sides`,
    /// drawn at `samples` points.
    pub fn light(&mut self, mesh: usize, radiance: Vec3, samples: u32, both_sides: bool) -> LightSource {
        self.count += 1;
        LightSource::Area { mesh, radiance, samples, seed: self.base + self.count, both_sides }
    }
}

/// A light as the scene file describes it, validated. `light::Lights::from_scene`
/// turns each into point lights of one kind ([LC05]; docs/design.md §6).
#[derive(Debug, Clone, PartialEq)]
pub enum LightSource {
    /// One omni light of `intensity` W/sr.
    Point { position: Vec3, intensity: Vec3 },
    /// A point light moving in a straight line over the shutter (`[[lights]]`
    /// `point` with `position_end`).
    MovingPoint { start: Vec3, end: Vec3, intensity: Vec3 },
    /// A spot light of `intensity` W/sr along `direction` (any length),
    /// falling off smoothly from the inner to the outer cone half-angle.
    Spot { position: Vec3, direction: Vec3, intensity: Vec3, inner_angle_degrees: f32, outer_angle_degrees: f32 },
    /// count[0] x count[1] omni lights of `intensity` W/sr each, at the cell
    /// centres of the parallelogram corner + s u + t v.
    Grid { corner: Vec3, u: Vec3, v: Vec3, count: [u32; 2], intensity: Vec3 },
    /// An area emitter: the mesh `meshes[mesh]` (visible, emitting `radiance`
    /// W/(m^2 sr) from the side its winding faces, and from the other too when
    /// `both_sides`) as about `samples` triangle lights per side (a
    /// textured one as `samples` points drawn with `seed`).
    Area { mesh: usize, radiance: Vec3, samples: u32, seed: u64, both_sides: bool },
    /// The sun: `irradiance` W/m^2 from `direction` (towards the sun, any length),
    /// as `samples` directional lights over a disc of `angular_radius_degrees`.
    Sun { direction: Vec3, irradiance: Vec3, angular_radius_degrees: f32, samples: u32, seed: u64 },
}

impl LightSource {
    /// Where its point lights are (none for emitters and the sun): a grid's
    /// four corners bound its lights.
    #[must_use]
    pub fn positions(&self) -> Vec<Vec3> {
        match *self {
            Self::Point { position, .. } | Self::Spot { position, .. } => vec![position],
            Self::MovingPoint { start, end, .. } => vec![start, end],
            Self::Grid { corner, u, v, .. } => vec![corner, corner + u, corner + v, corner + u + v],
            Self::Area { .. } | Self::Sun { .. } => Vec::new(),
        }
    }
}

/// A loaded, validated scene.
#[derive(Debug, Clone)]
pub struct Scene {
    pub path: PathBuf,
    pub film: Film,
    pub camera_spec: file::CameraSpec,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub meshes: Vec<Mesh>,
    /// What is drawn: the meshes placed in the world (each mesh once as
    /// itself, or, when instanced, once per instance).
    pub objects: Vec<Object>,
    /// The lights of `[[lights]]`, in file order, then the glTF file's.
    pub lights: Vec<LightSource>,
    /// The light group of each light and of the environment.
    pub groups: LightGroups,
    pub max_mirror_depth: u32,
    /// Radiance from infinitely far away: visible in the background, and
    /// sampled into directional lights.
    pub environment: Option<Environment>,
    /// Indirect light: camera paths, or VPLs traced per render (they need
    /// Embree and the seed); None for direct light only.
    pub indirect: Option<Indirect>,
    /// The power the scene's lights emit in all (W, as [`Indirect::Vpl`]'s
    /// light paths share it out), and the label of the light that emits
    /// the most: the command line's `--indirect vpl` checks it as the
    /// loader checks a scene's own `[indirect]`.
    pub emitted_power: (f64, String),
    /// Metres: 1/d^2 is evaluated at no less than this distance.
    pub distance_clamp: f32,
    /// Every file the scene was read from, in the order it was read: the scene
    /// file itself (when loaded from one), then its meshes, textures and
    /// environment map. What a fresh clone must contain to render it, and
    /// what a cached reference render depends on.
    pub inputs: Vec<PathBuf>,
    /// What the scene asks for that is rendered otherwise (a glTF alpha
    /// mask drawn opaque, a skin in its bind pose), one line each with the
    /// file and location: the commands print them.
    pub warnings: Vec<String>,
    /// What the asset lacks or holds that is not drawn: a layer, texture or
    /// file that is missing, a format or prim type this renderer does not
    /// read. One line each with the file and the prim; the render goes on
    /// without it (as USD's and glTF's own tools do), and `--strict` makes
    /// the first an error. The commands print them as warnings.
    pub incomplete: Vec<String>,
    /// What the command line added (`--environment`, `--sun`), as text: part
    /// of the scene's hash, so that a farm's tiles rendered with different
    /// additions are not assembled together.
    pub additions: Vec<String>,
    /// The glTF animation the scene plays, and over which shutter.
    pub animation: Option<gltf::PlayedAnimation>,
}

/// Film width of a glTF file rendered without a TOML, pixels.
pub const DEFAULT_GLTF_WIDTH: u32 = 640;

/// How a scene's indirect light is computed (docs/design.md §6.7).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Indirect {
    /// Instant radiosity: virtual point lights left by light paths,
    /// gathered by the cut as any light.
    Vpl(VplSettings),
    /// Camera paths continued by BSDF sampling, with next-event estimation
    /// at every vertex.
    Path(PathSettings),
}

/// Instant-radiosity settings of a scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct VplSettings {
    pub paths: usize,
    pub bounces: u32,
}

/// The path method's settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PathSettings {
    /// Surface interactions a camera path may have, each lit by next-event
    /// estimation (pbrt-v4's `maxdepth`: 1 is direct light only; Mitsuba
    /// 3's `max_depth` counts one more, Cycles' bounces one fewer).
    pub max_depth: u32,
}

/// VPL light paths `--indirect vpl` traces when the scene gives none.
pub const DEFAULT_VPL_PATHS: usize = 10_000;
/// The path method's `max_depth` when neither the scene nor the command
/// line gives one.
pub const DEFAULT_MAX_DEPTH: u32 = 8;
/// The deepest path a scene or the command line may ask for.
pub const MOST_PATH_DEPTH: u32 = 1024;

/// Most light paths a scene may ask for (each leaves up to `bounces` VPLs).
pub const MAX_VPL_PATHS: u32 = 1 << 24;
/// Most samples one emitter may become.
pub const MAX_EMITTER_SAMPLES: u32 = 1 << 24;

impl Scene {
    /// The camera for a film of `width` x `height` pixels (the film's own
    /// size unless the command line overrides it).
    #[must_use]
    pub fn camera(&self, width: u32, height: u32) -> Camera {
        let c = &self.camera_spec;
        let (eye, look_at) = (Vec3::from(c.eye), Vec3::from(c.look_at));
        let focus = c.focus_distance.unwrap_or_else(|| (look_at - eye).length());
        let camera =
            Camera::new(eye, look_at, Vec3::from(c.up), c.fov_y, width, height).with_lens(c.lens_radius, focus);
        if !self.moves() {
            return camera;
        }
        let camera = camera.with_open_shutter();
        if c.eye_end.is_none() && c.look_at_end.is_none() {
            return camera;
        }
        camera.with_motion(Vec3::from(c.eye_end.unwrap_or(c.eye)), Vec3::from(c.look_at_end.unwrap_or(c.look_at)))
    }

    /// Whether the shutter stays open: then camera samples, shadow rays and
    /// light paths are spread over it, and what moves blurs.
    #[must_use]
    pub fn moves(&self) -> bool {
        self.camera_spec.shutter_open()
    }

    /// Bounds of all geometry in the world: (min, max), infinite when there
    /// is none.
    #[must_use]
    pub fn mesh_bounds(&self) -> (Vec3, Vec3) {
        object::world_bounds(&self.meshes, &self.objects)
    }

    /// At most how many point lights the light sources and the environment
    /// become (without VPLs), known before any is made.
    #[must_use]
    pub fn light_count_bound(&self) -> u64 {
        let sources: u64 = self
            .lights
            .iter()
            .map(|source| match *source {
                LightSource::Point { .. } | LightSource::MovingPoint { .. } | LightSource::Spot { .. } => 1,
                LightSource::Grid { count, .. } => u64::from(count[0]) * u64::from(count[1]),
                LightSource::Area { samples, both_sides, .. } => u64::from(samples) * if both_sides { 2 } else { 1 },
                LightSource::Sun { samples, .. } => u64::from(samples),
            })
            .sum();
        sources + self.environment.as_ref().map_or(0, |e| u64::from(e.samples))
    }

    /// The light group of each mesh's emission: an emitter's mesh is in its
    /// light's group (group 0 for a mesh that emits nothing).
    #[must_use]
    pub fn emission_groups(&self) -> Vec<usize> {
        let mut of_mesh = vec![0; self.meshes.len()];
        for (source, &group) in self.lights.iter().zip(&self.groups.of_light) {
            if let LightSource::Area { mesh, .. } = *source {
                of_mesh[mesh] = group;
            }
        }
        of_mesh
    }

    /// A hash of every file the scene read (its `inputs`, in order), as 16
    /// hex digits: what names a render's scene in its EXR (`lightcuts:sceneHash`)
    /// and what `assemble` requires its tiles to share.
    pub fn content_hash(&self) -> Result<String, SceneError> {
        let hashes = self
            .inputs
            .iter()
            .map(|p| {
                crate::util::hash::hash_file(p)
                    .map_err(|e| SceneError::new(p, "file", format!("cannot read it to hash it: {e}")))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let additions = self.additions.iter().map(|a| crate::util::hash::hash_bytes(a.as_bytes()));
        Ok(crate::util::hash::combined_hex(hashes.into_iter().chain(additions)))
    }

    /// Triangles drawn: each object's mesh's, instances counted once each.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.objects.iter().map(|o| self.meshes[o.mesh].triangles.len()).sum()
    }

    /// Triangles stored: each mesh's once, however many objects place it.
    #[must_use]
    pub fn stored_triangle_count(&self) -> usize {
        self.meshes.iter().map(|m| m.triangles.len()).sum()
    }
}

/// Whether every coordinate is finite and within [`MAX_COORDINATE`].
fn within_limits(p: Vec3) -> bool {
    p.is_finite() && p.abs().max_element() <= MAX_COORDINATE
}

/// Checks a film size against [`MAX_PIXELS`]; `what` names the field or flag.
pub fn check_resolution(file: &Path, what: &str, width: u32, height: u32) -> Result<(), SceneError> {
    let pixels = u64::from(width) * u64::from(height);
    if pixels > MAX_PIXELS {
        return Err(SceneError::new(
            file,
            what,
            format!("{width} x {height} = {pixels} pixels would not fit in memory (at most {MAX_PIXELS})"),
        ));
    }
    Ok(())
}

/// A scene of `lights` (TOML `[[lights]]` and `[environment]` tables) with
/// a 4 x 4 film and a camera and nothing else: what the lights' unit tests
/// parse.
#[cfg(test)]
pub(crate) fn with_lights_only(lights: &str) -> Scene {
    let text =
        format!("[film]\nwidth = 4\nheight = 4\n[camera]\neye = [0, 1, 4]\nlook_at = [0, 0, 0]\nfov_y = 45\n{lights}");
    Scene::from_spec(Path::new("lights.toml"), toml::from_str(&text).unwrap()).unwrap()
}

#[cfg(test)]
mod tests;
