//! UsdLux lights as this renderer's (docs/scene-format.md, "USD", has the
//! table and the units): every light's radiance is L = intensity x
//! 2^exposure x color, divided by its emitting area in the stage's units
//! when `normalize` is on; rect, disk and cylinder lights become area
//! lights over their shapes (sampled on their surface, seen in
//! reflections); a sphere light is a point light of its far-field
//! intensity L pi r^2 (a spot with `ShapingAPI`); a distant light is the
//! sun with its disc; a dome light is the environment.

use std::f64::consts::PI;

use glam::{DMat4, DVec3, Vec3};

use super::geometry::Located;
use super::schema::Reader;
use crate::scene::mesh::Mesh;
use crate::scene::LightSource;

/// Segments of a disk light's polygon and around a cylinder light.
const SEGMENTS: usize = 48;

/// What a light prim becomes.
pub(super) enum Made {
    /// A light source; an area light's mesh (in world space, metres) comes
    /// with it, to be added as an emitter.
    Light(LightSource, Option<Mesh>),
    /// The environment: constant radiance, or a lat-long texture (its file,
    /// a scale, and the map's rotation into the world).
    Dome { radiance: Vec3, texture: Option<super::stage::Asset>, rotation: DMat4 },
}

/// How the stage's units relate to the world's.
pub(super) struct Units {
    /// Metres per stage unit (`metersPerUnit`).
    pub meters_per_unit: f64,
    /// What a distant light's irradiance is multiplied by: 1, or 4 for a
    /// stage Blender wrote (its exporter writes a sun's strength / 4, and
    /// its importer multiplies by 4 again: docs/scene-format.md).
    pub distant_scale: f64,
    /// Whether the stage is Z-up (DomeLight_1's `poleAxis = "scene"`).
    pub up_z: bool,
}

/// The light at `read.prim` (of type `read.schema`), placed by `world`
/// (the stage root's units and up axis included). `warnings` gets what is
/// rendered otherwise.
pub(super) fn light(
    read: &Reader<'_>,
    world: DMat4,
    units: &Units,
    api_schemas: &[String],
    warnings: &mut Vec<String>,
) -> Result<Option<Made>, Located> {
    let Some(emission) = emission(read, warnings)? else { return Ok(None) };
    let shaped = api_schemas.iter().any(|s| s == "ShapingAPI");
    let placed = Placed { world, units, shaped };
    let made = match read.schema {
        "SphereLight" => sphere_light(read, &emission, &placed, warnings)?,
        "RectLight" | "DiskLight" | "CylinderLight" => match area_light(read, &emission, &placed, warnings)? {
            Some(made) => made,
            None => return Ok(None),
        },
        "DistantLight" => distant_light(read, &emission, &placed)?,
        "DomeLight" | "DomeLight_1" => dome_light(read, &emission, &placed)?,
        other => {
            warnings.push(format!("{}: {other} is not implemented: it emits nothing", read.prim));
            return Ok(None);
        }
    };
    Ok(Some(made))
}

/// What every light says of its emission (UsdLuxLightAPI).
struct Emission {
    /// intensity x 2^exposure x color: radiance, per stage unit^2 when
    /// normalised (as a renderer in the stage's units has it).
    radiance: DVec3,
    normalize: bool,
}

/// How a light is placed.
struct Placed<'a> {
    world: DMat4,
    units: &'a Units,
    /// Whether ShapingAPI is applied.
    shaped: bool,
}

impl Placed<'_> {
    /// Areas in metres^2 as the stage's units^2, which a normalised
    /// light's radiance is divided by.
    fn area_in_stage_units(&self, area_m2: f64) -> f64 {
        area_m2 / (self.units.meters_per_unit * self.units.meters_per_unit)
    }

    /// The direction lights shine along: their local -Z in the world.
    fn forward(&self, prim: &str) -> Result<DVec3, Located> {
        let d = self.world.transform_vector3(DVec3::NEG_Z).normalize_or_zero();
        if d == DVec3::ZERO {
            return Err((format!("{prim}.xformOpOrder"), "the light's transform is degenerate (zero scale)".into()));
        }
        Ok(d)
    }
}

/// A value the renderer holds in f32 (at most 1e30 per channel).
fn finite_rgb(prim: &str, v: DVec3, what: &str) -> Result<Vec3, Located> {
    let v32 = v.as_vec3();
    if v32.is_finite() && v32.max_element() <= 1e30 {
        Ok(v32)
    } else {
        Err((format!("{prim}.inputs:intensity"), format!("the {what} {v} is beyond what the renderer holds (1e30)")))
    }
}

/// The light's emission, checked; None for a light that is not one here.
fn emission(read: &Reader<'_>, warnings: &mut Vec<String>) -> Result<Option<Emission>, Located> {
    let prim = read.prim;
    let at = |attribute: &str| format!("{prim}.{attribute}");
    if matches!(read.schema, "GeometryLight" | "PortalLight" | "PluginLight") {
        warnings.push(format!("{prim}: {} is not implemented: it emits nothing", read.schema));
        return Ok(None);
    }
    let intensity = read.number("inputs:intensity")?;
    let exposure = read.number("inputs:exposure")?;
    let color = read.vec3("inputs:color")?;
    if intensity < 0.0 || color.min_element() < 0.0 {
        return Err((at("inputs:intensity"), format!("intensity {intensity} and color {color} must be >= 0")));
    }
    if !(-200.0..=200.0).contains(&exposure) {
        return Err((at("inputs:exposure"), format!("must be within +/-200 stops, got {exposure}")));
    }
    // The temperature's colour is normalised so that 6500 K is white:
    // only another temperature would change the light.
    if read.boolean("inputs:enableColorTemperature")? && read.number("inputs:colorTemperature")? != 6500.0 {
        warnings.push(format!(
            "{prim}: inputs:colorTemperature other than 6500 K is not implemented: the light is its color alone"
        ));
    }
    for (attribute, what) in [("inputs:diffuse", "diffuse"), ("inputs:specular", "specular")] {
        if read.number(attribute)? != 1.0 {
            warnings.push(format!(
                "{prim}.{attribute}: the {what} multiplier (a non-physical control) is not implemented: 1"
            ));
        }
    }
    if read.stage.boolean(prim, "inputs:shadow:enable", read.time).ok().flatten() == Some(false) {
        warnings.push(format!("{prim}: inputs:shadow:enable = false is not implemented: the light casts shadows"));
    }
    let normalize = read.boolean("inputs:normalize")?;
    Ok(Some(Emission { radiance: color * intensity * 2f64.powf(exposure), normalize }))
}

/// A sphere light as a point light (a spot with ShapingAPI's cone) of its
/// far-field intensity: a Lambertian sphere of radiance L has intensity
/// L pi r^2 in every direction.
fn sphere_light(
    read: &Reader<'_>,
    emission: &Emission,
    placed: &Placed<'_>,
    warnings: &mut Vec<String>,
) -> Result<Made, Located> {
    let prim = read.prim;
    let radius = read.number("inputs:radius")?;
    if radius < 0.0 {
        return Err((format!("{prim}.inputs:radius"), format!("must be >= 0, got {radius}")));
    }
    // The radius in metres: times the world's scale (its axes' mean).
    let world = &placed.world;
    let scale =
        (world.x_axis.truncate().length() + world.y_axis.truncate().length() + world.z_axis.truncate().length()) / 3.0;
    let r_m = radius * scale;
    // Normalised, L / (4 pi r^2) (per stage unit^2) times pi r^2 (in
    // metres^2) is L mpu^2 / 4 whatever the radius: a point light of
    // radius 0 keeps its power.
    let mpu = placed.units.meters_per_unit;
    let intensity =
        if emission.normalize { emission.radiance * mpu * mpu / 4.0 } else { emission.radiance * PI * r_m * r_m };
    let intensity = finite_rgb(prim, intensity, "intensity")?;
    if r_m == 0.0 && !emission.normalize {
        warnings
            .push(format!("{prim}: a sphere light of radius 0 emits nothing (intensity is radiance, over no area)"));
    }
    let position = world.transform_point3(DVec3::ZERO).as_vec3();
    let source = match shaping(read, placed.shaped, prim, warnings)? {
        None => LightSource::Point { position, intensity },
        Some((inner, outer)) => LightSource::Spot {
            position,
            direction: placed.forward(prim)?.as_vec3(),
            intensity,
            inner_angle_degrees: inner,
            outer_angle_degrees: outer,
        },
    };
    Ok(Made::Light(source, None))
}

/// A rect, disk or cylinder light as an area light over its shape (in the
/// world, metres), emitting L (divided by its area in stage units^2 when
/// normalised) from the side the schema says.
fn area_light(
    read: &Reader<'_>,
    emission: &Emission,
    placed: &Placed<'_>,
    warnings: &mut Vec<String>,
) -> Result<Option<Made>, Located> {
    let (prim, type_name) = (read.prim, read.schema);
    let at = |attribute: &str| format!("{prim}.{attribute}");
    if placed.shaped {
        warnings
            .push(format!("{prim}: ShapingAPI on a {type_name} is not implemented: it emits as a Lambertian surface"));
    }
    if read.stage.has_value(prim, "inputs:texture:file", read.time).map_err(|e| (at("inputs:texture:file"), e))? {
        warnings.push(format!("{prim}: inputs:texture:file on a {type_name} is not implemented: its color is uniform"));
    }
    let local = match type_name {
        "RectLight" => {
            let (w, h) = (read.number("inputs:width")?, read.number("inputs:height")?);
            if w < 0.0 || h < 0.0 {
                return Err((at("inputs:width"), format!("width {w} and height {h} must be >= 0")));
            }
            // u x v points along -Z: the side it emits towards.
            let (w, h) = (w as f32, h as f32);
            Mesh::quad(Vec3::new(-0.5 * w, -0.5 * h, 0.0), Vec3::new(0.0, h, 0.0), Vec3::new(w, 0.0, 0.0), 0)
        }
        "DiskLight" => {
            let r = read.number("inputs:radius")?;
            if r < 0.0 {
                return Err((at("inputs:radius"), format!("must be >= 0, got {r}")));
            }
            disk(r as f32)
        }
        _ => {
            let (r, length) = (read.number("inputs:radius")?, read.number("inputs:length")?);
            if r < 0.0 || length < 0.0 {
                return Err((at("inputs:radius"), format!("radius {r} and length {length} must be >= 0")));
            }
            if read.boolean("treatAsLine")? {
                warnings.push(format!("{prim}: treatAsLine is a hint: the cylinder's surface emits"));
            }
            cylinder(r as f32, length as f32)
        }
    };
    let mesh = placed_mesh(local, &placed.world);
    let area_m2 = mesh.surface_area();
    if area_m2 == 0.0 {
        warnings.push(format!("{prim}: the {type_name} has no area: it emits nothing"));
        return Ok(None);
    }
    let radiance =
        if emission.normalize { emission.radiance / placed.area_in_stage_units(area_m2) } else { emission.radiance };
    let radiance = finite_rgb(prim, radiance, "radiance")?;
    let source = LightSource::Area { mesh: usize::MAX, radiance, samples: 0, seed: 0, both_sides: false };
    Ok(Some(Made::Light(source, Some(mesh))))
}

/// A distant light as the sun: a disc of `angle` (its diameter), whose
/// irradiance is the disc's radiance times its solid angle, or (normalised,
/// or a disc of no size) L itself.
fn distant_light(read: &Reader<'_>, emission: &Emission, placed: &Placed<'_>) -> Result<Made, Located> {
    let prim = read.prim;
    let angle = read.number("inputs:angle")?;
    if !(0.0..=90.0).contains(&angle) {
        return Err((format!("{prim}.inputs:angle"), format!("must be between 0 and 90 degrees here, got {angle}")));
    }
    let solid_angle = 2.0 * PI * (1.0 - (0.5 * angle).to_radians().cos());
    let irradiance =
        if emission.normalize || angle == 0.0 { emission.radiance } else { emission.radiance * solid_angle };
    let irradiance = irradiance * placed.units.distant_scale;
    let source = LightSource::Sun {
        // Towards the light: against the direction it shines.
        direction: (-placed.forward(prim)?).as_vec3(),
        irradiance: finite_rgb(prim, irradiance, "irradiance")?,
        angular_radius_degrees: (0.5 * angle) as f32,
        samples: 16,
        seed: 0,
    };
    Ok(Made::Light(source, None))
}

/// A dome light: its radiance, its lat-long texture if any, and the map's
/// rotation into the world (its axes, unit length: a dome is infinitely
/// far, neither moved nor scaled). DomeLight's pole is its local +Y;
/// DomeLight_1's the stage's up axis (`poleAxis = "scene"`) or as given,
/// turned onto +Y by 90 degrees about X as Hydra turns it.
fn dome_light(read: &Reader<'_>, emission: &Emission, placed: &Placed<'_>) -> Result<Made, Located> {
    let prim = read.prim;
    let at = |attribute: &str| format!("{prim}.{attribute}");
    let format = read.token("inputs:texture:format")?;
    if !matches!(format.as_str(), "automatic" | "latlong") {
        return Err((at("inputs:texture:format"), format!("'{format}' is not implemented (latlong is)")));
    }
    let texture =
        read.stage.asset(prim, "inputs:texture:file", read.time).map_err(|e| (at("inputs:texture:file"), e))?;
    let texture = texture.filter(|t| !t.authored.is_empty());
    let world = &placed.world;
    let axis = |v: glam::DVec4| v.truncate().normalize_or_zero().extend(0.0);
    let mut rotation = DMat4::from_cols(axis(world.x_axis), axis(world.y_axis), axis(world.z_axis), glam::DVec4::W);
    if read.schema == "DomeLight_1" {
        let pole_z = match read.token("poleAxis")?.as_str() {
            "scene" => placed.units.up_z,
            "Y" => false,
            "Z" => true,
            other => return Err((at("poleAxis"), format!("must be scene, Y or Z, got '{other}'"))),
        };
        if pole_z {
            rotation *= DMat4::from_rotation_x(PI / 2.0);
        }
    }
    Ok(Made::Dome { radiance: finite_rgb(prim, emission.radiance, "radiance")?, texture, rotation })
}

/// ShapingAPI's cone as a spot's (inner, outer) half-angles in degrees;
/// None without a cone (90 degrees or more, or no ShapingAPI). Softness s
/// widens the falloff inwards: inner = angle (1 - s).
fn shaping(
    read: &Reader<'_>,
    shaped: bool,
    prim: &str,
    warnings: &mut Vec<String>,
) -> Result<Option<(f32, f32)>, Located> {
    if !shaped {
        return Ok(None);
    }
    let angle = read.number("inputs:shaping:cone:angle")?;
    let softness = read.number("inputs:shaping:cone:softness")?.clamp(0.0, 1.0);
    if read.number("inputs:shaping:focus")? != 0.0 {
        warnings.push(format!("{prim}: inputs:shaping:focus is not implemented: 0"));
    }
    if read.stage.has_value(prim, "inputs:shaping:ies:file", read.time).unwrap_or(false) {
        warnings.push(format!("{prim}: IES profiles are not implemented"));
    }
    if angle <= 0.0 {
        return Err((format!("{prim}.inputs:shaping:cone:angle"), format!("must be > 0, got {angle}")));
    }
    if angle >= 90.0 {
        return Ok(None);
    }
    let outer = angle as f32;
    Ok(Some(((angle * (1.0 - softness)) as f32, outer)))
}

/// A disk of radius r in the xy plane, facing -z.
fn disk(r: f32) -> Mesh {
    let mut positions = vec![Vec3::ZERO];
    let mut triangles = Vec::new();
    for k in 0..SEGMENTS {
        let phi = std::f32::consts::TAU * k as f32 / SEGMENTS as f32;
        positions.push(Vec3::new(r * phi.cos(), r * phi.sin(), 0.0));
        let next = 1 + (k + 1) % SEGMENTS;
        // Clockwise seen from +z: the normal is -z.
        triangles.push([0, next as u32, (1 + k) as u32]);
    }
    Mesh { positions, triangles, ..Mesh::default() }
}

/// A cylinder's side (no caps) about the x axis, facing out.
fn cylinder(r: f32, length: f32) -> Mesh {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for k in 0..SEGMENTS {
        let phi = std::f32::consts::TAU * k as f32 / SEGMENTS as f32;
        let (y, z) = (r * phi.cos(), r * phi.sin());
        positions.push(Vec3::new(-0.5 * length, y, z));
        positions.push(Vec3::new(0.5 * length, y, z));
    }
    for k in 0..SEGMENTS {
        let (a0, a1) = ((2 * k) as u32, (2 * k + 1) as u32);
        let (b0, b1) = ((2 * ((k + 1) % SEGMENTS)) as u32, (2 * ((k + 1) % SEGMENTS) + 1) as u32);
        // (b0 - a0) runs along the circle, (a1 - a0) along +x: their cross
        // product, (b0 - a0) x (a1 - a0), points out.
        triangles.push([a0, b0, a1]);
        triangles.push([b0, b1, a1]);
    }
    Mesh { positions, triangles, ..Mesh::default() }
}

/// A mesh moved into the world by `world` (turned around if it mirrors).
pub(super) fn placed_mesh(mut mesh: Mesh, world: &DMat4) -> Mesh {
    for p in &mut mesh.positions {
        *p = world.transform_point3(p.as_dvec3()).as_vec3();
    }
    if let Some(normals) = &mut mesh.normals {
        let normal_matrix = glam::DMat3::from_mat4(*world).inverse().transpose();
        for n in normals {
            *n = (normal_matrix * n.as_dvec3()).normalize_or_zero().as_vec3();
        }
    }
    if let Some(strands) = &mut mesh.strands {
        // A radius scales as lengths do on average (exactly, for a similarity).
        let scale = world.determinant().abs().cbrt() as f32;
        for r in &mut strands.radii {
            *r *= scale;
        }
    }
    let mirrors = world.determinant() < 0.0;
    if let Some(tangents) = &mut mesh.tangents {
        for t in tangents {
            let xyz = world.transform_vector3(t.truncate().as_dvec3()).normalize_or_zero().as_vec3();
            *t = xyz.extend(if mirrors { -t.w } else { t.w });
        }
    }
    if mirrors {
        for t in &mut mesh.triangles {
            t.swap(1, 2);
        }
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    fn facing(mesh: &Mesh) -> Vec3 {
        mesh.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
                (b - a).cross(c - a)
            })
            .sum()
    }

    #[test]
    fn a_disk_faces_minus_z_and_has_its_area() {
        let d = disk(2.0);
        let f = facing(&d);
        assert!(f.z < 0.0 && f.x.abs() < 1e-4 && f.y.abs() < 1e-4, "{f}");
        let polygon = 0.5 * SEGMENTS as f64 * 4.0 * (std::f64::consts::TAU / SEGMENTS as f64).sin();
        assert!((d.surface_area() - polygon).abs() < 1e-4);
    }

    #[test]
    fn a_cylinder_light_faces_out() {
        let c = cylinder(1.0, 2.0);
        for t in &c.triangles {
            let [a, b, p] = t.map(|i| c.positions[i as usize]);
            let n = (b - a).cross(p - a);
            let out = ((a + b + p) / 3.0).with_x(0.0);
            assert!(n.dot(out) > 0.0);
        }
    }

    #[test]
    fn a_mirroring_placement_turns_the_triangles_around() {
        let quad = Mesh::quad(Vec3::ZERO, Vec3::Y, Vec3::X, 0);
        assert!(facing(&quad).z < 0.0);
        let mirrored = placed_mesh(quad, &DMat4::from_scale(DVec3::new(1.0, 1.0, -1.0)));
        // Mirrored in z, the quad that faced -z faces +z, and its winding says so.
        assert!(facing(&mirrored).z > 0.0);
    }
}
