//! Section tables kept on disk between runs: a file per table key
//! ([`Pair::section_key`]), refused unless it is exactly the tables that
//! key would build.
//!
//! The tables take about 50 ms to build for the seed pump (most of
//! `Pump::new`); read back they take well under a millisecond. Repeated CLI
//! calls on one design (a script sweeping operating points) read them from
//! a cache folder, and an FMU ships its design's tables in `resources/`.
//!
//! # File layout
//! A header of 40 bytes, then the tables as CBOR (`ciborium`):
//!
//! | bytes | content |
//! |---|---|
//! | 0..8 | magic `GPTABLES` |
//! | 8..16 | [`FORMAT`] (u64, little-endian) |
//! | 16..24 | the table key (u64) |
//! | 24..32 | length of the CBOR payload (u64) |
//! | 32..40 | FNV-1a of the payload (u64) |
//!
//! A file is used only when the magic, format, key, length and checksum all
//! match and the payload decodes; anything else is refused with the reason
//! ([`CacheError`]) and the tables are built afresh. Files are written to a
//! temporary name and renamed, so a reader never sees half a file.

use super::pair::Pair;
use super::tables::SectionTables;
use crate::hash::{Fingerprint, Fnv1a};
use std::path::{Path, PathBuf};

/// Version of the file layout.
pub const FORMAT: u64 = 1;
const MAGIC: &[u8; 8] = b"GPTABLES";
const HEADER: usize = 40;

/// Why a cached file was not used.
#[derive(Debug, Clone, thiserror::Error, PartialEq)]
pub enum CacheError {
    #[error("not a table file (no GPTABLES header)")]
    NotATableFile,
    #[error("file format {found}, this build reads {FORMAT}")]
    Format { found: u64 },
    #[error("tables of another design or build (key {found}, wanted {wanted})")]
    Key {
        found: Fingerprint,
        wanted: Fingerprint,
    },
    #[error("damaged: {0}")]
    Damaged(String),
}

/// The parameters the tables are built from, with their key.
#[derive(Debug, Clone, Copy)]
pub struct TableSpec<'a> {
    pub pair: &'a Pair,
    pub dphi: f64,
    pub delivery_groove: f64,
    pub suction_groove: f64,
    pub groove_width: f64,
}

impl TableSpec<'_> {
    /// The key of these tables ([`Pair::section_key`]).
    pub fn key(&self) -> Fingerprint {
        self.pair.section_key(
            self.dphi,
            self.delivery_groove,
            self.suction_groove,
            self.groove_width,
        )
    }

    /// The tables, built.
    pub fn build(&self) -> SectionTables {
        self.pair.section_tables(
            self.dphi,
            self.delivery_groove,
            self.suction_groove,
            self.groove_width,
        )
    }
}

/// The tables as the bytes of a table file for `key`.
pub fn to_bytes(tables: &SectionTables, key: Fingerprint) -> Vec<u8> {
    let mut payload = Vec::new();
    ciborium::into_writer(tables, &mut payload).expect("writing CBOR to memory cannot fail");
    let mut h = Fnv1a::new();
    h.write(&payload);
    let mut out = Vec::with_capacity(HEADER + payload.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&FORMAT.to_le_bytes());
    out.extend_from_slice(&key.0.to_le_bytes());
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(&h.finish().0.to_le_bytes());
    out.extend_from_slice(&payload);
    out
}

/// The tables of a table file, if it holds exactly the tables of `key`.
pub fn from_bytes(bytes: &[u8], key: Fingerprint) -> Result<SectionTables, CacheError> {
    if bytes.len() < HEADER || &bytes[..8] != MAGIC {
        return Err(CacheError::NotATableFile);
    }
    let word = |i: usize| {
        let mut b = [0u8; 8];
        b.copy_from_slice(&bytes[8 * i..8 * i + 8]);
        u64::from_le_bytes(b)
    };
    if word(1) != FORMAT {
        return Err(CacheError::Format { found: word(1) });
    }
    if word(2) != key.0 {
        return Err(CacheError::Key {
            found: Fingerprint(word(2)),
            wanted: key,
        });
    }
    let payload = &bytes[HEADER..];
    if word(3) != payload.len() as u64 {
        return Err(CacheError::Damaged(format!(
            "payload of {} bytes, the header says {}",
            payload.len(),
            word(3)
        )));
    }
    let mut h = Fnv1a::new();
    h.write(payload);
    if h.finish().0 != word(4) {
        return Err(CacheError::Damaged("checksum does not match".into()));
    }
    let tables: SectionTables =
        ciborium::from_reader(payload).map_err(|e| CacheError::Damaged(e.to_string()))?;
    if tables.samples.iter().any(|s| s.len() < 2) || tables.interfaces.is_empty() {
        return Err(CacheError::Damaged("empty tables".into()));
    }
    Ok(tables)
}

/// Where the tables came from.
#[derive(Debug, Clone, PartialEq)]
pub enum Source {
    /// Built; `stored` says whether they were written to the cache.
    Built { stored: bool },
    /// Read from this file.
    Read(PathBuf),
    /// The file there was refused for this reason; built afresh.
    Refused(PathBuf, CacheError),
}

impl Source {
    /// Where the tables came from, as `simulate --json` says it: `built`,
    /// `cached` or `built (cache refused: <why>)`.
    pub fn label(&self) -> String {
        match self {
            Source::Built { .. } => "built".to_string(),
            Source::Read(_) => "cached".to_string(),
            Source::Refused(_, why) => format!("built (cache refused: {why})"),
        }
    }
}

/// A folder of table files, one per key.
#[derive(Debug, Clone)]
pub struct TableCache {
    dir: PathBuf,
}

impl TableCache {
    pub fn new(dir: impl Into<PathBuf>) -> TableCache {
        TableCache { dir: dir.into() }
    }

    /// The folder the command line uses: `$GEARPUMP_TABLE_CACHE`, else
    /// `$XDG_CACHE_HOME/gearpump/tables`, else `$HOME/.cache/gearpump/tables`;
    /// none when `GEARPUMP_TABLE_CACHE` is `off` or no home is known.
    pub fn from_env() -> Option<TableCache> {
        let var = |name: &str| std::env::var_os(name).filter(|v| !v.is_empty());
        if let Some(dir) = var("GEARPUMP_TABLE_CACHE") {
            return (dir != "off").then(|| TableCache::new(dir));
        }
        let base = var("XDG_CACHE_HOME")
            .map(PathBuf::from)
            .or_else(|| var("HOME").map(|h| Path::new(&h).join(".cache")))?;
        Some(TableCache::new(base.join("gearpump").join("tables")))
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The file of tables with key `key`.
    pub fn path(&self, key: Fingerprint) -> PathBuf {
        self.dir.join(format!("{key}.gptables"))
    }

    /// The tables of `spec`: read from the cache when its file holds
    /// exactly them, else built and stored (a failure to store only means
    /// the next run builds them again).
    pub fn load_or_build(&self, spec: &TableSpec) -> (SectionTables, Source) {
        let key = spec.key();
        let path = self.path(key);
        let refused = match std::fs::read(&path) {
            Ok(bytes) => match from_bytes(&bytes, key) {
                Ok(tables) => return (tables, Source::Read(path)),
                Err(e) => Some(e),
            },
            Err(_) => None,
        };
        let tables = spec.build();
        let stored = self.store(&tables, key).is_ok();
        let source = match refused {
            Some(e) => Source::Refused(path, e),
            None => Source::Built { stored },
        };
        (tables, source)
    }

    /// Writes the tables under `key` (a temporary file renamed into place).
    pub fn store(&self, tables: &SectionTables, key: Fingerprint) -> std::io::Result<()> {
        std::fs::create_dir_all(&self.dir)?;
        let path = self.path(key);
        let tmp = self.dir.join(format!(
            ".{key}.{}.{:?}.tmp",
            std::process::id(),
            std::thread::current().id()
        ));
        std::fs::write(&tmp, to_bytes(tables, key))?;
        std::fs::rename(&tmp, &path).inspect_err(|_| {
            let _ = std::fs::remove_file(&tmp);
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::Design;

    fn seed_spec(d: &Design) -> (Pair, f64, f64, f64, f64) {
        let c = &d.casing;
        (
            d.pair(),
            d.numerics.table_step,
            c.delivery_groove_edge,
            c.suction_groove_edge,
            c.groove_width,
        )
    }

    fn spec_of<'a>(pair: &'a Pair, dphi: f64, dg: f64, sg: f64, w: f64) -> TableSpec<'a> {
        TableSpec {
            pair,
            dphi,
            delivery_groove: dg,
            suction_groove: sg,
            groove_width: w,
        }
    }

    /// Written and read back, the tables are the same to the bit; any
    /// other key, format, length or byte is refused with its reason.
    #[test]
    fn a_table_file_reads_back_exactly_and_refuses_anything_else() {
        let d = Design::seed();
        let (pair, dphi, dg, sg, w) = seed_spec(&d);
        let spec = spec_of(&pair, dphi, dg, sg, w);
        let tables = spec.build();
        let key = spec.key();
        let bytes = to_bytes(&tables, key);
        assert_eq!(from_bytes(&bytes, key).unwrap(), tables);
        // another design's key: a groove 1 um wider
        let other = pair.section_key(dphi, dg, sg, w + 1e-6);
        assert_ne!(other, key);
        assert!(matches!(
            from_bytes(&bytes, other),
            Err(CacheError::Key { .. })
        ));
        // another tooth (the pair's fields are in the key)
        let mut d2 = Design::seed();
        d2.gears[0].thinning += 1e-6;
        let (pair2, ..) = seed_spec(&d2);
        assert_ne!(pair2.section_key(dphi, dg, sg, w), key);
        // a changed byte of the payload, a cut file, another format, not a table file
        let mut flipped = bytes.clone();
        let i = bytes.len() - 100;
        flipped[i] ^= 0x10;
        assert!(matches!(
            from_bytes(&flipped, key),
            Err(CacheError::Damaged(_))
        ));
        assert!(matches!(
            from_bytes(&bytes[..bytes.len() - 1], key),
            Err(CacheError::Damaged(_))
        ));
        let mut format = bytes.clone();
        format[8] = 9;
        assert_eq!(
            from_bytes(&format, key),
            Err(CacheError::Format { found: 9 })
        );
        assert_eq!(from_bytes(b"hello", key), Err(CacheError::NotATableFile));
    }

    /// The cache builds and stores on the first call, reads on the second,
    /// and a file that does not hold its key's tables is refused, rebuilt
    /// and replaced.
    #[test]
    fn the_cache_reads_what_it_stored_and_replaces_a_bad_file() {
        let dir = std::env::temp_dir().join(format!("gearpump-cache-test-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let cache = TableCache::new(&dir);
        let d = Design::seed();
        let (pair, dphi, dg, sg, w) = seed_spec(&d);
        let spec = spec_of(&pair, dphi, dg, sg, w);
        let (built, source) = cache.load_or_build(&spec);
        assert_eq!(source, Source::Built { stored: true });
        let (read, source) = cache.load_or_build(&spec);
        assert_eq!(source, Source::Read(cache.path(spec.key())));
        assert_eq!(read, built);
        // another key's tables under this key's name
        let other = pair.section_key(dphi, dg, sg, w * 2.0);
        std::fs::write(cache.path(spec.key()), to_bytes(&built, other)).unwrap();
        let (again, source) = cache.load_or_build(&spec);
        assert!(
            matches!(source, Source::Refused(_, CacheError::Key { .. })),
            "{source:?}"
        );
        assert_eq!(again, built);
        assert_eq!(
            cache.load_or_build(&spec).1,
            Source::Read(cache.path(spec.key()))
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
