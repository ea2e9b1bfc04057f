//! `lightcuts inspect`: what a scene file becomes once loaded (objects
//! with their world bounds, light sources, the camera, the environment,
//! the warnings), without rendering: how a user checks what an importer
//! made of a glTF file or a USD stage, and how the tests compare an
//! import with another reader's evaluation of the same file.

use std::path::PathBuf;

use clap::Args;
use serde_json::json;

use super::CliError;
use crate::scene::mesh::StrandKind;
use crate::scene::{EnvironmentMap, LightSource, LoadOptions, Scene};

#[derive(Debug, Args)]
pub struct InspectArgs {
    /// Scene file: TOML (JSON by its .json extension), glTF 2.0 (.gltf,
    /// .glb) or a USD stage (.usd, .usda, .usdc, .usdz).
    pub scene: PathBuf,
    /// The glTF camera (name or #N) or USD camera (prim path) to load.
    #[arg(long, value_name = "NAME|#N|/PATH")]
    pub camera: Option<String>,
    /// The USD stage's time code to read.
    #[arg(long, value_name = "T", allow_hyphen_values = true)]
    pub time: Option<f64>,
    /// Open the shutter from OPEN to CLOSE (as `render --shutter`).
    #[arg(long, value_name = "OPEN,CLOSE", value_parser = super::args::parse_shutter, allow_hyphen_values = true)]
    pub shutter: Option<[f32; 2]>,
    /// Where a USD stage's assets are looked for (as `render --asset-path`).
    #[arg(long, value_name = "DIR")]
    pub asset_path: Vec<std::path::PathBuf>,
    /// What the scene lacks is an error (as `render --strict`).
    #[arg(long)]
    pub strict: bool,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &InspectArgs) -> Result<(), CliError> {
    let options = LoadOptions {
        camera: args.camera.as_deref(),
        time: args.time,
        shutter: args.shutter,
        asset_paths: &args.asset_path,
        strict: args.strict,
        ..LoadOptions::default()
    };
    super::process::read_usd_in_a_child(&args.scene, &options.flags())?;
    let scene = Scene::load_with(&args.scene, &options)?;
    let report = report(&scene);
    // A reader that stops early (`| head`) is not an error: printing stops.
    let _ = print(&scene, &report, args.json);
    Ok(())
}

fn print(scene: &Scene, report: &serde_json::Value, json: bool) -> std::io::Result<()> {
    use std::io::Write;
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    if json {
        writeln!(out, "{}", serde_json::to_string_pretty(report).expect("plain values serialise"))?;
        return out.flush();
    }
    writeln!(out, "scene        {}", scene.path.display())?;
    writeln!(out, "film         {} x {}, {} spp", scene.film.width, scene.film.height, scene.film.spp)?;
    let c = &scene.camera_spec;
    writeln!(
        out,
        "camera       eye {:?} looking at {:?}, up {:?}, {} degrees vertical",
        c.eye, c.look_at, c.up, c.fov_y
    )?;
    writeln!(
        out,
        "objects      {} ({} triangles drawn, {} stored)",
        scene.objects.len(),
        scene.triangle_count(),
        scene.stored_triangle_count()
    )?;
    for object in report["objects"].as_array().into_iter().flatten() {
        let strands = match (object["curve_segments"].as_u64(), object["spheres"].as_u64()) {
            (Some(n), _) if n > 0 => format!("  ({n} curve segments)"),
            (_, Some(n)) if n > 0 => format!("  ({n} spheres)"),
            _ => String::new(),
        };
        writeln!(out, "  {}  {}  {}{strands}", object["name"], object["min"], object["max"])?;
    }
    writeln!(out, "lights       {}", scene.lights.len())?;
    for light in report["lights"].as_array().into_iter().flatten() {
        writeln!(out, "  {light}")?;
    }
    writeln!(out, "environment  {}", report["environment"])?;
    for warning in &scene.warnings {
        writeln!(out, "warning: {warning}")?;
    }
    for missing in &scene.incomplete {
        writeln!(out, "not drawn: {missing}")?;
    }
    out.flush()
}

/// The scene as JSON: every object's name and world bounds (metres), every
/// light source, the camera, the environment, the warnings.
fn report(scene: &Scene) -> serde_json::Value {
    let objects: Vec<serde_json::Value> = scene
        .objects
        .iter()
        .map(|object| {
            let (lo, hi) = crate::scene::object::world_bounds(&scene.meshes, std::slice::from_ref(object));
            let mesh = &scene.meshes[object.mesh];
            // Curves and points: how many segments or spheres Embree draws.
            let (curve_segments, spheres) = match mesh.strands.as_ref().map(|s| &s.kind) {
                Some(StrandKind::Curves { segments, .. }) => (segments.len(), 0),
                Some(StrandKind::Spheres) => (0, mesh.positions.len()),
                None => (0, 0),
            };
            json!({
                "name": object.name,
                "mesh": object.mesh,
                "instance": object.transform.is_some(),
                "moves": object.motion.is_some(),
                "triangles": mesh.triangles.len(),
                "curve_segments": curve_segments,
                "spheres": spheres,
                "material": scene.materials[scene.meshes[object.mesh].material].name,
                "min": lo.to_array(),
                "max": hi.to_array(),
            })
        })
        .collect();
    let lights: Vec<serde_json::Value> = scene
        .lights
        .iter()
        .map(|light| match *light {
            LightSource::Point { position, intensity } => {
                json!({ "kind": "point", "position": position.to_array(), "intensity": intensity.to_array() })
            }
            LightSource::MovingPoint { start, end, intensity } => json!({
                "kind": "moving point", "start": start.to_array(), "end": end.to_array(), "intensity": intensity.to_array()
            }),
            LightSource::Spot { position, direction, intensity, inner_angle_degrees, outer_angle_degrees } => json!({
                "kind": "spot", "position": position.to_array(), "direction": direction.to_array(),
                "intensity": intensity.to_array(), "inner_degrees": inner_angle_degrees, "outer_degrees": outer_angle_degrees
            }),
            LightSource::Grid { count, intensity, .. } => {
                json!({ "kind": "grid", "count": count, "intensity": intensity.to_array() })
            }
            LightSource::Area { mesh, radiance, samples, both_sides, .. } => json!({
                "kind": "area", "mesh": scene.meshes[mesh].name, "radiance": radiance.to_array(),
                "area": scene.meshes[mesh].surface_area(), "samples": samples, "both_sides": both_sides
            }),
            LightSource::Sun { direction, irradiance, angular_radius_degrees, .. } => json!({
                "kind": "sun", "direction": direction.to_array(), "irradiance": irradiance.to_array(),
                "angular_radius_degrees": angular_radius_degrees
            }),
        })
        .collect();
    let environment = match scene.environment.as_ref().map(|e| &e.map) {
        None => json!(null),
        Some(EnvironmentMap::Constant(c)) => json!({ "constant": c.to_array() }),
        Some(EnvironmentMap::LatLong { width, height, scale, .. }) => {
            json!({ "latlong": [width, height], "scale": scale })
        }
    };
    let c = &scene.camera_spec;
    json!({
        "film": { "width": scene.film.width, "height": scene.film.height, "spp": scene.film.spp },
        "camera": {
            "eye": c.eye, "look_at": c.look_at, "up": c.up, "fov_y": c.fov_y,
            "lens_radius": c.lens_radius, "focus_distance": c.focus_distance, "shutter": c.shutter
        },
        "objects": objects,
        "lights": lights,
        "environment": environment,
        "warnings": scene.warnings,
        "incomplete": scene.incomplete,
        "inputs": scene.inputs.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
    })
}
