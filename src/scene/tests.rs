//! Scene parsing and validation: every error names the file and the field.
use super::*;

const VALID: &str = r#"
[film]
width = 64
height = 48

[camera]
eye = [0, 1, 4]
look_at = [0, 0, 0]
fov_y = 45

[materials.white]
albedo = [0.8, 0.8, 0.8]

[[shapes]]
type = "quad"
corner = [-2, 0, -2]
u = [4, 0, 0]
v = [0, 0, 4]
material = "white"

[[shapes]]
type = "sphere"
center = [0, 0.5, 0]
radius = 0.5
material = "white"

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
"#;

fn load_str(name: &str, text: &str) -> Result<Scene, SceneError> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, text).unwrap();
    Scene::load(&path)
}

fn error_of(name: &str, text: &str) -> String {
    let e = load_str(name, text).expect_err("scene should be rejected");
    let message = e.to_string();
    assert!(message.contains(name), "message does not name the file: {message}");
    message
}

#[test]
fn a_valid_scene_loads_with_its_lights_and_shapes() {
    let scene = load_str("ok.toml", VALID).unwrap();
    assert_eq!(scene.film, Film { width: 64, height: 48, spp: 1 });
    assert_eq!(scene.meshes.len(), 2);
    assert_eq!(
        scene.lights,
        vec![
            LightSource::Point { position: Vec3::new(0.0, 2.0, 0.0), intensity: Vec3::ONE },
            LightSource::Grid {
                corner: Vec3::new(-1.0, 3.0, -1.0),
                u: Vec3::new(2.0, 0.0, 0.0),
                v: Vec3::new(0.0, 0.0, 2.0),
                count: [3, 2],
                intensity: Vec3::splat(0.5),
            },
        ]
    );
}

#[test]
fn json_with_the_same_schema_loads_too() {
    let json = r#"{"film": {"width": 8, "height": 8}, "camera": {"eye": [0,0,1], "look_at": [0,0,0], "fov_y": 30},
        "lights": [{"type": "point", "position": [0,0,2], "intensity": [1,2,3]}]}"#;
    let scene = load_str("s.json", json).unwrap();
    assert_eq!(
        scene.lights,
        vec![LightSource::Point { position: Vec3::new(0.0, 0.0, 2.0), intensity: Vec3::new(1.0, 2.0, 3.0) }]
    );
}

#[test]
fn nan_intensity_names_the_light_and_field() {
    let text = VALID.replace("intensity = [1, 1, 1]", "intensity = [1, nan, 1]");
    let m = error_of("nan.toml", &text);
    assert!(m.contains("lights[0].intensity"), "{m}");
}

#[test]
fn negative_and_infinite_values_are_rejected_with_their_field() {
    for (from, to, field) in [
        ("radius = 0.5", "radius = -1", "shapes[1].radius"),
        ("radius = 0.5", "radius = inf", "shapes[1].radius"),
        ("intensity = [0.5, 0.5, 0.5]", "intensity = [-0.5, 0.5, 0.5]", "lights[1].intensity"),
        ("fov_y = 45", "fov_y = 180", "camera.fov_y"),
        ("albedo = [0.8, 0.8, 0.8]", "albedo = [0.8, 1.5, 0.8]", "materials.white.albedo"),
        ("width = 64", "width = 0", "film.width"),
        ("count = [3, 2]", "count = [0, 2]", "lights[1].count"),
        ("eye = [0, 1, 4]", "eye = [0, 1, -inf]", "camera.eye"),
    ] {
        assert!(VALID.contains(from));
        let m = error_of("bad.toml", &VALID.replacen(from, to, 1));
        assert!(m.contains(field), "expected {field} in: {m}");
    }
}

#[test]
fn a_misspelt_field_is_an_error_naming_it() {
    let m = error_of("typo.toml", &VALID.replace("radius = 0.5", "raduis = 0.5"));
    assert!(m.contains("shapes[1]") && m.contains("raduis"), "{m}");
    let m = error_of("typo2.toml", &VALID.replace("[film]\nwidth", "[film]\nwidht"));
    assert!(m.contains("widht"), "{m}");
}

#[test]
fn wrong_types_and_syntax_errors_give_a_position() {
    let m = error_of("type.toml", &VALID.replace("width = 64", "width = \"wide\""));
    assert!(m.contains("film.width"), "{m}");
    let m = error_of("syntax.toml", "[film\nwidth = 3");
    assert!(m.contains("line 1"), "{m}");
    let m = error_of("syntax.json", "{\"film\": {\"width\": 3,, }");
    assert!(m.contains("line 1"), "{m}");
}

#[test]
fn a_missing_mesh_file_names_the_shape_field() {
    let text = format!("{VALID}\n[[shapes]]\ntype = \"mesh\"\nfile = \"missing.obj\"\nmaterial = \"white\"\n");
    let m = error_of("mesh.toml", &text);
    assert!(m.contains("shapes[2].file") && m.contains("missing.obj"), "{m}");
}

#[test]
fn an_unknown_material_names_the_shape() {
    let m = error_of("mat.toml", &VALID.replacen("material = \"white\"", "material = \"black\"", 1));
    assert!(m.contains("shapes[0].material") && m.contains("black"), "{m}");
}

#[test]
fn a_film_too_large_for_memory_is_rejected() {
    let m = error_of(
        "huge.toml",
        &VALID.replace("width = 64", "width = 4000000000").replace("height = 48", "height = 4000000000"),
    );
    assert!(m.contains("film") && m.contains("memory"), "{m}");
}

#[test]
fn obj_meshes_load_relative_to_the_scene_file() {
    let temporary = tempfile::tempdir().unwrap();
    let dir = temporary.path();
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    std::fs::write(
        dir.join("meshes/tri.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nf 1//1 2//2 3//3\n",
    )
    .unwrap();
    std::fs::write(dir.join("bad.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n").unwrap();
    let text = format!("{VALID}\n[[shapes]]\ntype = \"mesh\"\nfile = \"meshes/tri.obj\"\nmaterial = \"white\"\nscale = 2\ntranslate = [1, 0, 0]\n");
    std::fs::write(dir.join("scene.toml"), &text).unwrap();
    let scene = Scene::load(&dir.join("scene.toml")).unwrap();
    let mesh = &scene.meshes[2];
    assert_eq!(mesh.positions, vec![Vec3::new(1.0, 0.0, 0.0), Vec3::new(3.0, 0.0, 0.0), Vec3::new(1.0, 2.0, 0.0)]);
    assert_eq!(mesh.normals.as_ref().unwrap()[0], Vec3::Z);
    let bad = text.replace("meshes/tri.obj", "bad.obj");
    std::fs::write(dir.join("bad.toml"), &bad).unwrap();
    let e = Scene::load(&dir.join("bad.toml")).expect_err("out-of-range face index");
    assert!(e.to_string().contains("bad.obj"), "{e}");
}
