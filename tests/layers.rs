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

#[test]
fn the_core_depends_on_no_workspace_crate_and_the_glue_only_on_the_core() {
    assert_eq!(
        path_deps(&manifest("crates/core/Cargo.toml")),
        Vec::<String>::new()
    );
    assert_eq!(
        path_deps(&manifest("crates/fmi2/Cargo.toml")),
        ["gearpump-core"]
    );
    let app = path_deps(&manifest("Cargo.toml"));
    assert_eq!(app, ["gearpump-core", "gearpump-fmi2"]);
}

#[test]
fn only_the_glue_may_hold_unsafe_code() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for lib in ["crates/core/src/lib.rs", "src/lib.rs"] {
        let text = std::fs::read_to_string(root.join(lib)).unwrap();
        assert!(
            text.contains("#![forbid(unsafe_code)]"),
            "{lib} does not forbid unsafe code"
        );
    }
}
