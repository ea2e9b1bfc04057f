//! A seeded mutation fuzzer for the scene parser, the OBJ loader, the
//! glTF loader (a small glTF with every kind of light, as JSON with an
//! embedded buffer and as GLB) and the USD import (a small stage with
//! every UsdLux light, instances and a point instancer, as `.usda` text and
//! as a `.usdc` crate file: scenes/usd/fuzz/).
//!
//! Each iteration mutates a valid scene (or OBJ) with byte flips, deletions,
//! duplications and splices of a dictionary of troublesome tokens, loads it
//! in-process under `catch_unwind`, and for scenes that still load, renders a
//! 4x3 image in every mode (exact, bounded, stochastic) and checks every
//! value is finite. A panic or a non-finite pixel fails the test and prints
//! the input. The counts say how many mutants were rendered, how many
//! loaded but were not rendered (too big for an iteration, or geometry
//! Embree refuses: an error the command line reports) and how many were
//! rejected by the loader.
//!
//! A second fuzzer runs the real binary on mutants of every file a render
//! reads besides the scene, each run under 1 GiB of address space and 30 s
//! of wall-clock time (`prlimit`; then killed): a `.usdz` package, a glTF
//! buffer file, PNG and JPEG textures (their headers' sizes mutated with
//! valid checksums, so that the decoders reach them), an EXR environment
//! map (its data window mutated) and a farm tile that `assemble` reads.
//! Every run must end by itself with exit 0, or 1 and one error line; an
//! abort (an allocation past the limit), a hang or a panic fails the test
//! and keeps the input.
//!
//! The suite runs 300 iterations of the first and 100 of the second. For a
//! long run of both (10 minutes each by default; LIGHTCUTS_FUZZ_ITERATIONS
//! and LIGHTCUTS_FUZZ_SEED also apply; `.ci/run` runs it when
//! LIGHTCUTS_FUZZ_SECONDS is set):
//!   LIGHTCUTS_FUZZ_SECONDS=600 cargo test --release --test fuzz -- --ignored --nocapture

mod common;

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

use lightcuts::embree::Device;
use lightcuts::light::Lights;
use lightcuts::lightcut::multidimensional::MULTIDIMENSIONAL_DEFAULTS;
use lightcuts::lightcut::stochastic::STOCHASTIC_DEFAULTS;
use lightcuts::lightcut::{self, CutSettings};
use lightcuts::render::direct::{bounded::Bounded, exact::Exact, multidimensional::Multidimensional};
use lightcuts::render::direct::{stochastic::Stochastic, DirectLight};
use lightcuts::render::integrator::Integrator;
use lightcuts::render::tracer::Tracer;
use lightcuts::render::{self, Aovs, PassSettings, PixelBounds, TextureFilter};
use lightcuts::scene::mesh::Mesh;
use lightcuts::scene::Scene;
use lightcuts::shading::Geometry;
use lightcuts::util::sampling::Rng;

const SCENE: &str = r#"[film]
width = 16
height = 12
spp = 1
[camera]
eye = [0, 3, 6]
look_at = [0, 0.5, 0]
fov_y = 45
[materials.a]
albedo = [0.5, 0.5, 0.5]
specular = [0.2, 0.2, 0.2]
exponent = 30
mirror = [0.1, 0.1, 0.1]
[materials.b]
type = "pbr"
albedo = [0.9, 0.6, 0.3]
metallic = 0.5
roughness = 0.3
[[shapes]]
type = "quad"
corner = [-3, 0, 3]
u = [6, 0, 0]
v = [0, 0, -6]
material = "a"
[[shapes]]
type = "sphere"
center = [0, 0.5, 0]
radius = 0.5
segments = 12
material = "b"
[[shapes]]
type = "box"
min = [1, 0, 0]
max = [2, 1, 1]
material = "a"
[[shapes]]
type = "mesh"
file = "m.obj"
material = "a"
[[lights]]
type = "point"
position = [0, 3, 0]
intensity = [1, 1, 1]
[[lights]]
type = "grid"
corner = [-1, 3, -1]
u = [2, 0, 0]
v = [0, 0, 2]
count = [16, 16]
intensity = [0.01, 0.01, 0.01]
"#;

const OBJ: &str = "# a quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1 4/4/1\nf -1 -2 -3\n";

const TOKENS: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "-1",
    "0",
    "1e39",
    "-1e39",
    "1e-45",
    "4294967296",
    "18446744073709551616",
    "[",
    "]",
    "{",
    "}",
    "=",
    "\"",
    "'",
    ",",
    "\n",
    "[[shapes]]",
    "[[lights]]",
    "type = \"sphere\"",
    "type = \"grid\"",
    "type = \"pbr\"",
    "roughness = 0",
    "metallic = 1",
    "count = [65536, 65536]",
    "radius = 0",
    "segments = 4096",
    "f 1 2 99",
    "f -999 1 2",
    "v nan 0 0",
    "v 1e38 1e38 1e38",
    "vt",
    "vn",
    "/",
    "//",
    "\u{0}",
    "\u{feff}",
    "é",
    "#",
];

/// Values a number in the input may be replaced with.
const NUMBERS: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "-1",
    "0",
    "-0.0",
    "1e30",
    "1e-30",
    "1e38",
    "3.4e38",
    "1e-45",
    "65536",
    "4096",
    "4294967295",
    "-2147483648",
    "0.5",
    "1",
    "2",
    "100000",
    "1e6",
    "-1e6",
];

/// Replaces one number of the text with a hostile value (keeps the syntax
/// valid most of the time, so validation and rendering are reached).
fn replace_number(rng: &mut Rng, data: &[u8]) -> Vec<u8> {
    let text = String::from_utf8_lossy(data);
    let numbers: Vec<(usize, usize)> = {
        let bytes = text.as_bytes();
        let mut spans = Vec::new();
        let mut i = 0;
        while i < bytes.len() {
            if bytes[i].is_ascii_digit() || (bytes[i] == b'-' && bytes.get(i + 1).is_some_and(u8::is_ascii_digit)) {
                let start = i;
                i += 1;
                while i < bytes.len() && (bytes[i].is_ascii_digit() || bytes[i] == b'.' || bytes[i] == b'e') {
                    i += 1;
                }
                spans.push((start, i));
            } else {
                i += 1;
            }
        }
        spans
    };
    if numbers.is_empty() {
        return data.to_vec();
    }
    let (a, b) = numbers[rng.below(numbers.len() as u64) as usize];
    let value = NUMBERS[rng.below(NUMBERS.len() as u64) as usize];
    format!("{}{value}{}", &text[..a], &text[b..]).into_bytes()
}

fn mutate(rng: &mut Rng, input: &[u8]) -> Vec<u8> {
    if rng.below(2) == 0 {
        let mut data = input.to_vec();
        for _ in 0..1 + rng.below(3) {
            data = replace_number(rng, &data);
        }
        return data;
    }
    let mut data = input.to_vec();
    for _ in 0..1 + rng.below(4) {
        let at = if data.is_empty() { 0 } else { rng.below(data.len() as u64 + 1) as usize };
        match rng.below(5) {
            0 if !data.is_empty() => {
                let i = at.min(data.len() - 1);
                data[i] ^= 1 << rng.below(8);
            }
            1 => {
                let end = (at + 1 + rng.below(16) as usize).min(data.len());
                data.drain(at.min(end)..end);
            }
            2 => {
                let end = (at + 1 + rng.below(64) as usize).min(data.len());
                let copy = data[at.min(end)..end].to_vec();
                let to = rng.below(data.len() as u64 + 1) as usize;
                data.splice(to..to, copy);
            }
            _ => {
                let token = TOKENS[rng.below(TOKENS.len() as u64) as usize].as_bytes();
                data.splice(at..at, token.iter().copied());
            }
        }
    }
    data
}

/// What became of a mutant.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Outcome {
    /// Loaded and rendered in every mode, every value finite.
    Rendered,
    /// Loaded, but too big for a fuzz iteration.
    TooBig,
    /// Loaded, but Embree refused its geometry (an error the command line reports).
    GeometryRefused,
    /// Refused by the loader with a one-line message naming the file.
    Rejected,
}

/// Tallies of outcomes.
#[derive(Debug, Default, Clone, Copy)]
struct Counts {
    rendered: u64,
    too_big: u64,
    geometry_refused: u64,
    rejected: u64,
}

impl Counts {
    fn add(&mut self, outcome: Outcome) {
        match outcome {
            Outcome::Rendered => self.rendered += 1,
            Outcome::TooBig => self.too_big += 1,
            Outcome::GeometryRefused => self.geometry_refused += 1,
            Outcome::Rejected => self.rejected += 1,
        }
    }
}

/// Renders a loaded scene at 4x3 in every mode; panics on a non-finite value.
fn render_small(scene: &Scene) -> Outcome {
    if scene.light_count_bound() > 20_000 || scene.triangle_count() > 200_000 {
        return Outcome::TooBig; // Valid but too slow for a fuzz iteration.
    }
    render_lit(scene, &Lights::by_group(scene))
}

/// Renders `scene` lit by `lights` (its lights by group) at 4x3 in every
/// mode (exact, bounded, stochastic, multidimensional), with direct light
/// and with paths of up to 4 vertices; panics when the film met a NaN or
/// an infinity, or holds one.
fn render_lit(scene: &Scene, lights: &[Lights]) -> Outcome {
    let device = Device::try_new().unwrap();
    let Ok(geometry) = Geometry::try_new(&device, scene, lights) else { return Outcome::GeometryRefused };
    let camera = scene.camera(4, 3);
    let settings = PassSettings {
        width: 4,
        height: 3,
        spp: 1,
        seed: 1,
        bounds: PixelBounds::full(4, 3),
        aovs: Aovs { cryptomatte: true, ..Aovs::all(true) },
        transparent: false,
        texture_filter: TextureFilter::Mip,
    };
    let trees = lightcut::build_trees(lights, 1);
    // The multidimensional mode builds every tree as a tree (as its session does).
    let whole_trees =
        lightcut::build_trees_with(lights, 1, &CutSettings { exhaustive_lights: 0, ..MULTIDIMENSIONAL_DEFAULTS });
    let emission_group = scene.emission_groups();
    let emitters = lightcuts::render::emitter_sampling::EmitterSampling::of(
        scene,
        settings.spp,
        lightcuts::light::EmitterLeaves::Parts,
    );
    let methods: [Box<dyn for<'a> DirectLight<'a> + '_>; 4] = [
        Box::new(Exact),
        Box::new(Bounded { trees: &trees, settings: CutSettings::default() }),
        Box::new(Stochastic { trees: &trees, settings: STOCHASTIC_DEFAULTS }),
        Box::new(Multidimensional { trees: &whole_trees, settings: MULTIDIMENSIONAL_DEFAULTS }),
    ];
    for (direct, path_depth) in methods.iter().flat_map(|m| [(m, None), (m, Some(4))]) {
        let integrator = Integrator {
            tracer: Tracer {
                geometry: &geometry,
                lights,
                split_groups: scene.groups.named(),
                emitters: emitters.as_ref(),
                spp: settings.spp,
                footprint: Some(camera.pixel_footprint(settings.spp)),
            },
            direct: &**direct,
            max_mirror_depth: scene.max_mirror_depth,
            emission_group: &emission_group,
            path_depth,
        };
        let (film, _) = render::render(&integrator, &camera, &settings, &|_| {}).unwrap();
        assert!(film.non_finite().is_empty(), "NaN or Inf reached the film: {:?}", film.non_finite());
        for channel in &film.channels {
            assert!(channel.values.iter().all(|v| v.is_finite()), "non-finite {}", channel.name);
        }
    }
    Outcome::Rendered
}

/// The check above can fail: one light whose intensity is NaN (which no
/// scene file can give: the loader refuses it) reaches the film as NaN in
/// every mode, and the check panics naming the channels.
#[test]
fn a_nan_in_one_light_fails_the_fuzzer_s_check() {
    let scene = lightcuts::scene::builder::floor_spheres_grid(4).load(Path::new("nan.toml")).unwrap();
    let mut lights = Lights::by_group(&scene);
    assert_eq!(render_lit(&scene, &lights), Outcome::Rendered);
    lights[0].omni[3].intensity.y = f32::NAN;
    let caught = catch_unwind(AssertUnwindSafe(|| render_lit(&scene, &lights)));
    let message = caught.expect_err("a NaN light must fail the check");
    let message = message.downcast_ref::<String>().cloned().unwrap_or_default();
    assert!(message.contains("NaN or Inf reached the film") && message.contains("(\"G\""), "{message}");
}

/// Loads `path` under `catch_unwind` and renders what loads; the outcome,
/// or None on a panic. A loader's error must name `file` on one line.
fn try_input(path: &Path, file: &str) -> Option<Outcome> {
    catch_unwind(AssertUnwindSafe(|| match Scene::load(path) {
        Ok(scene) => render_small(&scene),
        Err(e) => {
            let m = e.to_string();
            assert!(m.contains(file) || m.contains("m.obj"), "error names no file: {m}");
            assert!(!m.contains('\n'), "multi-line error: {m}");
            Outcome::Rejected
        }
    }))
    .ok()
}

/// Runs the fuzzer; the outcomes of the scene (TOML) mutants, of the glTF
/// mutants and of the USD mutants.
fn fuzz(iterations: u64, seed: u64, deadline: Option<std::time::Instant>) -> (Counts, Counts, Counts) {
    let temporary = tempfile::tempdir().unwrap();
    let dir = temporary.path();
    std::fs::write(dir.join("m.obj"), OBJ).unwrap();
    let scene_path = dir.join("scene.toml");
    let mut rng = Rng::seeded(seed);
    let (mut scenes, mut gltfs, mut usds) = (Counts::default(), Counts::default(), Counts::default());
    let (gltf_text, glb) = small_gltf();
    let stages = common::scenes().join("usd/fuzz");
    std::fs::copy(stages.join("texture.png"), dir.join("texture.png")).unwrap();
    let usda = std::fs::read(stages.join("stage.usda")).unwrap();
    let usdc = std::fs::read(stages.join("stage.usdc")).unwrap();
    for i in 0..iterations {
        if deadline.is_some_and(|d| std::time::Instant::now() >= d) {
            break;
        }
        // Scene mutants (the OBJ stays valid).
        let input = mutate(&mut rng, SCENE.as_bytes());
        std::fs::write(&scene_path, &input).unwrap();
        let Some(outcome) = try_input(&scene_path, "scene.toml") else {
            panic!("iteration {i}: panic on scene input:\n{}", String::from_utf8_lossy(&input))
        };
        scenes.add(outcome);
        // glTF mutants: the JSON text and the GLB bytes.
        for (name, valid) in [("fuzz.gltf", &gltf_text), ("fuzz.glb", &glb)] {
            let input = mutate(&mut rng, valid);
            let path = dir.join(name);
            std::fs::write(&path, &input).unwrap();
            let Some(outcome) = try_input(&path, name) else {
                panic!("iteration {i}: panic on {name}:\n{}", String::from_utf8_lossy(&input))
            };
            gltfs.add(outcome);
        }
        // USD mutants: the text stage and the crate file, through the
        // command line first (the reader can abort a process on a corrupt
        // crate file's counts, which the command catches in a child: it
        // must exit 0, or 1 with one line naming the file), then, when they
        // load, in this process to render.
        for (name, valid) in [("fuzz.usda", &usda), ("fuzz.usdc", &usdc)] {
            let input = mutate(&mut rng, valid);
            let path = dir.join(name);
            std::fs::write(&path, &input).unwrap();
            let out = common::lightcuts(&["inspect", common::s(&path)]);
            let stderr = String::from_utf8_lossy(&out.stderr);
            match out.status.code() {
                Some(0) => {}
                Some(1) => {
                    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error")).collect();
                    assert!(errors.len() == 1 && errors[0].contains(name), "iteration {i}: {name}: {stderr}");
                    usds.add(Outcome::Rejected);
                    continue;
                }
                other => panic!("iteration {i}: {name}: exit {other:?}: {stderr}\n{}", String::from_utf8_lossy(&input)),
            }
            assert!(!stderr.contains("panicked"), "iteration {i}: {name}: {stderr}");
            let Some(outcome) = try_input(&path, name) else {
                panic!("iteration {i}: panic on {name}:\n{}", String::from_utf8_lossy(&input))
            };
            usds.add(outcome);
        }
        // OBJ mutants.
        let obj = mutate(&mut rng, OBJ.as_bytes());
        let obj_path = dir.join("fuzz.obj");
        std::fs::write(&obj_path, &obj).unwrap();
        if catch_unwind(|| Mesh::load_obj(Path::new(&obj_path), 1.0, glam::Vec3::ZERO, 0)).is_err() {
            panic!("iteration {i}: panic on OBJ input:\n{}", String::from_utf8_lossy(&obj));
        }
    }
    (scenes, gltfs, usds)
}

/// The glTF the fuzzer mutates: a floor, a point light, a spot, a sun, an
/// emissive double-sided panel with an emissive texture, specular and
/// normal textures on the floor, a camera, and the paths the importer grew
/// for exporters' files: a skinned, morphed triangle with a sparse accessor
/// and quantised (SHORT) positions, GPU instances of the panel, and the
/// floor placed twice (an Embree instance) (JSON text, and as GLB).
fn small_gltf() -> (Vec<u8>, Vec<u8>) {
    use serde_json::json;
    let mut g = common::gltf::floor_and_point_light();
    let spot = g
        .light(json!({ "type": "spot", "intensity": 500.0, "spot": { "innerConeAngle": 0.2, "outerConeAngle": 0.6 } }));
    g.node(json!({ "translation": [1.0, 2.0, 0.0], "rotation": [-0.6, 0.0, 0.0, 0.8], "extensions": { "KHR_lights_punctual": { "light": spot } } }), true);
    let sun = g.light(json!({ "type": "directional", "intensity": 100.0 }));
    g.node(
        json!({ "rotation": [-0.5, 0.0, 0.0, 0.866], "extensions": { "KHR_lights_punctual": { "light": sun } } }),
        true,
    );
    // Textures: the panel's emission texel by texel, the floor's
    // KHR_materials_specular textures and a transformed normal texture.
    let texture = g.png_texture(2, 1, &[0, 0, 0, 255, 128, 0]);
    g.use_extension("KHR_texture_transform");
    g.json["materials"][0]["extensions"]["KHR_materials_specular"] = json!({
        "specularTexture": { "index": texture }, "specularColorTexture": { "index": texture } });
    g.json["materials"][0]["normalTexture"] =
        json!({ "index": texture, "extensions": { "KHR_texture_transform": { "offset": [0.5, 0.0] } } });
    let panel = g.material(
        json!({ "emissiveFactor": [1.0, 1.0, 1.0], "emissiveTexture": { "index": texture }, "doubleSided": true }),
    );
    let quad = g.quad([-0.5, 1.5, -0.5], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0], Some(panel));
    g.node(json!({ "mesh": quad, "scale": [1.0, 1.0, 1.0] }), true);
    g.json["scenes"][0]["nodes"] = json!([0, 1, 2, 3, 4, 5]);
    g.use_extension("KHR_mesh_quantization");
    g.use_extension("EXT_mesh_gpu_instancing");
    let shorts: Vec<u8> = [0i16, 0, 0, 0, 100, 0, 0, 0, 0, 100, 0, 0].iter().flat_map(|x| x.to_le_bytes()).collect();
    let position = g.raw(&shorts, 5122, 3, "VEC3", false);
    let view = g.json["accessors"][position]["bufferView"].clone();
    g.json["bufferViews"][view.as_u64().unwrap() as usize]["byteStride"] = json!(8);
    g.json["accessors"][position]["min"] = json!([0, 0, 0]);
    g.json["accessors"][position]["max"] = json!([100, 100, 0]);
    let joints = g.raw(&[0u8, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0], 5121, 3, "VEC4", false);
    let weights = g.floats(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.5, 0.5, 0.0, 0.0], "VEC4", 4);
    let target = g.floats(&[0.0; 9], "VEC3", 3);
    let (indices, values) = (g.bytes_view(&[2u8]), g.bytes_view(&[0.0f32, 0.0, 20.0].map(f32::to_le_bytes).concat()));
    g.json["accessors"][target]["sparse"] = json!({ "count": 1,
        "indices": { "bufferView": indices, "componentType": 5121 }, "values": { "bufferView": values } });
    let mesh = g.push_mesh(json!({ "primitives": [{
        "attributes": { "POSITION": position, "JOINTS_0": joints, "WEIGHTS_0": weights },
        "targets": [{ "POSITION": target }] }], "weights": [0.5] }));
    let j1 = g.node(json!({ "translation": [0.0, 0.5, 0.0] }), false);
    let j0 = g.node(json!({ "children": [j1], "translation": [2.0, 0.0, 0.0], "scale": [0.01, 0.01, 0.01] }), true);
    g.json["skins"] = json!([{ "joints": [j0, j1] }]);
    g.node(json!({ "mesh": mesh, "skin": 0 }), true);
    let translations = g.floats(&[0.0, 0.0, 0.0, -2.0, 0.0, 0.0], "VEC3", 3);
    g.node(
        json!({ "mesh": 1, "extensions": { "EXT_mesh_gpu_instancing": { "attributes": { "TRANSLATION": translations } } } }),
        true,
    );
    // The floor placed again, turned: an Embree instance of one mesh.
    g.node(json!({ "mesh": 0, "translation": [0.0, -1.0, 0.0], "rotation": [0.0, 0.38, 0.0, 0.92] }), true);
    // A small film for the in-process renders.
    g.json["cameras"][0]["perspective"]["aspectRatio"] = json!(1.33);
    (g.embedded().into_bytes(), g.glb())
}

#[test]
fn scene_and_obj_mutants_never_panic() {
    let (scenes, gltfs, usds) = fuzz(300, 1, None);
    println!("TOML mutants: {scenes:?}\nglTF mutants: {gltfs:?}\nUSD mutants: {usds:?}");
    // Every path must be exercised: mutants rendered in every mode, and
    // mutants rejected with a message.
    for (what, counts) in [("TOML", scenes), ("glTF", gltfs), ("USD", usds)] {
        assert!(counts.rendered > 10 && counts.rejected > 10, "{what} mutants: {counts:?}");
    }
}

/// The long run; see the module documentation. Stops after
/// LIGHTCUTS_FUZZ_ITERATIONS iterations or LIGHTCUTS_FUZZ_SECONDS seconds.
#[test]
#[ignore]
fn long_fuzz_run() {
    let env = |name: &str, default: u64| std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default);
    let (iterations, seconds, seed) = (
        env("LIGHTCUTS_FUZZ_ITERATIONS", 1_000_000),
        env("LIGHTCUTS_FUZZ_SECONDS", 600),
        env("LIGHTCUTS_FUZZ_SEED", 2),
    );
    let start = std::time::Instant::now();
    let (scenes, gltfs, usds) = fuzz(iterations, seed, Some(start + std::time::Duration::from_secs(seconds)));
    let iterations = scenes.rendered + scenes.too_big + scenes.geometry_refused + scenes.rejected;
    println!(
        "{iterations} iterations (seed {seed}) in {:.0} s, each a TOML, a glTF, a GLB, a USD text, a USD crate and an OBJ mutant; no panic, \
         every rendered value finite.\n  TOML: {} rendered in every mode, {} loaded but too big to render, {} loaded \
         but refused by Embree, {} rejected by the loader\n  glTF and GLB: {} rendered, {} too big, {} refused by \
         Embree, {} rejected\n  USD text and crate: {} rendered, {} too big, {} refused by Embree, {} rejected",
        start.elapsed().as_secs_f64(),
        scenes.rendered,
        scenes.too_big,
        scenes.geometry_refused,
        scenes.rejected,
        gltfs.rendered,
        gltfs.too_big,
        gltfs.geometry_refused,
        gltfs.rejected,
        usds.rendered,
        usds.too_big,
        usds.geometry_refused,
        usds.rejected
    );
}

/// The files the reader fuzzer mutates, each beside a scene that reads it,
/// and what runs it.
struct ReaderInputs {
    dir: common::TempDir,
    /// `stage.usdz`: the fuzz stage and its texture, stored.
    package: Vec<u8>,
    /// `buffers.bin` of `buffers.gltf` (and the glTF's JSON, whose
    /// byteLengths are mutated too).
    bin: Vec<u8>,
    gltf: String,
    /// `texture.png` of `png.toml`; `texture.jpg` of `jpeg.usda`.
    png: Vec<u8>,
    jpeg: Vec<u8>,
    /// `env.exr`, rendered as `--environment`.
    exr: Vec<u8>,
    /// `tile1.exr` of two tiles `assemble` joins (`tile0.exr` stays valid).
    tile: Vec<u8>,
}

impl ReaderInputs {
    fn new() -> Self {
        let dir = common::TempDir::new("reader-fuzz");
        let fuzz = common::scenes().join("usd/fuzz");
        let stage = std::fs::read(fuzz.join("stage.usda")).unwrap();
        let png = std::fs::read(fuzz.join("texture.png")).unwrap();
        let jpeg = std::fs::read(fuzz.join("texture.jpg")).unwrap();
        let package = {
            use std::io::Write;
            let mut package = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
            let stored = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
            package.start_file("stage.usda", stored).unwrap();
            package.write_all(&stage).unwrap();
            package.start_file("texture.png", stored).unwrap();
            package.write_all(&png).unwrap();
            package.finish().unwrap().into_inner()
        };
        let text = String::from_utf8(stage).unwrap().replace("@texture.png@", "@texture.jpg@");
        std::fs::write(dir.path("jpeg.usda"), text).unwrap();
        let textured = lightcuts::scene::builder::floor_spheres_grid(2).toml().replacen(
            "[materials.floor]\nalbedo = [0.7, 0.7, 0.7]\n",
            "[materials.floor]\ntexture = \"texture.png\"\n",
            1,
        );
        std::fs::write(dir.path("png.toml"), textured).unwrap();
        std::fs::write(dir.path("scene.toml"), lightcuts::scene::builder::floor_spheres_grid(2).toml()).unwrap();
        let g = common::gltf::floor_and_point_light();
        g.write_separate(&dir.path(""), "buffers");
        let bin = std::fs::read(dir.path("buffers.bin")).unwrap();
        let gltf = std::fs::read_to_string(dir.path("buffers.gltf")).unwrap();
        // A small environment map (16 x 8, uncompressed, so that a flipped
        // byte is often a pixel) and two tiles of a 16 x 12 frame.
        let env = dir.path("env.exr");
        {
            use exr::prelude::*;
            let channels = SpecificChannels::rgb(|p: Vec2<usize>| (0.5f32, 0.4 + 0.01 * p.x() as f32, 0.3f32));
            let mut image = Image::from_channels((16, 8), channels);
            image.layer_data.encoding.compression = Compression::Uncompressed;
            image.write().to_file(&env).unwrap();
        }
        let exr = std::fs::read(&env).unwrap();
        let scene = dir.path("scene.toml");
        for i in 0..2 {
            let tile = dir.path(&format!("tile{i}.exr"));
            let flags = ["--resolution", "16x12", "--tile", &format!("{i}/2"), "--quiet"];
            common::lightcuts_ok(&[&["render", common::s(&scene), "-o", common::s(&tile)][..], &flags].concat());
        }
        let tile = std::fs::read(dir.path("tile1.exr")).unwrap();
        Self { dir, package, bin, gltf, png, jpeg, exr, tile }
    }
}

/// The PNG `bytes` with its IHDR's width and height set, and the chunk's
/// CRC recomputed (so that the decoder reads the size rather than refusing
/// the checksum).
fn png_with_size(bytes: &[u8], width: u32, height: u32) -> Vec<u8> {
    let mut bytes = bytes.to_vec();
    if bytes.len() < 33 {
        return bytes;
    }
    bytes[16..20].copy_from_slice(&width.to_be_bytes());
    bytes[20..24].copy_from_slice(&height.to_be_bytes());
    let mut crc = !0u32;
    for &b in &bytes[12..29] {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
        }
    }
    bytes[29..33].copy_from_slice(&(!crc).to_be_bytes());
    bytes
}

/// A size a header may claim: small, at a limit, past one, or random.
fn claimed_size(rng: &mut Rng) -> u32 {
    const SIZES: [u32; 9] = [0, 1, 2, 255, 16384, 65535, 100_000, 1 << 30, u32::MAX];
    if rng.below(4) == 0 {
        rng.below(1 << 32) as u32
    } else {
        SIZES[rng.below(SIZES.len() as u64) as usize]
    }
}

/// A mutant of `bytes` whose `key` field (found by its bytes) is set to
/// random 32-bit values at `offset` past the key, `count` of them; else a
/// generic mutant.
fn with_fields(rng: &mut Rng, bytes: &[u8], key: &[u8], offset: usize, count: usize, big_endian: bool) -> Vec<u8> {
    let Some(at) = bytes.windows(key.len()).position(|w| w == key) else { return mutate(rng, bytes) };
    let mut bytes = bytes.to_vec();
    for k in 0..count {
        let start = at + key.len() + offset + 4 * k;
        if start + 4 <= bytes.len() && rng.below(2) == 0 {
            let v = claimed_size(rng);
            let v = if rng.below(4) == 0 { (v as i32).wrapping_neg() as u32 } else { v };
            bytes[start..start + 4].copy_from_slice(&if big_endian { v.to_be_bytes() } else { v.to_le_bytes() });
        }
    }
    bytes
}

/// One run of the binary on a mutant, under the limits; panics (keeping the
/// mutant's bytes in the message) on a signal, a hang or a panic.
fn run_limited(iteration: u64, what: &str, args: &[&str], input: &[u8]) -> Outcome {
    let run = common::lightcuts_limited(args, 1024, 30);
    let shown = || String::from_utf8_lossy(&input[..input.len().min(4096)]).into_owned();
    assert!(!run.timed_out, "iteration {iteration}: {what}: still running after 30 s; input:\n{}", shown());
    assert!(!run.stderr.contains("panicked"), "iteration {iteration}: {what}: {}", run.stderr);
    match run.code {
        Some(0) => Outcome::Rendered,
        Some(1) => {
            let errors = run.stderr.lines().filter(|l| l.starts_with("error")).count();
            assert_eq!(errors, 1, "iteration {iteration}: {what}: {}", run.stderr);
            Outcome::Rejected
        }
        other => panic!(
            "iteration {iteration}: {what}: exit {other:?} (a signal: an abort past 1 GiB?): {}\ninput:\n{}",
            run.stderr,
            shown()
        ),
    }
}

/// Runs the reader fuzzer: per iteration, one mutant of each input, each
/// through the binary; the outcomes by reader.
fn fuzz_readers(iterations: u64, seed: u64, deadline: Option<std::time::Instant>) -> Vec<(&'static str, Counts)> {
    let inputs = ReaderInputs::new();
    let dir = &inputs.dir;
    let mut rng = Rng::seeded(seed);
    let mut counts: Vec<(&'static str, Counts)> =
        ["usdz", "glTF buffer", "PNG", "JPEG", "EXR", "tile"].into_iter().map(|n| (n, Counts::default())).collect();
    let out = dir.path("out.exr");
    let o = common::s(&out);
    let small = ["--resolution", "16x12", "--quiet"];
    for i in 0..iterations {
        if deadline.is_some_and(|d| std::time::Instant::now() >= d) {
            break;
        }
        // The package: its zip structure (sizes, methods) and its members.
        let package = if rng.below(2) == 0 {
            let key: &[u8] = if rng.below(2) == 0 { b"PK\x01\x02" } else { b"PK\x03\x04" };
            // Method (offset 6 or 4), then CRC and the two sizes.
            with_fields(&mut rng, &inputs.package, key, 4, 4, false)
        } else {
            mutate(&mut rng, &inputs.package)
        };
        let path = dir.path("stage.usdz");
        std::fs::write(&path, &package).unwrap();
        counts[0].1.add(run_limited(
            i,
            "usdz",
            &[&["render", common::s(&path), "-o", o][..], &small].concat(),
            &package,
        ));
        // The glTF's buffer file, and its declared lengths.
        let bin = mutate(&mut rng, &inputs.bin);
        std::fs::write(dir.path("buffers.bin"), &bin).unwrap();
        let gltf = if rng.below(3) == 0 {
            replace_number(&mut rng, inputs.gltf.as_bytes())
        } else {
            inputs.gltf.clone().into_bytes()
        };
        std::fs::write(dir.path("buffers.gltf"), &gltf).unwrap();
        let scene = dir.path("buffers.gltf");
        counts[1].1.add(run_limited(
            i,
            "glTF buffer",
            &[&["render", common::s(&scene), "-o", o][..], &small].concat(),
            &bin,
        ));
        // The textures: sizes in their headers (checksums kept), or anything.
        let png = if rng.below(2) == 0 {
            png_with_size(&inputs.png, claimed_size(&mut rng), claimed_size(&mut rng))
        } else {
            mutate(&mut rng, &inputs.png)
        };
        std::fs::write(dir.path("texture.png"), &png).unwrap();
        let scene = dir.path("png.toml");
        counts[2].1.add(run_limited(i, "PNG", &[&["render", common::s(&scene), "-o", o][..], &small].concat(), &png));
        // SOF0: marker, length (2), precision (1), then height and width
        // (2 each): two 16-bit fields read as one 32-bit one here.
        let jpeg = if rng.below(2) == 0 {
            with_fields(&mut rng, &inputs.jpeg, &[0xff, 0xc0], 3, 1, true)
        } else {
            mutate(&mut rng, &inputs.jpeg)
        };
        std::fs::write(dir.path("texture.jpg"), &jpeg).unwrap();
        // An unreadable texture of a stage is a warning: --strict refuses it.
        let scene = dir.path("jpeg.usda");
        counts[3].1.add(run_limited(
            i,
            "JPEG",
            &[&["render", common::s(&scene), "-o", o, "--strict"][..], &small].concat(),
            &jpeg,
        ));
        // The environment map's data window, or anything.
        let exr = if rng.below(2) == 0 {
            with_fields(&mut rng, &inputs.exr, b"dataWindow\0box2i\0", 4, 4, false)
        } else {
            mutate(&mut rng, &inputs.exr)
        };
        let env = dir.path("env-mutant.exr");
        std::fs::write(&env, &exr).unwrap();
        let scene = dir.path("scene.toml");
        let args = [&["render", common::s(&scene), "-o", o, "--environment", common::s(&env)][..], &small].concat();
        counts[4].1.add(run_limited(i, "EXR", &args, &exr));
        // A farm tile.
        let tile = if rng.below(2) == 0 {
            with_fields(&mut rng, &inputs.tile, b"dataWindow\0box2i\0", 4, 4, false)
        } else {
            mutate(&mut rng, &inputs.tile)
        };
        let tile1 = dir.path("tile1-mutant.exr");
        std::fs::write(&tile1, &tile).unwrap();
        let tile0 = dir.path("tile0.exr");
        counts[5].1.add(run_limited(i, "tile", &["assemble", o, common::s(&tile0), common::s(&tile1)], &tile));
    }
    counts
}

#[test]
fn every_reader_survives_its_mutants_within_limits() {
    let counts = fuzz_readers(100, 3, None);
    println!("{counts:?}");
    // Each reader both accepted and refused some of its mutants.
    for (what, c) in counts {
        assert!(c.rendered > 0 && c.rejected > 0, "{what}: {c:?}");
    }
}

/// The reader fuzzer's long run; see the module documentation.
#[test]
#[ignore]
fn long_reader_fuzz_run() {
    let env = |name: &str, default: u64| std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default);
    let (iterations, seconds, seed) = (
        env("LIGHTCUTS_FUZZ_ITERATIONS", 1_000_000),
        env("LIGHTCUTS_FUZZ_SECONDS", 600),
        env("LIGHTCUTS_FUZZ_SEED", 2),
    );
    let start = std::time::Instant::now();
    let counts = fuzz_readers(iterations, seed, Some(start + std::time::Duration::from_secs(seconds)));
    println!("reader mutants (seed {seed}) in {:.0} s, each run within 1 GiB and 30 s:", start.elapsed().as_secs_f64());
    for (what, c) in counts {
        println!("  {what}: {} rendered, {} refused with one error line", c.rendered, c.rejected);
    }
}
