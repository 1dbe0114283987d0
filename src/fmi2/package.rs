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
