//! Builds the FMU of the model the `gearpump` library exports
//! ([`gearpump::fmi2::ExportedModel`], the gear pump: `GearPump.fmu`): runs
//! `cargo build --release --lib` for the `gearpump` package (with `$CARGO`,
//! honouring `CARGO_TARGET_DIR` and the workspace settings), takes the
//! cdylib cargo reports, strips its debug information (`strip
//! --strip-debug`, when binutils is installed; the release profile keeps
//! `debug = 1` for profiling), generates `modelDescription.xml` and the
//! documentation from the variable table and writes
//! `<target-dir>/fmu/<modelIdentifier>.fmu` atomically, with the bundled
//! design under `resources/`. Prints the FMU's path on stdout.
//!
//! `gearpump fmu [--out PATH]` does the same from an already built
//! `gearpump` binary (it packages the cdylib beside the executable).
//!
//! ```text
//! cargo run -p fmu-build [--release] -- [--out PATH] [--lib PATH] [--xml PATH]
//!   --out PATH   where to write the .fmu (default <target-dir>/fmu/<id>.fmu)
//!   --lib PATH   package this shared library instead of building one
//!   --xml PATH   also write modelDescription.xml to PATH
//! ```
//!
//! The packaged model is chosen in one place, `gearpump::fmi2::ExportedModel`
//! (the same type the cdylib exports), so the binary and the XML cannot
//! disagree.

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Stdio};

use gearpump::fmi2::{CoSimModel, ExportedModel as Model};

struct Args {
    out: Option<PathBuf>,
    lib: Option<PathBuf>,
    xml: Option<PathBuf>,
}

const USAGE: &str = "usage: fmu-build [--out PATH] [--lib PATH] [--xml PATH]";

fn parse_args() -> Result<Args, String> {
    let mut args = Args {
        out: None,
        lib: None,
        xml: None,
    };
    let mut it = std::env::args_os().skip(1);
    while let Some(a) = it.next() {
        let mut value = |name: &str| {
            it.next()
                .map(PathBuf::from)
                .ok_or_else(|| format!("{name} needs a path\n{USAGE}"))
        };
        match a.to_str() {
            Some("--out") => args.out = Some(value("--out")?),
            Some("--lib") => args.lib = Some(value("--lib")?),
            Some("--xml") => args.xml = Some(value("--xml")?),
            Some("-h" | "--help") => {
                println!("{USAGE}");
                std::process::exit(0);
            }
            _ => return Err(format!("unknown argument {a:?}\n{USAGE}")),
        }
    }
    Ok(args)
}

fn cargo() -> Command {
    let mut c = Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()));
    c.current_dir(workspace_root());
    c
}

fn workspace_root() -> &'static Path {
    // fmu-build lives in <workspace>/fmu-build.
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap_or(Path::new("."))
}

/// The workspace target directory, as cargo resolves it.
fn target_dir() -> Result<PathBuf, String> {
    let out = cargo()
        .args(["metadata", "--format-version", "1", "--no-deps"])
        .stderr(Stdio::inherit())
        .output()
        .map_err(|e| format!("running cargo metadata: {e}"))?;
    if !out.status.success() {
        return Err("cargo metadata failed".into());
    }
    let v: serde_json::Value =
        serde_json::from_slice(&out.stdout).map_err(|e| format!("reading cargo metadata: {e}"))?;
    v["target_directory"]
        .as_str()
        .map(PathBuf::from)
        .ok_or_else(|| "cargo metadata has no target_directory".into())
}

/// Builds the gearpump cdylib in release and returns its path, as cargo
/// reports it (so any target-dir setting is honoured).
fn build_cdylib() -> Result<PathBuf, String> {
    let out = cargo()
        .args([
            "build",
            "--release",
            "--lib",
            "-p",
            "gearpump",
            "--message-format=json-render-diagnostics",
        ])
        .stderr(Stdio::inherit())
        .output()
        .map_err(|e| format!("running cargo build: {e}"))?;
    if !out.status.success() {
        return Err("cargo build --release --lib -p gearpump failed".into());
    }
    let (_, ext) = gearpump::fmi2::package::platform()
        .ok_or("no FMI platform folder is known for this target")?;
    let suffix = format!(".{ext}");
    let mut found = None;
    for line in out.stdout.split(|&b| b == b'\n') {
        let Ok(msg) = serde_json::from_slice::<serde_json::Value>(line) else {
            continue;
        };
        if msg["reason"] == "compiler-artifact"
            && msg["target"]["name"] == "gearpump"
            && msg["target"]["kind"]
                .as_array()
                .is_some_and(|k| k.iter().any(|x| x == "cdylib"))
        {
            found = msg["filenames"]
                .as_array()
                .into_iter()
                .flatten()
                .filter_map(|f| f.as_str())
                .find(|f| f.ends_with(&suffix))
                .map(PathBuf::from);
        }
    }
    found.ok_or_else(|| "cargo reported no gearpump cdylib".into())
}

fn run() -> Result<PathBuf, String> {
    let args = parse_args()?;
    gearpump::fmi2::check_model::<Model>().map_err(|p| {
        format!(
            "the variable table of {} is invalid:\n  {}",
            Model::MODEL_IDENTIFIER,
            p.join("\n  ")
        )
    })?;
    if let Some(xml) = &args.xml {
        let text = gearpump::fmi2::model_description_xml::<Model>();
        std::fs::write(xml, text).map_err(|e| format!("{}: {e}", xml.display()))?;
        eprintln!("fmu-build: wrote {}", xml.display());
    }
    let lib = match args.lib {
        Some(p) => p,
        None => build_cdylib()?,
    };
    let out = match args.out {
        Some(p) => p,
        None => target_dir()?
            .join("fmu")
            .join(format!("{}.fmu", Model::MODEL_IDENTIFIER)),
    };
    let packaged = gearpump::fmi2::build_exported_fmu(&out, &lib).map_err(|e| e.to_string())?;
    if !packaged.stripped {
        eprintln!("fmu-build: note: `strip` not found or failed; the library is packaged with its debug information");
    }
    Ok(packaged.path)
}

fn main() -> ExitCode {
    match run() {
        Ok(path) => {
            println!("{}", path.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("fmu-build: {e}");
            ExitCode::FAILURE
        }
    }
}
