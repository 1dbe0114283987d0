//! Working conditions: the seed paper's Table 2 and conditions files
//! (`--conditions paper|FILE`), read and checked before anything runs.

use std::path::Path;

use thiserror::Error;

use super::data::Condition;
use gearpump_core::units::celsius_to_kelvin;

/// Seed paper Table 2: (pressure bar gauge, speed rpm, temperature degC).
pub const PAPER_CONDITIONS: [(f64, f64, f64); 14] = [
    (10.0, 1000.0, 60.0),
    (20.0, 1000.0, 60.0),
    (30.0, 1000.0, 60.0),
    (40.0, 1000.0, 60.0),
    (30.0, 500.0, 60.0),
    (30.0, 2000.0, 60.0),
    (30.0, 4000.0, 60.0),
    (10.0, 1000.0, 120.0),
    (20.0, 1000.0, 120.0),
    (30.0, 1000.0, 120.0),
    (40.0, 1000.0, 120.0),
    (30.0, 500.0, 120.0),
    (30.0, 2000.0, 120.0),
    (30.0, 4000.0, 120.0),
];

/// The working conditions of seed Table 2.
pub fn paper_conditions() -> Vec<Condition> {
    PAPER_CONDITIONS
        .iter()
        .map(|&(pressure_bar, speed_rpm, temp_c)| Condition {
            pressure_bar,
            speed_rpm,
            temp_c,
        })
        .collect()
}

/// A refused conditions file.
#[derive(Debug, Error)]
pub enum ConditionsError {
    #[error("{file}: cannot read: {message}")]
    Read { file: String, message: String },
    #[error("{file}: header, column {column}: required column is missing")]
    MissingColumn { file: String, column: &'static str },
    #[error("{file}: row {row}: malformed CSV: {message}")]
    Malformed {
        file: String,
        row: usize,
        message: String,
    },
    #[error("{file}: row {row}, column {column}: {message}")]
    Cell {
        file: String,
        row: usize,
        column: &'static str,
        message: String,
    },
    #[error("{file}: no conditions after the header")]
    Empty { file: String },
    #[error("{file}: row {row}: duplicate condition {condition} (first in row {first})")]
    Duplicate {
        file: String,
        row: usize,
        first: usize,
        condition: Condition,
    },
}

/// Reads a conditions CSV (`pressure_bar`, `speed_rpm`, `temp_c`; rows
/// numbered from 1 after the header, as the campaign reader does).
pub fn read_conditions(path: &Path) -> Result<Vec<Condition>, ConditionsError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| ConditionsError::Read {
        file: file.clone(),
        message: e.to_string(),
    })?;
    parse_conditions_str(&file, &text)
}

/// [`read_conditions`] on text; `file` names it in messages.
pub fn parse_conditions_str(file: &str, text: &str) -> Result<Vec<Condition>, ConditionsError> {
    const COLS: [&str; 3] = ["pressure_bar", "speed_rpm", "temp_c"];
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .from_reader(text.as_bytes());
    let headers = reader
        .headers()
        .map_err(|e| ConditionsError::Malformed {
            file: file.to_string(),
            row: 0,
            message: e.to_string(),
        })?
        .clone();
    let mut pos = [0usize; 3];
    for (k, name) in COLS.iter().enumerate() {
        pos[k] = headers
            .iter()
            .position(|h| h.trim() == *name)
            .ok_or_else(|| ConditionsError::MissingColumn {
                file: file.to_string(),
                column: name,
            })?;
    }
    let mut out: Vec<Condition> = Vec::new();
    for (i, rec) in reader.records().enumerate() {
        let row = i + 1;
        let rec = rec.map_err(|e| ConditionsError::Malformed {
            file: file.to_string(),
            row,
            message: e.to_string(),
        })?;
        let mut v = [0.0; 3];
        for k in 0..3 {
            let cell = rec.get(pos[k]).unwrap_or("").trim();
            let bad = |message: String| ConditionsError::Cell {
                file: file.to_string(),
                row,
                column: COLS[k],
                message,
            };
            let x: f64 = cell
                .parse()
                .map_err(|_| bad(format!("not a number: {cell:?}")))?;
            if !x.is_finite() {
                return Err(bad(format!("must be a finite number, got {cell:?}")));
            }
            let ok = match k {
                0 => x >= 0.0,
                1 => x > 0.0,
                _ => celsius_to_kelvin(x) > 0.0,
            };
            if !ok {
                return Err(bad(match k {
                    0 => format!("must be >= 0, got {x}"),
                    1 => format!("must be > 0, got {x}"),
                    _ => format!("must be above absolute zero, got {x}"),
                }));
            }
            v[k] = x;
        }
        let c = Condition {
            pressure_bar: v[0],
            speed_rpm: v[1],
            temp_c: v[2],
        };
        if let Some(first) = out.iter().position(|o| o.key() == c.key()) {
            return Err(ConditionsError::Duplicate {
                file: file.to_string(),
                row,
                first: first + 1,
                condition: c,
            });
        }
        out.push(c);
    }
    if out.is_empty() {
        return Err(ConditionsError::Empty {
            file: file.to_string(),
        });
    }
    Ok(out)
}

/// The conditions of `--conditions paper|FILE`.
pub fn conditions_from_arg(arg: &str) -> Result<Vec<Condition>, ConditionsError> {
    if arg == "paper" {
        Ok(paper_conditions())
    } else {
        read_conditions(Path::new(arg))
    }
}
