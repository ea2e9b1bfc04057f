//! The measuring commands, run as the real binary on small inputs.

mod common;
use common::*;

#[test]
fn sweep_writes_csv_svg_png_and_reuses_its_reference() {
    let dir = TempDir::new("sweep");
    let scene = dir.write("s.toml", &small_scene(16));
    let out = dir.path("out");
    let stdout = lightcuts_ok(&[
        "sweep",
        s(&scene),
        "--out",
        s(&out),
        "--errors",
        "0.01,0.1",
        "--modes",
        "bounded,stochastic",
        "--spp",
        "1,2",
        "--resolution",
        "32x24",
        "--quiet",
    ]);
    assert!(stdout.contains("threshold") && stdout.contains("speedup"), "{stdout}");
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 2 * 2 * 2, "two spp, two modes, two thresholds: {csv}");
    assert!(csv.starts_with("mode,spp,threshold,seconds,speedup"), "{csv}");
    for plot in ["sweep", "sweep-p99"] {
        assert!(std::fs::read_to_string(out.join(format!("{plot}.svg"))).unwrap().contains("<svg"));
        assert!(png::Decoder::new(std::fs::File::open(out.join(format!("{plot}.png"))).unwrap()).read_info().is_ok());
    }
    assert!(out.join("reference-spp1.exr").exists() && out.join("reference-spp2.exr").exists());
    // The rows: mode, spp, then numbers. For the bounded mode at 1 spp the
    // smaller threshold is no less accurate.
    let rows: Vec<(String, Vec<f64>)> = csv
        .lines()
        .skip(1)
        .map(|l| {
            let mut fields = l.split(',');
            let mode = fields.next().unwrap().to_string();
            (mode, fields.map(|v| v.parse().unwrap()).collect())
        })
        .collect();
    assert_eq!(rows[0].0, "bounded");
    assert!(rows.iter().any(|r| r.0 == "stochastic" && r.1[0] == 2.0));
    let mean = |r: &(String, Vec<f64>)| r.1[7];
    assert!(mean(&rows[0]) <= mean(&rows[1]), "mean error at 1% {} vs 10% {}", mean(&rows[0]), mean(&rows[1]));
    // A second sweep with the same settings reuses the reference untouched.
    let stamp = std::fs::metadata(out.join("reference-spp1.exr")).unwrap().modified().unwrap();
    let json = lightcuts_ok(&[
        "sweep",
        s(&scene),
        "--out",
        s(&out),
        "--errors",
        "0.05",
        "--resolution",
        "32x24",
        "--quiet",
        "--json",
    ]);
    assert_eq!(std::fs::metadata(out.join("reference-spp1.exr")).unwrap().modified().unwrap(), stamp);
    let rows: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(rows.as_array().unwrap().len(), 1);
    // Other settings render a new one.
    lightcuts_ok(&[
        "sweep",
        s(&scene),
        "--out",
        s(&out),
        "--errors",
        "0.05",
        "--resolution",
        "32x24",
        "--seed",
        "3",
        "--quiet",
    ]);
    assert_ne!(std::fs::metadata(out.join("reference-spp1.exr")).unwrap().modified().unwrap(), stamp);
}

#[test]
fn bench_tree_and_rays_print_json_figures() {
    let out =
        lightcuts_ok(&["bench", "tree", "--lights", "1000,2000", "--quality-lights", "300", "--repeat", "1", "--json"]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["builds"].as_array().unwrap().len(), 4, "two sizes, two distributions");
    assert!(v["builds"][0]["tree_bytes_per_light"].as_f64().unwrap() > 0.0);
    assert_eq!(v["quality"].as_array().unwrap().len(), 2);
    let dir = TempDir::new("rays");
    let scene = dir.write("s.toml", &small_scene(16));
    let out = lightcuts_ok(&["bench", "rays", s(&scene), "--resolution", "32x24", "--quiet", "--json"]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    for key in ["embree_single_mrays_per_s", "embree_batch_mrays_per_s", "lightcuts_mrays_per_s", "exact_mrays_per_s"] {
        assert!(v[key].as_f64().unwrap() > 0.0, "{key}: {v}");
    }
    assert!(v["recorded_rays"].as_u64().unwrap() > 1000);
    // A share of the pass's time: Embree was timed, and not all of it is Embree.
    let own = v["lightcuts_over_embree_own_rays"].as_f64().unwrap();
    assert!(own > 0.0 && own < 1.0, "lightcuts_over_embree_own_rays: {v}");
    assert!(v["lightcuts_timed_embree_seconds"].as_f64().unwrap() > 0.0, "{v}");
}

#[test]
fn render_stats_prints_the_full_block() {
    let dir = TempDir::new("stats");
    let scene = dir.write("s.toml", &small_scene(16));
    let out = lightcuts_ok(&["render", s(&scene), "-o", s(&dir.path("o.exr")), "--quiet", "--stats"]);
    for expect in ["statistics (--stats)", "Embree", "cut size       shading points", "peak memory"] {
        assert!(out.contains(expect), "'{expect}' missing: {out}");
    }
}

/// A 2 x 2 PNG texture of one grey level.
fn write_texture(path: &std::path::Path, grey: u8) {
    let file = std::fs::File::create(path).unwrap();
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), 2, 2);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.write_header().unwrap().write_image_data(&[grey; 12]).unwrap();
}

#[test]
fn sweep_renders_a_new_reference_when_a_file_the_scene_reads_changes() {
    let dir = TempDir::new("sweep-inputs");
    let scene = small_scene(16).replace("albedo = [0.7, 0.7, 0.7]", "texture = \"floor.png\"");
    let scene = dir.write("s.toml", &scene);
    write_texture(&dir.path("floor.png"), 200);
    let out = dir.path("out");
    let sweep = || {
        lightcuts_ok(&["sweep", s(&scene), "--out", s(&out), "--errors", "0.05", "--resolution", "24x18", "--quiet"])
    };
    let reference = || read_exr(&out.join("reference-spp1.exr")).unwrap().channels["R"].clone();
    sweep();
    let (first, stamp) = (reference(), std::fs::metadata(out.join("reference-spp1.exr")).unwrap().modified().unwrap());
    sweep();
    assert_eq!(std::fs::metadata(out.join("reference-spp1.exr")).unwrap().modified().unwrap(), stamp, "reused");
    // Same scene file, darker texture: the old reference is stale.
    write_texture(&dir.path("floor.png"), 50);
    sweep();
    let second = reference();
    assert_ne!(std::fs::metadata(out.join("reference-spp1.exr")).unwrap().modified().unwrap(), stamp, "re-rendered");
    assert!(second.iter().sum::<f32>() < 0.5 * first.iter().sum::<f32>(), "the new reference sees the new texture");
}

#[test]
fn aovs_choose_the_layers_written() {
    let dir = TempDir::new("aovs");
    let scene = dir.write("s.toml", &small_scene(16));
    let channels = |extra: &[&str]| {
        let out = dir.path("o.exr");
        lightcuts_ok(&[&["render", s(&scene), "-o", s(&out), "--resolution", "12x8", "--quiet"][..], extra].concat());
        read_exr(&out).unwrap().channels.keys().cloned().collect::<Vec<_>>().join(",")
    };
    assert_eq!(
        channels(&[]),
        "A,B,G,N.X,N.Y,N.Z,R,Z,albedo.B,albedo.G,albedo.R,lightcuts.cut_size,lightcuts.shadow_rays"
    );
    assert_eq!(channels(&["--exact"]), "A,B,G,N.X,N.Y,N.Z,R,Z,albedo.B,albedo.G,albedo.R");
    assert_eq!(channels(&["--aovs", "none"]), "A,B,G,R");
    assert_eq!(channels(&["--aovs", "Z,lightcuts"]), "A,B,G,R,Z,lightcuts.cut_size,lightcuts.shadow_rays");
    assert_eq!(channels(&["--aovs", "N", "--exact"]), "A,B,G,N.X,N.Y,N.Z,R");
    let stderr = lightcuts_fails(&["render", s(&scene), "-o", s(&dir.path("x.exr")), "--exact", "--aovs", "lightcuts"]);
    assert!(stderr.contains("--aovs") && !dir.path("x.exr").exists(), "{stderr}");
    let output = lightcuts(&["render", s(&scene), "-o", s(&dir.path("x.exr")), "--aovs", "albedo,Q"]);
    assert!(output.status.code() == Some(2) && String::from_utf8_lossy(&output.stderr).contains("unknown AOV 'Q'"));
    // Tiles keep their selection through assemble.
    let tiles: Vec<_> = (0..2)
        .map(|i| {
            let t = dir.path(&format!("t{i}.exr"));
            let tile = format!("{i}/2");
            lightcuts_ok(&[
                "render",
                s(&scene),
                "-o",
                s(&t),
                "--resolution",
                "12x8",
                "--tile",
                &tile,
                "--aovs",
                "Z",
                "--quiet",
            ]);
            t
        })
        .collect();
    let frame = dir.path("frame.exr");
    lightcuts_ok(&["assemble", s(&frame), s(&tiles[0]), s(&tiles[1])]);
    assert_eq!(read_exr(&frame).unwrap().channels.keys().cloned().collect::<Vec<_>>().join(","), "A,B,G,R,Z");
}

/// A sweep with paths measures against an exact reference with paths: on
/// the inside of a closed diffuse sphere (albedo 0.5) paths of 4 vertices
/// give 1 + 0.5 + 0.25 + 0.125 = 1.875 times the direct light everywhere,
/// and a reference rendered before without `--indirect` is not reused.
#[test]
fn a_sweep_with_paths_has_a_reference_with_paths() {
    let dir = TempDir::new("sweep-paths");
    let scene = dir.write("s.toml", &inside_sphere_scene(24, 24));
    let out = dir.path("out");
    let sweep = |extra: &[&str]| {
        let args = [&["sweep", s(&scene), "--out", s(&out), "--errors", "0.02", "--spp", "4"][..], extra].concat();
        let json = lightcuts_ok(&[&args[..], &["--modes", "bounded,stochastic", "--quiet", "--json"]].concat());
        let reference = read_exr(&out.join("reference-spp4.exr")).unwrap();
        (serde_json::from_str::<serde_json::Value>(&json).unwrap(), reference)
    };
    let (_, direct) = sweep(&[]);
    let (rows, paths) = sweep(&["--indirect", "path", "--max-depth", "4"]);
    let direct_answer = inside_sphere_answer([3.0, 6.0, 9.0]);
    // One bounce direction per sample: the pixels are noisy, their mean is not.
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        let values = paths.channel(&out, name).unwrap();
        let mean = values.iter().map(|&v| f64::from(v)).sum::<f64>() / values.len() as f64;
        let want = 1.875 * direct_answer[c];
        assert!((mean - want).abs() < 0.015 * want, "{name}: the reference with paths is {mean}, not {want}");
    }
    assert_inside_sphere_is(&out, &direct, direct_answer, 0.01);
    for row in rows.as_array().unwrap() {
        let error = row["mean_relative_error"].as_f64().unwrap();
        assert!(error < 0.05, "{} against the reference with paths: {error}", row["mode"]);
    }
}

/// Output piped into a reader that has stopped (`lightcuts inspect ... |
/// head`, the reader gone before the first line) ends the process as it
/// ends any Unix tool, by SIGPIPE, without a panic's message.
#[test]
fn a_closed_pipe_ends_the_output_quietly() {
    use std::os::unix::process::ExitStatusExt;
    let (reader, writer) = std::io::pipe().expect("a pipe");
    drop(reader);
    let scene = scenes().join("few4.toml");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_lightcuts"))
        .args(["inspect", s(&scene), "--json"])
        .stdout(writer)
        .stderr(std::process::Stdio::piped())
        .output()
        .expect("run lightcuts");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(out.status.signal(), Some(13), "ended by SIGPIPE: {:?}, {stderr}", out.status);
}
