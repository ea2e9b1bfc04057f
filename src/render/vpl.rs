//! Indirect light by instant radiosity (Keller 1997; [LC05]; docs/design.md §6.4): light
//! paths from every emitter leave virtual point lights (oriented lights) at
//! diffuse hits, carrying the reflected power.
//!
//! A path starts at an emitter chosen in proportion to its power (luminance)
//! and carries power Phi / (p * paths). At each diffuse hit it leaves a VPL of
//! intensity Phi_path * k_d / pi along the shading normal (a Lambertian
//! reflector's I(theta) = Phi k_d cos(theta) / pi), then continues in a
//! cosine-distributed direction with power Phi_path * k_d, up to `bounces`
//! hits. Mirror-only surfaces and emitters end a path. The 1/d^2 spike near
//! a VPL is clamped by the scene's `render.distance_clamp`, identically in
//! every render mode.
//!
//! Deterministic: path k draws from the stream (seed, k), and paths are
//! collected in order, for any thread count.

use std::f32::consts::PI;

use glam::Vec3;
use rayon::prelude::*;

use crate::embree::Ray;
use crate::light::{AreaLight, Light, Lights, OrientedLight, SpotLight};
use crate::scene::VplSettings;
use crate::shading::Geometry;
use crate::util::color::luminance;
use crate::util::streams::Stream;

/// Where a light path starts.
#[derive(Debug, Clone, Copy)]
enum Source {
    Omni {
        position: Vec3,
    },
    /// An omni light moving from `start` to `end` over the shutter.
    MovingOmni {
        start: Vec3,
        end: Vec3,
    },
    Oriented {
        position: Vec3,
        normal: Vec3,
    },
    /// An area light's triangle: from a point uniform on it.
    Triangle {
        light: AreaLight,
    },
    /// From infinity along -direction, through a disc covering the scene.
    Directional {
        direction: Vec3,
    },
    /// A spot: directions uniform in its outer cone, each path's power then
    /// scaled by the spot's falloff in its direction.
    Spot {
        position: Vec3,
        direction: Vec3,
        cos_inner: f32,
        cos_outer: f32,
    },
}

/// A cosine-distributed direction about unit `n`.
fn cosine_direction(n: Vec3, u: f32, v: f32) -> Vec3 {
    let r = u.sqrt();
    let phi = 2.0 * PI * v;
    let (t, b) = n.any_orthonormal_pair();
    (t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u).max(0.0).sqrt()).normalize()
}

fn uniform_direction(u: f32, v: f32) -> Vec3 {
    let z = 1.0 - 2.0 * u;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * v;
    Vec3::new(r * phi.cos(), z, r * phi.sin())
}

/// Traces `settings.paths` light paths from the lights of every group
/// (`groups[g]`: group g's lights); returns each group's VPLs, in path
/// order: a VPL belongs to the group of the light its path started from,
/// so that a group's layer holds its indirect light too.
#[must_use]
pub fn trace(geometry: &Geometry<'_>, groups: &[Lights], settings: VplSettings, seed: u64) -> Vec<Vec<OrientedLight>> {
    let mut by_group = vec![Vec::new(); groups.len()];
    let (lo, hi) = geometry.bounds;
    if !(lo.is_finite() && hi.is_finite()) || settings.paths == 0 {
        return by_group;
    }
    let centre = 0.5 * (lo + hi);
    let radius = (0.5 * (hi - lo).length()).max(geometry.ray_epsilon);
    // Emitters with their power: 4 pi I for omni, pi I for oriented (cosine
    // lobe), E times the disc's area for directional.
    let mut sources: Vec<(Source, Vec3)> = Vec::new();
    let mut source_group: Vec<usize> = Vec::new();
    for (g, lights) in groups.iter().enumerate() {
        source_group.resize(source_group.len() + lights.len() + lights.moving.len() + lights.suns.len(), g);
        lights.for_each(|light| {
            sources.push(match light {
                Light::Omni(l) => (Source::Omni { position: l.position }, 4.0 * PI * l.intensity),
                Light::Area(l) => (Source::Triangle { light: l }, PI * l.intensity),
                Light::Oriented(l) => (Source::Oriented { position: l.position, normal: l.normal }, PI * l.intensity),
                Light::Directional(l) | Light::Environment(l) => {
                    (Source::Directional { direction: l.direction }, PI * radius * radius * l.irradiance)
                }
                // At most I times the outer cone's solid angle (the falloff is at most 1).
                Light::Spot(l) => (
                    Source::Spot {
                        position: l.position,
                        direction: l.direction,
                        cos_inner: l.cos_inner,
                        cos_outer: l.cos_outer,
                    },
                    2.0 * PI * (1.0 - l.cos_outer) * l.intensity,
                ),
            });
        });
        for l in &lights.moving {
            sources.push((Source::MovingOmni { start: l.start, end: l.end }, 4.0 * PI * l.intensity));
        }
        // A sun's disc emits from its centre's direction (its few tenths of
        // a degree do not matter to light that bounces).
        for l in &lights.suns {
            sources.push((Source::Directional { direction: l.direction }, PI * radius * radius * l.irradiance));
        }
    }
    let total: f64 = sources.iter().map(|s| f64::from(luminance(s.1))).sum();
    if total <= 0.0 {
        return by_group;
    }
    let mut cdf = Vec::with_capacity(sources.len());
    let mut running = 0.0;
    for s in &sources {
        running += f64::from(luminance(s.1)) / total;
        cdf.push(running);
    }
    let eps = geometry.ray_epsilon;
    let moves = geometry.scene.moves();
    let paths: Vec<(usize, Vec<OrientedLight>)> = (0..settings.paths)
        .into_par_iter()
        .map(|k| {
            let mut rng = Stream::Vpl.rng(&[seed, k as u64]);
            let u = rng.next_f64();
            let index = cdf.partition_point(|&c| c < u).min(sources.len() - 1);
            let p_source = f64::from(luminance(sources[index].1)) / total;
            let mut power = sources[index].1 / (p_source * settings.paths as f64) as f32;
            // In a scene that moves, path k is traced at a time of its own,
            // stratified over the shutter; its VPLs then stay where it left
            // them for the whole shutter (docs/design.md §13.6).
            let time = if moves { (k as f32 + rng.next_f32()) / settings.paths as f32 } else { 0.0 };
            let (origin, direction) = match sources[index].0 {
                Source::Omni { position } => (position, uniform_direction(rng.next_f32(), rng.next_f32())),
                Source::MovingOmni { start, end } => {
                    (start.lerp(end, time), uniform_direction(rng.next_f32(), rng.next_f32()))
                }
                Source::Oriented { position, normal } => {
                    (position + normal * eps, cosine_direction(normal, rng.next_f32(), rng.next_f32()))
                }
                Source::Triangle { light } => {
                    let position = light.point_at([rng.next_f32(), rng.next_f32()]);
                    (position + light.normal * eps, cosine_direction(light.normal, rng.next_f32(), rng.next_f32()))
                }
                Source::Spot { position, direction, cos_inner, cos_outer } => {
                    // Uniform in the cone's solid angle: the path carries the
                    // power the falloff lets through in its direction.
                    let cos_theta = 1.0 - rng.next_f32() * (1.0 - cos_outer);
                    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
                    let phi = 2.0 * PI * rng.next_f32();
                    let (t, b) = direction.any_orthonormal_pair();
                    let d = direction * cos_theta + t * (sin_theta * phi.cos()) + b * (sin_theta * phi.sin());
                    power *= SpotLight::falloff(cos_theta, cos_inner, cos_outer);
                    (position, d.normalize())
                }
                Source::Directional { direction } => {
                    // A uniform point on the disc facing the light, outside the scene.
                    let (t, b) = direction.any_orthonormal_pair();
                    let (r, phi) = (radius * rng.next_f32().sqrt(), 2.0 * PI * rng.next_f32());
                    (centre + direction * (2.0 * radius) + t * (r * phi.cos()) + b * (r * phi.sin()), -direction)
                }
            };
            let mut ray = Ray { origin, direction, t_near: 0.0, t_far: f32::INFINITY, time };
            let mut vpls = Vec::new();
            for _ in 0..settings.bounces {
                let Some(hit) = geometry.embree.intersect(&ray) else { break };
                let sp = geometry.surface(&ray, &hit);
                if sp.emitted != Vec3::ZERO || sp.kd == Vec3::ZERO {
                    break;
                }
                vpls.push(OrientedLight { position: sp.offset_origin(), normal: sp.n, intensity: power * sp.kd / PI });
                power *= sp.kd;
                let direction = cosine_direction(sp.n, rng.next_f32(), rng.next_f32());
                ray = sp.ray_towards(direction);
            }
            (source_group[index], vpls)
        })
        .collect();
    for (group, vpls) in paths {
        by_group[group].extend(vpls);
    }
    by_group
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::embree::Device;
    use crate::scene::Scene;

    /// A 1 m^2 emitter of radiance 2 facing down, 0.5 m over a 400 m^2 floor
    /// of albedo 0.5: nearly all of its power pi * Le * A reaches the floor.
    fn scene() -> Scene {
        let text = r#"
[film]
width = 8
height = 8
[camera]
eye = [0, 3, 3]
look_at = [0, 0, 0]
fov_y = 60
[materials.floor]
albedo = [0.5, 0.5, 0.5]
[[shapes]]
type = "quad"
corner = [-10, 0, -10]
u = [0, 0, 20]
v = [20, 0, 0]
material = "floor"
[[lights]]
type = "area"
corner = [-0.5, 0.5, -0.5]
u = [1, 0, 0]
v = [0, 0, 1]
radiance = [2, 2, 2]
samples = 64
[indirect]
paths = 20000
bounces = 1
"#;
        Scene::from_spec(std::path::Path::new("vpl.toml"), toml::from_str(text).unwrap()).unwrap()
    }

    #[test]
    fn one_bounce_vpls_carry_the_reflected_power_and_are_deterministic() {
        let scene = scene();
        let lights = Lights::from_scene(&scene);
        let device = Device::try_new().unwrap();
        let geometry = Geometry::try_new(&device, &scene, std::slice::from_ref(&lights)).unwrap();
        let Some(crate::scene::Indirect::Vpl(settings)) = scene.indirect else { panic!("VPL settings") };
        let groups = std::slice::from_ref(&lights);
        let vpls = trace(&geometry, groups, settings, 7).remove(0);
        assert!(vpls.len() > 19_000, "nearly every path hits the floor: {}", vpls.len());
        // A VPL radiates pi * I in all (cosine lobe).
        let power: f32 = vpls.iter().map(|v| PI * v.intensity.x).sum();
        // The emitted power pi * Le * A; the floor catches all but the part
        // leaving at grazing angles past its edges (cos^2 beyond 10 m at 0.5 m
        // height: under 0.3%).
        let reflected = 0.5 * PI * 2.0 * 1.0;
        assert!((power - reflected).abs() <= 0.01 * reflected, "{power} vs {reflected}");
        assert!(vpls.iter().all(|v| v.normal.y > 0.99 && v.position.y > 0.0));
        assert_eq!(vpls, trace(&geometry, groups, settings, 7)[0], "same seed, same VPLs");
        assert_ne!(vpls, trace(&geometry, groups, settings, 8)[0], "another seed, other VPLs");
        let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        assert_eq!(vpls, one_thread.install(|| trace(&geometry, groups, settings, 7))[0], "any thread count");
    }
}
