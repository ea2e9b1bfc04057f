//! What a reader must survive, each case a file that once made the process
//! abort, eat the machine or hang (a 97,000-run fuzz of every reader found
//! them): the binary runs under 1 GiB of address space and 30 s, and must
//! end by itself, with exit 0 and a finite image where the input is
//! renderable, else exit 1 and one line naming the file and the field.
//! Also the outputs a render must not destroy, the messages that must name
//! the right file and limit, and the bounds of `--threads` and `--spp`.

mod common;
use common::*;

use serde_json::json;

/// A render of `args` within the limits: exit 0, no value non-finite; the
/// warnings it printed.
fn renders_within_limits(args: &[&str]) -> String {
    let run = lightcuts_limited(args, 1024, 60);
    assert!(!run.timed_out, "lightcuts {args:?} still ran after 60 s");
    assert_eq!(run.code, Some(0), "lightcuts {args:?} (exit {:?}): {}", run.code, run.stderr);
    assert_no_value_was_non_finite(&run.stdout);
    run.stderr
}

/// The floor of [`common::gltf::floor_and_point_light`] placed a second
/// time by `node` (its mesh 0).
fn floor_placed_again(node: serde_json::Value) -> common::gltf::GltfBuilder {
    let mut g = common::gltf::floor_and_point_light();
    let mut node = node;
    node["mesh"] = json!(0);
    g.node(node, true);
    g
}

/// Embree aborted the process (its `ray.valid()` assertion) on an
/// instance whose inverse carried rays beyond its bound: a node scaled by
/// [1e-20, 1, 1], or an EXT_mesh_gpu_instancing SCALE of 1e-30 or 1e-38.
/// Such an instance covers no pixel: it is left out with a warning naming
/// it, and the rest renders in every mode.
#[test]
fn an_instance_scaled_to_nothing_is_left_out_not_an_abort() {
    let dir = TempDir::new("squashed-instance");
    let squashed = floor_placed_again(json!({
        "scale": [1e-20, 1.0, 1.0], "translation": [0.3, 0.5, 0.2], "rotation": [0.0, 0.38, 0.0, 0.92] }));
    let scene = dir.write("squashed.gltf", &squashed.embedded());
    for mode in ["--exact", "--bounded", "--stochastic"] {
        let out = dir.path("squashed.exr");
        let warnings = renders_within_limits(&["render", s(&scene), "-o", s(&out), mode, "--resolution", "48x32"]);
        assert!(warnings.contains("instance(s) left out (nodes[3])"), "{warnings}");
    }
    for scale in [1e-30f32, 1e-38] {
        let mut g = common::gltf::floor_and_point_light();
        g.use_extension("EXT_mesh_gpu_instancing");
        let translations = g.floats(&[0.0, 0.5, 0.0, 1.0, 0.5, 0.0], "VEC3", 3);
        let scales = g.floats(&[1.0, 1.0, 1.0, scale, 1.0, 1.0], "VEC3", 3);
        g.node(
            json!({ "mesh": 0, "extensions": { "EXT_mesh_gpu_instancing": {
                "attributes": { "TRANSLATION": translations, "SCALE": scales } } } }),
            true,
        );
        let scene = dir.write("instanced.gltf", &g.embedded());
        let out = dir.path("instanced.exr");
        let warnings = renders_within_limits(&["render", s(&scene), "-o", s(&out), "--resolution", "48x32"]);
        assert!(warnings.contains("left out (nodes[3][1])"), "{scale}: {warnings}");
    }
}

/// `bytes` with the EXR header's `dataWindow` (xMin, yMin, xMax, yMax) set.
fn with_data_window(bytes: &[u8], window: [i32; 4]) -> Vec<u8> {
    let key = b"dataWindow\0box2i\0";
    let at = bytes.windows(key.len()).position(|w| w == key).expect("a dataWindow attribute") + key.len() + 4;
    let mut bytes = bytes.to_vec();
    for (k, v) in window.iter().enumerate() {
        bytes[at + 4 * k..at + 4 * k + 4].copy_from_slice(&v.to_le_bytes());
    }
    bytes
}

/// One byte of an EXR header (`dataWindow.xMin` above `xMax`) made the
/// `exr` crate allocate 103 GB, a `yMin` variant 3.1 GB over 14 s, in every
/// path that reads an EXR: `--environment`, a TOML `[environment]`,
/// `assemble` and `compare`. The header is checked against the file's
/// length first.
#[test]
fn an_exr_header_asking_for_more_than_its_file_holds_is_refused_before_any_pixel() {
    let dir = TempDir::new("exr-header");
    let good = std::fs::read(scenes().join("environment/courtyard.exr")).unwrap();
    // courtyard.exr is 256 x 128: its window is (0, 0) to (255, 127).
    for (name, window) in [("x.exr", [1 << 20, 0, 255, 127]), ("y.exr", [0, 1 << 20, 255, 127])] {
        let bad = dir.path(name);
        std::fs::write(&bad, with_data_window(&good, window)).unwrap();
        let scene = dir.write("scene.toml", &small_scene(2));
        let out = dir.path("out.exr");
        refused_within_limits(&["render", s(&scene), "-o", s(&out), "--environment", s(&bad)], &[name, "dataWindow"]);
        let toml = format!("{}\n[environment]\nfile = \"{name}\"\n", small_scene(2));
        let scene = dir.write("env.toml", &toml);
        refused_within_limits(&["render", s(&scene), "-o", s(&out)], &[name, "dataWindow"]);
        refused_within_limits(&["assemble", s(&out), s(&bad)], &[name, "dataWindow"]);
        refused_within_limits(&["compare", s(&bad), s(&bad)], &[name, "dataWindow"]);
        assert!(!out.exists());
    }
}

/// The CRC-32 of PNG chunks (ISO 3309), bit by bit.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
        }
    }
    !crc
}

/// A valid 2 x 1 RGB PNG whose IHDR then says `width` x `height` (its CRC
/// recomputed, so that only the size is wrong).
fn png_claiming(width: u32, height: u32) -> Vec<u8> {
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, 2, 1);
    encoder.set_color(png::ColorType::Rgb);
    encoder.write_header().unwrap().write_image_data(&[200, 100, 50, 50, 100, 200]).unwrap();
    // Signature (8), length (4), "IHDR" (4), then width and height.
    bytes[16..20].copy_from_slice(&width.to_be_bytes());
    bytes[20..24].copy_from_slice(&height.to_be_bytes());
    let crc = crc32(&bytes[12..29]);
    bytes[29..33].copy_from_slice(&crc.to_be_bytes());
    bytes
}

/// The committed 16 x 16 JPEG whose frame header (SOF0) then says
/// `width` x `height`.
fn jpeg_claiming(width: u16, height: u16) -> Vec<u8> {
    let mut bytes = std::fs::read(scenes().join("usd/fuzz/texture.jpg")).unwrap();
    let sof = bytes.windows(2).position(|w| w == [0xff, 0xc0]).expect("a baseline frame header");
    // Marker (2), length (2), precision (1), then height and width.
    bytes[sof + 5..sof + 7].copy_from_slice(&height.to_be_bytes());
    bytes[sof + 7..sof + 9].copy_from_slice(&width.to_be_bytes());
    bytes
}

/// Texture headers were trusted: a PNG whose IHDR says 100,000 x 100,000
/// allocated 30 GB; a JPEG frame of 65,535 x 65,535 allocated 8.6 GB inside
/// the decoder despite its buffer limit, 30,000 x 30,000 ran 39 s at
/// 5.4 GB. Each is refused from its header, the error naming the texture
/// (in a USD stage too, where it was blamed on the USD reader).
#[test]
fn texture_headers_are_checked_before_decoding() {
    let dir = TempDir::new("texture-headers");
    std::fs::write(dir.path("big.png"), png_claiming(100_000, 100_000)).unwrap();
    let toml = format!("{}\n[materials.wood]\ntexture = \"big.png\"\n", small_scene(2));
    let toml = toml.replacen("material = \"floor\"", "material = \"wood\"", 1);
    let scene = dir.write("png.toml", &toml);
    let out = dir.path("out.exr");
    refused_within_limits(&["render", s(&scene), "-o", s(&out)], &["big.png", "IHDR", "100000 x 100000"]);
    let stage = std::fs::read_to_string(scenes().join("usd/fuzz/stage.usda")).unwrap();
    for (name, bytes, field) in [
        ("wide.jpg", jpeg_claiming(65535, 65535), "SOF"),
        ("square.jpg", jpeg_claiming(30000, 30000), "SOF"),
        ("big.png", png_claiming(100_000, 100_000), "IHDR"),
    ] {
        std::fs::write(dir.path(name), bytes).unwrap();
        let scene = dir.write("stage.usda", &stage.replace("@texture.png@", &format!("@{name}@")));
        // A texture that cannot be read is a warning: --strict refuses it.
        refused_within_limits(
            &["render", s(&scene), "-o", s(&out), "--resolution", "16x12", "--strict"],
            &["stage.usda", "Texture.inputs:file", name, field],
        );
    }
    assert!(!out.exists());
}

/// A `.usdz` of 200 KB holding one deflated member of 200 MB (the fuzz
/// found 2.6 MB holding 2.5 GiB, inflated whole to 5.3 GB): a package's
/// members are stored uncompressed by the format's definition, and one
/// that is not is refused from the central directory, before it is read.
#[test]
fn a_usdz_with_a_compressed_member_is_refused_unread() {
    use std::io::Write;
    let dir = TempDir::new("usdz-bomb");
    let stage = std::fs::read(scenes().join("usd/fuzz/stage.usda")).unwrap();
    let stored = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
    let deflated = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    for (name, layer, texture) in [("texture.usdz", stored, deflated), ("layer.usdz", deflated, stored)] {
        let path = dir.path(name);
        let mut package = zip::ZipWriter::new(std::fs::File::create(&path).unwrap());
        package.start_file("stage.usda", layer).unwrap();
        package.write_all(&stage).unwrap();
        package.start_file("texture.png", texture).unwrap();
        let zeros = vec![0u8; 1 << 20];
        for _ in 0..if texture == deflated { 200 } else { 1 } {
            package.write_all(&zeros).unwrap();
        }
        package.finish().unwrap();
        let out = dir.path("out.exr");
        for command in [&["render", s(&path), "-o", s(&out)][..], &["inspect", s(&path)]] {
            refused_within_limits(command, &[name, "is compressed", "uncompressed"]);
        }
    }
}

/// glTF URIs read anything: `/dev/zero` read 4.2 GB before failing,
/// `/dev/urandom` never ended, and a FIFO named `x.gltf` (or one a buffer
/// names) blocked `render` and `inspect` forever. Only regular files are
/// read, and no more of a buffer's file than its `byteLength`.
#[test]
fn gltf_uris_read_only_regular_files_and_no_more_than_declared() {
    let dir = TempDir::new("gltf-uris");
    let fifo = |name: &str| {
        let path = dir.path(name);
        assert!(std::process::Command::new("mkfifo").arg(&path).status().unwrap().success());
        path
    };
    let out = dir.path("out.exr");
    let x = fifo("x.gltf");
    for command in [&["render", s(&x), "-o", s(&out)][..], &["inspect", s(&x)]] {
        refused_within_limits(command, &["x.gltf", "not a regular file"]);
    }
    fifo("pipe.bin");
    let good = common::gltf::floor_and_point_light();
    for uri in ["/dev/zero", "/dev/urandom", "pipe.bin"] {
        let mut g: serde_json::Value = serde_json::from_str(&good.embedded()).unwrap();
        g["buffers"][0]["uri"] = json!(uri);
        let scene = dir.write("device.gltf", &g.to_string());
        refused_within_limits(&["render", s(&scene), "-o", s(&out)], &["buffers[0].uri", uri, "not a regular file"]);
    }
    // A buffer file longer than its byteLength is read up to it; a shorter one is refused.
    let separate = good.write_separate(&dir.path(""), "separate");
    let bin = dir.path("separate.bin");
    let mut bytes = std::fs::read(&bin).unwrap();
    let length = bytes.len();
    bytes.extend(std::iter::repeat_n(7u8, 1 << 20));
    std::fs::write(&bin, &bytes).unwrap();
    renders_within_limits(&["render", s(&separate), "-o", s(&out), "--resolution", "24x16"]);
    std::fs::write(&bin, &bytes[..length - 1]).unwrap();
    refused_within_limits(&["render", s(&separate), "-o", s(&out)], &["buffers[0].uri", "fewer than"]);
}

/// An emissive quad of a USD stage with two points at 4.3e9 m (the
/// stage's 4.3e10 at 0.1 m a unit, within the 1e16 m it accepts) made
/// every pixel NaN in every mode: its triangles' areas overflowed `f32`.
#[test]
fn an_emitter_far_out_renders_finite() {
    let dir = TempDir::new("far-emitter");
    let stage = std::fs::read_to_string(scenes().join("usd/fuzz/stage.usda")).unwrap();
    let near = "point3f[] points = [(-20, -20, 0), (20, -20, 0), (20, 20, 0), (-20, 20, 0), (0, 0, 0)]";
    assert!(stage.contains(near));
    let far = "point3f[] points = [(-20, -20, 0), (20, -20, 0), (4.3e10, 4.3e10, 0), (-4.3e10, 4.3e10, 0), (0, 0, 0)]";
    std::fs::copy(scenes().join("usd/fuzz/texture.png"), dir.path("texture.png")).unwrap();
    let scene = dir.write("far.usda", &stage.replace(near, far));
    for mode in ["--exact", "--bounded", "--stochastic", "--multidimensional"] {
        let out = dir.path("far.exr");
        renders_within_limits(&["render", s(&scene), "-o", s(&out), mode, "--resolution", "32x24"]);
        let image = read_exr(&out).unwrap();
        assert!(luminance(&image).iter().any(|&l| l > 0.0), "{mode}: black");
    }
}

/// `-o /dev/null` replaced the device node with an EXR (exit 0: it did so
/// on this machine once, from this test run against the old code), and
/// `-o env.exr --environment env.exr` overwrote the map being read. An
/// output that is not a regular file, or that names an input or another
/// output, is refused before the render, and nothing is touched.
#[test]
fn an_output_never_replaces_a_device_a_directory_or_an_input() {
    let dir = TempDir::new("outputs");
    let scene = dir.write("scene.toml", &small_scene(2));
    let env = dir.path("env.exr");
    std::fs::copy(scenes().join("environment/courtyard.exr"), &env).unwrap();
    let before = std::fs::read(&env).unwrap();
    let (folder, a) = (dir.path("folder"), dir.path("a.exr"));
    std::fs::create_dir(&folder).unwrap();
    // The devices through links of the test's own (what is refused is what
    // a link leads to), and a FIFO: should the check ever regress, the
    // rename replaces the link, never the machine's /dev/null.
    let (null, full, fifo) = (dir.path("null.exr"), dir.path("full.exr"), dir.path("fifo.exr"));
    std::os::unix::fs::symlink("/dev/null", &null).unwrap();
    std::os::unix::fs::symlink("/dev/full", &full).unwrap();
    assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let cases: [(&[&str], &[&str]); 7] = [
        (&["-o", s(&null)], &["null.exr", "not a regular file"]),
        (&["-o", s(&full)], &["full.exr", "not a regular file"]),
        (&["-o", s(&fifo)], &["fifo.exr", "not a regular file"]),
        (&["-o", s(&folder)], &["folder", "not a regular file"]),
        (&["-o", s(&env), "--environment", s(&env)], &["env.exr", "an input"]),
        (&["-o", s(&scene)], &["scene.toml", "an input"]),
        (&["-o", s(&a), "--png", s(&a)], &["a.exr", "another output"]),
    ];
    for (flags, expect) in cases {
        let args = [&["render", s(&scene)][..], flags].concat();
        refused_within_limits(&args, expect);
    }
    for link in [&null, &full] {
        assert!(
            std::fs::symlink_metadata(link).unwrap().file_type().is_symlink(),
            "{} is still a link",
            link.display()
        );
    }
    assert_eq!(std::fs::read(&env).unwrap(), before, "the map read is untouched");
    assert!(dir.path("folder").is_dir() && !dir.path("a.exr").exists());
    // compare and assemble check their outputs too.
    let out = dir.path("out.exr");
    render(&scene, &out, &["--resolution", "8x6"]);
    refused_within_limits(&["compare", s(&out), s(&out), "--diff-exr", s(&out)], &["out.exr", "an input"]);
    refused_within_limits(&["assemble", s(&out), s(&out)], &["out.exr", "an input"]);
}

/// A `--png` that cannot be written (no such directory, a directory) failed
/// after the EXR was written and left it behind. Every output's place is
/// checked before the render, and both are written before either is put in
/// place: an existing EXR survives a failed render untouched.
#[test]
fn a_failing_preview_leaves_no_exr_and_destroys_none() {
    let dir = TempDir::new("preview");
    let scene = dir.write("scene.toml", &small_scene(2));
    let out = dir.path("out.exr");
    std::fs::create_dir(dir.path("folder.png")).unwrap();
    for png in [dir.path("no/such/dir/p.png"), dir.path("folder.png")] {
        refused_within_limits(&["render", s(&scene), "-o", s(&out), "--png", s(&png)], &[s(&png)]);
        assert!(!out.exists(), "{}: the EXR was left behind", png.display());
    }
    std::fs::write(&out, b"an earlier frame").unwrap();
    refused_within_limits(&["render", s(&scene), "-o", s(&out), "--png", s(&dir.path("folder.png"))], &["folder.png"]);
    assert_eq!(std::fs::read(&out).unwrap(), b"an earlier frame");
    assert!(dir.files().iter().all(|f| !f.contains(".partial")), "{:?}", dir.files());
}

/// A stage of `body` (Y up, metres) written as `name` in `dir`.
fn stage(dir: &TempDir, name: &str, body: &str) -> std::path::PathBuf {
    dir.write(name, &format!("#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\n\n{body}\n"))
}

/// Messages that sent the user the wrong way: each now names the real
/// file, prim and limit.
#[test]
fn messages_name_the_real_file_prim_and_limit() {
    let dir = TempDir::new("messages");
    let out = dir.path("out.exr");
    let render =
        |scene: &std::path::Path| -> Vec<String> { ["render", s(scene), "-o", s(&out)].map(String::from).to_vec() };
    // A stage with no camera and nothing to frame was "the glTF file".
    let empty = stage(&dir, "empty.usda", "def Xform \"World\"\n{\n}");
    let stderr = refused_within_limits(&strs(&render(&empty)), &["empty.usda", "the USD stage has no camera"]);
    assert!(!stderr.contains("glTF"), "{stderr}");
    // A negative face count was "the counts add up to 4".
    let counts = stage(
        &dir,
        "counts.usda",
        "def Mesh \"M\"\n{\n    int[] faceVertexCounts = [-4, 8]\n    int[] faceVertexIndices = [0, 1, 2, 0]\n    \
         point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]\n}",
    );
    refused_within_limits(&strs(&render(&counts)), &["/M.faceVertexCounts", "face 0's count is -4"]);
    // A radius past the coordinate limit was "must be finite".
    let radius = stage(&dir, "radius.usda", "def Sphere \"Ball\"\n{\n    double radius = 1e38\n}");
    refused_within_limits(&strs(&render(&radius)), &["/Ball.radius", "from 0 to 1e16"]);
    // An acyclic chain of 100 references was "composition arc cycle".
    for i in 0..100 {
        let reference =
            if i < 99 { format!("(\n    prepend references = @l{}.usda@\n)", i + 1) } else { String::new() };
        let inside = if i < 99 { "" } else { "def Sphere \"S\"\n    {\n    }" };
        let text = format!("def Xform \"World\" {reference}\n{{\n    {inside}\n}}\n");
        dir.write(&format!("l{i}.usda"), &format!("#usda 1.0\n(\n    defaultPrim = \"World\"\n)\n{text}"));
    }
    // The chain left out is a missing piece: --strict refuses it.
    let mut strict = render(&dir.path("l0.usda"));
    strict.push("--strict".into());
    refused_within_limits(&strs(&strict), &["l0.usda", "99 nested references", "no cycle"]);
    // A texel too bright was blamed on environment.scale without naming the EXR.
    let image = read_exr(&scenes().join("environment/courtyard.exr")).unwrap();
    let mut bright = image.channels["R"].clone();
    bright[0] = 2.7e38;
    write_rgb_exr(
        &dir.path("bright.exr"),
        image.width,
        image.height,
        &bright,
        &image.channels["G"],
        &image.channels["B"],
    );
    let toml = format!("{}\n[environment]\nfile = \"bright.exr\"\n", small_scene(2));
    let scene = dir.write("bright.toml", &toml);
    refused_within_limits(&strs(&render(&scene)), &["bright.exr", "environment.file", "pixel (0, 0)", "at most 1e30"]);
    // A camera far from the origin: "look_at must differ from the eye".
    let far = stage(
        &dir,
        "far.usda",
        "def Camera \"Cam\"\n{\n    double3 xformOp:translate = (0, 0, 9e15)\n    \
         uniform token[] xformOpOrder = [\"xformOp:translate\"]\n}\n\
         def SphereLight \"Bulb\"\n{\n    float inputs:intensity = 1\n}\n\
         def Sphere \"Ball\"\n{\n    double3 xformOp:translate = (0, 0, 8.99e15)\n    \
         uniform token[] xformOpOrder = [\"xformOp:translate\"]\n}",
    );
    renders_within_limits(&["render", s(&far), "-o", s(&out), "--resolution", "16x12"]);
    // A point instancer's tiny scale was blamed on another prim.
    let fuzz = std::fs::read_to_string(scenes().join("usd/fuzz/stage.usda")).unwrap();
    let scales = "float3[] scales = [(1, 1, 1), (0.5, 0.5, 2), (1, 1, 1)]";
    assert!(fuzz.contains(scales));
    std::fs::copy(scenes().join("usd/fuzz/texture.png"), dir.path("texture.png")).unwrap();
    let tiny = dir.write("tiny.usda", &fuzz.replace(scales, "float3[] scales = [(1, 1, 1), (1e-30, 1, 1), (1, 1, 1)]"));
    let warnings = renders_within_limits(&["render", s(&tiny), "-o", s(&out), "--resolution", "16x12"]);
    assert!(warnings.contains("left out (/World/Scatter[1]/Cone)"), "{warnings}");
}

/// Borrowed views of `args`.
fn strs(args: &[String]) -> Vec<&str> {
    args.iter().map(String::as_str).collect()
}

/// An RGB EXR of `width` x `height` (f32), written by the exr crate.
fn write_rgb_exr(path: &std::path::Path, width: usize, height: usize, r: &[f32], g: &[f32], b: &[f32]) {
    use exr::prelude::*;
    let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
        let i = p.y() * width + p.x();
        (r[i], g[i], b[i])
    });
    Image::from_channels((width, height), channels).write().to_file(path).unwrap();
}

/// `--threads` had no bound (20,000 threads took over a minute for a
/// 32 x 24 frame) and `--spp` took 2^32: both are refused with the limit.
#[test]
fn threads_and_samples_are_bounded() {
    let dir = TempDir::new("bounds");
    let scene = dir.write("scene.toml", &small_scene(2));
    let out = dir.path("out.exr");
    let run = lightcuts_limited(&["render", s(&scene), "-o", s(&out), "--threads", "20000"], 1024, 30);
    assert_eq!(run.code, Some(2), "{}", run.stderr);
    assert!(run.stderr.contains("from 0 (one per CPU) to 1024"), "{}", run.stderr);
    refused_within_limits(&["render", s(&scene), "-o", s(&out), "--spp", "4294967295"], &["--spp", "1 to 1048576"]);
    let many = dir.write("many.toml", &floor_spheres_grid(2).spp(4_000_000).toml());
    refused_within_limits(&["render", s(&many), "-o", s(&out)], &["film.spp", "1 to 1048576"]);
    assert!(!out.exists());
}
