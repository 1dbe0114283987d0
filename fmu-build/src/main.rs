//! Builds the FMUs of the models the `gearpump` library packages
//! ([`gearpump::fmi2::FmuModel`]): `GearPump.fmu` (the gear pump) and
//! `TransmissionCircuit.fmu` (the automatic-transmission circuit it feeds).
//! For each: runs `cargo build --release -p <its cdylib crate under fmus/>`
//! (with `$CARGO`, honouring `CARGO_TARGET_DIR` and the workspace settings),
//! takes the cdylib cargo reports, strips its debug information (`strip
//! --strip-debug`, when binutils is installed; the release profile keeps
//! `debug = 1` for profiling), generates `modelDescription.xml` and the
//! documentation from the variable table and writes
//! `<target-dir>/fmu/<modelIdentifier>.fmu` atomically.
//!
//! Output on stdout, one line per FMU built, in the order of `--model`
//! (default: every model, the gear pump first):
//!
//! ```text
//! <path of GearPump.fmu>
//! <path of TransmissionCircuit.fmu>
//! ```
//!
//! so `fmu="$(cargo run -p fmu-build | head -n1)"` is the pump as before.
//! With `--env` each line is `GEARPUMP_FMU=<path>` / `TRANSMISSION_FMU=<path>`
//! instead (the variables the FMU tests read), for `eval` or `export`.
//!
//! `gearpump fmu [--model NAME] [--out PATH]` does the same for one model from
//! an already built `gearpump` binary (it packages the cdylib beside the
//! executable).
//!
//! ```text
//! cargo run -p fmu-build [--release] -- [--model NAME]... [--out PATH] [--lib PATH] [--xml PATH] [--env]
//!   --model NAME  gear-pump or transmission-circuit (repeatable; default both)
//!   --out PATH    where to write the .fmu (one model only; default <target-dir>/fmu/<id>.fmu)
//!   --lib PATH    package this shared library instead of building one (one model only)
//!   --xml PATH    also write modelDescription.xml to PATH (one model only)
//!   --env         print NAME=PATH lines (GEARPUMP_FMU, TRANSMISSION_FMU)
//!   --design FILE the pump design the GearPump.fmu is built for (gear pump only)
//!   --set K=V     override a design value by its dotted TOML path (repeatable)
//! ```

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Stdio};

use gearpump::fmi2::FmuModel;

struct Args {
    models: Vec<FmuModel>,
    out: Option<PathBuf>,
    lib: Option<PathBuf>,
    xml: Option<PathBuf>,
    env: bool,
    design: Option<PathBuf>,
    sets: Vec<String>,
}

const USAGE: &str = "usage: fmu-build [--model gear-pump|transmission-circuit]... [--out PATH] [--lib PATH] [--xml PATH] [--env] [--design FILE] [--set KEY.PATH=VALUE]...";

/// The environment variable the FMU tests read for a model's `.fmu`.
fn env_var(model: FmuModel) -> &'static str {
    match model {
        FmuModel::GearPump => "GEARPUMP_FMU",
        FmuModel::TransmissionCircuit => "TRANSMISSION_FMU",
    }
}

fn parse_args() -> Result<Args, String> {
    let mut args = Args {
        models: Vec::new(),
        out: None,
        lib: None,
        xml: None,
        env: false,
        design: None,
        sets: Vec::new(),
    };
    let mut it = std::env::args_os().skip(1);
    while let Some(a) = it.next() {
        let mut value = |name: &str| {
            it.next()
                .map(PathBuf::from)
                .ok_or_else(|| format!("{name} needs a value\n{USAGE}"))
        };
        match a.to_str() {
            Some("--model") => {
                let v = value("--model")?;
                let name = v.to_string_lossy();
                let m = FmuModel::from_name(&name)
                    .ok_or_else(|| format!("unknown model {name:?}\n{USAGE}"))?;
                if !args.models.contains(&m) {
                    args.models.push(m);
                }
            }
            Some("--out") => args.out = Some(value("--out")?),
            Some("--lib") => args.lib = Some(value("--lib")?),
            Some("--xml") => args.xml = Some(value("--xml")?),
            Some("--env") => args.env = true,
            Some("--design") => args.design = Some(value("--design")?),
            Some("--set") => args
                .sets
                .push(value("--set")?.to_string_lossy().into_owned()),
            Some("-h" | "--help") => {
                println!("{USAGE}");
                std::process::exit(0);
            }
            _ => return Err(format!("unknown argument {a:?}\n{USAGE}")),
        }
    }
    let with_design = args.design.is_some() || !args.sets.is_empty();
    if args.models.is_empty() {
        if args.out.is_some() || args.lib.is_some() || args.xml.is_some() || with_design {
            // the options of one FMU keep meaning the pump, as before there were two
            args.models.push(FmuModel::GearPump);
        } else {
            args.models = FmuModel::ALL.to_vec();
        }
    }
    if args.models.len() > 1 && (args.out.is_some() || args.lib.is_some() || args.xml.is_some()) {
        return Err(format!(
            "--out, --lib and --xml need a single --model\n{USAGE}"
        ));
    }
    if with_design && args.models != [FmuModel::GearPump] {
        return Err(format!(
            "--design and --set apply to the gear pump only\n{USAGE}"
        ));
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

/// Builds the models' cdylib crates in release (one cargo call) and returns
/// each library's path, as cargo reports it (so any target-dir setting is
/// honoured).
fn build_cdylibs(models: &[FmuModel]) -> Result<Vec<PathBuf>, String> {
    let mut cmd = cargo();
    cmd.args([
        "build",
        "--release",
        "--message-format=json-render-diagnostics",
    ]);
    for m in models {
        cmd.args(["-p", m.cargo_package()]);
    }
    let out = cmd
        .stderr(Stdio::inherit())
        .output()
        .map_err(|e| format!("running cargo build: {e}"))?;
    if !out.status.success() {
        return Err("cargo build --release of the FMU crates failed".into());
    }
    let suffix = std::env::consts::DLL_SUFFIX;
    let mut found: Vec<Option<PathBuf>> = vec![None; models.len()];
    for line in out.stdout.split(|&b| b == b'\n') {
        let Ok(msg) = serde_json::from_slice::<serde_json::Value>(line) else {
            continue;
        };
        if msg["reason"] != "compiler-artifact"
            || !msg["target"]["kind"]
                .as_array()
                .is_some_and(|k| k.iter().any(|x| x == "cdylib"))
        {
            continue;
        }
        for (m, slot) in models.iter().zip(found.iter_mut()) {
            if msg["target"]["name"] == m.model_identifier() {
                *slot = msg["filenames"]
                    .as_array()
                    .into_iter()
                    .flatten()
                    .filter_map(|f| f.as_str())
                    .find(|f| f.ends_with(suffix))
                    .map(PathBuf::from);
            }
        }
    }
    models
        .iter()
        .zip(found)
        .map(|(m, f)| {
            f.ok_or_else(|| format!("cargo reported no cdylib for {}", m.cargo_package()))
        })
        .collect()
}

/// The FMUs written, and whether to print them as `NAME=PATH`.
fn run() -> Result<(Vec<(FmuModel, PathBuf)>, bool), String> {
    let args = parse_args()?;
    for &m in &args.models {
        m.check().map_err(|p| {
            format!(
                "the variable table of {} is invalid:\n  {}",
                m.model_identifier(),
                p.join("\n  ")
            )
        })?;
    }
    let design = if args.design.is_some() || !args.sets.is_empty() {
        Some(
            gearpump::fmi2::PumpDesign::load(args.design.as_deref(), &args.sets)
                .map_err(|e| format!("--design: {e}"))?,
        )
    } else {
        None
    };
    if let Some(xml) = &args.xml {
        let text = match &design {
            Some(d) => {
                gearpump::fmi2::xml::model_description_xml_for::<gearpump::fmi2::pump::GearPumpFmu>(
                    &gearpump::fmi2::pump::GearPumpFmu::variables_for(&d.design),
                    &gearpump::fmi2::pump::GearPumpFmu::guid_for_design(&d.toml),
                )
            }
            None => args.models[0].model_description_xml(),
        };
        std::fs::write(xml, text).map_err(|e| format!("{}: {e}", xml.display()))?;
        eprintln!("fmu-build: wrote {}", xml.display());
    }
    let libs = match &args.lib {
        Some(p) => vec![p.clone()],
        None => build_cdylibs(&args.models)?,
    };
    let fmu_dir = match &args.out {
        Some(_) => None,
        None => Some(target_dir()?.join("fmu")),
    };
    let mut written = Vec::new();
    for (&m, lib) in args.models.iter().zip(&libs) {
        let out = match (&args.out, &fmu_dir) {
            (Some(p), _) => p.clone(),
            (None, Some(dir)) => dir.join(format!("{}.fmu", m.model_identifier())),
            (None, None) => unreachable!("fmu_dir is set when --out is not"),
        };
        let packaged = m
            .package_design(&out, lib, design.as_ref())
            .map_err(|e| e.to_string())?;
        if !packaged.stripped {
            eprintln!(
                "fmu-build: note: `strip` not found or failed; {} is packaged with its debug information",
                lib.display()
            );
        }
        written.push((m, packaged.path));
    }
    Ok((written, args.env))
}

fn main() -> ExitCode {
    match run() {
        Ok((paths, env)) => {
            for (m, path) in paths {
                if env {
                    println!("{}={}", env_var(m), path.display());
                } else {
                    println!("{}", path.display());
                }
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("fmu-build: {e}");
            ExitCode::FAILURE
        }
    }
}
