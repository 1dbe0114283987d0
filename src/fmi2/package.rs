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
/// library that exports `M` (see [`crate::export_fmi2!`]).
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

/// A copy of the shared library `so` without debug information, written
/// beside `out_dir` by `strip --strip-debug` (binutils). `None` when no
/// `strip` program is found or it fails: the caller then packages `so` as
/// it is (larger, same behaviour).
pub fn strip_debuginfo(so: &Path, out_dir: &Path) -> Option<PathBuf> {
    std::fs::create_dir_all(out_dir).ok()?;
    let name = so.file_name()?.to_string_lossy().into_owned();
    let tmp = out_dir.join(format!(".{name}.stripped-{}", std::process::id()));
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

/// What [`build_exported_fmu`] did.
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

/// The FMU of the exported model ([`super::ExportedModel`]) from the built
/// cdylib `so`, with its debug information stripped when `strip` is
/// available (see [`strip_debuginfo`]). Used by `fmu-build` and
/// `gearpump fmu`.
pub fn build_exported_fmu(out: &Path, so: &Path) -> Result<Packaged, PackageError> {
    if !so.is_file() {
        return Err(PackageError::Io {
            path: so.to_path_buf(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"),
        });
    }
    let dir = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let stripped = strip_debuginfo(so, &dir);
    let result = build_model_fmu::<super::ExportedModel>(out, stripped.as_deref().unwrap_or(so));
    if let Some(tmp) = &stripped {
        let _ = std::fs::remove_file(tmp);
    }
    result.map(|()| Packaged {
        path: out.to_path_buf(),
        stripped: stripped.is_some(),
        debug_build: false,
    })
}

/// `gearpump fmu`: the FMU from the cdylib cargo built beside the running
/// executable (`target/<profile>/libgearpump.so`, or `deps/` below it, next
/// to `target/<profile>/gearpump`), so binary and XML come from the same
/// build. `out` defaults to `target/fmu/<modelIdentifier>.fmu` (the path
/// `fmu-build` writes) when the executable sits in cargo's target folder,
/// else `<modelIdentifier>.fmu` in the current folder.
pub fn build_fmu_beside_exe(out: Option<&Path>) -> Result<Packaged, PackageError> {
    let (_, ext) = platform().ok_or(PackageError::Platform)?;
    let exe = std::env::current_exe().map_err(|e| PackageError::NoLibrary(e.to_string()))?;
    let dir = exe.parent().unwrap_or(Path::new(".")).to_path_buf();
    let name = format!("lib{}.{ext}", env!("CARGO_CRATE_NAME"));
    // cargo uplifts the cdylib beside the binaries after `cargo build`; under
    // `cargo test` it stays in `deps/`
    let so = [dir.clone(), dir.join("deps"), dir.join("..")]
        .iter()
        .map(|d| d.join(&name))
        .find(|p| p.is_file())
        .ok_or_else(|| {
            PackageError::NoLibrary(format!(
                "{name} not found beside {}: build it with `cargo build --release` \
                 (or run `cargo run -p fmu-build --release`)",
                exe.display()
            ))
        })?;
    let id = <super::ExportedModel as CoSimModel>::MODEL_IDENTIFIER;
    let out = match out {
        Some(p) => p.to_path_buf(),
        None => {
            let profile = dir.file_name().and_then(|n| n.to_str());
            match (profile, dir.parent()) {
                (Some("release" | "debug"), Some(target)) => target.join("fmu"),
                _ => PathBuf::from("."),
            }
            .join(format!("{id}.fmu"))
        }
    };
    let mut packaged = build_exported_fmu(&out, &so)?;
    packaged.debug_build = cfg!(debug_assertions);
    Ok(packaged)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resource_names() {
        assert!(valid_resource_name("design.toml"));
        assert!(valid_resource_name("designs/a.toml"));
        for bad in ["", "/abs", "../x", "a/../b", "a//b", "a/", "./a", "a\\b"] {
            assert!(!valid_resource_name(bad), "{bad:?}");
        }
    }
}
