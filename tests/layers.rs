//! The crate's top-level modules are layers: each may use only the modules
//! below it, so every arrow of the architecture points down and no two
//! modules import each other in a circle. Read off every `crate::` path in
//! `src/` (use lines and inline paths alike), including the tests inside the
//! modules. Inside a layer, no two files import each other in a circle
//! either (a file may use its parent's items and its children's; siblings
//! and cousins only one way), no function outside the tests is longer than
//! 120 lines, and nothing in the repository points at a file outside it.

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

/// A file's module path inside the crate (`src/cli/args.rs` -> `cli::args`,
/// `src/scene/gltf/mod.rs` -> `scene::gltf`); None for lib.rs, main.rs and
/// the test files (`tests.rs`).
fn module_path(src: &Path, file: &Path) -> Option<Vec<String>> {
    let relative = file.strip_prefix(src).unwrap();
    let mut parts: Vec<String> = relative.components().map(|c| c.as_os_str().to_string_lossy().into_owned()).collect();
    let last = parts.pop()?.strip_suffix(".rs")?.to_string();
    match last.as_str() {
        "lib" | "main" if parts.is_empty() => return None,
        "tests" => return None,
        "mod" => {}
        _ => parts.push(last),
    }
    Some(parts)
}

/// The code of a file without its `#[cfg(test)] mod tests { ... }` block
/// and without `//` comments.
fn code_outside_tests(text: &str) -> String {
    let mut out = String::new();
    let mut lines = text.lines().peekable();
    while let Some(line) = lines.next() {
        if line.trim() == "#[cfg(test)]" && lines.peek().is_some_and(|next| next.trim_start().starts_with("mod tests"))
        {
            if lines.peek().is_some_and(|next| next.trim_end().ends_with(';')) {
                lines.next();
                continue;
            }
            break; // the inline test module runs to the end of the file
        }
        out.push_str(line.split("//").next().unwrap_or(""));
        out.push('\n');
    }
    out
}

/// The module paths a file at `from` names: `crate::a::b`, `super::b`,
/// `super::super::b`, `self::b`, each resolved to the longest prefix that is
/// a module of `modules`.
fn referenced_modules(from: &[String], code: &str, modules: &BTreeSet<Vec<String>>) -> BTreeSet<Vec<String>> {
    let mut found = BTreeSet::new();
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    for (at, _) in code.match_indices("::") {
        // The path around this `::`, from its first segment.
        let start = code[..at].rfind(|c: char| !(ident(c) || c == ':')).map_or(0, |i| i + 1);
        if start < at && code[..start].ends_with(|c: char| ident(c) || c == '$') {
            continue;
        }
        let path: String = code[start..].chars().take_while(|&c| ident(c) || c == ':').collect();
        if !code[start..].starts_with(&path) || start + path.find("::").unwrap_or(0) != at {
            continue; // not the first `::` of its path
        }
        let segments: Vec<&str> = path.split("::").filter(|s| !s.is_empty()).collect();
        let (mut base, rest): (Vec<String>, &[&str]) = match segments.first() {
            Some(&"crate") => (Vec::new(), &segments[1..]),
            Some(&"super") => {
                let ups = segments.iter().take_while(|s| **s == "super").count();
                if ups > from.len() {
                    continue;
                }
                (from[..from.len() - ups].to_vec(), &segments[ups..])
            }
            Some(&"self") => (from.to_vec(), &segments[1..]),
            _ => continue,
        };
        let mut resolved = base.clone();
        for segment in rest {
            base.push((*segment).to_string());
            if modules.contains(&base) {
                resolved = base.clone();
            }
        }
        found.insert(resolved);
    }
    found
}

/// The arrows between files of the same layer that are neither ancestor
/// nor descendant of each other: (from, to) -> the file that draws it.
fn file_arrows(files: &[(Vec<String>, String)]) -> BTreeMap<(Vec<String>, Vec<String>), ()> {
    let modules: BTreeSet<Vec<String>> = files.iter().map(|(m, _)| m.clone()).collect();
    let mut arrows = BTreeMap::new();
    for (from, code) in files {
        for to in referenced_modules(from, code, &modules) {
            let related = to.starts_with(from) || from.starts_with(&to);
            if !related && to.first() == from.first() {
                arrows.insert((from.clone(), to), ());
            }
        }
    }
    arrows
}

/// Circles among the arrows: each strongly connected set of two or more
/// modules (Tarjan's algorithm), as module paths.
fn circles(arrows: &BTreeMap<(Vec<String>, Vec<String>), ()>) -> Vec<Vec<String>> {
    let nodes: BTreeSet<&Vec<String>> = arrows.keys().flat_map(|(a, b)| [a, b]).collect();
    let nodes: Vec<&Vec<String>> = nodes.into_iter().collect();
    let index_of = |n: &Vec<String>| nodes.iter().position(|m| *m == n).unwrap();
    let mut next: Vec<Vec<usize>> = vec![Vec::new(); nodes.len()];
    for (a, b) in arrows.keys() {
        next[index_of(a)].push(index_of(b));
    }
    struct Tarjan<'a> {
        next: &'a [Vec<usize>],
        index: Vec<Option<usize>>,
        low: Vec<usize>,
        stack: Vec<usize>,
        on_stack: Vec<bool>,
        counter: usize,
        found: Vec<Vec<usize>>,
    }
    impl Tarjan<'_> {
        fn visit(&mut self, v: usize) {
            self.index[v] = Some(self.counter);
            self.low[v] = self.counter;
            self.counter += 1;
            self.stack.push(v);
            self.on_stack[v] = true;
            for &w in &self.next[v] {
                match self.index[w] {
                    None => {
                        self.visit(w);
                        self.low[v] = self.low[v].min(self.low[w]);
                    }
                    Some(i) if self.on_stack[w] => self.low[v] = self.low[v].min(i),
                    Some(_) => {}
                }
            }
            if Some(self.low[v]) == self.index[v] {
                let mut component = Vec::new();
                while let Some(w) = self.stack.pop() {
                    self.on_stack[w] = false;
                    component.push(w);
                    if w == v {
                        break;
                    }
                }
                if component.len() > 1 {
                    self.found.push(component);
                }
            }
        }
    }
    let n = nodes.len();
    let mut t = Tarjan {
        next: &next,
        index: vec![None; n],
        low: vec![0; n],
        stack: Vec::new(),
        on_stack: vec![false; n],
        counter: 0,
        found: Vec::new(),
    };
    for v in 0..n {
        if t.index[v].is_none() {
            t.visit(v);
        }
    }
    t.found.into_iter().map(|c| c.into_iter().map(|i| nodes[i].join("::")).collect()).collect()
}

/// Every file of `src/` (but the test files) with its module path and its
/// code outside tests.
fn files_of(src: &Path) -> Vec<(Vec<String>, String)> {
    let mut paths = Vec::new();
    rust_files(src, &mut paths);
    paths.sort();
    paths
        .iter()
        .filter_map(|p| Some((module_path(src, p)?, code_outside_tests(&std::fs::read_to_string(p).unwrap()))))
        .collect()
}

#[test]
fn no_two_files_of_a_layer_import_each_other_in_a_circle() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let files = files_of(&src);
    let arrows = file_arrows(&files);
    let found = circles(&arrows);
    assert!(found.is_empty(), "files of one layer that import each other in a circle: {found:?}");
    // The check sees the real arrows between siblings.
    let arrow = |a: &str, b: &str| {
        let split = |s: &str| s.split("::").map(String::from).collect::<Vec<_>>();
        arrows.contains_key(&(split(a), split(b)))
    };
    assert!(arrow("cli::render_cmd", "cli::args") && arrow("lightcut::stochastic", "lightcut::bounds"));
}

#[test]
fn a_circle_of_siblings_is_found_and_parents_and_children_are_not_one() {
    let m = |s: &str| s.split("::").map(String::from).collect::<Vec<_>>();
    let files = vec![
        (m("cli"), "mod a; mod b; use self::a::X;".to_string()),
        (m("cli::a"), "use super::b::Y; use super::CliError;".to_string()),
        (m("cli::b"), "fn f() { crate::cli::a::g(); }".to_string()),
        (m("cli::c"), "use super::a::Z;".to_string()),
    ];
    let found = circles(&file_arrows(&files));
    assert_eq!(found.len(), 1, "{found:?}");
    let mut circle = found[0].clone();
    circle.sort();
    assert_eq!(circle, ["cli::a", "cli::b"]);
}

/// The modules `file` (a module path of `files`) names.
fn named_by(files: &[(Vec<String>, String)], file: &str) -> BTreeSet<String> {
    let modules: BTreeSet<Vec<String>> = files.iter().map(|(m, _)| m.clone()).collect();
    let (from, code) = files.iter().find(|(m, _)| m.join("::") == file).unwrap_or_else(|| panic!("no file {file}"));
    referenced_modules(from, code, &modules).into_iter().map(|m| m.join("::")).collect()
}

/// Direct light is behind one interface (docs/design.md §2.1): the path
/// loop, next-event estimation and the tiles name no method and no cut
/// (only `render::direct`, the interface, and `lightcut`'s shared result),
/// and no method names another.
#[test]
fn the_path_loop_names_no_direct_light_method_and_no_method_another() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let files = files_of(&src);
    let methods: Vec<String> =
        files.iter().map(|(m, _)| m.join("::")).filter(|m| m.starts_with("render::direct::")).collect();
    assert!(methods.len() >= 4, "the methods' modules: {methods:?}");
    for loop_file in ["render", "render::integrator", "render::next_event", "render::tracer"] {
        let named = named_by(&files, loop_file);
        let wrong: Vec<&String> =
            named.iter().filter(|m| m.starts_with("render::direct::") || m.starts_with("lightcut::")).collect();
        assert!(wrong.is_empty(), "{loop_file} names a direct-light method or a cut: {wrong:?}");
    }
    assert!(named_by(&files, "render::integrator").contains("render::direct"), "the loop calls the interface");
    for method in &methods {
        let named = named_by(&files, method);
        let others: Vec<&String> = named.iter().filter(|m| methods.contains(m) && *m != method).collect();
        assert!(others.is_empty(), "{method} names another method: {others:?}");
    }
}

/// Every function outside the tests with its length in lines, from its
/// `fn` line to the `}` at the same indentation.
fn function_lengths(src: &Path) -> Vec<(usize, String)> {
    let mut paths = Vec::new();
    rust_files(src, &mut paths);
    let mut found = Vec::new();
    for path in paths.iter().filter(|p| module_path(src, p).is_some()) {
        let text = std::fs::read_to_string(path).unwrap();
        let code = code_outside_tests(&text);
        let lines: Vec<&str> = code.lines().collect();
        for (i, line) in lines.iter().enumerate() {
            let trimmed = line.trim_start();
            let indent = &line[..line.len() - trimmed.len()];
            let declaration = trimmed
                .strip_prefix("pub ")
                .or_else(|| trimmed.strip_prefix("pub(crate) "))
                .or_else(|| trimmed.strip_prefix("pub(super) "))
                .unwrap_or(trimmed);
            let declaration = declaration.strip_prefix("const ").unwrap_or(declaration);
            if !declaration.starts_with("fn ") || line.trim_end().ends_with(';') {
                continue;
            }
            let closing = format!("{indent}}}");
            if let Some(end) = lines[i + 1..].iter().position(|l| *l == closing) {
                let name: String = declaration[3..].chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
                found.push((end + 2, format!("{}: {name}", path.strip_prefix(src).unwrap().display())));
            }
        }
    }
    found
}

#[test]
fn no_function_outside_the_tests_is_longer_than_120_lines() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let lengths = function_lengths(&src);
    assert!(lengths.len() > 300, "the functions are found: {}", lengths.len());
    let long: Vec<_> = lengths.iter().filter(|(n, _)| *n > 120).collect();
    assert!(long.is_empty(), "functions over 120 lines: {long:?}");
}

#[test]
fn nothing_in_the_repository_points_outside_it() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let output =
        std::process::Command::new("git").arg("-C").arg(root).args(["ls-files", "-z"]).output().expect("run git");
    assert!(output.status.success(), "git ls-files (ci/setup.sh --test installs git)");
    // Spelled in pieces, so that this file does not match itself.
    let patterns = [
        ["..", "/shared"].concat(),
        ["/wo", "rk/"].concat(),
        ["/ho", "me/"].concat(),
        ["/ro", "ot/"].concat(),
        ["/Us", "ers/"].concat(),
    ];
    let mut found = Vec::new();
    let files: Vec<&str> = std::str::from_utf8(&output.stdout).unwrap().split('\0').filter(|f| !f.is_empty()).collect();
    assert!(files.len() > 100, "the repository's files are listed: {}", files.len());
    for file in files {
        let Ok(text) = std::fs::read_to_string(root.join(file)) else { continue }; // binary
        for (n, line) in text.lines().enumerate() {
            if let Some(p) = patterns.iter().find(|p| line.contains(p.as_str())) {
                found.push(format!("{file}:{}: {p}", n + 1));
            }
        }
    }
    assert!(found.is_empty(), "references to files outside the repository:\n{}", found.join("\n"));
}

/// The section numbers of docs/design.md's headings ("## 5. ...", "### 5.1 ...").
fn design_sections(root: &Path) -> BTreeSet<String> {
    let design = std::fs::read_to_string(root.join("docs/design.md")).unwrap();
    design
        .lines()
        .filter_map(|line| {
            let rest = line.strip_prefix('#')?.trim_start_matches('#').trim_start();
            let number: String = rest.chars().take_while(|c| c.is_ascii_digit() || *c == '.').collect();
            let number = number.trim_end_matches('.');
            (!number.is_empty()).then(|| number.to_string())
        })
        .collect()
}

/// Every "design §N.M" the source cites (`docs/design.md §5.3`, a citation
/// wrapped over two comment lines too), with the file and line it is on.
/// In `src/` every section sign is the design's (the glTF specification's
/// sections are written "section 3.11"), which the test also checks.
fn design_citations(root: &Path) -> Vec<(String, usize, String)> {
    let mut files = Vec::new();
    for dir in ["src", "tests", "benches"] {
        rust_files(&root.join(dir), &mut files);
    }
    let mut citations = Vec::new();
    for file in files {
        let text = std::fs::read_to_string(&file).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        for (i, line) in lines.iter().enumerate() {
            for (at, _) in line.match_indices('§') {
                let number: String =
                    line[at + '§'.len_utf8()..].chars().take_while(|c| c.is_ascii_digit() || *c == '.').collect();
                let number = number.trim_end_matches('.').to_string();
                if number.is_empty() {
                    continue; // Not a citation ("§N.M" in prose about them).
                }
                // What precedes it on this line (its comment marker taken
                // off), or at the end of the one before.
                let here = line[..at].trim_start().trim_start_matches('/').trim_start_matches('!').trim();
                let before = if here.is_empty() && i > 0 { lines[i - 1].trim_end() } else { here };
                let cites_design = before.ends_with("design.md") || before.ends_with("design");
                let in_src = file.starts_with(root.join("src"));
                let place = format!("{}:{}", file.strip_prefix(root).unwrap().display(), i + 1);
                assert!(
                    cites_design || !in_src,
                    "{place}: a section sign that is not docs/design.md's ({line}): write another document's sections as \"section N\""
                );
                if cites_design {
                    citations.push((place, i + 1, number));
                }
            }
        }
    }
    citations
}

#[test]
fn every_design_section_the_code_cites_exists() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let sections = design_sections(root);
    assert!(sections.contains("5.3") && sections.contains("13.6"), "{sections:?}");
    let citations = design_citations(root);
    assert!(citations.len() > 40, "the source cites the design often: found {}", citations.len());
    let missing: Vec<String> = citations
        .iter()
        .filter(|(_, _, number)| !sections.contains(number))
        .map(|(place, _, number)| format!("{place}: §{number}"))
        .collect();
    assert!(missing.is_empty(), "sections cited that docs/design.md does not have: {missing:?}");
}
