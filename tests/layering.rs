//! The crate layers of ARCHITECTURE.md, enforced: arrows point down only, and leaf crates stay
//! free of what they must not know (rerun checks its layers the same way).

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests may fail loudly

use std::collections::BTreeSet;
use std::path::Path;

/// Workspace crates each crate may depend on, and outside crates it must not.
const RULES: &[(&str, &str, &[&str], &[&str])] = &[
    // (crate, manifest, allowed mvgrasp crates, forbidden outside crates)
    (
        "mvgrasp-geometry",
        "crates/geometry/Cargo.toml",
        &[],
        &["wgpu", "pyo3", "numpy", "faer", "rapier3d", "safetensors"],
    ),
    (
        "mvgrasp-render",
        "crates/render/Cargo.toml",
        &[],
        &["parry3d", "rapier3d", "pyo3", "numpy", "faer", "nalgebra"],
    ),
    (
        "mvgrasp-infer",
        "crates/infer/Cargo.toml",
        &[],
        &["parry3d", "rapier3d", "wgpu", "pyo3", "numpy", "nalgebra"],
    ),
    (
        "mvgrasp-grasp",
        "crates/grasp/Cargo.toml",
        &["mvgrasp-geometry"],
        &["wgpu", "pyo3", "numpy", "faer"],
    ),
    (
        // Planning on depth images: no renderer, no dataset generator (those live above it,
        // in the root package, and use its crop), no Python.
        "mvgrasp-planner",
        "crates/planner/Cargo.toml",
        &["mvgrasp-geometry", "mvgrasp-grasp", "mvgrasp-infer"],
        &["wgpu", "pyo3", "numpy", "png", "indicatif"],
    ),
    (
        // The runtime: views -> depth -> candidates -> checks -> grasps, and its files. The
        // dataset generators, the evaluation and the command-line tools stand above it in the
        // root package, so it cannot import them.
        "mvgrasp-runtime",
        "crates/runtime/Cargo.toml",
        &[
            "mvgrasp-geometry",
            "mvgrasp-render",
            "mvgrasp-grasp",
            "mvgrasp-infer",
            "mvgrasp-planner",
        ],
        &["pyo3", "numpy", "clap", "indicatif", "sha2"],
    ),
    (
        "mvgrasp",
        "Cargo.toml",
        &[
            "mvgrasp-geometry",
            "mvgrasp-render",
            "mvgrasp-grasp",
            "mvgrasp-infer",
            "mvgrasp-planner",
            "mvgrasp-runtime",
        ],
        &["pyo3", "numpy"],
    ),
    (
        // The fuzz targets call the readers of every crate; nothing depends on them.
        "mvgrasp-fuzz",
        "crates/fuzz/Cargo.toml",
        &[
            "mvgrasp",
            "mvgrasp-geometry",
            "mvgrasp-grasp",
            "mvgrasp-infer",
        ],
        &["pyo3", "numpy"],
    ),
    (
        "mvgrasp-py",
        "py/Cargo.toml",
        &[
            "mvgrasp",
            "mvgrasp-geometry",
            "mvgrasp-render",
            "mvgrasp-grasp",
            "mvgrasp-infer",
            "mvgrasp-planner",
        ],
        &[],
    ),
];

fn dependencies(manifest: &Path) -> BTreeSet<String> {
    let text =
        std::fs::read_to_string(manifest).unwrap_or_else(|e| panic!("{}: {e}", manifest.display()));
    let doc: toml::Table = text
        .parse()
        .unwrap_or_else(|e| panic!("{}: {e}", manifest.display()));
    let mut names = BTreeSet::new();
    // [dependencies], [build-dependencies], and target-specific ones; dev-dependencies may
    // reach further (tests), they do not ship.
    let mut tables = vec![doc.get("dependencies"), doc.get("build-dependencies")];
    if let Some(targets) = doc.get("target").and_then(|t| t.as_table()) {
        for target in targets.values() {
            tables.push(target.get("dependencies"));
            tables.push(target.get("build-dependencies"));
        }
    }
    for table in tables.into_iter().flatten().filter_map(|t| t.as_table()) {
        for (key, value) in table {
            let package = value.get("package").and_then(|p| p.as_str()).unwrap_or(key);
            names.insert(package.to_string());
        }
    }
    names
}

fn check(name: &str, deps: &BTreeSet<String>, allowed: &[&str], forbidden: &[&str]) -> Vec<String> {
    let layers: BTreeSet<&str> = RULES.iter().map(|r| r.0).collect();
    let mut violations = Vec::new();
    for dep in deps {
        if layers.contains(dep.as_str()) && !allowed.contains(&dep.as_str()) {
            violations.push(format!("{name} depends on {dep}: not a layer below it"));
        }
        if forbidden.contains(&dep.as_str()) {
            violations.push(format!("{name} depends on {dep}, which it must not know"));
        }
    }
    violations
}

#[test]
fn crates_depend_only_downwards_and_leaves_stay_leaves() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let violations: Vec<String> = RULES
        .iter()
        .flat_map(|&(name, manifest, allowed, forbidden)| {
            check(
                name,
                &dependencies(&root.join(manifest)),
                allowed,
                forbidden,
            )
        })
        .collect();
    assert!(
        violations.is_empty(),
        "layering violations:\n{}",
        violations.join("\n")
    );
}

#[test]
fn every_workspace_member_has_a_rule() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let doc: toml::Table = std::fs::read_to_string(root.join("Cargo.toml"))
        .unwrap()
        .parse()
        .unwrap();
    let members = doc["workspace"]["members"].as_array().unwrap();
    for member in members {
        let manifest = format!("{}/Cargo.toml", member.as_str().unwrap());
        assert!(
            RULES.iter().any(|r| r.1 == manifest),
            "{manifest} has no layering rule"
        );
    }
    // The Python crate stays out of default-members: a bare `cargo test` needs no Python.
    let defaults = doc["workspace"]["default-members"].as_array().unwrap();
    assert!(!defaults.iter().any(|m| m.as_str() == Some("py")));
}

#[test]
fn the_checker_catches_an_upward_arrow() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dir.path().join("Cargo.toml");
    std::fs::write(&manifest, "[package]\nname='x'\n[dependencies]\nrender = { package = 'mvgrasp-render', path = '..' }\nwgpu = '30'\n").unwrap();
    let deps = dependencies(&manifest);
    assert!(
        deps.contains("mvgrasp-render") && deps.contains("wgpu"),
        "renamed packages count"
    );
    let (_, _, allowed, forbidden) = RULES[2]; // infer
    let violations = check("mvgrasp-infer", &deps, allowed, forbidden);
    assert_eq!(violations.len(), 2, "{violations:?}");
}

/// The checker catches the arrows the layers exist to forbid: the planner reaching the dataset
/// generators (the root package) or the renderer; the runtime reaching the root package (the
/// dataset generators, the evaluation, the CLIs) or a command-line parser.
#[test]
fn the_planner_and_the_runtime_cannot_reach_above_them() {
    for (crate_name, dependencies_toml) in [
        (
            "mvgrasp-planner",
            "mvgrasp = { path = '..' }\nmvgrasp-render = { path = '..' }\n",
        ),
        ("mvgrasp-runtime", "mvgrasp = { path = '..' }\nclap = '4'\n"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let manifest = dir.path().join("Cargo.toml");
        std::fs::write(
            &manifest,
            format!("[package]\nname='x'\n[dependencies]\n{dependencies_toml}"),
        )
        .unwrap();
        let rule = RULES.iter().find(|r| r.0 == crate_name).unwrap();
        let violations = check(rule.0, &dependencies(&manifest), rule.2, rule.3);
        assert_eq!(violations.len(), 2, "{crate_name}: {violations:?}");
    }
}

/// The modules each module of a crate's `src/` names (`crate::NAME`), in its code before its
/// tests (comments left out).
fn module_imports(src: &Path) -> std::collections::BTreeMap<String, BTreeSet<String>> {
    let mut graph = std::collections::BTreeMap::new();
    for entry in std::fs::read_dir(src).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "rs") {
            continue;
        }
        let name = path.file_stem().unwrap().to_str().unwrap().to_string();
        let text = std::fs::read_to_string(&path).unwrap();
        let code = text.split("#[cfg(test)]").next().unwrap_or("");
        let mut names = BTreeSet::new();
        for line in code
            .lines()
            .filter(|line| !line.trim_start().starts_with("//"))
        {
            for (at, _) in line.match_indices("crate::") {
                let rest = &line[at + "crate::".len()..];
                let used: String = rest
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if !used.is_empty() && used != name {
                    names.insert(used);
                }
            }
        }
        graph.insert(name, names);
    }
    graph
}

/// A circle of modules in `graph`, if there is one (each module then imports the next).
fn a_circle(graph: &std::collections::BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        node: &str,
        graph: &std::collections::BTreeMap<String, BTreeSet<String>>,
        path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) -> Option<Vec<String>> {
        if let Some(start) = path.iter().position(|n| n == node) {
            let mut circle = path[start..].to_vec();
            circle.push(node.to_string());
            return Some(circle);
        }
        if done.contains(node) {
            return None;
        }
        path.push(node.to_string());
        for next in graph.get(node).into_iter().flatten() {
            if graph.contains_key(next)
                && let Some(circle) = visit(next, graph, path, done)
            {
                return Some(circle);
            }
        }
        path.pop();
        done.insert(node.to_string());
        None
    }
    let mut done = BTreeSet::new();
    graph
        .keys()
        .find_map(|node| visit(node, graph, &mut Vec::new(), &mut done))
}

#[test]
fn the_planner_crate_has_no_circle_of_modules() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/planner/src");
    let graph = module_imports(&src);
    assert!(graph.len() > 10, "{} modules found", graph.len());
    assert!(graph["virtual_view"].contains("policy"), "{graph:?}");
    if let Some(circle) = a_circle(&graph) {
        panic!("a circle of modules: {}", circle.join(" -> "));
    }
}

#[test]
fn the_circle_finder_finds_a_circle() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("a.rs"), "use crate::b::B;\n").unwrap();
    std::fs::write(
        dir.path().join("b.rs"),
        "// crate::c in a comment\nuse crate::c::C;\n#[cfg(test)]\nmod tests { use crate::a::A; }\n",
    )
    .unwrap();
    std::fs::write(dir.path().join("c.rs"), "pub fn f() { crate::a::g(); }\n").unwrap();
    let graph = module_imports(dir.path());
    let circle = a_circle(&graph).unwrap();
    assert_eq!(circle, ["a", "b", "c", "a"]);
    std::fs::write(dir.path().join("c.rs"), "pub fn f() {}\n").unwrap();
    assert_eq!(a_circle(&module_imports(dir.path())), None);
}
