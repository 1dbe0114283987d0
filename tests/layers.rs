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
