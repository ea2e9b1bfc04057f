//! The `[[lights]]`: point, spot, grid, area (quad or OBJ emitters, visible
//! geometry too) and sun lights, each with an optional light group and name.

use std::path::{Path, PathBuf};

use glam::Vec3;

use super::{within_limits, Validator, MAX_COORDINATE};
use crate::scene::file::{self, AreaMeshSpec, AreaSpec, GridSpec, LightSpec, PointSpec, SceneFile, SunSpec};
use crate::scene::{Albedo, Environment, LightSource, Material, Mesh, SceneError, MAX_GRID_LIGHTS};

pub use crate::scene::MAX_EMISSION;

/// The most the lights of a scene may emit in all: their intensities'
/// sum (W/sr; irradiances in W/m^2 for lights at infinity, an area light
/// counted as radiance x area), and with indirect light the power its light
/// paths share out (W). The light trees sum intensities in f32 (at most
/// 3.4e38) and VPLs carry a path's share of the power in f32: 1e36 keeps
/// both finite with room to spare (docs/scene-format.md, "Limits").
pub const MAX_TOTAL_EMISSION: f64 = 1e36;

/// The light group each light asks for, with the field that names it.
pub(super) type RequestedGroups = Vec<(Option<String>, String)>;

/// The lights, in file order, and the group each asks for; emitters add
/// their meshes and materials.
pub(super) fn lights(
    v: &Validator<'_>,
    base: &Path,
    spec: &SceneFile,
    meshes: &mut Vec<Mesh>,
    materials: &mut Vec<Material>,
    inputs: &mut Vec<PathBuf>,
) -> Result<(Vec<LightSource>, RequestedGroups), SceneError> {
    let mut lights = Vec::new();
    // The group each light asks for, with the field that names it.
    let mut requested_groups = Vec::new();
    for (i, raw) in spec.lights.iter().enumerate() {
        let field = |f: &str| format!("lights[{i}].{f}");
        let entry_error = |e: file::SpecError| v.error(&format!("lights[{i}]{}", e.field()), &e.to_string());
        let mut raw = raw.clone();
        let name = file::take_string(&mut raw, "name", ".name").map_err(entry_error)?;
        let group = file::take_string(&mut raw, "group", ".group").map_err(entry_error)?;
        requested_groups.push((group, field("group")));
        let light = LightSpec::parse(&raw).map_err(entry_error)?;
        // An emitter's geometry is an object too (Cryptomatte).
        let emitter_name = name.unwrap_or_else(|| format!("lights[{i}]"));
        let source = light_source(v, base, i, &light, emitter_name, meshes, materials, inputs)?;
        lights.push(source);
    }
    Ok((lights, requested_groups))
}

/// The light source `lights[i]` describes, validated; an emitter adds its
/// mesh (named `emitter_name`) and material.
#[allow(clippy::too_many_arguments)]
fn light_source(
    v: &Validator<'_>,
    base: &Path,
    i: usize,
    light: &LightSpec,
    emitter_name: String,
    meshes: &mut Vec<Mesh>,
    materials: &mut Vec<Material>,
    inputs: &mut Vec<PathBuf>,
) -> Result<LightSource, SceneError> {
    let field = |f: &str| format!("lights[{i}].{f}");
    Ok(match light {
        LightSpec::Point(PointSpec { position, intensity, position_end }) => {
            let position = v.point(*position, &field("position"))?;
            let intensity = v.emission(*intensity, &field("intensity"))?;
            match position_end {
                Some(end) => {
                    LightSource::MovingPoint { start: position, end: v.point(*end, &field("position_end"))?, intensity }
                }
                None => LightSource::Point { position, intensity },
            }
        }
        LightSpec::Spot(file::SpotSpec { position, direction, intensity, inner_angle, outer_angle }) => {
            let position = v.point(*position, &field("position"))?;
            let direction = v.point(*direction, &field("direction"))?;
            v.check(direction.length() > 0.0, &field("direction"), || "must not be zero".into())?;
            let intensity = v.emission(*intensity, &field("intensity"))?;
            v.check(
                outer_angle.is_finite() && *outer_angle > 0.0 && *outer_angle <= 90.0,
                &field("outer_angle"),
                || format!("must be above 0 and at most 90 degrees, got {outer_angle}"),
            )?;
            v.check(
                inner_angle.is_finite() && *inner_angle >= 0.0 && inner_angle < outer_angle,
                &field("inner_angle"),
                || format!("must be at least 0 and below outer_angle ({outer_angle}), got {inner_angle}"),
            )?;
            LightSource::Spot {
                position,
                direction,
                intensity,
                inner_angle_degrees: *inner_angle,
                outer_angle_degrees: *outer_angle,
            }
        }
        LightSpec::Grid(GridSpec { corner, u, v: edge_v, count, intensity }) => {
            let c = v.point(*corner, &field("corner"))?;
            let (u, w) = (v.point(*u, &field("u"))?, v.point(*edge_v, &field("v"))?);
            let intensity = v.emission(*intensity, &field("intensity"))?;
            let total = u64::from(count[0]) * u64::from(count[1]);
            v.check(count[0] >= 1 && count[1] >= 1 && total <= MAX_GRID_LIGHTS, &field("count"), || {
                format!("must be at least [1, 1] and at most {MAX_GRID_LIGHTS} lights in all, got {count:?}")
            })?;
            // The lights are convex combinations of the corners: corners
            // within the limits keep every light within them.
            for (corner, name) in [(c + u, "u"), (c + w, "v"), (c + u + w, "v")] {
                v.check(within_limits(corner), &field(name), || {
                    format!("the grid reaches {corner}: coordinates must be within +/-{MAX_COORDINATE:e} m")
                })?;
            }
            LightSource::Grid { corner: c, u, v: w, count: *count, intensity }
        }
        LightSpec::Area(AreaSpec { corner, u, v: edge_v, radiance, samples }) => {
            let c = v.point(*corner, &field("corner"))?;
            let (u, w) = (v.point(*u, &field("u"))?, v.point(*edge_v, &field("v"))?);
            v.check(u.cross(w).length() > 0.0, &field("v"), || {
                "the emitter has zero area (u and v are parallel)".into()
            })?;
            let radiance = v.emission(*radiance, &field("radiance"))?;
            v.sample_count(*samples, &field("samples"))?;
            let quad = Mesh { name: emitter_name, ..Mesh::quad(c, u, w, 0) };
            add_emitter(meshes, materials, quad, radiance, *samples, i as u64)
        }
        LightSpec::AreaMesh(AreaMeshSpec { file, scale, translate, radiance, samples }) => {
            v.check(scale.is_finite() && *scale > 0.0, &field("scale"), || {
                format!("must be finite and > 0, got {scale}")
            })?;
            let t = v.point(*translate, &field("translate"))?;
            let radiance = v.emission(*radiance, &field("radiance"))?;
            v.sample_count(*samples, &field("samples"))?;
            let mesh_path = base.join(file);
            inputs.push(mesh_path.clone());
            if !mesh_path.is_file() {
                return Err(v.error(&field("file"), &format!("mesh file '{}' not found", mesh_path.display())));
            }
            let mesh = Mesh { name: emitter_name, ..Mesh::load_obj(&mesh_path, *scale, t, 0)? };
            if let Some(bad) = mesh.positions.iter().position(|p| !within_limits(*p)) {
                return Err(
                    v.error(&field("file"), &format!("vertex {bad} is outside +/-{MAX_COORDINATE:e} m after scaling"))
                );
            }
            add_emitter(meshes, materials, mesh, radiance, *samples, i as u64)
        }
        LightSpec::Sun(SunSpec { direction, irradiance, angular_radius, samples }) => {
            let d = v.point(*direction, &field("direction"))?;
            v.check(d.length() > 0.0, &field("direction"), || "must not be zero".into())?;
            let irradiance = v.emission(*irradiance, &field("irradiance"))?;
            v.check(
                angular_radius.is_finite() && (0.0..=45.0).contains(angular_radius),
                &field("angular_radius"),
                || format!("must be between 0 and 45 degrees, got {angular_radius}"),
            )?;
            v.sample_count(*samples, &field("samples"))?;
            LightSource::Sun {
                direction: d,
                irradiance,
                angular_radius_degrees: *angular_radius,
                samples: *samples,
                seed: i as u64,
            }
        }
    })
}

/// Checks that the light sources' sums stay within [`MAX_TOTAL_EMISSION`]
/// (each one's emission is within [`MAX_EMISSION`] already): their
/// intensities in all, and, when the scene has indirect light, the power
/// its light paths carry (a light at infinity lights a disc as wide as the
/// scene, `radius` metres). The error names the source that emits the most:
/// `labels[i]` names source i, and `environment` the environment. Returns
/// the power in all and the label of the source that emits the most
/// (`Scene::emitted_power`).
pub(super) fn check_totals(
    v: &Validator<'_>,
    sources: &[LightSource],
    labels: &[String],
    meshes: &[Mesh],
    environment: Option<&Environment>,
    indirect: bool,
    radius: f64,
) -> Result<(f64, String), SceneError> {
    use std::f64::consts::PI;
    let most = |c: Vec3| f64::from(c.max_element());
    // (intensity, power) of each source, and of the environment last.
    let disc = PI * radius * radius;
    let mut each: Vec<(f64, f64)> = sources
        .iter()
        .map(|source| match *source {
            LightSource::Point { intensity, .. }
            | LightSource::MovingPoint { intensity, .. }
            | LightSource::Spot { intensity, .. } => (most(intensity), 4.0 * PI * most(intensity)),
            LightSource::Grid { count, intensity, .. } => {
                let n = f64::from(count[0]) * f64::from(count[1]);
                (n * most(intensity), n * 4.0 * PI * most(intensity))
            }
            LightSource::Area { mesh, radiance, both_sides, .. } => {
                let sides = if both_sides { 2.0 } else { 1.0 };
                let intensity = sides * most(radiance) * meshes[mesh].surface_area();
                (intensity, PI * intensity)
            }
            LightSource::Sun { irradiance, .. } => (most(irradiance), disc * most(irradiance)),
        })
        .collect();
    if let Some(environment) = environment {
        // Its directional lights' irradiances sum to the map's integral,
        // at most 4 pi times its brightest radiance.
        let brightest = f64::from(environment.map.brightest());
        each.push((4.0 * PI * brightest, disc * 4.0 * PI * brightest));
    }
    let label = |k: usize| labels.get(k).map_or("environment", String::as_str).to_string();
    let largest = |part: fn(&(f64, f64)) -> f64| {
        (0..each.len()).max_by(|&a, &b| part(&each[a]).total_cmp(&part(&each[b]))).map_or(0, |k| k)
    };
    let intensity: f64 = each.iter().map(|e| e.0).sum();
    v.check(intensity <= MAX_TOTAL_EMISSION, &label(largest(|e| e.0)), || {
        format!(
            "the lights' intensities sum to {intensity:.3e} in all (W/sr, and W/m^2 for the sun and the \
             environment; this one emits the most): at most {MAX_TOTAL_EMISSION:e}, which the light trees' f32 \
             sums hold"
        )
    })?;
    let power: f64 = each.iter().map(|e| e.1).sum();
    let brightest = label(largest(|e| e.1));
    if indirect {
        v.check(power <= MAX_TOTAL_EMISSION, &brightest, || vpl_power_message(power))?;
    }
    Ok((power, brightest))
}

/// Why a scene emitting `power` W cannot have VPLs.
pub(crate) fn vpl_power_message(power: f64) -> String {
    format!(
        "the lights emit {power:.3e} W in all over the scene (this one the most), which [indirect]'s \
         light paths share out: at most {MAX_TOTAL_EMISSION:e} W, which their VPLs' f32 intensities hold"
    )
}

/// Adds an area emitter's geometry: visible, black, emitting `radiance` from
/// the side its triangles' winding faces. Returns its light: about
/// `samples` triangle lights (a textured emitter's `samples` points drawn
/// with `seed`).
fn add_emitter(
    meshes: &mut Vec<Mesh>,
    materials: &mut Vec<Material>,
    mut mesh: Mesh,
    radiance: Vec3,
    samples: u32,
    seed: u64,
) -> LightSource {
    mesh.material = materials.len();
    mesh.normals = None; // emission is one-sided by the triangles' winding
    materials.push(Material {
        emission: radiance,
        ..Material::diffuse(format!("emitter {seed}"), Albedo::Constant(Vec3::ZERO))
    });
    meshes.push(mesh);
    LightSource::Area { mesh: meshes.len() - 1, radiance, samples, seed, both_sides: false }
}
