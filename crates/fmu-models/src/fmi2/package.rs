//! Zips an FMU: `modelDescription.xml`, `binaries/<platform>/<id>.so`,
//! `resources/...`, `documentation/index.html`. The file is written to a
//! temporary name beside the target and renamed, so a reader never sees a
//! half-written FMU.

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

use zip::write::SimpleFileOptions;
use zip::{CompressionMethod, ZipWriter};

use super::model::{check_model, is_c_identifier, CoSimModel};

/// Errors of [`build_fmu`].
#[derive(Debug, thiserror::Error)]
pub enum PackageError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("writing the zip archive: {0}")]
    Zip(#[from] zip::result::ZipError),
    #[error("writing the zip archive: {0}")]
    ZipName(String),
    #[error("invalid modelIdentifier {0:?} (must be a C identifier)")]
    ModelIdentifier(String),
    #[error("invalid resource name {0:?} (relative, '/'-separated, no '..')")]
    ResourceName(String),
    #[error("the model's variable table is invalid:\n  {}", .0.join("\n  "))]
    Model(Vec<String>),
    #[error("no FMI platform folder is known for this target (only linux64, win64, darwin64)")]
    Platform,
    #[error("{0}")]
    NoLibrary(String),
    #[error("--design applies to the gear pump only, not to {0}")]
    DesignNotApplicable(&'static str),
}

/// The pump design a `GearPump.fmu` is built for: the TOML text it ships in
/// `resources/design.toml` and the design that text loads to (see
/// `gearpump_core::design::load_with_text`, which applies `--set`
/// overrides to the text).
#[derive(Debug, Clone)]
pub struct PumpDesign {
    pub toml: String,
    pub design: gearpump_core::design::Design,
}

impl PumpDesign {
    /// The design of `path` (the bundled one when None) with `sets`; the
    /// error names the file and the key.
    pub fn load(
        path: Option<&Path>,
        sets: &[String],
    ) -> Result<PumpDesign, gearpump_core::design::DesignError> {
        let (toml, design) = gearpump_core::design::load_with_text(path, sets)?;
        Ok(PumpDesign { toml, design })
    }
}

/// `GearPump.fmu` of `design`: the variable table with the design's start
/// values, its design file and section tables under `resources/`.
fn build_pump_fmu_of(out: &Path, so_path: &Path, design: &PumpDesign) -> Result<(), PackageError> {
    use super::pump::GearPumpFmu;
    check_model::<GearPumpFmu>().map_err(PackageError::Model)?;
    let vars = GearPumpFmu::variables_for(&design.design);
    let guid = GearPumpFmu::guid_for_design(&design.toml);
    build_fmu(
        out,
        GearPumpFmu::MODEL_IDENTIFIER,
        &super::xml::model_description_xml_for::<GearPumpFmu>(&vars, &guid),
        so_path,
        &GearPumpFmu::resource_files_for(&design.toml, design.design.clone()),
        &super::xml::documentation_html_for::<GearPumpFmu>(&vars, &guid),
    )
}

/// The FMI 2.0 platform folder of the target this crate is compiled for
/// (`linux64`, `win64`, `darwin64`) and its shared-library extension.
pub fn platform() -> Option<(&'static str, &'static str)> {
    if cfg!(all(target_os = "linux", target_pointer_width = "64")) {
        Some(("linux64", "so"))
    } else if cfg!(all(target_os = "windows", target_pointer_width = "64")) {
        Some(("win64", "dll"))
    } else if cfg!(all(target_os = "macos", target_pointer_width = "64")) {
        Some(("darwin64", "dylib"))
    } else {
        None
    }
}

fn valid_resource_name(name: &str) -> bool {
    !name.is_empty()
        && !name.starts_with('/')
        && !name.contains('\\')
        && !name.contains('\0')
        && name
            .split('/')
            .all(|part| !part.is_empty() && part != "." && part != "..")
}

/// The longest entry name a zip archive can hold, bytes (a 16-bit field).
pub(crate) const ZIP_NAME_MAX: usize = u16::MAX as usize;

/// Refuses a zip entry name the archive cannot hold (the zip crate panics
/// on one instead of returning an error).
pub(crate) fn check_zip_name(name: &str) -> Result<(), String> {
    if name.len() > ZIP_NAME_MAX {
        let start: String = name.chars().take(32).collect();
        return Err(format!(
            "entry name {start:?}... of {} bytes, longer than a zip entry name can be ({ZIP_NAME_MAX} bytes)",
            name.len()
        ));
    }
    Ok(())
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> PackageError + '_ {
    move |source| PackageError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Writes the FMU `out` (atomically: temporary file + rename; parent
/// folders are created). `so_path` is the built shared library, stored as
/// `binaries/<platform>/<model_identifier>.<ext>`; `resources` are
/// `(relative path, bytes)` under `resources/` (the folder is always
/// present, as `fmi2Instantiate` requires it).
pub fn build_fmu(
    out: &Path,
    model_identifier: &str,
    xml: &str,
    so_path: &Path,
    resources: &[(String, Vec<u8>)],
    documentation_html: &str,
) -> Result<(), PackageError> {
    if !is_c_identifier(model_identifier) {
        return Err(PackageError::ModelIdentifier(model_identifier.to_string()));
    }
    if let Some((name, _)) = resources.iter().find(|(n, _)| !valid_resource_name(n)) {
        return Err(PackageError::ResourceName(name.clone()));
    }
    let (platform, ext) = platform().ok_or(PackageError::Platform)?;
    // every entry name fits a zip archive (checked before any file is made;
    // the folders' entries are shorter than the files' in them)
    let fits = |name: &str| check_zip_name(name).map_err(PackageError::ZipName);
    fits(&format!("binaries/{platform}/{model_identifier}.{ext}"))?;
    for (name, _) in resources {
        fits(&format!("resources/{name}"))?;
    }
    let binary = std::fs::read(so_path).map_err(io_err(so_path))?;

    let dir = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir).map_err(io_err(&dir))?;
    let file_name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "model.fmu".into());
    let tmp = dir.join(format!(".{file_name}.tmp-{}", std::process::id()));

    let result = (|| {
        let file = File::create(&tmp).map_err(io_err(&tmp))?;
        let mut zip = ZipWriter::new(file);
        let deflate = SimpleFileOptions::default()
            .compression_method(CompressionMethod::Deflated)
            .unix_permissions(0o644);
        let dirs = SimpleFileOptions::default().unix_permissions(0o755);

        zip.start_file("modelDescription.xml", deflate)?;
        zip.write_all(xml.as_bytes()).map_err(io_err(&tmp))?;

        zip.add_directory("binaries/", dirs)?;
        zip.add_directory(format!("binaries/{platform}/"), dirs)?;
        zip.start_file(
            format!("binaries/{platform}/{model_identifier}.{ext}"),
            deflate.unix_permissions(0o755),
        )?;
        zip.write_all(&binary).map_err(io_err(&tmp))?;

        zip.add_directory("resources/", dirs)?;
        let mut made_dirs: Vec<String> = Vec::new();
        for (name, bytes) in resources {
            // Parent folders first, so every unzip tool creates them.
            let parts: Vec<&str> = name.split('/').collect();
            for k in 1..parts.len() {
                let d = format!("resources/{}/", parts[..k].join("/"));
                if !made_dirs.contains(&d) {
                    zip.add_directory(d.clone(), dirs)?;
                    made_dirs.push(d);
                }
            }
            zip.start_file(format!("resources/{name}"), deflate)?;
            zip.write_all(bytes).map_err(io_err(&tmp))?;
        }

        zip.add_directory("documentation/", dirs)?;
        zip.start_file("documentation/index.html", deflate)?;
        zip.write_all(documentation_html.as_bytes())
            .map_err(io_err(&tmp))?;

        let file = zip.finish()?;
        file.sync_all().map_err(io_err(&tmp))?;
        std::fs::rename(&tmp, out).map_err(io_err(out))
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Checks model `M`'s table, then writes its FMU with the generated XML,
/// documentation and [`CoSimModel::resource_files`]; `so_path` must be a
/// library that exports `M` (see [`gearpump_fmi2::export_fmi2!`]).
pub fn build_model_fmu<M: CoSimModel>(out: &Path, so_path: &Path) -> Result<(), PackageError> {
    check_model::<M>().map_err(PackageError::Model)?;
    build_fmu(
        out,
        M::MODEL_IDENTIFIER,
        &super::xml::model_description_xml::<M>(),
        so_path,
        &M::resource_files(),
        &super::xml::documentation_html::<M>(),
    )
}

/// A fresh folder under the system's temporary folder, removed with what
/// it holds when dropped: scratch files of the packaging live there, never
/// in the user's output folder (a run killed half-way leaves nothing there).
pub struct ScratchDir(PathBuf);

impl ScratchDir {
    /// Creates `<temp>/gearpump-<what>-<pid>-<n>` (a new name each call).
    pub fn new(what: &str) -> std::io::Result<ScratchDir> {
        use std::sync::atomic::{AtomicUsize, Ordering};
        static N: AtomicUsize = AtomicUsize::new(0);
        let base = std::env::temp_dir();
        loop {
            let dir = base.join(format!(
                "gearpump-{what}-{}-{}",
                std::process::id(),
                N.fetch_add(1, Ordering::Relaxed)
            ));
            match std::fs::create_dir(&dir) {
                Ok(()) => return Ok(ScratchDir(dir)),
                // left by an earlier process of the same id: take the next
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
                Err(e) => return Err(e),
            }
        }
    }

    /// The folder.
    pub fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A copy of the shared library `so` without debug information, written
/// into the folder `scratch` (a [`ScratchDir`], not the output folder) by
/// `strip --strip-debug` (binutils). `None` when no `strip` program is
/// found or it fails: the caller then packages `so` as it is (larger, same
/// behaviour).
pub fn strip_debuginfo(so: &Path, scratch: &Path) -> Option<PathBuf> {
    let name = so.file_name()?.to_string_lossy().into_owned();
    let tmp = scratch.join(format!("{name}.stripped"));
    let status = std::process::Command::new("strip")
        .arg("--strip-debug")
        .arg("-o")
        .arg(&tmp)
        .arg(so)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .ok()?;
    if status.success() && tmp.is_file() {
        Some(tmp)
    } else {
        let _ = std::fs::remove_file(&tmp);
        None
    }
}

/// What [`FmuModel::package`] did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Packaged {
    /// The `.fmu` written.
    pub path: PathBuf,
    /// Whether the library's debug information was stripped.
    pub stripped: bool,
    /// Whether the packaged library is an unoptimised (debug) build: it
    /// works but steps about 20 times slower.
    pub debug_build: bool,
}

/// The models packaged as FMUs, each exported by its own thin cdylib crate
/// under `fmus/` (one `export_fmi2!` line). `fmu-build` and `gearpump fmu`
/// go through this list, so the binary packaged and the XML generated always
/// name the same model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FmuModel {
    /// `GearPump.fmu`: [`super::pump::GearPumpFmu`], crate `fmus/gear-pump`.
    GearPump,
    /// `TransmissionCircuit.fmu`: [`super::circuit::TransmissionCircuitFmu`],
    /// crate `fmus/transmission-circuit`.
    TransmissionCircuit,
}

/// Calls `$f::<M>($args)` with `M` the model type of `$self`.
macro_rules! with_model {
    ($self:expr, $f:ident ( $($arg:expr),* )) => {
        match $self {
            FmuModel::GearPump => $f::<super::pump::GearPumpFmu>($($arg),*),
            FmuModel::TransmissionCircuit => {
                $f::<super::circuit::TransmissionCircuitFmu>($($arg),*)
            }
        }
    };
}

fn identifier<M: CoSimModel>() -> &'static str {
    M::MODEL_IDENTIFIER
}
fn guid<M: CoSimModel>() -> &'static str {
    M::GUID
}

impl FmuModel {
    /// Every packaged model.
    pub const ALL: [FmuModel; 2] = [FmuModel::GearPump, FmuModel::TransmissionCircuit];

    /// The name used on the command line (`--model NAME`), which is also the
    /// folder of its crate under `fmus/`.
    pub fn name(self) -> &'static str {
        match self {
            FmuModel::GearPump => "gear-pump",
            FmuModel::TransmissionCircuit => "transmission-circuit",
        }
    }

    /// The model named `name` ([`FmuModel::name`] or its modelIdentifier).
    pub fn from_name(name: &str) -> Option<FmuModel> {
        Self::ALL
            .into_iter()
            .find(|m| m.name() == name || m.model_identifier() == name)
    }

    /// The cargo package of its cdylib crate.
    pub fn cargo_package(self) -> &'static str {
        match self {
            FmuModel::GearPump => "gear-pump-fmu",
            FmuModel::TransmissionCircuit => "transmission-circuit-fmu",
        }
    }

    /// `modelIdentifier` (also the cdylib crate's library name).
    pub fn model_identifier(self) -> &'static str {
        with_model!(self, identifier())
    }

    /// `guid`.
    pub fn guid(self) -> &'static str {
        with_model!(self, guid())
    }

    /// The shared library cargo writes for the cdylib crate, e.g.
    /// `libGearPump.so` on Linux.
    pub fn cdylib_file_name(self) -> String {
        format!(
            "{}{}{}",
            std::env::consts::DLL_PREFIX,
            self.model_identifier(),
            std::env::consts::DLL_SUFFIX
        )
    }

    /// The committed model description, relative to the repository root.
    pub fn committed_xml(self) -> &'static str {
        match self {
            FmuModel::GearPump => "modelDescription/modelDescription.xml",
            FmuModel::TransmissionCircuit => "modelDescription/TransmissionCircuit.xml",
        }
    }

    /// Checks the variable table ([`check_model`]).
    pub fn check(self) -> Result<(), Vec<String>> {
        with_model!(self, check_model())
    }

    /// `modelDescription.xml`, generated from the variable table.
    pub fn model_description_xml(self) -> String {
        with_model!(self, model_description_xml_of())
    }

    /// Writes the FMU `out` from the built cdylib `so` of this model, with
    /// its debug information stripped when `strip` is available (see
    /// [`strip_debuginfo`]).
    pub fn package(self, out: &Path, so: &Path) -> Result<Packaged, PackageError> {
        self.package_design(out, so, None)
    }

    /// [`package`](Self::package) for `design` (gear pump only; None: the
    /// bundled design).
    pub fn package_design(
        self,
        out: &Path,
        so: &Path,
        design: Option<&PumpDesign>,
    ) -> Result<Packaged, PackageError> {
        if design.is_some() && self != FmuModel::GearPump {
            return Err(PackageError::DesignNotApplicable(self.model_identifier()));
        }
        if !so.is_file() {
            return Err(PackageError::Io {
                path: so.to_path_buf(),
                source: std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"),
            });
        }
        // the stripped copy in a scratch folder of its own (removed when
        // `scratch` drops), never beside `out`
        let scratch = ScratchDir::new("strip").ok();
        let stripped = scratch.as_ref().and_then(|d| strip_debuginfo(so, d.path()));
        let lib = stripped.as_deref().unwrap_or(so);
        let result = match design {
            Some(d) => build_pump_fmu_of(out, lib, d),
            None => with_model!(self, build_model_fmu(out, lib)),
        };
        drop(scratch);
        result.map(|()| Packaged {
            path: out.to_path_buf(),
            stripped: stripped.is_some(),
            debug_build: false,
        })
    }
}

fn model_description_xml_of<M: CoSimModel>() -> String {
    super::xml::model_description_xml::<M>()
}

/// `GearPump.fmu` from the built cdylib `so` (`libGearPump.so`):
/// [`FmuModel::GearPump`]`.package(out, so)`.
pub fn build_exported_fmu(out: &Path, so: &Path) -> Result<Packaged, PackageError> {
    FmuModel::GearPump.package(out, so)
}

/// `gearpump fmu` for the gear pump: [`build_model_fmu_beside_exe`].
pub fn build_fmu_beside_exe(out: Option<&Path>) -> Result<Packaged, PackageError> {
    build_model_fmu_beside_exe(FmuModel::GearPump, out)
}

/// `gearpump fmu [--model NAME]`: the FMU of `model` from its cdylib
/// (`lib<modelIdentifier>.so`) cargo built beside the running executable
/// (`target/<profile>/`, or `deps/` below it), so binary and XML come from
/// the same build. When it is not there and the executable sits in a cargo
/// target folder of this workspace, it is built first with `cargo build -p
/// <crate>` in the executable's profile (`$CARGO`, default `cargo`; cargo's
/// output goes to stderr). `out` defaults to
/// `target/fmu/<modelIdentifier>.fmu` (the path `fmu-build` writes) when the
/// executable sits in cargo's target folder, else `<modelIdentifier>.fmu` in
/// the current folder.
pub fn build_model_fmu_beside_exe(
    model: FmuModel,
    out: Option<&Path>,
) -> Result<Packaged, PackageError> {
    build_model_fmu_beside_exe_with(model, out, None)
}

/// [`build_model_fmu_beside_exe`] for `design` (gear pump only).
pub fn build_model_fmu_beside_exe_with(
    model: FmuModel,
    out: Option<&Path>,
    design: Option<&PumpDesign>,
) -> Result<Packaged, PackageError> {
    if design.is_some() && model != FmuModel::GearPump {
        return Err(PackageError::DesignNotApplicable(model.model_identifier()));
    }
    platform().ok_or(PackageError::Platform)?;
    let exe = std::env::current_exe().map_err(|e| PackageError::NoLibrary(e.to_string()))?;
    let dir = exe.parent().unwrap_or(Path::new(".")).to_path_buf();
    let name = model.cdylib_file_name();
    let profile = dir.file_name().and_then(|n| n.to_str());
    let target = match (profile, dir.parent()) {
        (Some("release" | "debug"), Some(target)) => Some(target.to_path_buf()),
        _ => None,
    };
    let find = || {
        [dir.clone(), dir.join("deps"), dir.join("..")]
            .iter()
            .map(|d| d.join(&name))
            .find(|p| p.is_file())
    };
    let so = match find() {
        Some(so) => so,
        None => {
            if let (Some(target), Some(profile)) = (&target, profile) {
                cargo_build_cdylib(model, target, profile)?;
            }
            find().ok_or_else(|| {
                PackageError::NoLibrary(format!(
                    "{name} not found beside {}: build it with `cargo build --release -p {}` \
                     (or run `cargo run -p fmu-build --release`)",
                    exe.display(),
                    model.cargo_package()
                ))
            })?
        }
    };
    let out = match out {
        Some(p) => p.to_path_buf(),
        None => target
            .map(|t| t.join("fmu"))
            .unwrap_or_else(|| PathBuf::from("."))
            .join(format!("{}.fmu", model.model_identifier())),
    };
    let mut packaged = model.package_design(&out, &so, design)?;
    packaged.debug_build = cfg!(debug_assertions);
    Ok(packaged)
}

/// `cargo build -p <crate of model>` into `target` for `profile` (release
/// or debug), in the workspace this library was compiled from; quietly does
/// nothing when that workspace is not there any more.
fn cargo_build_cdylib(model: FmuModel, target: &Path, profile: &str) -> Result<(), PackageError> {
    // this crate lives in crates/fmu-models of the workspace
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let root = root.as_path();
    if !root
        .join("fmus")
        .join(model.name())
        .join("Cargo.toml")
        .is_file()
    {
        return Ok(());
    }
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let mut cmd = std::process::Command::new(cargo);
    cmd.current_dir(root)
        .args(["build", "-p", model.cargo_package()])
        .env("CARGO_TARGET_DIR", target)
        .stdout(std::process::Stdio::null());
    if profile == "release" {
        cmd.arg("--release");
    }
    let status = cmd
        .status()
        .map_err(|e| PackageError::NoLibrary(format!("running cargo: {e}")))?;
    if status.success() {
        Ok(())
    } else {
        Err(PackageError::NoLibrary(format!(
            "cargo build -p {} failed",
            model.cargo_package()
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn model_list_names_and_identifiers() {
        for m in FmuModel::ALL {
            assert_eq!(FmuModel::from_name(m.name()), Some(m));
            assert_eq!(FmuModel::from_name(m.model_identifier()), Some(m));
            m.check().unwrap();
            assert!(m.model_description_xml().contains(m.guid()));
        }
        assert_eq!(FmuModel::GearPump.model_identifier(), "GearPump");
        assert_eq!(
            FmuModel::TransmissionCircuit.model_identifier(),
            "TransmissionCircuit"
        );
        assert_eq!(FmuModel::from_name("pump"), None);
    }

    /// A name longer than a zip entry can hold is an error, not a panic of
    /// the zip crate, and nothing is left behind.
    #[test]
    fn over_long_entry_names_are_refused() {
        assert!(check_zip_name(&"a".repeat(ZIP_NAME_MAX)).is_ok());
        let e = check_zip_name(&"a".repeat(ZIP_NAME_MAX + 1)).unwrap_err();
        assert!(e.contains("65536 bytes") && e.len() < 200, "{e}");
        let dir = ScratchDir::new("zipname-test").unwrap();
        let so = dir.path().join("lib.so");
        std::fs::write(&so, b"not a library").unwrap();
        let out = dir.path().join("sub").join("M.fmu");
        let long = "r".repeat(70_000);
        let e = build_fmu(&out, "M", "<x/>", &so, &[(long, vec![1])], "").unwrap_err();
        assert!(matches!(e, PackageError::ZipName(_)), "{e}");
        assert!(!dir.path().join("sub").exists(), "no folder made");
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(left.len(), 1, "only lib.so: {left:?}");
        let scratch = dir.path().to_path_buf();
        drop(dir);
        assert!(!scratch.exists(), "a scratch folder is removed on drop");
    }

    #[test]
    fn resource_names() {
        assert!(valid_resource_name("design.toml"));
        assert!(valid_resource_name("designs/a.toml"));
        for bad in ["", "/abs", "../x", "a/../b", "a//b", "a/", "./a", "a\\b"] {
            assert!(!valid_resource_name(bad), "{bad:?}");
        }
    }
}
