//! USD stages (docs/scene-format.md, "USD") against answers that do not
//! come from this renderer: stages written by Pixar's usd-core with what
//! each should render as (scenes/usd/make_fixtures.py: the UsdLux
//! schema's units and closed forms; usd-core's own evaluation of a
//! composed, packaged stage), and the Blender lobby exported as USD
//! against its glTF export and Cycles.

mod common;

use common::{channel, lightcuts, lightcuts_fails, lightcuts_ok, means, render, s, scenes, TempDir};

/// Each UsdLux light (and an emissive mesh) over a Lambertian floor of
/// albedo rho, in Y-up metres and Z-up centimetres, normalised or not: the
/// irradiance E = pi L / rho the camera sees at its point, per channel,
/// against the schema's closed form, within 1% (2% for the textured dome,
/// whose map becomes 4,096 directional lights), in the exact and the
/// stochastic modes. A light read in the wrong units, at the wrong
/// fallback or normalised by the wrong area is off by a factor, not a
/// percent.
#[test]
fn every_usdlux_light_matches_its_closed_form_in_the_schema_s_units() {
    let dir = TempDir::new("usd-lights");
    let folder = scenes().join("usd/lights");
    let expected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(folder.join("expected.json")).unwrap()).unwrap();
    let albedo = expected["albedo"].as_f64().unwrap();
    let mut failures = Vec::new();
    let stages = expected["irradiance"].as_object().unwrap();
    assert!(stages.len() >= 12, "{} stages", stages.len());
    for (stage, cameras) in stages {
        for (camera, want) in cameras.as_object().unwrap() {
            let want: Vec<f64> = want.as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
            let tolerance = if stage == "dome_texture" { 0.02 } else { 0.01 };
            // The stage through a TOML that asks for 4,096 points per area
            // light (the default 256 are a quadrature off by up to 1% at
            // these distances: docs/notebook/measurements.md).
            let path = dir.write(
                &format!("{stage}.toml"),
                &format!("[usd]\nfile = {:?}\nemitter_samples = 4096\n", s(&folder.join(format!("{stage}.usda")))),
            );
            for mode in [&["--exact", "--spp", "4"][..], &["--stochastic", "--spp", "64"][..]] {
                let mut flags = vec!["--camera", camera.as_str(), "--resolution", "8x8", "--aovs", "none"];
                flags.extend_from_slice(mode);
                let image = render(&path, &dir.path("out.exr"), &flags);
                let got = means(&image).map(|l| std::f64::consts::PI * l / albedo);
                let error = (0..3).map(|k| (got[k] - want[k]).abs() / want[k]).fold(0.0, f64::max);
                eprintln!("{stage} {camera} {mode:?}: E {got:.5?}, closed form {want:.5?}, {:.3}%", 100.0 * error);
                if error > tolerance {
                    failures.push(format!("{stage} {camera} {mode:?}: {got:?} vs {want:?}"));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// A packaged stage that composes (a reference, a payload with a variant
/// selected, three instanceable references, a textured quad): the objects
/// `lightcuts inspect` reports are usd-core's drawn gprims, by the paths
/// usd-core gives them (an instance's prims under the instance), each with
/// usd-core's world bounds within 1e-4 m (the spheres are tessellated
/// through their poles and equator, whose extremes are the sphere's).
#[test]
fn a_composed_usdz_package_has_usd_core_s_objects_where_usd_core_puts_them() {
    let folder = scenes().join("usd/composition");
    let expected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(folder.join("expected.json")).unwrap()).unwrap();
    let expected = expected["objects"].as_object().unwrap();
    let report = lightcuts_ok(&["inspect", s(&folder.join("composition.usdz")), "--json"]);
    let report: serde_json::Value = serde_json::from_str(&report).unwrap();
    let objects = report["objects"].as_array().unwrap();
    let names: Vec<&str> = objects.iter().map(|o| o["name"].as_str().unwrap()).collect();
    let mut want: Vec<&str> = expected.keys().map(String::as_str).collect();
    let mut got = names.clone();
    want.sort_unstable();
    got.sort_unstable();
    assert_eq!(got, want, "the objects differ from usd-core's gprims");
    for object in objects {
        let name = object["name"].as_str().unwrap();
        let bounds = &expected[name];
        for (k, corner) in ["min", "max"].into_iter().enumerate() {
            for axis in 0..3 {
                let (ours, theirs) = (object[corner][axis].as_f64().unwrap(), bounds[k][axis].as_f64().unwrap());
                assert!((ours - theirs).abs() < 1e-4, "{name} {corner}[{axis}]: {ours} vs usd-core's {theirs}");
            }
        }
    }
    // The three instances share one prototype's meshes through Embree instances.
    let instances = objects.iter().filter(|o| o["instance"].as_bool().unwrap()).count();
    assert_eq!(instances, 6, "{report}");
    // And it renders: the texture is read from inside the package.
    let dir = TempDir::new("usd-composition");
    let image = render(&folder.join("composition.usdz"), &dir.path("out.exr"), &["--resolution", "48x32"]);
    assert!(means(&image).iter().all(|&c| c > 0.0));
}

/// The lobby (scenes/lobby/) exported by Blender 5.0's own USD exporter
/// renders as its glTF export does (mean within 1%, measured 0.00%) and
/// within 1.5% of Cycles' render of the .blend (measured 0.65%, the glTF
/// export's own difference).
#[test]
fn the_lobby_exported_as_usd_renders_as_its_gltf_export_and_as_cycles() {
    let dir = TempDir::new("usd-lobby");
    let lobby = scenes().join("lobby");
    let flags = ["--exact", "--spp", "8", "--resolution", "160x120"];
    let usd = render(&lobby.join("lobby.usdc"), &dir.path("usd.exr"), &flags);
    let gltf = render(&scenes().join("lobby.toml"), &dir.path("gltf.exr"), &flags);
    let cycles = common::read_exr(&lobby.join("cycles_2048.exr")).unwrap();
    let mean = |image: &common::ExrImage| common::luminance(image).iter().sum::<f64>();
    let against_gltf = mean(&usd) / mean(&gltf);
    let against_cycles = mean(&usd) / mean(&cycles);
    eprintln!("lobby.usdc: mean {against_gltf:.5} x the glTF export's, {against_cycles:.5} x Cycles'");
    assert!((against_gltf - 1.0).abs() < 0.01, "{against_gltf}");
    assert!((against_cycles - 1.0).abs() < 0.015, "{against_cycles}");
}

/// A prim that moves over its time samples blurs under `--shutter` (in
/// time codes), and `--time` reads the stage at one time code: the sphere
/// at frame 1 and at frame 24 lands where its samples put it, and the same
/// bits come for any thread count.
#[test]
fn time_samples_move_a_prim_under_the_shutter_and_time_picks_a_frame() {
    let dir = TempDir::new("usd-time");
    let stage = dir.write(
        "moving.usda",
        r#"#usda 1.0
(
    defaultPrim = "World"
    metersPerUnit = 1
    upAxis = "Y"
    startTimeCode = 1
    endTimeCode = 24
)
def Xform "World"
{
    def Sphere "Ball"
    {
        double radius = 0.5
        double3 xformOp:translate.timeSamples = { 1: (-2, 0.5, 0), 24: (2, 0.5, 0) }
        uniform token[] xformOpOrder = ["xformOp:translate"]
    }
    def Camera "Camera"
    {
        float focalLength = 35
        float horizontalAperture = 36
        float verticalAperture = 24
        double3 xformOp:translate = (0, 1, 8)
        uniform token[] xformOpOrder = ["xformOp:translate"]
    }
    def DomeLight "Sky"
    {
        float inputs:intensity = 1
    }
}
"#,
    );
    let at = |time: &str| {
        let report = lightcuts_ok(&["inspect", s(&stage), "--time", time, "--json"]);
        let report: serde_json::Value = serde_json::from_str(&report).unwrap();
        let ball = report["objects"].as_array().unwrap().iter().find(|o| o["name"] == "/World/Ball").unwrap().clone();
        0.5 * (ball["min"][0].as_f64().unwrap() + ball["max"][0].as_f64().unwrap())
    };
    assert!((at("1") + 2.0).abs() < 1e-5, "{}", at("1"));
    assert!((at("24") - 2.0).abs() < 1e-5);
    // Halfway between the samples, linearly.
    assert!((at("12.5") - 0.0).abs() < 1e-5, "{}", at("12.5"));
    // Without --time: the stage's start.
    let report: serde_json::Value = serde_json::from_str(&lightcuts_ok(&["inspect", s(&stage), "--json"])).unwrap();
    assert!(report["objects"][0]["min"][0].as_f64().unwrap() < -2.4);
    // Under the shutter the ball is an instance with motion, and blurs.
    let report: serde_json::Value =
        serde_json::from_str(&lightcuts_ok(&["inspect", s(&stage), "--shutter", "1,24", "--json"])).unwrap();
    assert_eq!(report["objects"][0]["moves"], true, "{report}");
    let flags = ["--resolution", "96x64", "--spp", "16", "--stochastic", "--shutter", "1,24"];
    let blurred = render(&stage, &dir.path("blurred.exr"), &flags);
    let still = render(&stage, &dir.path("still.exr"), &["--resolution", "96x64", "--spp", "16", "--stochastic"]);
    assert!(common::mean_relative_error(&blurred, &still) > 0.05);
    common::assert_same_bits_for_any_threads_and_window(&dir, &stage, 96, &flags);
}

/// What a stage says that is not in the schemas, or breaks them: a clear
/// error naming the file and the prim (or the file's part), exit code 1, no
/// output, no panic.
#[test]
fn broken_stages_fail_with_the_file_and_the_prim_named() {
    let dir = TempDir::new("usd-broken");
    let lights = scenes().join("usd/lights");
    let bad = |name: &str, text: &str| dir.write(name, text);
    let header = "#usda 1.0\n(\n    metersPerUnit = 1\n)\n";
    let cases: Vec<(std::path::PathBuf, &str)> = vec![
        (bad("negative.usda", &format!("{header}def SphereLight \"L\"\n{{\n    float inputs:intensity = -3\n}}\n")), "/L.inputs:intensity"),
        (
            bad("indices.usda", &format!("{header}def Mesh \"M\"\n{{\n    point3f[] points = [(0,0,0),(1,0,0),(0,1,0)]\n    int[] faceVertexCounts = [3]\n    int[] faceVertexIndices = [0, 1, 7]\n}}\n")),
            "/M.faceVertexIndices",
        ),
        (
            bad("counts.usda", &format!("{header}def Mesh \"M\"\n{{\n    point3f[] points = [(0,0,0),(1,0,0),(0,1,0)]\n    int[] faceVertexCounts = [4]\n    int[] faceVertexIndices = [0, 1, 2]\n}}\n")),
            "/M.faceVertexCounts",
        ),
        (
            bad("primvar.usda", &format!("{header}def Mesh \"M\"\n{{\n    point3f[] points = [(0,0,0),(1,0,0),(0,1,0)]\n    int[] faceVertexCounts = [3]\n    int[] faceVertexIndices = [0, 1, 2]\n    texCoord2f[] primvars:st = [(0,0)] (\n        interpolation = \"faceVarying\"\n    )\n}}\n")),
            "/M.primvars:st",
        ),
        (bad("xform.usda", &format!("{header}def Xform \"X\"\n{{\n    uniform token[] xformOpOrder = [\"xformOp:translate\"]\n}}\n")), "/X.xformOp:translate"),
        (bad("camera.usda", &format!("{header}def Camera \"C\"\n{{\n    token projection = \"orthographic\"\n}}\n")), "/C.projection"),
    ];
    for (path, location) in cases {
        let out = dir.path("out.exr");
        let stderr = lightcuts_fails(&["render", s(&path), "-o", s(&out)]);
        let file = path.file_name().unwrap().to_string_lossy().into_owned();
        assert!(stderr.contains(&file) && stderr.contains(location), "{file}: expected '{location}' in: {stderr}");
        assert!(!out.exists(), "{file}: an output was written");
    }
    // Truncated and corrupted crate files, and a .usdz whose zip is broken.
    let crate_bytes = std::fs::read(scenes().join("lobby/lobby.usdc")).unwrap();
    let package = std::fs::read(scenes().join("usd/composition/composition.usdz")).unwrap();
    let mut corrupted = crate_bytes.clone();
    for k in (64..corrupted.len()).step_by(97) {
        corrupted[k] ^= 0x5a;
    }
    let broken: Vec<(&str, Vec<u8>)> = vec![
        ("truncated.usdc", crate_bytes[..crate_bytes.len() / 3].to_vec()),
        ("header.usdc", crate_bytes[..40].to_vec()),
        ("corrupted.usdc", corrupted),
        ("empty.usda", Vec::new()),
        ("zip.usdz", package[..package.len() / 2].to_vec()),
    ];
    for (name, bytes) in broken {
        let path = dir.path(name);
        std::fs::write(&path, bytes).unwrap();
        let out = dir.path("out.exr");
        let stderr = lightcuts_fails(&["render", s(&path), "-o", s(&out), "--resolution", "8x8"]);
        assert!(stderr.contains(name), "{name}: {stderr}");
        assert!(!out.exists());
    }
    // A crate file whose one corrupt byte (byte 100 of scenes/usd/fuzz/
    // stage.usdc set to 207, found by mutating each byte) makes an array's count
    // ask for 3.5 TB: the reader's allocation fails, which aborts the
    // process it runs in, so the command reads stages in a child first.
    let huge = scenes().join("usd/broken/huge-count.usdc");
    let out = dir.path("huge.exr");
    let stderr = lightcuts_fails(&["render", s(&huge), "-o", s(&out), "--resolution", "8x8"]);
    assert!(stderr.contains("huge-count.usdc") && stderr.contains("aborted"), "{stderr}");
    assert!(!out.exists());
    // Read in this process the same file does abort it (so the child is needed).
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_lightcuts"))
        .args(["inspect", s(&huge)])
        .env("LIGHTCUTS_USD_CHILD", "1")
        .output()
        .unwrap();
    assert!(std::os::unix::process::ExitStatusExt::signal(&child.status).is_some(), "{:?}", child.status);
    // The fixtures themselves load (so the cases above fail for their fault).
    assert!(lightcuts(&["inspect", s(&lights.join("sphere.usda"))]).status.success());
}

/// UsdPreviewSurface's texture network as the schema defines it, seen
/// through emission (the camera sees an emissive surface's radiance as
/// is): a 2 x 2 sRGB PNG read through UsdUVTexture's `rgb` and `r`
/// outputs with its `scale` and `bias`, on a quad that fills a 2 x 2 film
/// so that each pixel's centre is a texel's centre. Each pixel is the
/// texel, decoded from sRGB, times the scale plus the bias.
#[test]
fn a_texture_s_channels_scale_and_bias_are_the_schema_s() {
    let dir = TempDir::new("usd-texture");
    // Four 8 x 8 blocks (row 0 at the top): red, green / blue, grey 128,
    // on a 16 x 16 film: a pixel at least one pixel from a block's edge
    // reads its block's colour wherever its sample falls (bilinear reads
    // the four nearest texels), and the texture clamps at its edges.
    let png = [[[255u8, 0, 0], [0, 255, 0]], [[0, 0, 255], [128, 128, 128]]];
    let texels: Vec<u8> = (0..16).flat_map(|y| (0..16).flat_map(move |x| png[y / 8][x / 8])).collect();
    let mut encoder = png::Encoder::new(std::fs::File::create(dir.path("t.png")).unwrap(), 16, 16);
    encoder.set_color(png::ColorType::Rgb);
    encoder.write_header().unwrap().write_image_data(&texels).unwrap();
    let srgb = |v: u8| {
        let c = f64::from(v) / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    for (output, scale, bias) in [("rgb", [2.0, 1.0, 0.5], [0.1, 0.0, 0.2]), ("r", [3.0, 3.0, 3.0], [0.0, 0.05, 0.0])] {
        let kind = if output == "rgb" { "float3" } else { "float" };
        let stage = dir.write(
            "textured.usda",
            &format!(
                r#"#usda 1.0
(
    metersPerUnit = 1
    upAxis = "Y"
)
def Xform "World"
{{
    def Mesh "Quad" (
        prepend apiSchemas = ["MaterialBindingAPI"]
    )
    {{
        int[] faceVertexCounts = [4]
        int[] faceVertexIndices = [0, 1, 2, 3]
        point3f[] points = [(-1, -1, -5), (1, -1, -5), (1, 1, -5), (-1, 1, -5)]
        texCoord2f[] primvars:st = [(0, 0), (1, 0), (1, 1), (0, 1)] (
            interpolation = "vertex"
        )
        uniform token subdivisionScheme = "none"
        rel material:binding = </World/Looks/Glow>
    }}
    def Scope "Looks"
    {{
        def Material "Glow"
        {{
            token outputs:surface.connect = </World/Looks/Glow/Surface.outputs:surface>
            def Shader "Surface"
            {{
                uniform token info:id = "UsdPreviewSurface"
                color3f inputs:diffuseColor = (0, 0, 0)
                color3f inputs:emissiveColor.connect = </World/Looks/Glow/Texture.outputs:{output}>
                token outputs:surface
            }}
            def Shader "Texture"
            {{
                uniform token info:id = "UsdUVTexture"
                asset inputs:file = @t.png@
                token inputs:sourceColorSpace = "sRGB"
                token inputs:wrapS = "clamp"
                token inputs:wrapT = "clamp"
                float4 inputs:scale = ({}, {}, {}, 1)
                float4 inputs:bias = ({}, {}, {}, 0)
                float2 inputs:st.connect = </World/Looks/Glow/Reader.outputs:result>
                {kind} outputs:{output}
            }}
            def Shader "Reader"
            {{
                uniform token info:id = "UsdPrimvarReader_float2"
                string inputs:varname = "st"
                float2 outputs:result
            }}
        }}
    }}
    def Camera "Camera"
    {{
        float focalLength = 50
        float horizontalAperture = 20
        float verticalAperture = 20
    }}
}}
"#,
                scale[0], scale[1], scale[2], bias[0], bias[1], bias[2]
            ),
        );
        let image = render(&stage, &dir.path("out.exr"), &["--resolution", "16x16", "--exact", "--aovs", "none"]);
        let [r, g, b] = ["R", "G", "B"].map(|c| channel(&image, c));
        for (y, x) in (0..16).flat_map(|y| (0..16).map(move |x| (y, x))) {
            // Pixels beside a block's edge blend two blocks.
            if [y, x].iter().any(|&v| matches!(v, 7 | 8)) {
                continue;
            }
            let linear = png[y / 8][x / 8].map(srgb);
            let want: Vec<f64> =
                (0..3).map(|k| if output == "rgb" { linear[k] } else { linear[0] } * scale[k] + bias[k]).collect();
            let p = y * 16 + x;
            let got = [r[p], g[p], b[p]].map(f64::from);
            for k in 0..3 {
                assert!((got[k] - want[k]).abs() < 1e-3, "{output}: pixel ({x}, {y}): {got:?}, want {want:?}");
            }
        }
    }
}

/// `lightcuts:group` on a light or an ancestor puts its light in that
/// group: the layers sum to the beauty, and each holds its lights' light.
#[test]
fn lightcuts_group_attributes_make_light_groups() {
    let dir = TempDir::new("usd-groups");
    let stage = dir.write(
        "groups.usda",
        r#"#usda 1.0
(
    metersPerUnit = 1
    upAxis = "Y"
)
def Xform "World"
{
    def Mesh "Floor"
    {
        int[] faceVertexCounts = [4]
        int[] faceVertexIndices = [0, 1, 2, 3]
        point3f[] points = [(-5, 0, 5), (5, 0, 5), (5, 0, -5), (-5, 0, -5)]
        uniform token subdivisionScheme = "none"
    }
    def Xform "Warm" (
    )
    {
        custom string lightcuts:group = "key"
        def SphereLight "A"
        {
            color3f inputs:color = (1, 0.5, 0.2)
            float inputs:intensity = 100
            float inputs:radius = 0.1
            double3 xformOp:translate = (-1, 2, 0)
            uniform token[] xformOpOrder = ["xformOp:translate"]
        }
    }
    def SphereLight "B"
    {
        custom token lightcuts:group = "fill"
        color3f inputs:color = (0.2, 0.5, 1)
        float inputs:intensity = 100
        float inputs:radius = 0.1
        double3 xformOp:translate = (1, 2, 0)
        uniform token[] xformOpOrder = ["xformOp:translate"]
    }
    def Camera "Camera"
    {
        float focalLength = 20
        double3 xformOp:translate = (0, 3, 8)
        float xformOp:rotateX = -25
        uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:rotateX"]
    }
}
"#,
    );
    let image = render(&stage, &dir.path("out.exr"), &["--resolution", "32x24", "--exact"]);
    assert!(means(&image)[1] > 0.0, "the camera sees the lit floor");
    let mean = |name: &str| channel(&image, name).iter().map(|&v| f64::from(v)).sum::<f64>();
    for c in ["R", "G", "B"] {
        let sum = mean(&format!("Combined_key.{c}")) + mean(&format!("Combined_fill.{c}"));
        assert!((sum - mean(c)).abs() <= 1e-4 * mean(c), "{c}: {sum} vs {}", mean(c));
    }
    assert!(mean("Combined_key.R") > 2.0 * mean("Combined_key.B"), "the key is warm");
    assert!(mean("Combined_fill.B") > 2.0 * mean("Combined_fill.R"), "the fill is cool");
}

/// What the schemas say of visibility, purpose, cameras and materials a
/// renderer cannot draw, read back through `lightcuts inspect --json`:
/// invisible prims (and their subtrees) and proxy or guide prims are not
/// drawn; a camera's fStop and focusDistance make the thin lens (radius
/// focalLength / 10 / (2 fStop) in scene units, here centimetres); a
/// material with only a MaterialX surface is grey with a warning naming it.
#[test]
fn visibility_purpose_the_thin_lens_and_unsupported_shaders() {
    let dir = TempDir::new("usd-details");
    let stage = dir.write(
        "details.usda",
        r#"#usda 1.0
(
    metersPerUnit = 0.01
    upAxis = "Y"
)
def Xform "World"
{
    def Sphere "Shown"
    {
        rel material:binding = </World/Looks/OnlyX>
    }
    def Xform "Hidden"
    {
        token visibility = "invisible"
        def Sphere "Child"
        {
        }
    }
    def Sphere "Proxy"
    {
        uniform token purpose = "proxy"
    }
    def Xform "Guides"
    {
        uniform token purpose = "guide"
        def Cube "Inherits"
        {
        }
    }
    def Cube "Render"
    {
        uniform token purpose = "render"
        double3 xformOp:translate = (0, 0, -300)
        uniform token[] xformOpOrder = ["xformOp:translate"]
    }
    def Scope "Looks"
    {
        def Material "OnlyX"
        {
            token outputs:mtlx:surface.connect = </World/Looks/OnlyX/Standard.outputs:out>
            def Shader "Standard"
            {
                uniform token info:id = "ND_standard_surface_surfaceshader"
                token outputs:out
            }
        }
    }
    def Camera "Camera"
    {
        float focalLength = 50
        float horizontalAperture = 36
        float verticalAperture = 24
        float fStop = 2
        float focusDistance = 400
        double3 xformOp:translate = (0, 0, 500)
        uniform token[] xformOpOrder = ["xformOp:translate"]
    }
    def DomeLight "Sky"
    {
    }
}
"#,
    );
    let report: serde_json::Value = serde_json::from_str(&lightcuts_ok(&["inspect", s(&stage), "--json"])).unwrap();
    let mut names: Vec<&str> =
        report["objects"].as_array().unwrap().iter().map(|o| o["name"].as_str().unwrap()).collect();
    names.sort_unstable();
    assert_eq!(names, ["/World/Render", "/World/Shown"], "{report}");
    let camera = &report["camera"];
    // 50 mm in a centimetre stage is 5 scene units, 0.05 m: / (2 x 2).
    let lens = camera["lens_radius"].as_f64().unwrap();
    assert!((lens - 0.0125).abs() < 1e-6, "{camera}");
    assert!((camera["focus_distance"].as_f64().unwrap() - 4.0).abs() < 1e-5, "{camera}");
    // 2 atan(12 / 50): the vertical aperture over the focal length.
    let fov = camera["fov_y"].as_f64().unwrap();
    assert!((fov - 2.0 * (12.0f64 / 50.0).atan().to_degrees()).abs() < 1e-4, "{fov}");
    assert_eq!((report["film"]["width"].as_u64(), report["film"]["height"].as_u64()), (Some(640), Some(427)));
    let warnings = report["warnings"].as_array().unwrap();
    assert!(
        warnings
            .iter()
            .any(|w| w.as_str().unwrap().contains("/World/Looks/OnlyX") && w.as_str().unwrap().contains("mtlx")),
        "{warnings:?}"
    );
}

/// Asset paths as USD resolves them, usd-core's own resolvedPath the
/// answer (scenes/usd/resolution/expected.json): a texture path authored
/// in a referenced layer is relative to that layer, not the root; `./x`
/// likewise; a search path is found through `--asset-path` (or
/// PXR_AR_DEFAULT_SEARCH_PATH, as USD's default resolver reads it); a
/// missing texture is a warning and its `inputs:fallback` is drawn; the
/// referenced layer is one of the scene's inputs; and a primvar reader
/// feeding diffuseColor draws the mesh's displayColor.
#[test]
fn asset_paths_resolve_against_the_layer_that_authors_them_as_usd_core_does() {
    let folder = scenes().join("usd/resolution");
    let expected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(folder.join("expected.json")).unwrap()).unwrap();
    let search = folder.join(expected["search_path"].as_str().unwrap());
    let root = folder.join("root.usda");
    let inspect = |extra: &[&str], env: Option<&std::path::Path>| -> serde_json::Value {
        let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_lightcuts"));
        command.args([&["inspect", s(&root), "--json"][..], extra].concat());
        command.env_remove("PXR_AR_DEFAULT_SEARCH_PATH");
        if let Some(path) = env {
            command.env("PXR_AR_DEFAULT_SEARCH_PATH", path);
        }
        let out = command.output().unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let canonical = |p: &str| std::fs::canonicalize(p).unwrap_or_else(|_| std::path::PathBuf::from(p));
    let inputs = |report: &serde_json::Value| -> Vec<std::path::PathBuf> {
        report["inputs"].as_array().unwrap().iter().map(|p| canonical(p.as_str().unwrap())).collect()
    };
    for report in [inspect(&["--asset-path", s(&search)], None), inspect(&[], Some(&search))] {
        let read = inputs(&report);
        for (name, resolved) in expected["resolved"].as_object().unwrap() {
            match resolved.as_str() {
                Some(path) => {
                    let file = canonical(s(&folder.join(path)));
                    assert!(read.contains(&file), "{name}: usd-core resolves {path}; read: {read:?}");
                }
                None => {
                    let incomplete = report["incomplete"].to_string();
                    assert!(incomplete.contains("missing.png") && incomplete.contains("fallback"), "{incomplete}");
                }
            }
        }
        assert!(read.contains(&canonical(s(&folder.join("layers/asset.usda")))), "{read:?}");
        assert_eq!(report["incomplete"].as_array().unwrap().len(), 1, "only missing.png: {report}");
    }
    // Without the search path, maps/search.png is not found either.
    let report = inspect(&[], None);
    let incomplete = report["incomplete"].to_string();
    assert!(incomplete.contains("maps/search.png"), "{incomplete}");
    // --strict refuses the stage, naming what is missing.
    let dir = TempDir::new("usd-resolution");
    let out = dir.path("out.exr");
    let stderr = lightcuts_fails(&["render", s(&root), "-o", s(&out), "--asset-path", s(&search), "--strict"]);
    assert!(stderr.contains("--strict") && stderr.contains("missing.png"), "{stderr}");
    assert!(!out.exists());
    // Drawn: the missing texture's fallback (0.9, 0.6, 0.1) and the painted
    // quad's displayColor (0.8, 0.1, 0.7), as hues (a dielectric's grey
    // specular adds a little to each channel).
    let image = render(&root, &out, &["--asset-path", s(&search), "--exact", "--resolution", "96x64"]);
    let rgb = |x: usize, y: usize| ["R", "G", "B"].map(|c| f64::from(channel(&image, c)[y * 96 + x]));
    let [r, g, b] = rgb(78, 42);
    assert!((r / g - 1.5).abs() < 0.05 && (b / g) < 0.25, "the fallback: {r} {g} {b}");
    let [r, g, b] = rgb(48, 22);
    assert!(r / g > 6.0 && b / g > 5.0 && r > b, "the display colour: {r} {g} {b}");
}

/// What a stage lacks is drawn around, as usdview does, with one warning
/// line per kind naming the file and the prim: a missing reference, a
/// reference cycle, a reference to MaterialX, a dome texture that is not
/// there, a UsdUVTexture naming no file, prim types this renderer does not
/// draw (listed by `inspect`); `--strict` makes the first an error.
#[test]
fn incomplete_stages_render_with_a_warning_and_strict_refuses_them() {
    let dir = TempDir::new("usd-incomplete");
    let header = "#usda 1.0\n(\n    metersPerUnit = 1\n)\n";
    dir.write("a.usda", &format!("{header}def Xform \"A\" (\n    references = @./b.usda@</B>\n)\n{{\n}}\n"));
    dir.write("b.usda", &format!("{header}def Xform \"B\" (\n    references = @./a.usda@</A>\n)\n{{\n}}\n"));
    dir.write("looks.mtlx", "<?xml version=\"1.0\"?>\n<materialx version=\"1.38\"/>\n");
    let ball = "def Sphere \"Ball\"\n{\n}\n";
    let cases: Vec<(&str, String, &[&str])> = vec![
        (
            "reference.usda",
            format!("{header}{ball}def Xform \"X\" (\n    references = @./missing.usda@\n)\n{{\n}}\n"),
            &["missing.usda", "cannot be found", "/X"],
        ),
        (
            "cycle.usda",
            format!("{header}{ball}def Xform \"C\" (\n    references = @./a.usda@</A>\n)\n{{\n}}\n"),
            &["cycle"],
        ),
        (
            "mtlx.usda",
            format!("{header}{ball}def Xform \"M\" (\n    references = @./looks.mtlx@\n)\n{{\n}}\n"),
            &["looks.mtlx", "(.mtlx)"],
        ),
        (
            "dome.usda",
            format!("{header}{ball}def DomeLight \"D\"\n{{\n    asset inputs:texture:file = @./missing.exr@\n}}\n"),
            &["/D.inputs:texture:file", "missing.exr", "constant radiance"],
        ),
        (
            "types.usda",
            format!(
                "{header}{ball}def NurbsCurves \"Hair\"\n{{\n}}\ndef NurbsCurves \"Fur\"\n{{\n}}\n\
                 def NurbsPatch \"Dust\"\n{{\n}}\ndef Volume \"Smoke\"\n{{\n}}\n"
            ),
            &["/Hair and 1 more: NurbsCurves not drawn", "/Dust: NurbsPatch not drawn", "/Smoke: Volume not drawn"],
        ),
    ];
    for (name, text, expect) in cases {
        let stage = dir.write(name, &text);
        let out = dir.path("out.exr");
        let run = lightcuts(&["render", s(&stage), "-o", s(&out), "--resolution", "16x12", "--environment", "1,1,1"]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(run.status.success(), "{name}: {stderr}");
        for e in expect {
            let line = stderr.lines().find(|l| l.starts_with("warning") && l.contains(e));
            assert!(line.is_some_and(|l| l.contains(name)), "{name}: no warning with '{e}': {stderr}");
        }
        if expect.is_empty() {
            continue;
        }
        let report: serde_json::Value = serde_json::from_str(&lightcuts_ok(&["inspect", s(&stage), "--json"])).unwrap();
        // One line per kind: each expected text on a line, and no other line.
        let lines = report["incomplete"].as_array().unwrap();
        let matched: std::collections::BTreeSet<usize> = expect
            .iter()
            .map(|e| lines.iter().position(|l| l.as_str().unwrap().contains(e)).expect("listed by inspect"))
            .collect();
        assert_eq!(lines.len(), matched.len(), "{name}: {report}");
        std::fs::remove_file(&out).unwrap();
        let stderr = lightcuts_fails(&["render", s(&stage), "-o", s(&out), "--strict"]);
        assert!(stderr.contains("--strict") && stderr.contains(expect[0]), "{name}: {stderr}");
        assert!(!out.exists());
    }
    // A UsdUVTexture naming no file draws the input's own value.
    let stage = dir.write(
        "empty-file.usda",
        &format!(
            "{header}def Sphere \"Ball\"\n{{\n    rel material:binding = </M>\n}}\n\
             def Material \"M\"\n{{\n    token outputs:surface.connect = </M/S.outputs:surface>\n    \
             def Shader \"S\"\n    {{\n        uniform token info:id = \"UsdPreviewSurface\"\n        \
             color3f inputs:diffuseColor = (0.2, 0.3, 0.4)\n        \
             color3f inputs:diffuseColor.connect = </M/T.outputs:rgb>\n        token outputs:surface\n    }}\n    \
             def Shader \"T\"\n    {{\n        uniform token info:id = \"UsdUVTexture\"\n        float3 outputs:rgb\n    }}\n}}\n"
        ),
    );
    let report: serde_json::Value = serde_json::from_str(&lightcuts_ok(&["inspect", s(&stage), "--json"])).unwrap();
    let incomplete = report["incomplete"].to_string();
    assert!(incomplete.contains("/M/T.inputs:file: names no file") && incomplete.contains("own value"), "{report}");
    // A stage of NURBS curves only has nothing to frame: the error says why.
    let curves = dir.write("curves.usda", &format!("{header}def NurbsCurves \"Hair\"\n{{\n}}\n"));
    let stderr = lightcuts_fails(&["render", s(&curves), "-o", s(&dir.path("out.exr"))]);
    assert!(stderr.contains("nothing to frame") || stderr.contains("no geometry to frame"), "{stderr}");
    assert!(stderr.contains("left out: /Hair: NurbsCurves not drawn"), "{stderr}");
}

/// Subdivision surfaces against known answers (docs/design.md §4.2): the
/// Catmull-Clark limit surface of the cube [-1, 1]^3 reaches 68/81 at its
/// face centres (Halstead et al.'s limit mask, (16 v + 4 sum e + sum d) / 36,
/// on the once-refined cube: v = 1, edge points 3/4, corners 5/9); the cage
/// reaches 1, and so does the cube with every edge infinitely sharp; a Loop
/// octahedron's vertex goes to 1 - 4 chi (Loop's limit mask, valence 4).
/// A crease whose counts disagree is an error naming the attribute.
#[test]
fn subdivision_meshes_draw_their_limit_surface() {
    let dir = TempDir::new("usd-subdivision");
    let mesh = |extra: &str, points: &str, counts: &str, indices: &str| {
        format!(
            "#usda 1.0\n(\n    metersPerUnit = 1\n)\ndef Mesh \"Shape\"\n{{\n    point3f[] points = [{points}]\n    \
             int[] faceVertexCounts = [{counts}]\n    int[] faceVertexIndices = [{indices}]\n{extra}}}\n"
        )
    };
    let cube = |extra: &str| {
        mesh(
            extra,
            "(-1,-1,-1),(1,-1,-1),(-1,1,-1),(1,1,-1),(-1,-1,1),(1,-1,1),(-1,1,1),(1,1,1)",
            "4,4,4,4,4,4",
            "0,2,3,1, 4,5,7,6, 0,1,5,4, 2,6,7,3, 0,4,6,2, 1,3,7,5",
        )
    };
    let creases = "    int[] creaseIndices = [0,1, 2,3, 4,5, 6,7, 0,2, 1,3, 4,6, 5,7, 0,4, 1,5, 2,6, 3,7]\n    \
                   int[] creaseLengths = [2,2,2,2,2,2,2,2,2,2,2,2]\n    float[] creaseSharpnesses = [10]\n";
    let beta = (0.625 - 0.375f64.powi(2)) / 4.0;
    let chi = 1.0 / (3.0 / (8.0 * beta) + 4.0);
    let octahedron = mesh(
        "    uniform token subdivisionScheme = \"loop\"\n",
        "(1,0,0),(-1,0,0),(0,1,0),(0,-1,0),(0,0,1),(0,0,-1)",
        "3,3,3,3,3,3,3,3",
        "0,2,4, 2,1,4, 1,3,4, 3,0,4, 2,0,5, 1,2,5, 3,1,5, 0,3,5",
    );
    let cases = [
        ("smooth.usda", cube(""), 68.0 / 81.0, 6 * 256 * 2),
        ("cage.usda", cube("    uniform token subdivisionScheme = \"none\"\n"), 1.0, 12),
        // One sharpness for every crease (one value per crease, not per edge).
        ("sharp.usda", cube(&creases.replace("[10]", "[10,10,10,10,10,10,10,10,10,10,10,10]")), 1.0, 3072),
        ("loop.usda", octahedron, 1.0 - 4.0 * chi, 8 * 256),
    ];
    for (name, text, reach, triangles) in cases {
        let stage = dir.write(name, &text);
        let report: serde_json::Value = serde_json::from_str(&lightcuts_ok(&["inspect", s(&stage), "--json"])).unwrap();
        let object = &report["objects"][0];
        let max = object["max"][0].as_f64().unwrap();
        assert!((max - reach).abs() < 1e-6, "{name}: reaches {max}, the limit surface {reach}");
        assert_eq!(object["triangles"].as_u64().unwrap(), triangles, "{name}: {object}");
    }
    let stage = dir.write("bad.usda", &cube(&creases.replace("[2,2,2,2,2,2,2,2,2,2,2,2]", "[2,2,3]")));
    let stderr = lightcuts_fails(&["render", s(&stage), "-o", s(&dir.path("bad.exr"))]);
    assert!(stderr.contains("bad.usda") && stderr.contains("/Shape.creaseLengths"), "{stderr}");
    assert!(!dir.path("bad.exr").exists());
}

/// Curves and points against the closed form of their silhouettes: seen
/// through a pinhole f pixels from the image plane, a sphere of radius r
/// whose centre is d away covers a disc of radius f r / sqrt(d^2 - r^2)
/// pixels, and a tube (or a ray-facing ribbon) of radius r whose axis
/// passes d from the eye, parallel to the image, a band of that half-width.
/// (A primvar without interpolation metadata is constant, `widths` per
/// vertex.)
#[test]
fn curves_and_points_cover_what_their_widths_say() {
    let dir = TempDir::new("usd-strands");
    // focal length / aperture x 200 pixels = 500 pixels.
    let (f, d) = (500.0f64, 10.0f64);
    let stage = |body: &str| {
        format!(
            "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\ndef Camera \"Cam\"\n{{\n    float focalLength = 50\n    \
             float horizontalAperture = 20\n    float verticalAperture = 20\n    double3 xformOp:translate = (0, 0, {d})\n    \
             uniform token[] xformOpOrder = [\"xformOp:translate\"]\n}}\n{body}"
        )
    };
    let band = |r: f64| 2.0 * f * r / (d * d - r * r).sqrt() * 200.0;
    let disc = |r: f64| std::f64::consts::PI * (f * r / (d * d - r * r).sqrt()).powi(2);
    let line = "(-50,0,0),(-25,0,0),(0,0,0),(25,0,0),(50,0,0)";
    let cases = [
        ("points", "def Points \"P\"\n{\n    point3f[] points = [(0,0,0)]\n    float[] widths = [2]\n}\n".to_string(), disc(1.0)),
        (
            "linear",
            format!(
                "def BasisCurves \"C\"\n{{\n    uniform token type = \"linear\"\n    int[] curveVertexCounts = [5]\n    \
                 point3f[] points = [{line}]\n    float[] widths = [0.6] (interpolation = \"constant\")\n    \
                 color3f[] primvars:displayColor = [(0.5, 0.4, 0.3)]\n}}\n"
            ),
            band(0.3),
        ),
        (
            "bspline-pinned",
            format!(
                "def BasisCurves \"C\"\n{{\n    uniform token basis = \"bspline\"\n    uniform token wrap = \"pinned\"\n    \
                 int[] curveVertexCounts = [5]\n    point3f[] points = [{line}]\n    \
                 float[] widths = [0.4, 0.4, 0.4, 0.4, 0.4] (interpolation = \"varying\")\n}}\n"
            ),
            band(0.2),
        ),
        (
            "bezier-ribbon",
            "def BasisCurves \"C\"\n{\n    int[] curveVertexCounts = [4]\n    \
             point3f[] points = [(-50,0,0),(-20,0,0),(20,0,0),(50,0,0)]\n    normal3f[] normals = [(0,0,1),(0,0,1),(0,0,1),(0,0,1)]\n    \
             float[] widths = [0.5, 0.5, 0.5, 0.5]\n}\n"
                .to_string(),
            band(0.25),
        ),
    ];
    for (name, body, expected) in cases {
        let path = dir.write(&format!("{name}.usda"), &stage(&body));
        let flags = ["--resolution", "200x200", "--spp", "16", "--transparent", "--environment", "1,1,1"];
        let image = render(&path, &dir.path(&format!("{name}.exr")), &flags);
        let covered: f64 = channel(&image, "A").iter().map(|&a| f64::from(a)).sum();
        assert!(
            (covered / expected - 1.0).abs() < 0.01,
            "{name}: {covered} pixels covered, the closed form {expected}"
        );
    }
    // A count that makes no whole segment is an error naming the attribute.
    let bad = dir.write(
        "bad.usda",
        &stage("def BasisCurves \"C\"\n{\n    int[] curveVertexCounts = [5]\n    point3f[] points = [(0,0,0),(1,0,0),(2,0,0),(3,0,0),(4,0,0)]\n}\n"),
    );
    let stderr = lightcuts_fails(&["render", s(&bad), "-o", s(&dir.path("bad.exr"))]);
    assert!(stderr.contains("bad.usda") && stderr.contains("/C.curveVertexCounts"), "{stderr}");
    assert!(!dir.path("bad.exr").exists());
}

/// A round curve is a fibre (docs/design.md §5.7): lit only by lights
/// behind it (a 4 x 4 grid of them, the camera's view passing between),
/// its near side shows the light that crossed it (the TT lobe), where a
/// ray-facing ribbon of the same material, a surface, is black; its own
/// far side does not shadow it. The cuts stay within their error of the
/// exact render.
#[test]
fn a_tube_is_a_fibre_lit_through_from_behind() {
    let dir = TempDir::new("usd-fibre");
    let lights: String = (0..16)
        .map(|k| {
            let (x, y) = (-1.5 + (k % 4) as f64, -1.5 + (k / 4) as f64);
            format!(
                "def SphereLight \"L{k}\"\n{{\n    float inputs:intensity = 30\n    float inputs:radius = 0.05\n    \
                 double3 xformOp:translate = ({x}, {y}, -4)\n    uniform token[] xformOpOrder = [\"xformOp:translate\"]\n}}\n"
            )
        })
        .collect();
    let stage = |normals: &str| {
        format!(
            "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\ndef Camera \"Cam\"\n{{\n    float focalLength = 50\n    \
             float horizontalAperture = 20\n    float verticalAperture = 20\n    double3 xformOp:translate = (0, 0, 10)\n    \
             uniform token[] xformOpOrder = [\"xformOp:translate\"]\n}}\ndef BasisCurves \"Hair\"\n{{\n    \
             uniform token type = \"linear\"\n    int[] curveVertexCounts = [2]\n    point3f[] points = [(-3,0,0),(3,0,0)]\n    \
             float[] widths = [0.8] (interpolation = \"constant\")\n{normals}    \
             color3f[] primvars:displayColor = [(0.9, 0.8, 0.6)]\n}}\n{lights}"
        )
    };
    let tube = dir.write("tube.usda", &stage(""));
    let ribbon = dir.write("ribbon.usda", &stage("    normal3f[] normals = [(0,0,1),(0,0,1)]\n"));
    let flags = ["--resolution", "64x64", "--spp", "4"];
    // The middle row of the image crosses the curve's axis.
    let middle = |image: &common::ExrImage| -> f64 {
        let r = channel(image, "G");
        (16..48).map(|x| f64::from(r[32 * 64 + x])).sum::<f64>() / 32.0
    };
    let exact = render(&tube, &dir.path("exact.exr"), &[&flags[..], &["--exact"]].concat());
    let lit = middle(&exact);
    assert!(lit > 0.01, "the fibre lit from behind is black: {lit}");
    let surface = middle(&render(&ribbon, &dir.path("ribbon.exr"), &[&flags[..], &["--exact"]].concat()));
    assert!(surface < 1e-3 * lit, "a ribbon, a surface, shows light from behind it: {surface} against {lit}");
    for mode in ["--bounded", "--stochastic"] {
        let out = dir.path(&format!("{}.exr", &mode[2..]));
        let image = render(&tube, &out, &[&flags[..], &[mode]].concat());
        let value = middle(&image);
        assert!((value / lit - 1.0).abs() < 0.03, "{mode}: {value} against the exact {lit}");
    }
}

/// A `<UDIM>` texture reads tile 1001 + u + 10 v where the texture
/// coordinates fall in [u, u + 1) x [v, v + 1), and black where the tile
/// is absent, its tiles found beside the layer that names the pattern.
#[test]
fn udim_tiles_are_read_where_their_coordinates_fall() {
    let dir = TempDir::new("usd-udim");
    std::fs::create_dir(dir.path("tex")).unwrap();
    // Tile 1011 is smaller: resampled to the first tile's size.
    for (tile, rgb, size) in [(1001, [255u8, 0, 0], 4), (1002, [0, 255, 0], 4), (1011, [0, 0, 255], 2)] {
        let file = std::fs::File::create(dir.path(&format!("tex/c.{tile}.png"))).unwrap();
        let mut encoder = png::Encoder::new(file, size, size);
        encoder.set_color(png::ColorType::Rgb);
        let texels: Vec<u8> = (0..size * size).flat_map(|_| rgb).collect();
        encoder.write_header().unwrap().write_image_data(&texels).unwrap();
    }
    let stage = dir.write(
        "udim.usda",
        r#"#usda 1.0
(
    metersPerUnit = 1
    upAxis = "Y"
)
def Mesh "Quad"
{
    int[] faceVertexCounts = [4]
    int[] faceVertexIndices = [0, 1, 2, 3]
    point3f[] points = [(-1, -1, -5), (1, -1, -5), (1, 1, -5), (-1, 1, -5)]
    texCoord2f[] primvars:st = [(0, 0), (2, 0), (2, 2), (0, 2)] (interpolation = "vertex")
    uniform token subdivisionScheme = "none"
    rel material:binding = </Glow>
}
def Material "Glow"
{
    token outputs:surface.connect = </Glow/Surface.outputs:surface>
    def Shader "Surface"
    {
        uniform token info:id = "UsdPreviewSurface"
        color3f inputs:diffuseColor = (0, 0, 0)
        color3f inputs:emissiveColor.connect = </Glow/Texture.outputs:rgb>
        token outputs:surface
    }
    def Shader "Texture"
    {
        uniform token info:id = "UsdUVTexture"
        asset inputs:file = @tex/c.<UDIM>.png@
        token inputs:sourceColorSpace = "raw"
        token inputs:wrapS = "clamp"
        token inputs:wrapT = "clamp"
        float3 outputs:rgb
    }
}
def Camera "Camera"
{
    float focalLength = 50
    float horizontalAperture = 20
    float verticalAperture = 20
}
"#,
    );
    let image = render(&stage, &dir.path("out.exr"), &["--resolution", "16x16", "--exact", "--aovs", "none"]);
    let [r, g, b] = ["R", "G", "B"].map(|c| channel(&image, c));
    // Row 0 of the film is the top: v in [1, 2) there.
    let expected = |x: usize, y: usize| match (x < 8, y >= 8) {
        (true, true) => [1.0, 0.0, 0.0],
        (false, true) => [0.0, 1.0, 0.0],
        (true, false) => [0.0, 0.0, 1.0],
        (false, false) => [0.0, 0.0, 0.0],
    };
    for (y, x) in (0..16).flat_map(|y| (0..16).map(move |x| (y, x))) {
        // Pixels beside a tile's edge blend two tiles.
        if [y, x].iter().any(|&v| matches!(v, 7 | 8)) {
            continue;
        }
        let p = y * 16 + x;
        let got = [r[p], g[p], b[p]];
        let want = expected(x, y);
        assert!((0..3).all(|k| (got[k] - want[k]).abs() < 1e-3), "pixel ({x}, {y}): {got:?}, want {want:?}");
    }
    // No tile at all: the texture is missing, a warning, and the input's own value.
    let none = dir.write("none.usda", &std::fs::read_to_string(&stage).unwrap().replace("tex/c.", "tex/d."));
    let run = lightcuts(&["render", s(&none), "-o", s(&dir.path("none.exr")), "--resolution", "8x8"]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success() && stderr.contains("no UDIM tile of 'tex/d.<UDIM>.png'"), "{stderr}");
}

/// A primvar reader of any type but float2 feeds diffuseColor as vertex
/// colours: a float or int as grey, a float4's RGB, the reader's fallback
/// (a float's as grey) where the prim lacks the primvar.
#[test]
fn primvar_readers_of_every_type_feed_the_base_colour() {
    let dir = TempDir::new("usd-readers");
    let stage = |kind: &str, primvar: &str, fallback: &str| {
        format!(
            r#"#usda 1.0
(
    metersPerUnit = 1
    upAxis = "Y"
)
def Mesh "Quad"
{{
    int[] faceVertexCounts = [4]
    int[] faceVertexIndices = [0, 1, 2, 3]
    point3f[] points = [(-1, -1, -5), (1, -1, -5), (1, 1, -5), (-1, 1, -5)]
    uniform token subdivisionScheme = "none"
    {primvar}
    rel material:binding = </M>
}}
def Material "M"
{{
    token outputs:surface.connect = </M/Surface.outputs:surface>
    def Shader "Surface"
    {{
        uniform token info:id = "UsdPreviewSurface"
        color3f inputs:diffuseColor.connect = </M/Reader.outputs:result>
        token outputs:surface
    }}
    def Shader "Reader"
    {{
        uniform token info:id = "UsdPrimvarReader_{kind}"
        string inputs:varname = "tint"
        {fallback}
    }}
}}
def Camera "Camera"
{{
    float focalLength = 50
    float horizontalAperture = 20
    float verticalAperture = 20
}}
"#
        )
    };
    let albedo = |name: &str, text: String| -> [f32; 3] {
        let path = dir.write(&format!("{name}.usda"), &text);
        let flags = ["--resolution", "4x4", "--exact", "--environment", "1,1,1", "--aovs", "albedo"];
        let image = render(&path, &dir.path(&format!("{name}.exr")), &flags);
        ["albedo.R", "albedo.G", "albedo.B"].map(|c| channel(&image, c)[5])
    };
    let float3 = albedo("float3", stage("float3", "color3f[] primvars:tint = [(0.5, 0.5, 0.5)]", ""));
    assert!(float3[0] > 0.1, "{float3:?}");
    let float = albedo("float", stage("float", "float[] primvars:tint = [0.5]", ""));
    assert_eq!(float, float3, "a float reads as grey");
    let int = albedo("int", stage("int", "int[] primvars:tint = [1]", ""));
    assert!(int.iter().zip(&float3).all(|(a, b)| (a / b - 2.0).abs() < 1e-4), "an int reads as grey: {int:?}");
    let float4 = albedo("float4", stage("float4", "float4[] primvars:tint = [(0.2, 0.4, 0.6, 1)]", ""));
    let ratio = [float4[0] / float4[1], float4[2] / float4[1]];
    assert!((ratio[0] - 0.5).abs() < 1e-4 && (ratio[2 - 1] - 1.5).abs() < 1e-4, "a float4's RGB: {float4:?}");
    let lacking = albedo("lacking", stage("float", "", "float inputs:fallback = 0.25\n        float outputs:result"));
    assert!(lacking.iter().zip(&float3).all(|(a, b)| (a / b - 0.5).abs() < 1e-4), "the fallback as grey: {lacking:?}");
}

/// The USD Working Group's own test assets (scenes/usdwg/, Apache-2.0),
/// as a user brings them: each renders with `--strict` (every layer,
/// reference and texture read: TGA inside a `.usdz`; JPEG in RGB, grey and
/// CMYK; PNG in 8 and 16 bits), its cube drawn as its limit surface. The
/// texture formats' stages show one gradient each in several encodings:
/// the same picture, so the frames' means agree across formats within 1%
/// (a 16-bit value read with its bytes swapped, or an 8-bit image read as
/// another encoding, is off by far more), and differ from the grey ones'.
#[test]
fn the_usd_working_group_s_assets_render_in_every_texture_format_they_carry() {
    let dir = TempDir::new("usd-wg");
    let folder = scenes().join("usdwg");
    let light = ["--environment", "0.6,0.6,0.6", "--sun", "30,45", "--strict", "--aovs", "none"];
    for stage in ["RoughnessTest/RoughnessTest.usdz", "SubdivisionSurfaces/Creases_SpinningPyramids.usda"] {
        let image =
            render(&folder.join(stage), &dir.path("out.exr"), &[&light[..], &["--resolution", "32x24"]].concat());
        assert!(means(&image).iter().all(|&m| m > 0.05), "{stage}: {:?}", means(&image));
    }
    let cube = folder.join("subdiv_catmullClark/subdiv_catmullClark.usda");
    let report: serde_json::Value = serde_json::from_str(&lightcuts_ok(&["inspect", s(&cube), "--json"])).unwrap();
    let triangles = report["objects"][0]["triangles"].as_u64().unwrap();
    assert!(triangles > 12 * 16, "the cube is drawn as its cage: {triangles} triangles");
    let mean = |name: &str| -> [f64; 3] {
        let stage = folder.join(format!("TextureFileFormatTests/{name}.usda"));
        means(&render(&stage, &dir.path(&format!("{name}.exr")), &[&light[..], &["--resolution", "64x64"]].concat()))
    };
    let close = |a: [f64; 3], b: [f64; 3]| (0..3).all(|k| (a[k] - b[k]).abs() <= 0.01 * b[k]);
    let colour = mean("png_rgb_8-bit");
    let grey = mean("png_grayscale_8-bit");
    for (name, like) in [
        ("png_rgb_16-bit", colour),
        ("jpeg_rgb_8-bit", colour),
        ("png_grayscale_16-bit", grey),
        ("jpeg_grayscale_8-bit", grey),
    ] {
        let got = mean(name);
        assert!(close(got, like), "{name}: mean {got:?}, the 8-bit PNG's {like:?}");
    }
    assert!(!close(colour, grey), "the gradient and the grey ramp render alike: {colour:?} {grey:?}");
    // The whole set, through its references, in one stage.
    lightcuts_ok(
        &[
            &["render", s(&folder.join("TextureFileFormatTests/all_files.usda")), "-o", s(&dir.path("all.exr")), "-q"]
                [..],
            &light[..],
            &["--resolution", "32x24"],
        ]
        .concat(),
    );
}

/// Primvar readers into inputs other than diffuseColor (roughness,
/// metallic, emissiveColor): each gprim reads its own constant value of
/// the primvar, its own or inherited from an ancestor (UsdGeomPrimvarsAPI),
/// so the stage renders bit for bit as one with those values written into
/// a material per gprim. A gprim without the primvar reads the reader's
/// fallback, with a note naming the gprim and the primvar that `--strict`
/// makes an error.
#[test]
fn primvar_readers_give_each_gprim_its_constant_values_in_any_input() {
    let dir = TempDir::new("usd-primvar-inputs");
    let reader = |name: &str, kind: &str, varname: &str, fallback: &str, output: &str| {
        format!(
            "    def Shader \"{name}\"\n    {{\n        uniform token info:id = \"UsdPrimvarReader_{kind}\"\n        \
             string inputs:varname = \"{varname}\"\n        {fallback}\n        {output} outputs:result\n    }}\n"
        )
    };
    let surface = |inputs: &str| {
        format!(
            "    token outputs:surface.connect = <Surface.outputs:surface>\n    def Shader \"Surface\"\n    {{\n        \
             uniform token info:id = \"UsdPreviewSurface\"\n        color3f inputs:diffuseColor = (0.5, 0.5, 0.5)\n{inputs}        \
             token outputs:surface\n    }}\n"
        )
    };
    let stage = |left: &str, right: &str, materials: &str| {
        format!(
            "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\n{left}\n{right}\n{materials}\n\
             def Camera \"Camera\"\n{{\n    float focalLength = 35\n    double3 xformOp:translate = (0, 0, 8)\n    \
             uniform token[] xformOpOrder = [\"xformOp:translate\"]\n}}\n"
        )
    };
    let ball = |name: &str, x: f64, extra: &str, material: &str| {
        format!(
            "def Sphere \"{name}\"\n{{\n    double radius = 1\n    double3 xformOp:translate = ({x}, 0, 0)\n    \
             uniform token[] xformOpOrder = [\"xformOp:translate\"]\n{extra}    rel material:binding = <{material}>\n}}\n"
        )
    };
    let connected = surface(
        "        float inputs:roughness.connect = </M/Rough.outputs:result>\n        \
         float inputs:metallic.connect = </M/Metal.outputs:result>\n        \
         color3f inputs:emissiveColor.connect = </M/Glow.outputs:result>\n",
    );
    let read = stage(
        &format!(
            "def Xform \"Left\" \n{{\n    float primvars:metal = 1 (\n        interpolation = \"constant\"\n    )\n{}}}",
            ball(
                "Ball",
                -1.5,
                "    float[] primvars:rough = [0.2] (\n        interpolation = \"constant\"\n    )\n    \
                 color3f[] primvars:glow = [(0.5, 0.25, 0.125)]\n",
                "/M"
            )
        ),
        &ball("Right", 1.5, "    float primvars:rough = 0.6\n    color3f[] primvars:glow = [(0, 0, 0)]\n", "/M"),
        &format!(
            "def Material \"M\"\n{{\n{connected}{}{}{}}}",
            reader("Rough", "float", "rough", "float inputs:fallback = 0.9", "float"),
            reader("Metal", "float", "metal", "float inputs:fallback = 0", "float"),
            reader("Glow", "float3", "glow", "float3 inputs:fallback = (0, 0, 0)", "float3"),
        ),
    );
    let direct = stage(
        &format!("def Xform \"Left\"\n{{\n{}}}", ball("Ball", -1.5, "", "/A")),
        &ball("Right", 1.5, "", "/B"),
        &format!(
            "def Material \"A\"\n{{\n{}}}\ndef Material \"B\"\n{{\n{}}}",
            surface(
                "        float inputs:roughness = 0.2\n        float inputs:metallic = 1\n        \
                 color3f inputs:emissiveColor = (0.5, 0.25, 0.125)\n"
            ),
            surface("        float inputs:roughness = 0.6\n        float inputs:metallic = 0\n"),
        ),
    );
    let flags =
        ["--resolution", "48x32", "--exact", "--environment", "0.5,0.5,0.5", "--sun", "30,45", "--aovs", "none"];
    let run = |name: &str, text: &str| {
        let path = dir.write(&format!("{name}.usda"), text);
        let out =
            lightcuts(&[&["render", s(&path), "-o", s(&dir.path(&format!("{name}.exr"))), "-q"][..], &flags].concat());
        assert!(out.status.success(), "{name}: {}", String::from_utf8_lossy(&out.stderr));
        (path, String::from_utf8_lossy(&out.stderr).into_owned())
    };
    let (read_path, stderr) = run("read", &read);
    let (_, direct_stderr) = run("direct", &direct);
    let a = common::read_exr(&dir.path("read.exr")).unwrap();
    let b = common::read_exr(&dir.path("direct.exr")).unwrap();
    for c in ["R", "G", "B"] {
        assert!(channel(&a, c) == channel(&b, c), "channel {c} differs from the materials written out");
    }
    assert!(channel(&a, "R").iter().any(|&v| v > 0.0), "a black frame proves nothing");
    // Right has no 'metal': the reader's fallback (0), noted.
    assert!(stderr.contains("/Right") && stderr.contains("'metal'"), "{stderr}");
    assert!(!stderr.contains("'rough'") && !stderr.contains("'glow'"), "{stderr}");
    assert!(!direct_stderr.contains("primvar"), "{direct_stderr}");
    let strict = lightcuts_fails(
        &[&["render", s(&read_path), "-o", s(&dir.path("strict.exr")), "--strict"][..], &flags].concat(),
    );
    assert!(strict.contains("'metal'"), "{strict}");
    assert!(!dir.path("strict.exr").exists());
    // Two gprims without 'metal': one line naming the first and the count.
    let (_, both) =
        run("both", &read.replace("    float primvars:metal = 1 (\n        interpolation = \"constant\"\n    )\n", ""));
    assert_eq!(both.matches("'metal'").count(), 1, "{both}");
    assert!(both.contains("/Left/Ball and 1 more"), "{both}");
    // A primvar no reader reads (a 2-vector), or one varying over the
    // surface: the fallback, noted; not an error.
    for (name, rough) in [
        ("vec2", "texCoord2f[] primvars:rough = [(0.2, 0.2)]"),
        ("varying", "float[] primvars:rough = [0.2, 0.4] (\n        interpolation = \"vertex\"\n    )"),
    ] {
        let (_, stderr) = run(name, &read.replace("float primvars:rough = 0.6", rough));
        assert!(stderr.contains("/Right") && stderr.contains("'rough'"), "{name}: {stderr}");
    }
}

/// UsdPreviewSurface's `clearcoat` is a white coat of IOR 1.5 over the
/// base (docs/design.md §5.10), smooth at the schema's clearcoatRoughness
/// of 0.01: a quad seen straight on under a uniform dome of radiance L
/// shows the coat's Fresnel weight F_c = 0.04 of the dome plus 0.96 of the
/// base it covers, L being what a white mirror shows.
#[test]
fn a_clearcoat_reflects_its_fresnel_weight_and_covers_the_rest() {
    let dir = TempDir::new("usd-clearcoat");
    let stage = |name: &str, inputs: &str| {
        dir.write(
            name,
            &format!(
                "#usda 1.0\n(\n    upAxis = \"Y\"\n)\n\
                 def Mesh \"Quad\"\n{{\n    int[] faceVertexCounts = [4]\n    int[] faceVertexIndices = [0, 1, 2, 3]\n    \
                 point3f[] points = [(-1, -1, -5), (1, -1, -5), (1, 1, -5), (-1, 1, -5)]\n    \
                 uniform token subdivisionScheme = \"none\"\n    rel material:binding = </Look>\n}}\n\
                 def Material \"Look\"\n{{\n    token outputs:surface.connect = </Look/Surface.outputs:surface>\n    \
                 def Shader \"Surface\"\n    {{\n        uniform token info:id = \"UsdPreviewSurface\"\n        \
                 {inputs}\n        token outputs:surface\n    }}\n}}\n\
                 def DomeLight \"Sky\"\n{{\n}}\n\
                 def Camera \"Camera\"\n{{\n    float focalLength = 50\n    float horizontalAperture = 10\n    \
                 float verticalAperture = 10\n}}\n"
            ),
        )
    };
    let mean = |name: &str, inputs: &str| {
        let path = stage(&format!("{name}.usda"), inputs);
        means(&render(&path, &dir.path(&format!("{name}.exr")), &["--resolution", "8x8", "--spp", "16"]))[1]
    };
    let sky = mean(
        "mirror",
        "color3f inputs:diffuseColor = (1, 1, 1)\n float inputs:metallic = 1\n float inputs:roughness = 0",
    );
    let grey = "color3f inputs:diffuseColor = (0.5, 0.5, 0.5)\n float inputs:roughness = 0.7";
    let bare = mean("bare", grey);
    let coated = mean("coated", &format!("{grey}\n float inputs:clearcoat = 1"));
    let expected = 0.04 * sky + 0.96 * bare;
    eprintln!("dome {sky:.5}, bare {bare:.5}, coated {coated:.5}, expected {expected:.5}");
    assert!(sky > 0.0 && (coated - expected).abs() < 2e-3 * sky, "coated {coated} vs {expected}");
    assert!((coated - bare).abs() > 0.01 * sky, "the coat changes nothing: {coated} vs {bare}");
}
