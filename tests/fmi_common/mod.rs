//! Helpers shared by the FMI tests: a Rust logger callback that records
//! messages per instance (no global state), and temporary resources folders.
#![allow(dead_code, unsafe_code)]

use std::ffi::{c_char, c_int, c_void, CStr};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use gearpump::fmi2::types::*;

/// One logged message.
#[derive(Debug, Clone, PartialEq)]
pub struct Message {
    pub instance: String,
    pub status: Status,
    pub category: String,
    pub message: String,
}

/// The messages of one instance; its address is the `componentEnvironment`.
#[derive(Debug, Default)]
pub struct Log(pub Mutex<Vec<Message>>);

impl Log {
    pub fn messages(&self) -> Vec<Message> {
        self.0.lock().unwrap().clone()
    }
    pub fn clear(&self) {
        self.0.lock().unwrap().clear();
    }
    /// Whether some message of at least `status` contains every needle.
    pub fn has(&self, status: Status, needles: &[&str]) -> bool {
        self.messages()
            .iter()
            .any(|m| m.status >= status && needles.iter().all(|n| m.message.contains(n)))
    }
    pub fn dump(&self) -> String {
        format!("{:#?}", self.messages())
    }
}

fn lossy(p: *const c_char) -> String {
    if p.is_null() {
        "<NULL>".into()
    } else {
        // SAFETY: the FMU passes NUL-terminated strings.
        unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
    }
}

/// The logger, written with the fixed arguments the FMU always passes
/// (format "%s" + one string). Rust cannot define a C variadic function, so
/// it is called through the variadic pointer type: on the x86_64 and
/// aarch64 Linux calling conventions a variadic call passes these arguments
/// exactly like a fixed-argument call (as ctypes loggers rely on too).
unsafe extern "C" fn record(
    env: *mut c_void,
    instance: *const c_char,
    status: c_int,
    category: *const c_char,
    format: *const c_char,
    message: *const c_char,
) {
    assert_eq!(
        lossy(format),
        "%s",
        "the FMU must log with the format \"%s\""
    );
    // SAFETY: env is the address of a live Log (see `callbacks`).
    let log = unsafe { &*(env as *const Log) };
    log.0.lock().unwrap().push(Message {
        instance: lossy(instance),
        status: Status::from_raw(status).expect("valid status"),
        category: lossy(category),
        message: lossy(message),
    });
}

type Fixed = unsafe extern "C" fn(
    *mut c_void,
    *const c_char,
    c_int,
    *const c_char,
    *const c_char,
    *const c_char,
);
type Variadic = unsafe extern "C" fn(
    fmi2ComponentEnvironment,
    fmi2String,
    fmi2Status,
    fmi2String,
    fmi2String,
    ...
);

/// Callback functions that record into `log` (which must outlive the
/// instance).
pub fn callbacks(log: &Log) -> fmi2CallbackFunctions {
    // SAFETY: see `record`: same ABI for the arguments the FMU passes.
    let logger = unsafe { std::mem::transmute::<Fixed, Variadic>(record) };
    fmi2CallbackFunctions {
        logger: Some(logger),
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: log as *const Log as *mut c_void,
    }
}

/// A temporary folder, removed on drop.
pub struct TempDir(pub PathBuf);

static COUNTER: AtomicUsize = AtomicUsize::new(0);

impl TempDir {
    pub fn new(tag: &str) -> TempDir {
        let n = COUNTER.fetch_add(1, Ordering::SeqCst);
        let p = std::env::temp_dir().join(format!("gearpump-fmi-{tag}-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&p);
        std::fs::create_dir_all(&p).unwrap();
        TempDir(p)
    }
    pub fn path(&self) -> &Path {
        &self.0
    }
    /// `file:///...` URI of a path (percent-encoding spaces and '%').
    pub fn uri(p: &Path) -> String {
        let s = p.to_str().unwrap().replace('%', "%25").replace(' ', "%20");
        format!("file://{s}")
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The shared library of one FMU's cdylib crate (`fmus/<name>`, e.g.
/// `libGearPump.so`), built for the profile of this test run. The library
/// `gearpump` is an rlib, so `cargo test` does not build the cdylibs: the
/// first call per process runs `cargo build -p <crate>` (with `$CARGO`, in
/// the same target folder and profile; cargo's own lock serialises
/// concurrent test binaries), then returns `target/<profile>/lib<id>.so`.
/// An up-to-date library costs one no-op cargo call.
pub fn cdylib(model: gearpump::fmi2::FmuModel) -> PathBuf {
    use std::collections::HashMap;
    use std::sync::OnceLock;
    static BUILT: OnceLock<Mutex<HashMap<&'static str, PathBuf>>> = OnceLock::new();
    let mut built = BUILT.get_or_init(Default::default).lock().unwrap();
    if let Some(p) = built.get(model.cargo_package()) {
        return p.clone();
    }
    // <target>/<profile>/deps/<test exe>
    let exe = std::env::current_exe().unwrap();
    let profile_dir = exe.parent().unwrap().parent().unwrap().to_path_buf();
    let target = profile_dir.parent().unwrap();
    let release = profile_dir.file_name().is_some_and(|n| n == "release");
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let mut cmd = std::process::Command::new(cargo);
    cmd.current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["build", "--quiet", "-p", model.cargo_package()])
        .env("CARGO_TARGET_DIR", target);
    if release {
        cmd.arg("--release");
    }
    let status = cmd.status().expect("running cargo build");
    assert!(
        status.success(),
        "cargo build -p {} failed",
        model.cargo_package()
    );
    let so = profile_dir.join(model.cdylib_file_name());
    assert!(so.is_file(), "{} not built", so.display());
    built.insert(model.cargo_package(), so.clone());
    so
}
