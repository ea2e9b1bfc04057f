//! The crate's top-level modules are layers: each may use only the modules
//! below it, so every arrow of the architecture points down and no two
//! modules import each other in a circle. Read off every `crate::` path in
//! `src/` (use lines and inline paths alike), including the tests inside the
//! modules.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Bottom to top. A module may use the modules before it, never one after it.
const LAYERS: [&str; 10] =
    ["util", "embree", "scene", "light", "light_tree", "shading", "lightcut", "render", "output", "cli"];

fn rust_files(dir: &Path, found: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, found);
        } else if path.extension().is_some_and(|e| e == "rs") {
            found.push(path);
        }
    }
}

/// The top-level module a file of `src/` belongs to (None for lib.rs and main.rs).
fn module_of(src: &Path, file: &Path) -> Option<String> {
    let relative = file.strip_prefix(src).unwrap();
    let first = relative.components().next()?.as_os_str().to_string_lossy().into_owned();
    match first.strip_suffix(".rs") {
        Some("lib" | "main") => None,
        Some(name) => Some(name.to_string()),
        None => Some(first),
    }
}

/// Every top-level module named by a `crate::x` path in `text`, outside
/// `//` comments.
fn crate_paths(text: &str) -> BTreeSet<String> {
    let mut used = BTreeSet::new();
    for line in text.lines() {
        let code = line.split("//").next().unwrap_or("");
        let mut rest = code;
        while let Some(at) = rest.find("crate::") {
            let preceded_by_ident =
                rest[..at].chars().next_back().is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '$');
            let after = &rest[at + "crate::".len()..];
            let name: String = after.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
            if !preceded_by_ident && !name.is_empty() {
                used.insert(name);
            }
            rest = after;
        }
    }
    used
}

/// The arrows between top-level modules: (from, to) -> a file that draws it.
fn arrows(src: &Path) -> BTreeMap<(String, String), PathBuf> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    files.sort();
    let mut arrows = BTreeMap::new();
    for file in files {
        let Some(from) = module_of(src, &file) else { continue };
        for to in crate_paths(&std::fs::read_to_string(&file).unwrap()) {
            if to != from {
                arrows.entry((from.clone(), to)).or_insert(file.clone());
            }
        }
    }
    arrows
}

/// Every arrow that does not point down, and every module missing from LAYERS.
fn violations(src: &Path) -> Vec<String> {
    let rank = |m: &str| LAYERS.iter().position(|l| *l == m);
    let mut problems = Vec::new();
    for ((from, to), file) in arrows(src) {
        match (rank(&from), rank(&to)) {
            (Some(a), Some(b)) if b < a => {}
            (Some(_), Some(_)) => problems.push(format!("{} ({from}) uses {to}, a layer above it", file.display())),
            (None, _) => {
                problems.push(format!("{} is in module '{from}', which LAYERS does not place", file.display()))
            }
            (_, None) => problems.push(format!("{} uses '{to}', which LAYERS does not place", file.display())),
        }
    }
    problems
}

#[test]
fn every_module_uses_only_the_layers_below_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let problems = violations(&src);
    assert!(problems.is_empty(), "imports that point up the layers:\n{}", problems.join("\n"));
    // The check sees the real arrows (a test that finds none proves nothing).
    let found = arrows(&src);
    for (from, to) in [("light", "scene"), ("lightcut", "shading"), ("cli", "render"), ("shading", "embree")] {
        assert!(found.contains_key(&(from.to_string(), to.to_string())), "expected {from} -> {to}");
    }
}

#[test]
fn paths_are_read_from_use_lines_and_inline_paths() {
    let text =
        "use crate::light::{Light, Lights};\nlet x = crate::util::color::luminance(c); // crate::cli\nmy_crate::x;";
    let found = crate_paths(text);
    assert_eq!(found, ["light", "util"].iter().map(|s| s.to_string()).collect());
}
