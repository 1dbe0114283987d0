//! The workspace's layers (issue "One house"): a lower crate names no
//! higher one, so Cargo refuses a wrong-way import; only the FMI glue may
//! hold `unsafe` code. Read from the manifests and crate roots themselves.

use std::path::Path;

fn manifest(rel: &str) -> toml::Table {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{rel}: {e}"));
    text.parse().unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// The workspace crates a manifest depends on (path dependencies).
fn path_deps(m: &toml::Table) -> Vec<String> {
    let mut out = Vec::new();
    for section in ["dependencies", "dev-dependencies", "build-dependencies"] {
        if let Some(t) = m.get(section).and_then(|v| v.as_table()) {
            for (name, spec) in t {
                if spec.get("path").is_some() {
                    out.push(name.clone());
                }
            }
        }
    }
    out.sort();
    out
}

/// Each layer and the workspace crates it may name (and names).
const LAYERS: &[(&str, &[&str])] = &[
    ("crates/core/Cargo.toml", &[]),
    ("crates/fmi2/Cargo.toml", &["gearpump-core"]),
    ("crates/campaign/Cargo.toml", &["gearpump-core"]),
    (
        "crates/diagnosis/Cargo.toml",
        &["gearpump-campaign", "gearpump-core"],
    ),
    (
        "crates/fmu-models/Cargo.toml",
        &["gearpump-core", "gearpump-fmi2"],
    ),
    (
        "crates/gearpump/Cargo.toml",
        &[
            "gearpump-campaign",
            "gearpump-core",
            "gearpump-diagnosis",
            "gearpump-fmi2",
            "gearpump-fmu-models",
        ],
    ),
    ("Cargo.toml", &["gearpump"]),
    ("python/Cargo.toml", &["gearpump"]),
];

#[test]
fn every_layer_names_only_the_layers_below_it() {
    for (manifest_path, below) in LAYERS {
        assert_eq!(
            path_deps(&manifest(manifest_path)),
            *below,
            "{manifest_path}"
        );
    }
}

/// The command line's own crates are no library's dependency.
#[test]
fn clap_and_indicatif_belong_to_the_command_line_alone() {
    for (manifest_path, _) in LAYERS.iter().filter(|(m, _)| *m != "Cargo.toml") {
        let m = manifest(manifest_path);
        let deps = m.get("dependencies").and_then(|v| v.as_table()).unwrap();
        for cli in ["clap", "indicatif"] {
            assert!(!deps.contains_key(cli), "{manifest_path} depends on {cli}");
        }
    }
}

#[test]
fn only_the_glue_may_hold_unsafe_code() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for lib in [
        "crates/core/src/lib.rs",
        "crates/campaign/src/lib.rs",
        "crates/diagnosis/src/lib.rs",
        "crates/fmu-models/src/lib.rs",
        "crates/gearpump/src/lib.rs",
    ] {
        let text = std::fs::read_to_string(root.join(lib)).unwrap();
        assert!(
            text.contains("#![forbid(unsafe_code)]"),
            "{lib} does not forbid unsafe code"
        );
    }
}

/// The modules of a crate's `src/` (a file `m.rs` or a folder `m/`, not the
/// crate root) and, for each, the modules of the same crate it names
/// (`crate::m`, or `super::m` from a top-level file), outside its tests and
/// comments.
fn module_graph(src: &Path) -> Vec<(String, Vec<String>)> {
    let mut modules: Vec<(String, Vec<std::path::PathBuf>)> = Vec::new();
    for entry in std::fs::read_dir(src).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        if name == "lib" || name == "main" {
            continue;
        }
        let files = if path.is_dir() {
            let mut v = Vec::new();
            let mut stack = vec![path.clone()];
            while let Some(d) = stack.pop() {
                for e in std::fs::read_dir(&d).unwrap() {
                    let p = e.unwrap().path();
                    if p.is_dir() {
                        stack.push(p);
                    } else if p.extension().is_some_and(|x| x == "rs") {
                        v.push(p);
                    }
                }
            }
            v
        } else if path.extension().is_some_and(|x| x == "rs") {
            vec![path.clone()]
        } else {
            continue;
        };
        modules.push((name, files));
    }
    let names: Vec<String> = modules.iter().map(|(n, _)| n.clone()).collect();
    modules
        .iter()
        .map(|(name, files)| {
            let mut deps = Vec::new();
            for f in files {
                let text = std::fs::read_to_string(f).unwrap();
                let code = text.split("#[cfg(test)]").next().unwrap();
                let top_level = f.parent() == Some(src);
                for line in code.lines().map(str::trim).filter(|l| !l.starts_with("//")) {
                    for other in names.iter().filter(|o| *o != name) {
                        let named = line.contains(&format!("crate::{other}::"))
                            || line.contains(&format!("crate::{other};"))
                            || line.contains(&format!("crate::{other}}}"))
                            || (top_level
                                && (line.contains(&format!("super::{other}::"))
                                    || line.contains(&format!("super::{other};"))
                                    || line.contains(&format!("super::{other}}}"))));
                        if named && !deps.contains(other) {
                            deps.push(other.clone());
                        }
                    }
                }
            }
            (name.clone(), deps)
        })
        .collect()
}

/// No module of a crate names, through others, itself: the arrows inside
/// each crate go one way too (an import circle once made the model build
/// its pump in two phases).
#[test]
fn no_import_circles_inside_the_crates() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for krate in ["core", "fmi2", "campaign", "diagnosis", "fmu-models"] {
        let graph = module_graph(&root.join("crates").join(krate).join("src"));
        // depth-first search for a cycle
        fn visit<'a>(
            m: &'a str,
            graph: &'a [(String, Vec<String>)],
            path: &mut Vec<&'a str>,
            done: &mut Vec<&'a str>,
        ) -> Option<String> {
            if let Some(i) = path.iter().position(|p| *p == m) {
                return Some(format!("{} -> {m}", path[i..].join(" -> ")));
            }
            if done.contains(&m) {
                return None;
            }
            path.push(m);
            let deps = &graph.iter().find(|(n, _)| n == m).unwrap().1;
            for d in deps {
                if let Some(c) = visit(d, graph, path, done) {
                    return Some(c);
                }
            }
            path.pop();
            done.push(m);
            None
        }
        let (mut path, mut done) = (Vec::new(), Vec::new());
        for (m, _) in &graph {
            if let Some(cycle) = visit(m, &graph, &mut path, &mut done) {
                panic!("crates/{krate}: import circle {cycle}");
            }
        }
        assert!(
            graph.len() >= 2,
            "crates/{krate}: {} modules read",
            graph.len()
        );
    }
}
