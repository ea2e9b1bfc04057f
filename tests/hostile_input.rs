//! Hostile input: the real binary must exit 1 with one clear line naming the
//! file and the field or line, never panic, and create no output file.

mod common;
use common::*;

/// A scene that uses every kind of field: film, camera, materials (albedo
/// and texture), every shape, every light.
fn full_scene() -> String {
    r#"
[film]
width = 16
height = 12
spp = 1

[camera]
eye = [0, 3, 6]
look_at = [0, 0.5, 0]
up = [0, 1, 0]
fov_y = 45

[materials.plain]
albedo = [0.5, 0.5, 0.5]
specular = [0.1, 0.1, 0.1]
exponent = 10
mirror = [0, 0, 0]

[materials.wood]
texture = "wood.png"
texture_scale = [2, 2]

[materials.metal]
type = "pbr"
albedo = [0.9, 0.6, 0.3]
metallic = 1
roughness = 0.3

[[shapes]]
type = "quad"
corner = [-3, 0, 3]
u = [6, 0, 0]
v = [0, 0, -6]
material = "wood"

[[shapes]]
type = "box"
min = [1, 0, -1]
max = [2, 1, 0]
material = "plain"

[[shapes]]
type = "sphere"
center = [-1, 0.5, 0]
radius = 0.5
segments = 24
material = "plain"

[[shapes]]
type = "mesh"
file = "tri.obj"
material = "plain"
scale = 1
translate = [0, 0, 0]

[[lights]]
type = "point"
position = [0, 3, 0]
intensity = [1, 1, 1]

[[lights]]
type = "grid"
corner = [-1, 3, -1]
u = [2, 0, 0]
v = [0, 0, 2]
count = [2, 2]
intensity = [0.5, 0.5, 0.5]

[render]
max_mirror_depth = 2
"#
    .to_string()
}

fn setup(name: &str) -> TempDir {
    let dir = TempDir::new(name);
    std::fs::write(dir.path("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let file = std::fs::File::create(dir.path("wood.png")).unwrap();
    let mut encoder = png::Encoder::new(file, 2, 2);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.write_header().unwrap().write_image_data(&[200, 150, 100, 90, 60, 30, 90, 60, 30, 200, 150, 100]).unwrap();
    dir
}

/// Renders `text` (named `name`) and asserts a clean rejection mentioning
/// every string of `expect`.
fn rejects(dir: &TempDir, name: &str, text: &[u8], expect: &[&str]) {
    let scene = dir.path(name);
    std::fs::write(&scene, text).unwrap();
    let out = dir.path("out.exr");
    let stderr = lightcuts_fails(&["render", s(&scene), "-o", s(&out), "--quiet"]);
    assert_eq!(stderr.trim_end().lines().count(), 1, "one line: {stderr}");
    for e in expect {
        assert!(stderr.contains(e), "'{e}' missing from: {stderr}");
    }
    assert!(!out.exists(), "output written for {name}");
    assert!(dir.files().iter().all(|f| !f.contains("out.exr")), "temporary file left: {:?}", dir.files());
}

/// Renders `text` (named `name`): an incomplete scene, drawn with a warning
/// that mentions every string of `expect`, and refused under `--strict`.
fn incomplete(dir: &TempDir, name: &str, text: &[u8], expect: &[&str]) {
    let scene = dir.path(name);
    std::fs::write(&scene, text).unwrap();
    let out = dir.path("incomplete.exr");
    let run = lightcuts(&["render", s(&scene), "-o", s(&out), "--resolution", "16x12", "--quiet"]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let warning = (stderr.lines())
        .find(|l| l.starts_with("warning") && l.contains(expect[0]))
        .unwrap_or_else(|| panic!("no warning naming {}: {stderr}", expect[0]));
    for e in expect {
        assert!(warning.contains(e), "'{e}' missing from: {warning}");
    }
    std::fs::remove_file(&out).unwrap();
    let stderr = lightcuts_fails(&["render", s(&scene), "-o", s(&out), "--quiet", "--strict"]);
    for e in [name, "--strict"].iter().chain(expect) {
        assert!(stderr.contains(e), "'{e}' missing from: {stderr}");
    }
    assert!(!out.exists(), "output written for {name} under --strict");
}

#[test]
fn the_full_scene_itself_renders() {
    let dir = setup("full-ok");
    let scene = dir.write("full.toml", &full_scene());
    lightcuts_ok(&["render", s(&scene), "-o", s(&dir.path("ok.exr")), "--quiet"]);
}

#[test]
fn nan_inf_and_negative_values_in_every_numeric_field() {
    let dir = setup("numbers");
    let text = full_scene();
    // (line as written, field path, values that must be rejected)
    let cases: &[(&str, &str, &[&str])] = &[
        ("width = 16", "film.width", &["-16", "nan", "inf", "0"]),
        ("height = 12", "film.height", &["-1", "nan", "0"]),
        ("spp = 1", "film.spp", &["-1", "inf", "0"]),
        ("eye = [0, 3, 6]", "camera.eye", &["[nan, 3, 6]", "[0, inf, 6]", "[0, 3, -inf]"]),
        ("look_at = [0, 0.5, 0]", "camera.look_at", &["[nan, 0, 0]", "[0, 0, inf]"]),
        ("up = [0, 1, 0]", "camera.up", &["[nan, 1, 0]", "[0, 0, 0]"]),
        ("fov_y = 45", "camera.fov_y", &["nan", "inf", "-45", "0", "180"]),
        (
            "albedo = [0.5, 0.5, 0.5]",
            "materials.plain.albedo",
            &["[nan, 0.5, 0.5]", "[-0.1, 0.5, 0.5]", "[0.5, inf, 0.5]"],
        ),
        ("specular = [0.1, 0.1, 0.1]", "materials.plain.specular", &["[nan, 0, 0]", "[-1, 0, 0]"]),
        ("exponent = 10", "materials.plain.exponent", &["nan", "-1", "inf"]),
        ("mirror = [0, 0, 0]", "materials.plain.mirror", &["[nan, 0, 0]", "[-0.5, 0, 0]", "[2, 0, 0]"]),
        ("metallic = 1", "materials.metal.metallic", &["nan", "-1", "1.5", "inf"]),
        ("roughness = 0.3", "materials.metal.roughness", &["nan", "-0.1", "2", "inf"]),
        ("type = \"pbr\"", "materials.metal", &["\"ggx\"", "1"]),
        ("roughness = 0.3", "materials.metal.exponent", &["0.3\nexponent = 20"]),
        ("exponent = 10", "materials.plain.metallic", &["10\nmetallic = 0.5"]),
        ("texture_scale = [2, 2]", "materials.wood.texture_scale", &["[nan, 2]", "[0, 2]", "[-1, 2]", "[inf, 2]"]),
        ("corner = [-3, 0, 3]", "shapes[0].corner", &["[nan, 0, 3]", "[-inf, 0, 3]"]),
        ("u = [6, 0, 0]", "shapes[0].u", &["[nan, 0, 0]", "[inf, 0, 0]"]),
        ("v = [0, 0, -6]", "shapes[0].v", &["[0, 0, nan]", "[6, 0, 0]"]),
        ("min = [1, 0, -1]", "shapes[1].min", &["[nan, 0, -1]", "[1, -inf, -1]"]),
        ("max = [2, 1, 0]", "shapes[1].max", &["[2, nan, 0]", "[0, 1, 0]"]),
        ("center = [-1, 0.5, 0]", "shapes[2].center", &["[nan, 0.5, 0]", "[-1, 3e38, 0]"]),
        // A radius so large the sphere's vertices leave Embree's range.
        ("radius = 0.5", "shapes[2]", &["1e30"]),
        ("radius = 0.5", "shapes[2].radius", &["nan", "inf", "-0.5", "0"]),
        ("segments = 24", "shapes[2].segments", &["-3", "1", "nan", "1000000"]),
        ("scale = 1", "shapes[3].scale", &["nan", "-1", "0", "inf"]),
        ("translate = [0, 0, 0]", "shapes[3].translate", &["[nan, 0, 0]", "[0, inf, 0]", "[0, 0, 1e20]"]),
        ("scale = 1", "shapes[3]", &["1e30"]),
        ("position = [0, 3, 0]", "lights[0].position", &["[nan, 3, 0]", "[0, inf, 0]", "[1e30, 3, 0]"]),
        ("intensity = [1, 1, 1]", "lights[0].intensity", &["[nan, 1, 1]", "[-1, 1, 1]", "[1, inf, 1]", "[1, 1, 2e30]"]),
        ("corner = [-1, 3, -1]", "lights[1].corner", &["[nan, 3, -1]"]),
        ("count = [2, 2]", "lights[1].count", &["[-2, 2]", "[0, 2]", "[nan, 2]", "[100000, 100000]"]),
        (
            "intensity = [0.5, 0.5, 0.5]",
            "lights[1].intensity",
            &["[nan, 0.5, 0.5]", "[-0.5, 0.5, 0.5]", "[0, 0, 3.4e38]"],
        ),
        ("max_mirror_depth = 2", "render.max_mirror_depth", &["-1", "nan"]),
    ];
    for (line, field, values) in cases {
        assert!(text.contains(line), "scene lacks '{line}'");
        let key = line.split(" = ").next().unwrap();
        for value in *values {
            let bad = text.replacen(line, &format!("{key} = {value}"), 1);
            rejects(&dir, "scene.toml", bad.as_bytes(), &["scene.toml", field]);
        }
    }
}

/// Each light within its own cap, but their sum (which the light trees
/// keep in f32), or the power [indirect]'s light paths share out, beyond
/// what f32 holds: refused, naming the light that emits the most.
#[test]
fn lights_whose_sums_f32_cannot_hold() {
    let dir = setup("sums");
    let grid = full_scene().replacen("count = [2, 2]", "count = [1000, 1000]", 1).replacen(
        "intensity = [0.5, 0.5, 0.5]",
        "intensity = [1e30, 1, 1]",
        1,
    );
    rejects(&dir, "grid.toml", grid.as_bytes(), &["grid.toml", "lights[1]", "1.000e36"]);
    // A sun of 1e30 W/m^2 is allowed alone; over a scene 2e6 m wide, its
    // light paths would carry 3e42 W.
    let sun = "[[lights]]\ntype = \"sun\"\ndirection = [0, 1, 0]\nirradiance = [1e30, 1e30, 1e30]\n";
    let far = "[[shapes]]\ntype = \"sphere\"\ncenter = [1e6, 0, 0]\nradius = 1\nmaterial = \"plain\"\n";
    let alone = format!("{}{sun}{far}", full_scene());
    lightcuts_ok(&["render", s(&dir.write("alone.toml", &alone)), "-o", s(&dir.path("alone.exr")), "--quiet"]);
    let indirect = format!("{alone}[indirect]\npaths = 100\n");
    rejects(&dir, "indirect.toml", indirect.as_bytes(), &["indirect.toml", "lights[2]", "[indirect]"]);
}

#[test]
fn malformed_truncated_and_garbage_files() {
    let dir = setup("garbage");
    let text = full_scene();
    rejects(&dir, "truncated.toml", &text.as_bytes()[..text.len() / 2], &["truncated.toml"]);
    rejects(&dir, "syntax.toml", b"[film\nwidth = 3\n", &["syntax.toml", "line 1"]);
    rejects(&dir, "garbage.toml", &[0xff, 0xfe, 0x00, 0x13, 0x37, 0x80, 0x81, 0x00, 0x9f], &["garbage.toml"]);
    rejects(&dir, "empty.toml", b"", &["empty.toml", "film"]);
    rejects(&dir, "bad.json", b"{\"film\": {\"width\": 16, \"height\": ", &["bad.json", "line 1"]);
    rejects(&dir, "trailing.json", b"{\"film\": {\"width\": 1, \"height\": 1}, \"camera\": {\"eye\": [0,0,1], \"look_at\": [0,0,0], \"fov_y\": 30}} extra", &["trailing.json"]);
    rejects(&dir, "nan.json", b"{\"film\": {\"width\": NaN, \"height\": 1}}", &["nan.json", "line 1"]);
}

#[test]
fn wrong_types_and_unknown_fields() {
    let dir = setup("types");
    let text = full_scene();
    for (from, to, field) in [
        ("width = 16", "width = \"sixteen\"", "film.width"),
        ("radius = 0.5", "radius = [0.5]", "radius"),
        ("eye = [0, 3, 6]", "eye = [0, 3]", "camera.eye"),
        ("type = \"sphere\"", "type = \"torus\"", "torus"),
        ("material = \"wood\"", "material = 7", "shapes[0]"),
        ("fov_y = 45", "fov_y = 45\nfocal_length = 35", "focal_length"),
        ("[render]", "[rendr]", "rendr"),
        ("type = \"grid\"", "type = \"grid\"\nspacing = 1", "spacing"),
    ] {
        assert!(text.contains(from), "{from}");
        rejects(&dir, "types.toml", text.replacen(from, to, 1).as_bytes(), &["types.toml", field]);
    }
}

#[test]
fn missing_unreadable_and_malformed_meshes_and_textures() {
    let dir = setup("files");
    let text = full_scene();
    rejects(&dir, "m1.toml", text.replace("tri.obj", "gone.obj").as_bytes(), &["shapes[3].file", "gone.obj"]);
    rejects(&dir, "m2.toml", text.replace("wood.png", "gone.png").as_bytes(), &["materials.wood.texture", "gone.png"]);
    // A directory where a file should be: unreadable even for root.
    std::fs::create_dir_all(dir.path("folder.png")).unwrap();
    rejects(
        &dir,
        "m3.toml",
        text.replace("wood.png", "folder.png").as_bytes(),
        &["materials.wood.texture", "folder.png"],
    );
    std::fs::create_dir_all(dir.path("folder.obj")).unwrap();
    rejects(&dir, "m4.toml", text.replace("tri.obj", "folder.obj").as_bytes(), &["shapes[3].file", "folder.obj"]);
    std::fs::write(dir.path("notpng.png"), "this is not a png").unwrap();
    rejects(
        &dir,
        "m5.toml",
        text.replace("wood.png", "notpng.png").as_bytes(),
        &["notpng.png", "materials.wood.texture"],
    );
    for (name, obj, expect) in [
        ("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "line 4"),
        ("text.obj", "v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n", "line 2"),
        ("empty.obj", "", "no faces"),
        ("points.obj", "v 0 0 0\nv 1 0 0\n", "no faces"),
    ] {
        std::fs::write(dir.path(name), obj).unwrap();
        rejects(&dir, "o.toml", text.replace("tri.obj", name).as_bytes(), &[name, expect]);
    }
    std::fs::write(dir.path("binary.obj"), [0u8, 159, 146, 150, 255, 10, 102, 32, 49]).unwrap();
    rejects(&dir, "o.toml", text.replace("tri.obj", "binary.obj").as_bytes(), &["binary.obj"]);
}

#[test]
fn impossible_resolutions_and_output_paths() {
    let dir = setup("resolution");
    let text = full_scene().replace("width = 16", "width = 200000").replace("height = 12", "height = 200000");
    rejects(&dir, "huge.toml", text.as_bytes(), &["huge.toml", "film", "memory"]);
    let scene = dir.write("ok.toml", &full_scene());
    let stderr = lightcuts_fails(&["render", s(&scene), "-o", s(&dir.path("no/such/dir/o.exr")), "--quiet"]);
    assert!(stderr.contains("no/such/dir"), "{stderr}");
    let stderr = lightcuts_fails(&["render", s(&scene), "-o", s(&dir.path("o.exr")), "--quiet", "--error", "nan"]);
    assert!(stderr.contains("--error"), "{stderr}");
    let stderr = lightcuts_fails(&["render", s(&scene), "-o", s(&dir.path("o.exr")), "--quiet", "--max-cut", "0"]);
    assert!(stderr.contains("--max-cut"), "{stderr}");
    assert!(!dir.path("o.exr").exists());
}

/// Sends SIGINT with the shell's builtin kill: a minimal system (the
/// Embree 4 chroot) has no /usr/bin/kill.
fn interrupt(child: &std::process::Child) {
    let killed = std::process::Command::new("sh").args(["-c", &format!("kill -INT {}", child.id())]).status().unwrap();
    assert!(killed.success());
}

#[test]
fn sigint_while_rendering_exits_130_and_writes_nothing() {
    let dir = setup("sigint-render");
    // Still rendering (minutes of work) when interrupted after half a second.
    let text = full_scene()
        .replace("count = [2, 2]", "count = [300, 300]")
        .replace("width = 16", "width = 320")
        .replace("height = 12", "height = 240");
    let scene = dir.write("slow.toml", &text);
    let out = dir.path("slow.exr");
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_lightcuts"))
        .args(["render", s(&scene), "-o", s(&out), "--exact", "--quiet"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(500));
    interrupt(&child);
    let output = child.wait_with_output().unwrap();
    assert_eq!(output.status.code(), Some(130), "{}", String::from_utf8_lossy(&output.stderr));
    assert!(!out.exists());
    assert!(dir.files().iter().all(|f| !f.contains("slow.exr")), "{:?}", dir.files());
}

/// Interrupted while the EXR is being written: the temporary file it is
/// written to must exist at that moment (so its removal is exercised), and
/// afterwards neither it nor anything under the output name may exist.
#[test]
fn sigint_while_writing_the_exr_removes_the_temporary_file() {
    let dir = setup("sigint-write");
    // No lights: the 2400 x 2400 render takes a few seconds, and writing its
    // 11 ZIP-compressed channels (250 MB of samples) takes a few more.
    let text = r#"
[film]
width = 2400
height = 2400
[camera]
eye = [0, 3, 6]
look_at = [0, 0, 0]
fov_y = 45
[materials.grey]
albedo = [0.5, 0.5, 0.5]
[[shapes]]
type = "sphere"
center = [0, 0.5, 0]
radius = 1
material = "grey"
"#;
    let scene = dir.write("big.toml", text);
    let out = dir.path("big.exr");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_lightcuts"))
        .args(["render", s(&scene), "-o", s(&out), "--exact", "--quiet", "--threads", "1"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let is_temporary = |f: &String| f.starts_with(".big.exr.") && f.ends_with(".partial");
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(300);
    let temporary = loop {
        if let Some(t) = dir.files().into_iter().find(is_temporary) {
            break t;
        }
        assert!(child.try_wait().unwrap().is_none(), "the render ended before its temporary file was seen");
        assert!(std::time::Instant::now() < deadline, "no temporary file after 300 s");
        std::thread::sleep(std::time::Duration::from_millis(2));
    };
    interrupt(&child);
    let output = child.wait_with_output().unwrap();
    assert_eq!(output.status.code(), Some(130), "{}", String::from_utf8_lossy(&output.stderr));
    assert!(!dir.path(&temporary).exists(), "{temporary} survived the interrupt");
    assert!(!out.exists(), "an output appeared under the output name");
    assert!(dir.files().iter().all(|f| !f.contains("big.exr")), "{:?}", dir.files());
}

/// glTF files broken in every way the loader must survive: each is one
/// line naming the file and the JSON location, exit 1, no output.
#[test]
fn hostile_gltf_files() {
    use common::gltf::{floor_and_point_light, GltfBuilder};
    use serde_json::json;
    let dir = setup("gltf");
    let good = floor_and_point_light();
    let text = good.embedded();
    let glb = good.glb();
    rejects(&dir, "truncated.gltf", &text.as_bytes()[..text.len() / 2], &["truncated.gltf", "line"]);
    rejects(&dir, "garbage.gltf", b"\x00\x01\x02 not json", &["garbage.gltf", "not a readable glTF"]);
    rejects(&dir, "truncated.glb", &glb[..40], &["truncated.glb", "GLB"]);
    rejects(&dir, "garbage.glb", b"glTF\x02\x00\x00\x00\xff\xff\xff\xffJSON", &["garbage.glb", "GLB"]);
    let mutated = |f: &dyn Fn(&mut GltfBuilder)| {
        let mut g = floor_and_point_light();
        f(&mut g);
        g.embedded().into_bytes()
    };
    let case = |name: &str, f: &dyn Fn(&mut GltfBuilder), expect: &[&str]| {
        let mut expect = expect.to_vec();
        expect.push(name);
        rejects(&dir, name, &mutated(f), &expect);
    };
    case(
        "overrun.gltf",
        &|g| g.json["accessors"][0]["count"] = json!(1000),
        &["accessors[0]", "meshes[0].primitives[0].attributes.POSITION", "overrun"],
    );
    case("absurd.gltf", &|g| g.json["accessors"][0]["count"] = json!(1u64 << 40), &["accessors[0].count"]);
    case(
        "offset.gltf",
        &|g| g.json["bufferViews"][0]["byteOffset"] = json!(1u64 << 33),
        &["bufferViews[0]", "past the end"],
    );
    case("stride.gltf", &|g| g.json["bufferViews"][0]["byteStride"] = json!(4), &["bufferViews[0].byteStride"]);
    case(
        "index.gltf",
        &|g| {
            let m = g.mesh(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], Some(&[0, 1, 7]), None, None, None, None);
            g.node(json!({ "mesh": m }), true);
        },
        &["meshes[1].primitives[0].indices", "past the 3 vertices"],
    );
    case(
        "nan.gltf",
        &|g| {
            let m = g.mesh(&[[f32::NAN, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], None, None, None, None, None);
            g.node(json!({ "mesh": m }), true);
        },
        &["meshes[1].primitives[0].attributes.POSITION", "vertex 0"],
    );
    case(
        "huge.gltf",
        &|g| g.json["nodes"][0]["scale"] = json!([1e38, 1e38, 1e38]),
        &["meshes[0].primitives[0].attributes.POSITION", "vertex 0"],
    );
    case("far.gltf", &|g| g.json["nodes"][0]["translation"] = json!([1e20, 0, 0]), &["nodes[0]", "outside"]);
    case(
        "matrix.gltf",
        &|g| g.json["nodes"][0]["matrix"] = json!([1e38, 0, 0, 0, 0, 1e38, 0, 0, 0, 0, 1e38, 0, 1e38, 1e38, 1e38, 1]),
        &["nodes[0]"],
    );
    case("cycle.gltf", &|g| g.json["nodes"][0]["children"] = json!([0]), &["nodes[0]"]);
    case(
        "draco.gltf",
        &|g| g.json["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]),
        &["extensionsRequired[0]", "KHR_draco_mesh_compression", "does not implement"],
    );
    case(
        "light.gltf",
        &|g| g.json["nodes"][1]["extensions"]["KHR_lights_punctual"]["light"] = json!(9),
        &["nodes[1]", "light"],
    );
    case(
        "intensity.gltf",
        &|g| g.json["extensions"]["KHR_lights_punctual"]["lights"][0]["intensity"] = json!(-5.0),
        &["extensions.KHR_lights_punctual.lights[0].intensity"],
    );
    case(
        "cone.gltf",
        &|g| {
            g.json["extensions"]["KHR_lights_punctual"]["lights"][0] =
                json!({ "type": "spot", "intensity": 1.0, "spot": { "innerConeAngle": 0.9, "outerConeAngle": 0.5 } })
        },
        &["lights[0].spot.innerConeAngle"],
    );
    // The paths of this round: sparse accessors, skins, GPU instances.
    case(
        "sparse.gltf",
        &|g| {
            let indices = g.bytes_view(&[9u8]);
            let values = g.bytes_view(&[0u8; 12]);
            g.json["accessors"][0]["sparse"] = json!({ "count": 1,
                "indices": { "bufferView": indices, "componentType": 5121 }, "values": { "bufferView": values } });
        },
        &["accessors[0].sparse.indices", "index 0 is 9", "below the accessor's count 4"],
    );
    case(
        "sparse_count.gltf",
        &|g| {
            let indices = g.bytes_view(&[0u8]);
            let values = g.bytes_view(&[0u8; 12]);
            g.json["accessors"][0]["sparse"] = json!({ "count": 100000,
                "indices": { "bufferView": indices, "componentType": 5121 }, "values": { "bufferView": values } });
        },
        &["accessors[0].sparse.count", "100000"],
    );
    let skinned = |g: &mut GltfBuilder, joints: serde_json::Value| {
        let joint_indices = g.raw(&[0u8, 0, 0, 0].repeat(4), 5121, 4, "VEC4", false);
        let weights = g.floats(&[1.0, 0.0, 0.0, 0.0].repeat(4), "VEC4", 4);
        let attributes = &mut g.json["meshes"][0]["primitives"][0]["attributes"];
        attributes["JOINTS_0"] = json!(joint_indices);
        attributes["WEIGHTS_0"] = json!(weights);
        g.json["skins"] = json!([{ "joints": joints }]);
        g.json["nodes"][0]["skin"] = json!(0);
    };
    case("joints.gltf", &|g| skinned(g, json!(vec![1; 70000])), &["skins[0].joints", "70000 joints"]);
    case(
        "joint_index.gltf",
        &|g| {
            skinned(g, json!([1]));
            let bad = g.raw(&[5u8, 0, 0, 0].repeat(4), 5121, 4, "VEC4", false);
            g.json["meshes"][0]["primitives"][0]["attributes"]["JOINTS_0"] = json!(bad);
        },
        &["JOINTS_0", "names joint 5, but the skin has 1"],
    );
    case(
        "instances.gltf",
        &|g| {
            let t = g.floats(&[0.0; 6], "VEC3", 3);
            let s = g.floats(&[1.0; 9], "VEC3", 3);
            g.json["nodes"][0]["extensions"] =
                json!({ "EXT_mesh_gpu_instancing": { "attributes": { "TRANSLATION": t, "SCALE": s } } });
        },
        &["nodes[0].extensions.EXT_mesh_gpu_instancing.attributes", "one element an instance"],
    );
    case(
        "instance_nan.gltf",
        &|g| {
            let t = g.floats(&[f32::NAN, 0.0, 0.0], "VEC3", 3);
            g.json["nodes"][0]["extensions"] =
                json!({ "EXT_mesh_gpu_instancing": { "attributes": { "TRANSLATION": t } } });
        },
        &["EXT_mesh_gpu_instancing", "instance 0's transform is not finite"],
    );
    // An Embree instance placed outside the coordinates Embree accepts.
    case(
        "instance_far.gltf",
        &|g| {
            let t = g.floats(&[0.0, 0.0, 0.0, 1e20, 0.0, 0.0], "VEC3", 3);
            g.json["nodes"][0]["extensions"] =
                json!({ "EXT_mesh_gpu_instancing": { "attributes": { "TRANSLATION": t } } });
        },
        &["nodes[0]", "places meshes[0]", "in the world"],
    );
    let bad_base64 = floor_and_point_light().embedded().replace(";base64,", ";base64,!!");
    rejects(&dir, "base64.gltf", bad_base64.as_bytes(), &["base64.gltf", "buffers[0].uri", "base64"]);
    // A missing image is drawn around (the factor alone), as glTF viewers
    // do, with a warning; --strict refuses it.
    let missing = mutated(&|g| {
        g.json["images"] = json!([{ "uri": "nope.png" }]);
        g.json["textures"] = json!([{ "source": 0 }]);
        g.json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({ "index": 0 });
    });
    incomplete(&dir, "image.gltf", &missing, &["nope.png", "images[0].uri"]);
    // gltf 1.4.1 unwraps what the specification requires of an image.
    for (name, image, expect) in [
        ("no_source.gltf", json!({ "mimeType": "image/png" }), "images[0]"),
        ("no_mime.gltf", json!({ "bufferView": 0 }), "images[0].mimeType"),
    ] {
        case(
            name,
            &|g| {
                g.json["images"] = json!([image.clone()]);
                g.json["textures"] = json!([{ "source": 0 }]);
                g.json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({ "index": 0 });
            },
            &[expect],
        );
    }
    std::fs::write(dir.path("junk.png"), b"junk").unwrap();
    // So is an image that cannot be decoded.
    let junk = mutated(&|g| {
        g.json["images"] = json!([{ "uri": "junk.png" }]);
        g.json["textures"] = json!([{ "source": 0 }]);
        g.json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({ "index": 0 });
    });
    incomplete(&dir, "junk_image.gltf", &junk, &["junk.png", "images[0]", "not a PNG, JPEG"]);
    // A missing .bin beside the .gltf.
    let path = floor_and_point_light().write_separate(&dir.path(""), "room");
    std::fs::remove_file(dir.path("room.bin")).unwrap();
    let text = std::fs::read(&path).unwrap();
    rejects(&dir, "room.gltf", &text, &["room.bin", "buffers[0].uri"]);
    // A camera named on the command line that the file lacks.
    let scene = dir.write("cams.gltf", &floor_and_point_light().embedded());
    let stderr = lightcuts_fails(&["render", s(&scene), "--camera", "nope", "-o", s(&dir.path("out.exr"))]);
    assert!(stderr.contains("cams.gltf") && stderr.contains("no camera named 'nope'"), "{stderr}");
}
