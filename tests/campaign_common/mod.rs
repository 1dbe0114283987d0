//! Helpers shared by the campaign and command-line integration tests.
#![allow(dead_code)]

use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};

use gearpump::design::Design;
use gearpump::model::Pump;

/// The bundled design's pump, built once per test binary.
pub fn pump() -> &'static Arc<Pump> {
    static PUMP: OnceLock<Arc<Pump>> = OnceLock::new();
    PUMP.get_or_init(|| Arc::new(Pump::new(Design::seed())))
}

/// A fresh scratch directory, removed on drop.
pub struct Scratch(pub PathBuf);

impl Scratch {
    pub fn new(name: &str) -> Self {
        static N: AtomicUsize = AtomicUsize::new(0);
        let p = std::env::temp_dir().join(format!(
            "gearpump-test-{name}-{}-{}",
            std::process::id(),
            N.fetch_add(1, Ordering::Relaxed)
        ));
        let _ = std::fs::remove_dir_all(&p);
        std::fs::create_dir_all(&p).expect("create scratch dir");
        Scratch(p)
    }
    pub fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The operating-point flags of the reference point, 1000 rpm / 30 bar /
/// 60 degC (the rig's units, as typed).
pub const POINT_1000_30_60: [&str; 6] = ["--speed", "1000", "--pressure", "30", "--temp", "60"];

/// `base` followed by `extra`.
pub fn with_args<'a>(base: &[&'a str], extra: &[&'a str]) -> Vec<&'a str> {
    let mut v = base.to_vec();
    v.extend_from_slice(extra);
    v
}

/// Runs the binary with the section-table cache off (`geometry::cache`),
/// so every test builds the tables of the code under test.
pub fn gearpump(args: &[&str]) -> Output {
    gearpump_env(args, &[("GEARPUMP_TABLE_CACHE", "off")])
}

/// Runs the binary with these environment variables.
pub fn gearpump_env(args: &[&str], env: &[(&str, &str)]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_gearpump"))
        .args(args)
        .envs(env.iter().copied())
        .output()
        .expect("run gearpump")
}

/// Runs the binary, asserts success, returns stdout.
pub fn gearpump_ok(args: &[&str]) -> String {
    let out = gearpump(args);
    assert!(
        out.status.success(),
        "gearpump {args:?} failed ({:?}): {}",
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("utf-8 stdout")
}

/// Writes a conditions CSV (pressure bar, speed rpm, temperature degC).
pub fn write_conditions(path: &Path, conditions: &[(f64, f64, f64)]) {
    let mut s = String::from("pressure_bar,speed_rpm,temp_c\n");
    for (p, n, t) in conditions {
        s.push_str(&format!("{p},{n},{t}\n"));
    }
    std::fs::write(path, s).expect("write conditions");
}

/// A parsed CSV: header and rows of cells.
pub fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).expect("read csv");
    let mut r = csv::ReaderBuilder::new()
        .has_headers(true)
        .from_reader(text.as_bytes());
    let header = r
        .headers()
        .expect("header")
        .iter()
        .map(str::to_string)
        .collect();
    let rows = r
        .records()
        .map(|x| x.expect("record").iter().map(str::to_string).collect())
        .collect();
    (header, rows)
}

/// Column `name` of a parsed CSV as numbers (empty cells as NaN).
pub fn column(csv: &(Vec<String>, Vec<Vec<String>>), name: &str) -> Vec<f64> {
    let k = csv
        .0
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name} in {:?}", csv.0));
    csv.1
        .iter()
        .map(|r| {
            if r[k].is_empty() {
                f64::NAN
            } else {
                r[k].parse().expect("number")
            }
        })
        .collect()
}

/// Every file and folder under `dir`, relative, sorted.
pub fn tree(dir: &std::path::Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            out.push(p.strip_prefix(dir).unwrap().display().to_string());
            if p.is_dir() {
                stack.push(p);
            }
        }
    }
    out.sort();
    out
}

/// `Command` with a file size limit (RLIMIT_FSIZE) in the child, SIGXFSZ
/// ignored so that a write beyond it fails with EFBIG instead of killing.
pub trait FileSizeLimit {
    fn pre_exec_file_size_limit(&mut self, bytes: u64) -> &mut Self;
}

impl FileSizeLimit for Command {
    fn pre_exec_file_size_limit(&mut self, bytes: u64) -> &mut Self {
        // SAFETY: the closure runs in the forked child before exec and only
        // calls async-signal-safe functions (signal, setrlimit).
        unsafe {
            self.pre_exec(move || {
                libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
                let limit = libc::rlimit {
                    rlim_cur: bytes as libc::rlim_t,
                    rlim_max: bytes as libc::rlim_t,
                };
                if libc::setrlimit(libc::RLIMIT_FSIZE, &limit) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            })
        }
    }
}
