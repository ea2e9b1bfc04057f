//! Every output file gets the permissions a plain `create` gives under the
//! process's umask (0666 less the umask), not a temporary file's 0600: on a
//! farm the compositing user is often not the render user.

mod common;
use common::*;

use std::os::unix::fs::PermissionsExt as _;
use std::process::Command;

/// Runs lightcuts with `args` under `umask`, asserting success.
fn lightcuts_under_umask(umask: u32, args: &[&str]) {
    let status = Command::new("sh")
        .arg("-c")
        .arg(format!("umask {umask:03o} && exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_lightcuts"))
        .args(args)
        .stdout(std::process::Stdio::null())
        .status()
        .expect("run sh");
    assert!(status.success(), "lightcuts {args:?} under umask {umask:03o}");
}

fn mode(path: &std::path::Path) -> u32 {
    std::fs::metadata(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).permissions().mode() & 0o777
}

#[test]
fn every_output_has_the_mode_a_plain_create_gives_under_the_umask() {
    for umask in [0o022, 0o077] {
        let dir = TempDir::new(&format!("umask{umask:03o}"));
        let scene = dir.write("s.toml", &small_scene(16));
        let small = ["--resolution", "16x12", "--quiet"];
        let (exr, png) = (dir.path("frame.exr"), dir.path("frame.png"));
        lightcuts_under_umask(umask, &[&["render", s(&scene), "-o", s(&exr), "--png", s(&png)][..], &small].concat());
        let tiles: Vec<_> = (0..2).map(|i| dir.path(&format!("tile{i}.exr"))).collect();
        for (i, tile) in tiles.iter().enumerate() {
            let spec = format!("{i}/2");
            let args = [&["render", s(&scene), "-o", s(tile), "--tile", &spec, "--no-overwrite"][..], &small].concat();
            lightcuts_under_umask(umask, &args);
        }
        let assembled = dir.path("assembled.exr");
        lightcuts_under_umask(umask, &["assemble", s(&assembled), s(&tiles[0]), s(&tiles[1])]);
        let (diff_png, diff_exr) = (dir.path("diff.png"), dir.path("diff.exr"));
        lightcuts_under_umask(
            umask,
            &["compare", s(&exr), s(&assembled), "--diff", s(&diff_png), "--diff-exr", s(&diff_exr)],
        );
        let sweep = dir.path("sweep");
        std::fs::create_dir(&sweep).unwrap();
        lightcuts_under_umask(
            umask,
            &["sweep", s(&scene), "--out", s(&sweep), "--errors", "0.05", "--resolution", "16x12", "--quiet"],
        );

        let expected = 0o666 & !umask;
        let mut outputs = vec![exr, png, assembled, diff_png, diff_exr];
        outputs.extend(tiles);
        outputs.extend(
            ["sweep.csv", "sweep.svg", "sweep.png", "sweep-p99.svg", "sweep-p99.png", "reference-spp1.exr"]
                .map(|f| sweep.join(f)),
        );
        for path in &outputs {
            assert_eq!(mode(path), expected, "{} under umask {umask:03o}: {:03o}", path.display(), mode(path));
        }
    }
}
