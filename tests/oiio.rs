//! OpenImageIO (an EXR and PNG reader that is not ours) reads every kind of
//! file the renderer writes: renders (float, half, a window, a tile), an
//! assembled frame, comparison EXRs and PNGs, previews, a sweep's images and
//! plots; and finds the standard attributes (chromaticities, worldToCamera,
//! worldToNDC, pixelAspectRatio) and ours in a render.
//!
//! `ci/setup.sh --test` installs openimageio-tools, and ci/embree4.sh
//! installs them in its Debian 13 root: the test never skips, and fails
//! when the tools are missing.

mod common;
use common::*;

fn oiio_reads(path: &std::path::Path) -> String {
    let mut text = String::new();
    for (tool, args) in [("oiiotool", vec!["--info", "-v"]), ("iinfo", vec!["-v"])] {
        let output = std::process::Command::new(tool)
            .args(&args)
            .arg(path)
            .output()
            .unwrap_or_else(|e| panic!("cannot run {tool} (ci/setup.sh --test installs openimageio-tools): {e}"));
        let stdout = String::from_utf8_lossy(&output.stdout);
        assert!(
            output.status.success(),
            "{tool} fails on {}: {}",
            path.display(),
            String::from_utf8_lossy(&output.stderr)
        );
        text += &stdout;
    }
    text
}

#[test]
fn openimageio_reads_every_file_the_renderer_writes() {
    let dir = TempDir::new("oiio");
    let scene = dir.write("s.toml", &small_scene(16));
    let small = ["--resolution", "24x16", "--quiet"];
    let render = |name: &str, extra: &[&str]| {
        let out = dir.path(name);
        lightcuts_ok(&[&["render", s(&scene), "-o", s(&out)][..], &small, extra].concat());
        out
    };
    let full = render("full.exr", &["--png", s(&dir.path("preview.png"))]);
    let half = render("half.exr", &["--half"]);
    let window = render("window.exr", &["--pixel-bounds", "3,20,2,9", "--exact"]);
    let tiles: Vec<_> = (0..2).map(|i| render(&format!("tile{i}.exr"), &["--tile", &format!("{i}/2")])).collect();
    let frame = dir.path("frame.exr");
    lightcuts_ok(&["assemble", s(&frame), s(&tiles[0]), s(&tiles[1])]);
    let (diff_png, diff_exr) = (dir.path("diff.png"), dir.path("diff.exr"));
    lightcuts_ok(&["compare", s(&full), s(&frame), "--diff", s(&diff_png), "--diff-exr", s(&diff_exr)]);
    let sweep = dir.path("sweep");
    lightcuts_ok(&[&["sweep", s(&scene), "--out", s(&sweep), "--errors", "0.05", "--spp", "1"][..], &small].concat());
    // Light groups and Cryptomatte: the scene with its lights in two groups.
    let grouped = dir.write(
        "grouped.toml",
        &(small_scene(16).replacen("[[lights]]\n", "[[lights]]\ngroup = \"key\"\n", 1)
            + "[[lights]]\ntype = \"point\"\ngroup = \"fill\"\nposition = [2, 2, 2]\nintensity = [0.5, 0.5, 0.5]\n"),
    );
    let layers = dir.path("layers.exr");
    lightcuts_ok(&[&["render", s(&grouped), "-o", s(&layers), "--cryptomatte"][..], &small].concat());
    let mut files = vec![
        full.clone(),
        half,
        window,
        tiles[0].clone(),
        frame.clone(),
        diff_png,
        diff_exr,
        dir.path("preview.png"),
        layers.clone(),
    ];
    for entry in std::fs::read_dir(&sweep).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "exr" || e == "png") {
            files.push(path);
        }
    }
    assert!(files.len() >= 12, "{files:?}");
    for file in &files {
        oiio_reads(file);
    }
    for render in [&full, &frame] {
        let info = oiio_reads(render);
        for attribute in [
            "chromaticities: 0.64, 0.33, 0.3, 0.6, 0.15, 0.06, 0.3127, 0.329",
            "worldToCamera",
            "worldToNDC",
            "PixelAspectRatio: 1",
            "lightcuts:sceneHash",
            "lightcuts:renderMode",
        ] {
            assert!(info.contains(attribute), "{attribute} missing from {}: {info}", render.display());
        }
    }
    let info = oiio_reads(&layers);
    for expected in ["Combined_", "CryptoObject00.R", "CryptoMaterial02.A", "cryptomatte/", "MurmurHash3_32"] {
        assert!(info.contains(expected), "{expected} missing from {}: {info}", layers.display());
    }
}
