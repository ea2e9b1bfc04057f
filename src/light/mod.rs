//! Light kinds and the lights of a scene. Every light reduces to a point
//! light of one of six kinds, and each kind gets its own light tree
//! ([LC05]; docs/design.md §5.2); a scene builds trees
//! only for the kinds it has. `Lights::from_scene` turns the scene's light
//! sources (point lights, grids, area emitters, the sun, the environment)
//! into lights of these kinds (docs/design.md §6, `emitters`).

use glam::Vec3;

pub mod area;
pub mod emitters;
pub mod environment;

use crate::scene::{LightSource, Scene};

/// The light kinds, each with its own tree: [LC05]'s three, spots, and
/// the stand-ins of continuous emitters (area lights' points, the
/// environment's directions) apart from the other oriented and
/// directional lights.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LightKind {
    /// Point lights radiating equally in all directions.
    Omni,
    /// An area light's points: oriented lights as `Oriented`, in trees of
    /// their own because a shading point whose glossy lobe is too sharp
    /// for them lights them with its broad lobes alone and samples the
    /// emitter's surface for the rest (docs/design.md §6.1).
    Area,
    /// Cosine-weighted lights with a normal (area-light samples, virtual point lights).
    Oriented,
    /// Lights at infinity from one direction (the sun).
    Directional,
    /// The environment's directions: lights at infinity as `Directional`,
    /// in trees of their own because a shading point whose glossy lobe is
    /// too sharp for them lights them with its broad lobes alone and the
    /// rest by sampling the environment (docs/design.md §6.2).
    Environment,
    /// Spot lights: a point light shining into a cone with a smooth edge.
    Spot,
}

impl LightKind {
    /// Every kind, in the order the renderer visits them (the
    /// environment's directions right after the sun's, as they were
    /// summed when they shared a kind).
    /// (Area lights before the other oriented ones, where they were summed
    /// when they shared a kind.)
    pub const ALL: [Self; 6] =
        [Self::Omni, Self::Area, Self::Oriented, Self::Directional, Self::Environment, Self::Spot];

    /// Whether the kind's lights are at infinity (a direction, not a
    /// position; G = 1).
    #[must_use]
    pub fn at_infinity(self) -> bool {
        matches!(self, Self::Directional | Self::Environment)
    }

    /// Whether the kind's lights have a direction of emission (oriented
    /// lights' normals, spots' axes), so that their trees carry cones.
    #[must_use]
    pub fn has_cone(self) -> bool {
        matches!(self, Self::Area | Self::Oriented | Self::Spot)
    }

    /// Whether the kind's lights stand in for a continuous emitter (an
    /// area light's surface, the environment) that a sharp glossy lobe
    /// samples instead (docs/design.md §6.1 and design.md §6.2).
    #[must_use]
    pub fn stands_in_for_emitter(self) -> bool {
        matches!(self, Self::Area | Self::Environment)
    }

    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Omni => "omni",
            Self::Area => "area",
            Self::Oriented => "oriented",
            Self::Directional => "directional",
            Self::Environment => "environment",
            Self::Spot => "spot",
        }
    }
}

/// An omni-directional point light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OmniLight {
    /// Metres.
    pub position: Vec3,
    /// Radiant intensity per RGB channel, W/sr.
    pub intensity: Vec3,
}

/// An omni light that moves over the shutter, in a straight line from
/// `start` (at its open) to `end` (at its close). Moving lights are not
/// clustered: every render mode evaluates each one at the shading point's
/// time with a shadow ray of its own (docs/design.md §13.6).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MovingOmniLight {
    /// Metres, at the shutter's open and close.
    pub start: Vec3,
    pub end: Vec3,
    /// W/sr.
    pub intensity: Vec3,
}

impl MovingOmniLight {
    /// The light where it is at `time` (0 at the shutter's open, 1 at its close).
    #[must_use]
    pub fn at(&self, time: f32) -> Light {
        Light::Omni(OmniLight { position: self.start.lerp(self.end, time), intensity: self.intensity })
    }
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

/// One of an area light's triangles (a whole emitting triangle, or one
/// of the equal parts a large one is split into: docs/design.md §6.1), as
/// a leaf of the light tree: it radiates L_e A cos(phi) (W/sr) from a point
/// drawn uniformly on it per shading point ([`AreaLight::point_at`]), so
/// the light over many shading points is the triangle's, not a dot's.
/// A light with zero edges is a fixed point (a textured emitter's points).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AreaLight {
    /// The triangle's centroid, metres: where the tree clusters it and what
    /// a fixed representative stands at.
    pub position: Vec3,
    /// Unit normal of the emitting side.
    pub normal: Vec3,
    /// Radiant intensity along the normal, L_e x area, W/sr.
    pub intensity: Vec3,
    /// The triangle's edges q1 - q0 and q2 - q0, metres (zero for a point).
    pub edges: [Vec3; 2],
}

impl AreaLight {
    /// The point at the numbers `u` in [0, 1)^2, uniform by area over the
    /// triangle (the unit square folded onto it): q0 + a e1 + b e2, with q0
    /// = position - (e1 + e2) / 3.
    #[must_use]
    pub fn point_at(&self, u: [f32; 2]) -> Vec3 {
        point_on_triangle(self.position, self.edges, u)
    }

    /// The triangle's corners (three times its position for a point).
    #[must_use]
    pub fn corners(&self) -> [Vec3; 3] {
        triangle_corners(self.position, self.edges)
    }
}

/// The point at the numbers `u` in [0, 1)^2 on the triangle of centroid
/// `centroid` and edges `edges`, uniform by area ([`AreaLight::point_at`]).
#[must_use]
#[inline(always)]
pub fn point_on_triangle(centroid: Vec3, edges: [Vec3; 2], u: [f32; 2]) -> Vec3 {
    let (a, b) = fold(u);
    centroid + (a - 1.0 / 3.0) * edges[0] + (b - 1.0 / 3.0) * edges[1]
}

/// The corners of the triangle of centroid `centroid` and edges `edges`.
#[must_use]
pub fn triangle_corners(centroid: Vec3, edges: [Vec3; 2]) -> [Vec3; 3] {
    let q0 = centroid - (edges[0] + edges[1]) / 3.0;
    [q0, q0 + edges[0], q0 + edges[1]]
}

/// The unit square folded onto the triangle a + b <= 1 (uniform in area).
#[must_use]
pub fn fold(u: [f32; 2]) -> (f32, f32) {
    if u[0] + u[1] > 1.0 {
        (1.0 - u[0], 1.0 - u[1])
    } else {
        (u[0], u[1])
    }
}

/// A light at infinity: irradiance `irradiance` (W/m^2 on a surface facing
/// it) arriving from unit `direction` (pointing *towards* the light).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectionalLight {
    pub direction: Vec3,
    pub irradiance: Vec3,
}

/// The sun as a disc of angular radius > 0: irradiance `irradiance` (W/m^2
/// on a surface facing it) from directions spread uniformly over the cone
/// of half-angle acos(`cos_max`) about unit `direction`. It is in no tree:
/// every shading point draws directions from it with a shadow ray each,
/// `samples` over a pixel (docs/design.md §6.3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SunDisc {
    pub direction: Vec3,
    pub irradiance: Vec3,
    pub cos_max: f32,
    pub samples: u32,
}

impl SunDisc {
    /// The direction at the numbers `u` in [0, 1)^2: uniform in the
    /// cone's solid angle (cos theta uniform in [cos_max, 1]).
    #[must_use]
    pub fn direction_at(&self, u: [f32; 2]) -> Vec3 {
        let cos_theta = 1.0 - u[0] * (1.0 - self.cos_max);
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let phi = 2.0 * std::f32::consts::PI * u[1];
        let (t, b) = self.direction.any_orthonormal_pair();
        (self.direction * cos_theta + t * (sin_theta * phi.cos()) + b * (sin_theta * phi.sin())).normalize()
    }
}

/// A spot light (KHR_lights_punctual's): intensity `intensity` (W/sr)
/// along unit `direction`, scaled at angle theta from it by t^2 with
/// t = clamp((cos theta - cos_outer) / (cos_inner - cos_outer), 0, 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpotLight {
    pub position: Vec3,
    /// Unit direction the spot shines towards.
    pub direction: Vec3,
    pub intensity: Vec3,
    /// Cosines of the inner and outer cone half-angles (cos_inner > cos_outer).
    pub cos_inner: f32,
    pub cos_outer: f32,
}

impl SpotLight {
    /// The smooth falloff at cos theta from the axis (KHR_lights_punctual's
    /// recommended formula; the difference of cosines at least 0.001).
    #[must_use]
    pub fn falloff(cos_theta: f32, cos_inner: f32, cos_outer: f32) -> f32 {
        let scale = 1.0 / (cos_inner - cos_outer).max(0.001);
        let t = ((cos_theta - cos_outer) * scale).clamp(0.0, 1.0);
        t * t
    }
}

/// One light of any kind.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Light {
    Omni(OmniLight),
    /// One of an area light's triangles.
    Area(AreaLight),
    Oriented(OrientedLight),
    Directional(DirectionalLight),
    /// One of the environment's directions.
    Environment(DirectionalLight),
    Spot(SpotLight),
}

impl Light {
    #[must_use]
    pub fn kind(&self) -> LightKind {
        match self {
            Self::Omni(_) => LightKind::Omni,
            Self::Area(_) => LightKind::Area,
            Self::Oriented(_) => LightKind::Oriented,
            Self::Directional(_) => LightKind::Directional,
            Self::Environment(_) => LightKind::Environment,
            Self::Spot(_) => LightKind::Spot,
        }
    }
}

/// What a light tree needs of one light (one leaf).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TreeLight {
    /// The point the tree clusters: the position of an omni or oriented
    /// light, the unit direction towards a directional light.
    pub point: Vec3,
    /// Unit normal of an oriented light; zero for the other kinds.
    pub normal: Vec3,
    /// W/sr (omni, oriented, spot), or a directional light's irradiance in W/m^2.
    pub intensity: Vec3,
    /// A spot's cosines of its inner and outer cone half-angles; (0, 0)
    /// for the other kinds. (A spot's `normal` is its direction.)
    pub spread: [f32; 2],
    /// An area light's triangle's edges (`AreaLight::edges`); zero for
    /// the other kinds.
    pub edges: [Vec3; 2],
}

impl TreeLight {
    /// The leaf of `light`.
    #[must_use]
    pub fn of(light: &Light) -> Self {
        match *light {
            Light::Omni(l) => Self::at(l.position, Vec3::ZERO, l.intensity),
            Light::Area(l) => Self { edges: l.edges, ..Self::at(l.position, l.normal, l.intensity) },
            Light::Oriented(l) => Self::at(l.position, l.normal, l.intensity),
            Light::Directional(l) | Light::Environment(l) => Self::at(l.direction, Vec3::ZERO, l.irradiance),
            Light::Spot(l) => {
                Self { spread: [l.cos_inner, l.cos_outer], ..Self::at(l.position, l.direction, l.intensity) }
            }
        }
    }

    /// A leaf at `point` with `normal` and `intensity`, no spread, no edges.
    #[must_use]
    pub fn at(point: Vec3, normal: Vec3, intensity: Vec3) -> Self {
        Self { point, normal, intensity, spread: [0.0; 2], edges: [Vec3::ZERO; 2] }
    }

    /// The box the light can be anywhere in: its triangle's (an area
    /// light's), else its point.
    #[must_use]
    pub fn bounds(&self) -> (Vec3, Vec3) {
        if self.edges == [Vec3::ZERO; 2] {
            return (self.point, self.point);
        }
        let [a, b, c] = triangle_corners(self.point, self.edges);
        (a.min(b).min(c), a.max(b).max(c))
    }

    /// The light this leaf stands for, given its tree's kind.
    #[must_use]
    pub fn light(&self, kind: LightKind) -> Light {
        match kind {
            LightKind::Omni => Light::Omni(OmniLight { position: self.point, intensity: self.intensity }),
            LightKind::Area => Light::Area(AreaLight {
                position: self.point,
                normal: self.normal,
                intensity: self.intensity,
                edges: self.edges,
            }),
            LightKind::Oriented => {
                Light::Oriented(OrientedLight { position: self.point, normal: self.normal, intensity: self.intensity })
            }
            LightKind::Directional => {
                Light::Directional(DirectionalLight { direction: self.point, irradiance: self.intensity })
            }
            LightKind::Environment => {
                Light::Environment(DirectionalLight { direction: self.point, irradiance: self.intensity })
            }
            LightKind::Spot => Light::Spot(SpotLight {
                position: self.point,
                direction: self.normal,
                intensity: self.intensity,
                cos_inner: self.spread[0],
                cos_outer: self.spread[1],
            }),
        }
    }
}

/// How the continuous emitters (untextured area lights, the environment)
/// become leaves of the light trees (docs/design.md §6.1 and docs/design.md §6.2). A
/// textured emitter's leaves are its fixed points either way: they follow
/// its emitted power.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum EmitterLeaves {
    /// An area light as about its `samples` equal parts, the environment
    /// as its `samples` directions: the representatives a cut that keeps
    /// its lights over a pixel's samples needs to see a soft shadow smooth
    /// at one sample (the bounded and multidimensional cuts, and the exact
    /// sum over them).
    #[default]
    Parts,
    /// An area light as one leaf per triangle (a rectangle is two), its
    /// point drawn by solid angle, and the environment in no tree: one
    /// light beside them that every vertex draws a direction from, by
    /// multiple importance sampling with its BSDF. The stochastic cut draws
    /// one light per cut node and sample, and a whole emitter drawn well is
    /// as good a draw as one of its parts, for fewer shadow rays.
    Whole,
}

/// Every light of a scene, by kind.
#[derive(Debug, Clone, Default)]
pub struct Lights {
    pub omni: Vec<OmniLight>,
    /// Area lights' triangles (`LightKind::Area`).
    pub area: Vec<AreaLight>,
    pub oriented: Vec<OrientedLight>,
    pub directional: Vec<DirectionalLight>,
    /// The environment's directions (`LightKind::Environment`).
    pub environment: Vec<DirectionalLight>,
    pub spot: Vec<SpotLight>,
    /// Lights that move over the shutter: in no tree, and not counted by
    /// [`Lights::len`] or visited by [`Lights::for_each`].
    pub moving: Vec<MovingOmniLight>,
    /// Suns with a disc, sampled per shading point: in no tree either.
    pub suns: Vec<SunDisc>,
}

impl Lights {
    /// The scene's light sources as lights, in file order within each kind,
    /// then the environment's directional lights. Deterministic: every
    /// emitter samples from its own seeded stream.
    #[must_use]
    pub fn from_scene(scene: &Scene) -> Self {
        Self::of_group(scene, None, EmitterLeaves::Parts)
    }

    /// The scene's lights split by light group (`Scene::groups`): one
    /// `Lights` per group, each as [`Lights::from_scene`] orders them. A
    /// light is sampled the same whichever group it is in.
    #[must_use]
    pub fn by_group(scene: &Scene) -> Vec<Self> {
        Self::by_group_with(scene, EmitterLeaves::Parts)
    }

    /// [`Lights::by_group`], with area lights as `leaves`.
    #[must_use]
    pub fn by_group_with(scene: &Scene, leaves: EmitterLeaves) -> Vec<Self> {
        if !scene.groups.named() {
            return vec![Self::of_group(scene, None, leaves)];
        }
        (0..scene.groups.count()).map(|g| Self::of_group(scene, Some(g), leaves)).collect()
    }

    /// The lights of group `group`, or of every group.
    fn of_group(scene: &Scene, group: Option<usize>, leaves: EmitterLeaves) -> Self {
        let wanted = |g: usize| group.is_none_or(|want| want == g);
        let mut lights = Self::default();
        for (i, source) in scene.lights.iter().enumerate() {
            if !wanted(scene.groups.of_light.get(i).copied().unwrap_or(0)) {
                continue;
            }
            match *source {
                LightSource::Point { position, intensity } => lights.omni.push(OmniLight { position, intensity }),
                // With the shutter closed, everything is where it is at its open.
                LightSource::MovingPoint { start, end, intensity } if scene.moves() => {
                    lights.moving.push(MovingOmniLight { start, end, intensity });
                }
                LightSource::MovingPoint { start, intensity, .. } => {
                    lights.omni.push(OmniLight { position: start, intensity });
                }
                LightSource::Spot { position, direction, intensity, inner_angle_degrees, outer_angle_degrees } => {
                    lights.spot.push(SpotLight {
                        position,
                        direction: direction.normalize(),
                        intensity,
                        cos_inner: inner_angle_degrees.to_radians().cos(),
                        cos_outer: outer_angle_degrees.to_radians().cos(),
                    });
                }
                LightSource::Grid { corner, u, v, count, intensity } => {
                    for j in 0..count[1] {
                        for k in 0..count[0] {
                            // Cell centres: the grid is symmetric within its parallelogram.
                            let s = (k as f32 + 0.5) / count[0] as f32;
                            let t = (j as f32 + 0.5) / count[1] as f32;
                            lights.omni.push(OmniLight { position: corner + s * u + t * v, intensity });
                        }
                    }
                }
                LightSource::Area { mesh, radiance, samples, seed, both_sides } => {
                    let mesh = &scene.meshes[mesh];
                    let triangles: Vec<emitters::EmitterTriangle> = mesh
                        .triangles
                        .iter()
                        .map(|t| emitters::EmitterTriangle { p: t.map(|i| mesh.positions[i as usize]) })
                        .collect();
                    let front = match &scene.materials[mesh.material].emissive_texture {
                        None => {
                            // One part per triangle: each triangle's share of 1 is 1.
                            let parts = if leaves == EmitterLeaves::Whole { samples.min(1) } else { samples } as usize;
                            emitters::sample_area_light(&triangles, radiance, parts, 0.0)
                        }
                        Some(texture) => emitters::sample_textured_area_light(
                            &triangles,
                            |k, ab| radiance * texture.lookup(&mesh.tex_coords(k, ab.x, ab.y), &scene.textures),
                            samples as usize,
                            0.0,
                            seed,
                        ),
                    };
                    // The back: the same triangles, facing the other way.
                    let back: Vec<_> = if both_sides {
                        front.iter().map(|l| AreaLight { normal: -l.normal, ..*l }).collect()
                    } else {
                        Vec::new()
                    };
                    lights.area.extend(front);
                    lights.area.extend(back);
                }
                LightSource::Sun { direction, irradiance, angular_radius_degrees, samples, .. }
                    if angular_radius_degrees > 0.0 && samples > 1 =>
                {
                    lights.suns.push(SunDisc {
                        direction: direction.normalize(),
                        irradiance,
                        cos_max: angular_radius_degrees.to_radians().cos(),
                        samples,
                    });
                }
                LightSource::Sun { direction, irradiance, angular_radius_degrees, samples, seed } => {
                    lights.directional.extend(emitters::sample_sun(
                        direction,
                        irradiance,
                        angular_radius_degrees,
                        samples as usize,
                        seed,
                    ));
                }
            }
        }
        let environment = scene.environment.as_ref().filter(|_| leaves == EmitterLeaves::Parts);
        if let Some(environment) = environment.filter(|_| wanted(scene.groups.environment)) {
            lights.environment.extend(emitters::sample_environment(
                &environment.map,
                environment.samples as usize,
                0xe4f,
            ));
        }
        lights
    }

    /// Adds `other`'s lights after these, kind by kind.
    pub fn append(&mut self, other: &Self) {
        self.omni.extend_from_slice(&other.omni);
        self.area.extend_from_slice(&other.area);
        self.oriented.extend_from_slice(&other.oriented);
        self.directional.extend_from_slice(&other.directional);
        self.environment.extend_from_slice(&other.environment);
        self.spot.extend_from_slice(&other.spot);
        self.moving.extend_from_slice(&other.moving);
        self.suns.extend_from_slice(&other.suns);
    }

    #[must_use]
    pub fn len(&self) -> usize {
        self.omni.len()
            + self.area.len()
            + self.oriented.len()
            + self.directional.len()
            + self.environment.len()
            + self.spot.len()
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
            LightKind::Area => self.area.len(),
            LightKind::Oriented => self.oriented.len(),
            LightKind::Directional => self.directional.len(),
            LightKind::Environment => self.environment.len(),
            LightKind::Spot => self.spot.len(),
        }
    }

    /// Calls `f` for every light, omni, area, oriented, directional,
    /// environment, then spot, each in order. Plain loops: after inlining, each loop's `Light`
    /// variant is known, so the exact renderer's hot path does not branch
    /// on the kind per light.
    #[inline(always)]
    pub fn for_each(&self, mut f: impl FnMut(Light)) {
        for l in &self.omni {
            f(Light::Omni(*l));
        }
        for l in &self.area {
            f(Light::Area(*l));
        }
        for l in &self.oriented {
            f(Light::Oriented(*l));
        }
        for l in &self.directional {
            f(Light::Directional(*l));
        }
        for l in &self.environment {
            f(Light::Environment(*l));
        }
        for l in &self.spot {
            f(Light::Spot(*l));
        }
    }

    /// The lights of one kind as tree leaves, in order.
    #[must_use]
    pub fn tree_lights(&self, kind: LightKind) -> Vec<TreeLight> {
        match kind {
            LightKind::Omni => self.omni.iter().map(|l| TreeLight::of(&Light::Omni(*l))).collect(),
            LightKind::Area => self.area.iter().map(|l| TreeLight::of(&Light::Area(*l))).collect(),
            LightKind::Oriented => self.oriented.iter().map(|l| TreeLight::of(&Light::Oriented(*l))).collect(),
            LightKind::Directional => self.directional.iter().map(|l| TreeLight::of(&Light::Directional(*l))).collect(),
            LightKind::Environment => self.environment.iter().map(|l| TreeLight::of(&Light::Environment(*l))).collect(),
            LightKind::Spot => self.spot.iter().map(|l| TreeLight::of(&Light::Spot(*l))).collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scene_becomes_lights_of_each_kind_in_file_order() {
        let text = r#"
[[lights]]
type = "point"
position = [0, 2, 0]
intensity = [1, 1, 1]
[[lights]]
type = "grid"
corner = [-1, 3, -1]
u = [2, 0, 0]
v = [0, 0, 2]
count = [3, 2]
intensity = [0.5, 0.5, 0.5]
[[lights]]
type = "area"
corner = [0, 2, 0]
u = [1, 0, 0]
v = [0, 0, 1]
radiance = [1, 1, 1]
samples = 10
[[lights]]
type = "sun"
direction = [0, 2, 0]
irradiance = [3, 3, 3]
[environment]
radiance = [0.1, 0.1, 0.1]
samples = 7
"#;
        let scene = crate::scene::with_lights_only(text);
        let lights = Lights::from_scene(&scene);
        assert_eq!(lights.omni.len(), 1 + 6);
        // Grid lights sit at cell centres, row by row.
        let first = lights.omni[1].position;
        assert!((first - Vec3::new(-1.0 + 2.0 / 6.0, 3.0, -0.5)).length() < 1e-6, "{first}");
        // Two triangles, five samples' share each: 2 x 2 parts each.
        assert_eq!(lights.area.len(), 8);
        assert_eq!(lights.directional, vec![DirectionalLight { direction: Vec3::Y, irradiance: Vec3::splat(3.0) }]);
        assert_eq!(lights.environment.len(), 7, "the environment's lights apart from the sun's");
        let mut kinds = Vec::new();
        lights.for_each(|l| kinds.push(l.kind()));
        assert_eq!(kinds.len(), lights.len());
        assert!(kinds.windows(2).all(|w| w[0] as u8 <= w[1] as u8), "omni, oriented, directional, environment");
    }

    #[test]
    fn tree_leaves_round_trip_their_lights() {
        let lights = [
            Light::Omni(OmniLight { position: Vec3::X, intensity: Vec3::ONE }),
            Light::Oriented(OrientedLight { position: Vec3::Y, normal: Vec3::Z, intensity: Vec3::ONE }),
            Light::Area(AreaLight {
                position: Vec3::Y,
                normal: Vec3::Z,
                intensity: Vec3::ONE,
                edges: [Vec3::X, Vec3::Y],
            }),
            Light::Directional(DirectionalLight { direction: Vec3::Z, irradiance: Vec3::ONE }),
            Light::Spot(SpotLight {
                position: Vec3::X,
                direction: Vec3::NEG_Y,
                intensity: Vec3::ONE,
                cos_inner: 0.9,
                cos_outer: 0.8,
            }),
        ];
        for light in lights {
            assert_eq!(TreeLight::of(&light).light(light.kind()), light);
        }
    }
}
