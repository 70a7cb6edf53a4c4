//! The workspace keeps its shape: no circle of files inside any crate (a
//! file that uses another never ends up used by it, through any chain),
//! the product never depends on the research in `lab/`, and no crate
//! declares a dependency its code does not use.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const CRATES: [&str; 7] = ["ubf-core", "perception", "behaviors", "robots", "session", "lab", "."];

/// Every `.rs` file under `src`, by module path (`sim::camera`).
fn modules(src: &Path) -> BTreeMap<String, PathBuf> {
    let mut found = BTreeMap::new();
    let mut stack = vec![src.to_owned()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let relative = path.strip_prefix(src).unwrap().with_extension("");
                let mut parts: Vec<String> = relative.iter().map(|p| p.to_string_lossy().into_owned()).collect();
                if matches!(parts.last().map(String::as_str), Some("mod" | "lib" | "main")) {
                    parts.pop();
                }
                found.insert(parts.join("::"), path);
            }
        }
    }
    found
}

/// The modules of `modules` that `name`'s code (not its comments, not its
/// tests) names through `crate::` or `super::`.
fn uses(name: &str, path: &Path, modules: &BTreeMap<String, PathBuf>) -> BTreeSet<String> {
    let text = std::fs::read_to_string(path).unwrap();
    let code: String = text
        .lines()
        .take_while(|line| !line.trim_start().starts_with("#[cfg(test)]"))
        .filter(|line| !line.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n");
    let parent: Vec<&str> = name.split("::").filter(|s| !s.is_empty()).collect();
    let parent = &parent[..parent.len().saturating_sub(1)];
    let mut used = BTreeSet::new();
    for (prefix, base) in [("crate::", &[][..]), ("super::", parent)] {
        for (at, _) in code.match_indices(prefix) {
            let rest = &code[at + prefix.len()..];
            let path: Vec<&str> = rest
                .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == ':'))
                .next()
                .unwrap_or("")
                .split("::")
                .collect();
            // The longest module the path names.
            let named = (1..=path.len()).rev().find_map(|k| {
                let candidate: Vec<&str> = base.iter().copied().chain(path[..k].iter().copied()).collect();
                let candidate = candidate.join("::");
                modules.contains_key(&candidate).then_some(candidate)
            });
            if let Some(module) = named.filter(|m| m != name) {
                used.insert(module);
            }
        }
    }
    used
}

/// The circles of a crate's files: sets of modules that use each other.
fn circles(src: &Path) -> Vec<BTreeSet<String>> {
    let modules = modules(src);
    let graph: BTreeMap<String, BTreeSet<String>> =
        modules.iter().map(|(name, path)| (name.clone(), uses(name, path, &modules))).collect();
    // Two modules are in one circle when each reaches the other.
    let reach = |from: &String| {
        let mut seen = BTreeSet::new();
        let mut stack = vec![from.clone()];
        while let Some(m) = stack.pop() {
            for next in &graph[&m] {
                if seen.insert(next.clone()) {
                    stack.push(next.clone());
                }
            }
        }
        seen
    };
    let reached: BTreeMap<&String, BTreeSet<String>> = graph.keys().map(|m| (m, reach(m))).collect();
    let mut found: Vec<BTreeSet<String>> = Vec::new();
    for (m, reaches) in &reached {
        let circle: BTreeSet<String> = reaches.iter().filter(|o| reached[o].contains(*m)).cloned().collect();
        if !circle.is_empty() && !found.contains(&circle) {
            found.push(circle);
        }
    }
    found
}

#[test]
fn no_crate_has_a_circle_of_files() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for krate in CRATES {
        let found = circles(&root.join(krate).join("src"));
        assert!(found.is_empty(), "{krate}: files that use each other: {found:?}");
    }
}

#[test]
fn the_circle_finder_finds_a_circle() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("lib.rs"), "mod a;\nmod b;\n").unwrap();
    std::fs::write(dir.path().join("a.rs"), "use crate::b::B;\n// crate::nothing\n").unwrap();
    std::fs::write(dir.path().join("b.rs"), "pub struct B;\nfn f() { crate::a::g() }\n").unwrap();
    assert_eq!(circles(dir.path()), vec![BTreeSet::from(["a".to_owned(), "b".to_owned()])]);
}

#[test]
fn the_product_never_depends_on_the_lab() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for krate in ["ubf-core", "perception", "behaviors", "robots", "session"] {
        let manifest = std::fs::read_to_string(root.join(krate).join("Cargo.toml")).unwrap();
        assert!(!manifest.contains("ubf-lab"), "{krate}/Cargo.toml depends on the lab");
        for path in modules(&root.join(krate).join("src")).values() {
            let text = std::fs::read_to_string(path).unwrap();
            assert!(!text.contains("ubf_lab"), "{} names the lab", path.display());
        }
    }
}

/// The dependencies `manifest` declares (normal, dev and per-target), as
/// the names code uses them by (`rand_chacha` for `rand-chacha`).
fn declared_dependencies(manifest: &str) -> Vec<String> {
    let mut names = Vec::new();
    let mut in_dependencies = false;
    for line in manifest.lines().map(str::trim) {
        if line.starts_with('[') {
            in_dependencies = line.ends_with("dependencies]") && !line.starts_with("[workspace");
            continue;
        }
        if !in_dependencies || line.is_empty() || line.starts_with('#') {
            continue;
        }
        let name = line.split(['=', '.', ' ']).next().unwrap_or("");
        names.push(name.replace('-', "_"));
    }
    names
}

#[test]
fn every_crate_uses_the_dependencies_it_declares() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for krate in CRATES.iter().copied().chain(["examples/wander"]) {
        let dir = root.join(krate);
        let manifest = std::fs::read_to_string(dir.join("Cargo.toml")).unwrap();
        // The root package's examples/ holds other packages, not its own.
        let folders: &[&str] =
            if krate == "." { &["src", "tests", "benches"] } else { &["src", "tests", "benches", "examples"] };
        let mut code = String::new();
        for folder in folders {
            let mut stack = vec![dir.join(folder)];
            while let Some(path) = stack.pop() {
                if path.is_dir() {
                    stack.extend(std::fs::read_dir(&path).unwrap().map(|e| e.unwrap().path()));
                } else if path.extension().is_some_and(|e| e == "rs") {
                    let text = std::fs::read_to_string(&path).unwrap();
                    code.extend(
                        text.lines().filter(|l| !l.trim_start().starts_with("//")).map(|l| l.to_owned() + "\n"),
                    );
                }
            }
        }
        for name in declared_dependencies(&manifest) {
            let used = [format!("{name}::"), format!("use {name}"), format!("{name}!")]
                .iter()
                .any(|p| code.contains(p.as_str()));
            assert!(used, "{krate}/Cargo.toml declares `{name}`, which its code never names: drop it");
        }
    }
}
