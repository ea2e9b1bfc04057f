//! Every file a scene in `scenes/` reads is committed: a fresh clone must be
//! able to render every scene (the gallery's sky was once ignored by
//! `.gitignore`, so the README's first command failed on every machine but
//! the one that generated it).

use std::path::{Path, PathBuf};
use std::process::Command;

use lightcuts::scene::Scene;

/// Extensions of the files `Scene::load` reads as scenes.
const SCENE_EXTENSIONS: [&str; 8] = ["toml", "json", "gltf", "glb", "usd", "usda", "usdc", "usdz"];

/// Files with a scene's extension that are not scenes: the answers the
/// tests compare with (`expected.json`), the layers a USD stage composes
/// (referenced, not rendered by themselves), and the broken files the
/// tests feed the command line (scenes/usd/broken/).
fn is_scene(path: &Path) -> bool {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or_default();
    let broken = path.parent().and_then(Path::file_name).is_some_and(|d| d == "broken");
    // geo.usda and mtl.usda: the geometry and material layers of the USD
    // asset structure (scenes/usdwg/).
    let layer = matches!(name, "asset.usda" | "payload.usda" | "main.usda" | "geo.usda" | "mtl.usda" | "_scene.usda");
    name != "expected.json" && !layer && !broken
}

fn scene_files(dir: &Path, found: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            scene_files(&path, found);
        } else if path.extension().and_then(|e| e.to_str()).is_some_and(|e| SCENE_EXTENSIONS.contains(&e))
            && is_scene(&path)
        {
            found.push(path);
        }
    }
}

/// Whether git tracks `path` (run in the repository, so a clone without
/// `.git` fails here loudly instead of passing without checking anything).
fn tracked(repository: &Path, path: &Path) -> Result<(), String> {
    let output = Command::new("git")
        .arg("-C")
        .arg(repository)
        .args(["ls-files", "--error-unmatch", "--"])
        .arg(path)
        .output()
        .map_err(|e| format!("cannot run git: {e}"))?;
    if output.status.success() {
        Ok(())
    } else {
        Err(String::from_utf8_lossy(&output.stderr).trim().to_string())
    }
}

#[test]
fn every_file_every_scene_reads_is_tracked_by_git() {
    let repository = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut scenes = Vec::new();
    scene_files(&repository.join("scenes"), &mut scenes);
    assert!(scenes.len() >= 10, "expected the gallery and measuring scenes, found {scenes:?}");
    let mut problems = Vec::new();
    let mut checked = 0;
    for scene in &scenes {
        match Scene::load(scene) {
            Err(e) => problems.push(format!("{}: does not load: {e}", scene.display())),
            Ok(loaded) => {
                assert_eq!(loaded.inputs.first(), Some(scene), "the scene file is its first input");
                for input in &loaded.inputs {
                    checked += 1;
                    if let Err(e) = tracked(repository, input) {
                        problems.push(format!(
                            "{} reads {}, which git does not track: {e}",
                            scene.display(),
                            input.display()
                        ));
                    }
                }
            }
        }
    }
    assert!(problems.is_empty(), "a fresh clone could not render these scenes:\n{}", problems.join("\n"));
    assert!(checked > scenes.len(), "some scene must read a file besides itself (meshes, textures, the sky)");
}
