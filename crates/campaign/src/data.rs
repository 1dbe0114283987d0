//! The measured campaign CSV: strict reading, writing, grouping by condition.
//!
//! # CSV contract (docs/interfaces.md section 4)
//! One row per test. A header row is required; column order is free; columns
//! other than the ten below are ignored by the model but kept verbatim (they
//! are written back unchanged to `tests.csv`). Column names are matched after
//! trimming surrounding whitespace, case-sensitively; a UTF-8 byte-order mark
//! is accepted.
//!
//! | column | unit | rule |
//! |---|---|---|
//! | `sample` | text | not empty, at most 64 characters (`gearpump_core::limits::SAMPLE_ID_MAX_CHARS`; surrounding whitespace trimmed) |
//! | `tip_clearance_drive_um`, `tip_clearance_driven_um` | um | finite, within 0.1-500 |
//! | `bearing_clearance_drive_um`, `bearing_clearance_driven_um` | um | finite, within 0.1-500 |
//! | `pressure_bar` | bar gauge (above suction) | finite, within 0-500 |
//! | `speed_rpm` | rpm | finite, within 1-20,000 |
//! | `temp_c` | degC | finite, above absolute zero (and within the oil model's range, checked by the run) |
//! | `flow_lpm` | l/min | finite, within 0-10,000 |
//! | `torque_nm` | N.m | empty (= not measured) or finite, within 0-10,000 |
//!
//! The ranges are `gearpump_core::limits`'s.
//!
//! A numeric cell is parsed after trimming whitespace with Rust's `f64`
//! grammar (`30`, `30.0`, `3e1`; no decimal comma). `NaN` and `inf` are
//! refused. Two rows with the same `sample` and the same working condition
//! (pressure, speed, temperature equal to 1e-6 bar/rpm/degC) are refused.
//!
//! # Row numbering in messages
//! Errors name the file, the row and the column, e.g.
//! `c.csv: row 7, column speed_rpm: must be > 0, got -3`.
//! **Rows are data rows numbered from 1: the header is not counted**, so
//! `row 1` is the first test after the header (line 2 of a plain file).
//! Blank lines are skipped by the CSV reader and not counted either.
//! Problems with the header itself are reported as `header, column NAME`.
//!
//! Inside the library every value is SI ([`TestRow`] fields); the original
//! cell text is kept in [`TestRow::cells`] so no user data is lost.

use std::collections::HashMap;
use std::fmt;
use std::path::Path;

use serde::Serialize;
use thiserror::Error;

use gearpump_core::units::{bar_to_pa, celsius_to_kelvin, lpm_to_m3_s, rpm_to_rad_s, um_to_m};

/// Required columns of the measured campaign CSV, in the canonical order
/// used when writing one.
pub const COLUMNS: [&str; 10] = [
    "sample",
    "tip_clearance_drive_um",
    "tip_clearance_driven_um",
    "bearing_clearance_drive_um",
    "bearing_clearance_driven_um",
    "pressure_bar",
    "speed_rpm",
    "temp_c",
    "flow_lpm",
    "torque_nm",
];

// Indices into COLUMNS.
const SAMPLE: usize = 0;
const TIP_DRIVE: usize = 1;
const TIP_DRIVEN: usize = 2;
const BRG_DRIVE: usize = 3;
const BRG_DRIVEN: usize = 4;
const PRESSURE: usize = 5;
const SPEED: usize = 6;
const TEMP: usize = 7;
const FLOW: usize = 8;
const TORQUE: usize = 9;

/// Resolution used to compare working conditions: 1e-6 of the edge unit
/// (bar, rpm, degC).
pub const CONDITION_RESOLUTION: f64 = 1.0e-6;

/// What is wrong with one cell.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum CellProblem {
    #[error("must not be empty")]
    Empty,
    /// A sample id longer than `gearpump_core::limits::SAMPLE_ID_MAX_CHARS`.
    #[error("a sample id may have at most {max} characters, got {chars}")]
    TooLong { chars: usize, max: usize },
    #[error("not a number: {text:?}")]
    NotNumeric { text: String },
    #[error("must be a finite number, got {text:?}")]
    NotFinite { text: String },
    #[error("must be >= 0, got {value}")]
    Negative { value: f64 },
    #[error("must be > 0, got {value}")]
    NotPositive { value: f64 },
    #[error("must be above absolute zero (-273.15 degC), got {value}")]
    BelowAbsoluteZero { value: f64 },
    /// Outside the physical range of `gearpump_core::limits`.
    #[error("{message}")]
    OutOfRange { message: String },
}

/// Error reading a measured campaign CSV. Every message starts with the file
/// name; `row` is the 1-based data row (header not counted).
#[derive(Debug, Error)]
pub enum DataError {
    #[error("{file}: cannot read: {source}")]
    Read {
        file: String,
        #[source]
        source: std::io::Error,
    },
    #[error("{file}: empty file: a header row and at least one test row are required")]
    Empty { file: String },
    #[error("{file}: no data rows after the header")]
    NoDataRows { file: String },
    #[error("{file}: header, column {column}: required column is missing")]
    MissingColumn { file: String, column: &'static str },
    #[error("{file}: header, column {column}: appears more than once")]
    DuplicateColumn { file: String, column: &'static str },
    #[error("{file}: row {row}: malformed CSV: {message}")]
    Malformed {
        file: String,
        row: usize,
        message: String,
    },
    #[error("{file}: row {row}, column {column}: {problem}")]
    Cell {
        file: String,
        row: usize,
        column: &'static str,
        problem: CellProblem,
    },
    #[error(
        "{file}: row {row}, column sample: duplicate test: sample {sample:?} at {condition} is already in row {first_row}"
    )]
    DuplicateRow {
        file: String,
        row: usize,
        first_row: usize,
        sample: String,
        condition: Condition,
    },
}

impl DataError {
    /// The file named in the message.
    pub fn file(&self) -> &str {
        match self {
            DataError::Read { file, .. }
            | DataError::Empty { file }
            | DataError::NoDataRows { file }
            | DataError::MissingColumn { file, .. }
            | DataError::DuplicateColumn { file, .. }
            | DataError::Malformed { file, .. }
            | DataError::Cell { file, .. }
            | DataError::DuplicateRow { file, .. } => file,
        }
    }

    /// The 1-based data row (header not counted), when the error is in a row.
    pub fn row(&self) -> Option<usize> {
        match self {
            DataError::Malformed { row, .. }
            | DataError::Cell { row, .. }
            | DataError::DuplicateRow { row, .. } => Some(*row),
            _ => None,
        }
    }

    /// The column, when the error is about one.
    pub fn column(&self) -> Option<&'static str> {
        match self {
            DataError::MissingColumn { column, .. }
            | DataError::DuplicateColumn { column, .. }
            | DataError::Cell { column, .. } => Some(column),
            DataError::DuplicateRow { .. } => Some(COLUMNS[SAMPLE]),
            _ => None,
        }
    }
}

/// A working condition in the edge units of the CSV, as measured.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Condition {
    /// Delivery pressure, bar gauge (above suction).
    pub pressure_bar: f64,
    /// Driving shaft speed, rpm.
    pub speed_rpm: f64,
    /// Oil temperature, degC.
    pub temp_c: f64,
}

impl Condition {
    /// Comparison key: each value rounded to [`CONDITION_RESOLUTION`] of its
    /// edge unit. Two conditions are the same when their keys are equal.
    pub fn key(&self) -> (i64, i64, i64) {
        // `as` saturates for out-of-range values; validated input is finite.
        let q = |x: f64| (x / CONDITION_RESOLUTION).round() as i64;
        (q(self.pressure_bar), q(self.speed_rpm), q(self.temp_c))
    }
}

impl fmt::Display for Condition {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} bar, {} rpm, {} degC",
            self.pressure_bar, self.speed_rpm, self.temp_c
        )
    }
}

/// One test (one data row), validated. Numeric fields are SI.
#[derive(Debug, Clone, PartialEq)]
pub struct TestRow {
    /// 1-based data row number (header not counted).
    pub row: usize,
    /// The original cell text of every column, in input column order
    /// (same length as [`Campaign::headers`]).
    pub cells: Vec<String>,
    /// Pump sample id (trimmed).
    pub sample: String,
    /// Tooth tip / casing radial clearance [driving, driven], m.
    pub tip_clearance: [f64; 2],
    /// Journal bearing radial clearance [driving, driven], m.
    pub bearing_clearance: [f64; 2],
    /// Delivery pressure above the suction pressure (gauge), Pa.
    pub pressure: f64,
    /// Driving shaft speed, rad/s.
    pub speed: f64,
    /// Oil temperature, K.
    pub temp: f64,
    /// Measured mean delivered flow, m^3/s.
    pub flow: f64,
    /// Measured mean shaft torque, N.m (`None`: cell empty, not measured).
    pub torque: Option<f64>,
    /// The working condition in edge units as written in the file (used for
    /// grouping and for reports).
    pub condition: Condition,
}

/// A validated measured campaign.
#[derive(Debug, Clone, PartialEq)]
pub struct Campaign {
    /// File name used in messages.
    pub file: String,
    /// Header cells as written (BOM removed), in input order.
    pub headers: Vec<String>,
    /// Data rows in input order.
    pub rows: Vec<TestRow>,
}

/// Read and validate a measured campaign CSV file.
pub fn read_campaign(path: &Path) -> Result<Campaign, DataError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|source| DataError::Read {
        file: file.clone(),
        source,
    })?;
    parse_campaign_str(&file, &text)
}

/// Parse and validate a measured campaign CSV held in memory; `file` is the
/// name used in error messages.
pub fn parse_campaign_str(file: &str, text: &str) -> Result<Campaign, DataError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let err_file = || file.to_string();
    if text.trim().is_empty() {
        return Err(DataError::Empty { file: err_file() });
    }
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(false)
        .trim(csv::Trim::None)
        .from_reader(text.as_bytes());
    let mut records = reader.records();

    let headers: Vec<String> = match records.next() {
        None => return Err(DataError::Empty { file: err_file() }),
        Some(Err(e)) => {
            return Err(DataError::Malformed {
                file: err_file(),
                row: 0,
                message: format!("header: {e}"),
            })
        }
        Some(Ok(rec)) => rec.iter().map(str::to_string).collect(),
    };
    let cols = locate_columns(file, &headers)?;

    let mut rows = Vec::new();
    let mut seen: HashMap<(String, (i64, i64, i64)), usize> = HashMap::new();
    for (i, rec) in records.enumerate() {
        let row = i + 1;
        let rec = rec.map_err(|e| DataError::Malformed {
            file: err_file(),
            row,
            message: match e.kind() {
                csv::ErrorKind::UnequalLengths {
                    expected_len, len, ..
                } => format!("{len} fields, the header has {expected_len}"),
                _ => e.to_string(),
            },
        })?;
        let cells: Vec<String> = rec.iter().map(str::to_string).collect();
        let test = parse_row(file, row, &cols, cells)?;
        let key = (test.sample.clone(), test.condition.key());
        if let Some(&first_row) = seen.get(&key) {
            return Err(DataError::DuplicateRow {
                file: err_file(),
                row,
                first_row,
                sample: test.sample,
                condition: test.condition,
            });
        }
        seen.insert(key, row);
        rows.push(test);
    }
    if rows.is_empty() {
        return Err(DataError::NoDataRows { file: err_file() });
    }
    Ok(Campaign {
        file: err_file(),
        headers,
        rows,
    })
}

/// Position of each required column in the header.
fn locate_columns(file: &str, headers: &[String]) -> Result<[usize; 10], DataError> {
    let mut pos = [usize::MAX; 10];
    for (k, name) in COLUMNS.iter().enumerate() {
        let mut found = headers
            .iter()
            .enumerate()
            .filter(|(_, h)| h.trim() == *name);
        match (found.next(), found.next()) {
            (None, _) => {
                return Err(DataError::MissingColumn {
                    file: file.to_string(),
                    column: name,
                })
            }
            (Some(_), Some(_)) => {
                return Err(DataError::DuplicateColumn {
                    file: file.to_string(),
                    column: name,
                })
            }
            (Some((j, _)), None) => pos[k] = j,
        }
    }
    Ok(pos)
}

fn parse_row(
    file: &str,
    row: usize,
    cols: &[usize; 10],
    cells: Vec<String>,
) -> Result<TestRow, DataError> {
    let cell_err = |k: usize, problem: CellProblem| DataError::Cell {
        file: file.to_string(),
        row,
        column: COLUMNS[k],
        problem,
    };
    // The reader is not flexible, so every record has as many cells as the
    // header; `get` keeps this panic-free regardless.
    let text = |k: usize| cells.get(cols[k]).map(|s| s.trim()).unwrap_or("");
    let number = |k: usize| -> Result<f64, DataError> {
        let t = text(k);
        if t.is_empty() {
            return Err(cell_err(k, CellProblem::Empty));
        }
        let v: f64 = t.parse().map_err(|_| {
            cell_err(
                k,
                CellProblem::NotNumeric {
                    text: t.to_string(),
                },
            )
        })?;
        if !v.is_finite() {
            return Err(cell_err(
                k,
                CellProblem::NotFinite {
                    text: t.to_string(),
                },
            ));
        }
        Ok(v)
    };
    let non_negative = |k: usize| -> Result<f64, DataError> {
        let v = number(k)?;
        if v < 0.0 {
            return Err(cell_err(k, CellProblem::Negative { value: v }));
        }
        Ok(v)
    };

    let sample = text(SAMPLE).to_string();
    if sample.is_empty() {
        return Err(cell_err(SAMPLE, CellProblem::Empty));
    }
    let chars = sample.chars().count();
    if chars > gearpump_core::limits::SAMPLE_ID_MAX_CHARS {
        return Err(cell_err(
            SAMPLE,
            CellProblem::TooLong {
                chars,
                max: gearpump_core::limits::SAMPLE_ID_MAX_CHARS,
            },
        ));
    }
    // within the physical ranges of `gearpump_core::limits`: refused here, before
    // any simulation sees them
    let in_range =
        |k: usize, v: f64, range: gearpump_core::limits::Range| -> Result<f64, DataError> {
            range
                .check(v)
                .map_err(|message| cell_err(k, CellProblem::OutOfRange { message }))
        };
    let clearance = |k: usize| -> Result<f64, DataError> {
        let v = non_negative(k)?;
        in_range(k, v, gearpump_core::limits::clearance("clearance"))
    };
    let tip = [clearance(TIP_DRIVE)?, clearance(TIP_DRIVEN)?];
    let brg = [clearance(BRG_DRIVE)?, clearance(BRG_DRIVEN)?];
    let pressure_bar = non_negative(PRESSURE)?;
    let pressure_bar = in_range(PRESSURE, pressure_bar, gearpump_core::limits::PRESSURE_BAR)?;
    let speed_rpm = number(SPEED)?;
    if speed_rpm <= 0.0 {
        return Err(cell_err(
            SPEED,
            CellProblem::NotPositive { value: speed_rpm },
        ));
    }
    let speed_rpm = in_range(SPEED, speed_rpm, gearpump_core::limits::SPEED_RPM)?;
    let temp_c = number(TEMP)?;
    if temp_c <= -gearpump_core::units::ZERO_CELSIUS_K {
        return Err(cell_err(
            TEMP,
            CellProblem::BelowAbsoluteZero { value: temp_c },
        ));
    }
    let flow_lpm = non_negative(FLOW)?;
    let flow_lpm = in_range(FLOW, flow_lpm, gearpump_core::limits::FLOW_LPM)?;
    let torque = if text(TORQUE).is_empty() {
        None
    } else {
        Some(in_range(
            TORQUE,
            number(TORQUE)?,
            gearpump_core::limits::TORQUE_NM,
        )?)
    };

    Ok(TestRow {
        row,
        sample,
        tip_clearance: tip.map(um_to_m),
        bearing_clearance: brg.map(um_to_m),
        pressure: bar_to_pa(pressure_bar),
        speed: rpm_to_rad_s(speed_rpm),
        temp: celsius_to_kelvin(temp_c),
        flow: lpm_to_m3_s(flow_lpm),
        torque,
        condition: Condition {
            pressure_bar,
            speed_rpm,
            temp_c,
        },
        cells,
    })
}

/// Rows sharing one working condition.
#[derive(Debug, Clone, PartialEq)]
pub struct ConditionGroup {
    /// The condition as written in its first row.
    pub condition: Condition,
    /// Indices into the row slice, in input order.
    pub rows: Vec<usize>,
}

/// Group rows by working condition (pressure, speed, temperature compared at
/// [`CONDITION_RESOLUTION`]). Groups come in order of first appearance, rows
/// within a group in input order: the result is deterministic.
pub fn group_by_condition(rows: &[TestRow]) -> Vec<ConditionGroup> {
    let mut groups: Vec<ConditionGroup> = Vec::new();
    let mut index: HashMap<(i64, i64, i64), usize> = HashMap::new();
    for (i, r) in rows.iter().enumerate() {
        let key = r.condition.key();
        match index.get(&key) {
            Some(&g) => groups[g].rows.push(i),
            None => {
                index.insert(key, groups.len());
                groups.push(ConditionGroup {
                    condition: r.condition,
                    rows: vec![i],
                });
            }
        }
    }
    groups
}

/// One row of a measured campaign CSV, in the CSV's edge units (used to
/// write one, e.g. by `synth`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CampaignRecord {
    pub sample: String,
    pub tip_clearance_drive_um: f64,
    pub tip_clearance_driven_um: f64,
    pub bearing_clearance_drive_um: f64,
    pub bearing_clearance_driven_um: f64,
    pub pressure_bar: f64,
    pub speed_rpm: f64,
    pub temp_c: f64,
    pub flow_lpm: f64,
    /// `None` writes an empty cell.
    pub torque_nm: Option<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "sample,tip_clearance_drive_um,tip_clearance_driven_um,bearing_clearance_drive_um,bearing_clearance_driven_um,pressure_bar,speed_rpm,temp_c,flow_lpm,torque_nm";

    fn csv_with(rows: &[&str]) -> String {
        let mut s = format!("{HEADER}\n");
        for r in rows {
            s.push_str(r);
            s.push('\n');
        }
        s
    }

    const GOOD1: &str = "N01,30,32,10,12,30,1000,60,13.5,7.1";
    const GOOD2: &str = "N02,31,33,11,13,30,1000,60,13.4,";

    fn err_of(rows: &[&str]) -> DataError {
        match parse_campaign_str("c.csv", &csv_with(rows)) {
            Ok(_) => panic!("expected an error"),
            Err(e) => e,
        }
    }

    fn assert_cell(e: &DataError, row: usize, column: &str, fragment: &str) {
        let msg = e.to_string();
        assert!(
            msg.starts_with(&format!("c.csv: row {row}, column {column}: ")),
            "{msg}"
        );
        assert!(msg.contains(fragment), "{msg}");
        assert_eq!(e.file(), "c.csv");
        assert_eq!(e.row(), Some(row));
        assert_eq!(e.column(), Some(column));
    }

    #[test]
    fn campaign_reads_good_file_to_si() {
        let c = parse_campaign_str("c.csv", &csv_with(&[GOOD1, GOOD2])).unwrap();
        assert_eq!(c.rows.len(), 2);
        let r = &c.rows[0];
        assert_eq!(r.row, 1);
        assert_eq!(r.sample, "N01");
        assert!((r.tip_clearance[0] - 30e-6).abs() < 1e-18);
        assert!((r.bearing_clearance[1] - 12e-6).abs() < 1e-18);
        assert!((r.pressure - 30e5).abs() < 1e-6);
        assert!((r.speed - 1000.0 * std::f64::consts::PI / 30.0).abs() < 1e-12);
        assert!((r.temp - 333.15).abs() < 1e-12);
        assert!((r.flow - 13.5 / 60_000.0).abs() < 1e-18);
        assert_eq!(r.torque, Some(7.1));
        assert_eq!(c.rows[1].row, 2);
    }

    #[test]
    fn campaign_empty_torque_is_none() {
        let c = parse_campaign_str("c.csv", &csv_with(&[GOOD2])).unwrap();
        assert_eq!(c.rows[0].torque, None);
        let c = parse_campaign_str("c.csv", &csv_with(&["N02,31,33,11,13,30,1000,60,13.4,  "]))
            .unwrap();
        assert_eq!(c.rows[0].torque, None);
    }

    #[test]
    fn campaign_column_order_free_and_extra_columns_kept() {
        let text = "note,speed_rpm,sample,flow_lpm,torque_nm,temp_c,pressure_bar,bearing_clearance_driven_um,bearing_clearance_drive_um,tip_clearance_driven_um,tip_clearance_drive_um,operator\n\
                    \"first, run\",1000,N01,13.5,,60,30,12,10,32,30,ann\n";
        let c = parse_campaign_str("c.csv", text).unwrap();
        let r = &c.rows[0];
        assert_eq!(r.sample, "N01");
        assert!((r.tip_clearance[0] - 30e-6).abs() < 1e-18);
        assert!((r.tip_clearance[1] - 32e-6).abs() < 1e-18);
        assert_eq!(r.cells[0], "first, run");
        assert_eq!(r.cells[11], "ann");
        assert_eq!(c.headers[0], "note");
        assert_eq!(c.headers.len(), 12);
    }

    #[test]
    fn campaign_bom_and_padded_header_accepted() {
        let text = format!(
            "\u{feff} {}\n{GOOD1}\n",
            HEADER.replace(",speed_rpm,", ", speed_rpm ,")
        );
        let c = parse_campaign_str("c.csv", &text).unwrap();
        assert_eq!(c.rows[0].condition.speed_rpm, 1000.0);
    }

    #[test]
    fn campaign_blank_lines_are_not_counted_as_rows() {
        let text = format!("{HEADER}\n{GOOD1}\n\n{GOOD2}\nN03,1,1,1,1,30,-5,60,1,\n");
        let e = parse_campaign_str("c.csv", &text).unwrap_err();
        assert_cell(&e, 3, "speed_rpm", "must be > 0, got -5");
    }

    #[test]
    fn campaign_error_missing_column() {
        let text = HEADER.replace(",speed_rpm", "") + "\nN01,30,32,10,12,30,60,13.5,7.1\n";
        let e = parse_campaign_str("c.csv", &text).unwrap_err();
        assert!(matches!(
            e,
            DataError::MissingColumn {
                column: "speed_rpm",
                ..
            }
        ));
        assert_eq!(
            e.to_string(),
            "c.csv: header, column speed_rpm: required column is missing"
        );
        assert_eq!(e.column(), Some("speed_rpm"));
    }

    #[test]
    fn campaign_error_duplicate_column() {
        let text = format!("{HEADER},flow_lpm\n{GOOD1},1\n");
        let e = parse_campaign_str("c.csv", &text).unwrap_err();
        assert!(
            matches!(
                e,
                DataError::DuplicateColumn {
                    column: "flow_lpm",
                    ..
                }
            ),
            "{e}"
        );
    }

    #[test]
    fn campaign_error_non_numeric() {
        let e = err_of(&[GOOD1, "N02,31,33,11,13,30,1000,60,13,4,", GOOD2]);
        // 11 fields: malformed row
        assert!(matches!(e, DataError::Malformed { row: 2, .. }), "{e}");
        assert!(e.to_string().starts_with("c.csv: row 2: "), "{e}");
        let e = err_of(&[GOOD1, "N02,31,33,11,13,30,1000,60,\"13,4\","]);
        assert!(matches!(
            e,
            DataError::Cell {
                problem: CellProblem::NotNumeric { .. },
                ..
            }
        ));
        assert_cell(&e, 2, "flow_lpm", "not a number: \"13,4\"");
    }

    #[test]
    fn campaign_error_empty_numeric_cell() {
        let e = err_of(&["N01,30,32,10,12,30,1000,,13.5,7.1"]);
        assert!(matches!(
            e,
            DataError::Cell {
                problem: CellProblem::Empty,
                ..
            }
        ));
        assert_cell(&e, 1, "temp_c", "must not be empty");
    }

    #[test]
    fn campaign_error_nan_and_inf() {
        let e = err_of(&[GOOD1, "N02,31,33,11,NaN,30,1000,60,13.4,"]);
        assert!(matches!(
            e,
            DataError::Cell {
                problem: CellProblem::NotFinite { .. },
                ..
            }
        ));
        assert_cell(&e, 2, "bearing_clearance_driven_um", "finite");
        let e = err_of(&["N02,31,33,11,13,30,1000,60,13.4,-inf"]);
        assert_cell(&e, 1, "torque_nm", "finite");
    }

    #[test]
    fn campaign_error_negative_clearance() {
        let e = err_of(&[GOOD1, GOOD2, "N03,-1,33,11,13,30,1000,60,13.4,"]);
        assert!(matches!(
            e,
            DataError::Cell {
                problem: CellProblem::Negative { .. },
                ..
            }
        ));
        assert_cell(&e, 3, "tip_clearance_drive_um", "must be >= 0, got -1");
    }

    #[test]
    fn campaign_error_speed_not_positive() {
        let rows = [
            GOOD1,
            GOOD2,
            "N03,1,1,1,1,30,1000,60,1,",
            "N04,1,1,1,1,30,1000,60,1,",
            "N05,1,1,1,1,30,1000,60,1,",
            "N06,1,1,1,1,30,-3,60,1,",
        ];
        let e = err_of(&rows);
        assert!(matches!(
            e,
            DataError::Cell {
                problem: CellProblem::NotPositive { .. },
                ..
            }
        ));
        assert_eq!(
            e.to_string(),
            "c.csv: row 6, column speed_rpm: must be > 0, got -3"
        );
        let e = err_of(&["N01,1,1,1,1,30,0,60,1,"]);
        assert_cell(&e, 1, "speed_rpm", "must be > 0, got 0");
    }

    #[test]
    fn campaign_error_negative_flow() {
        let e = err_of(&["N01,1,1,1,1,30,1000,60,-0.5,"]);
        assert_cell(&e, 1, "flow_lpm", "must be >= 0, got -0.5");
    }

    #[test]
    fn campaign_error_negative_pressure_and_absurd_temperature() {
        let e = err_of(&["N01,1,1,1,1,-2,1000,60,1,"]);
        assert_cell(&e, 1, "pressure_bar", "must be >= 0, got -2");
        let e = err_of(&["N01,1,1,1,1,2,1000,-300,1,"]);
        assert_cell(&e, 1, "temp_c", "absolute zero");
    }

    #[test]
    fn campaign_error_empty_sample() {
        let e = err_of(&[GOOD1, "  ,31,33,11,13,30,1000,60,13.4,"]);
        assert_cell(&e, 2, "sample", "must not be empty");
    }

    #[test]
    fn campaign_error_sample_id_too_long() {
        let max = gearpump_core::limits::SAMPLE_ID_MAX_CHARS;
        let ok = format!("{},31,33,11,13,30,1000,60,13.4,", "N".repeat(max));
        let c = parse_campaign_str("c.csv", &csv_with(&[GOOD1, &ok])).unwrap();
        assert_eq!(c.rows[1].sample.len(), max);
        // counted in characters, not bytes
        let wide = format!("{},31,33,11,13,30,1000,60,13.4,", "\u{c4}".repeat(max));
        parse_campaign_str("c.csv", &csv_with(&[GOOD1, &wide])).unwrap();
        let long = format!("{},31,33,11,13,30,1000,60,13.4,", "N".repeat(65_600));
        let e = err_of(&[GOOD1, &long]);
        assert_cell(&e, 2, "sample", "at most 64 characters, got 65600");
    }

    #[test]
    fn campaign_error_duplicate_row() {
        // Same sample and condition within 1e-6 bar.
        let e = err_of(&[GOOD1, GOOD2, "N01,30,32,10,12,30.0000001,1000,60,13.6,"]);
        match &e {
            DataError::DuplicateRow {
                row,
                first_row,
                sample,
                ..
            } => {
                assert_eq!((*row, *first_row, sample.as_str()), (3, 1, "N01"));
            }
            other => panic!("{other}"),
        }
        let msg = e.to_string();
        assert!(
            msg.starts_with("c.csv: row 3, column sample: duplicate"),
            "{msg}"
        );
        assert!(msg.contains("row 1"), "{msg}");
        assert_eq!(e.column(), Some("sample"));
        // Same sample at another condition is fine.
        parse_campaign_str(
            "c.csv",
            &csv_with(&[GOOD1, "N01,30,32,10,12,30,2000,60,27,"]),
        )
        .unwrap();
    }

    #[test]
    fn campaign_error_empty_file() {
        for text in ["", "  \n\n", "\u{feff}"] {
            let e = parse_campaign_str("c.csv", text).unwrap_err();
            assert!(matches!(e, DataError::Empty { .. }), "{e}");
            assert!(e.to_string().starts_with("c.csv: empty file"));
        }
        let e = parse_campaign_str("c.csv", &format!("{HEADER}\n")).unwrap_err();
        assert!(matches!(e, DataError::NoDataRows { .. }), "{e}");
        assert!(e.to_string().starts_with("c.csv: "));
    }

    #[test]
    fn campaign_error_unreadable_file_names_path() {
        let e = read_campaign(Path::new("/nonexistent/dir/c.csv")).unwrap_err();
        assert!(e
            .to_string()
            .starts_with("/nonexistent/dir/c.csv: cannot read"));
    }

    #[test]
    fn campaign_grouping_first_appearance_with_tolerance() {
        let rows = [
            "A,1,1,1,1,30,1000,60,1,",
            "A,1,1,1,1,10,1000,60,1,",
            "B,1,1,1,1,30.0000000001,1000,60,1,",
            "B,1,1,1,1,10,1000,60.0000002,1,",
            "C,1,1,1,1,10,1000,120,1,",
            "C,1,1,1,1,30,1000,60,1,",
        ];
        let c = parse_campaign_str("c.csv", &csv_with(&rows)).unwrap();
        let g = group_by_condition(&c.rows);
        assert_eq!(g.len(), 3);
        assert_eq!(g[0].rows, vec![0, 2, 5]);
        assert_eq!(g[1].rows, vec![1, 3]);
        assert_eq!(g[2].rows, vec![4]);
        assert_eq!(g[0].condition.pressure_bar, 30.0);
        assert_eq!(g[2].condition.temp_c, 120.0);
    }

    #[test]
    fn campaign_writer_roundtrip() {
        let recs = vec![
            CampaignRecord {
                sample: "N,01".into(),
                tip_clearance_drive_um: 30.123456789012345,
                tip_clearance_driven_um: 31.0,
                bearing_clearance_drive_um: 10.0,
                bearing_clearance_driven_um: 12.5,
                pressure_bar: 30.0,
                speed_rpm: 1000.0,
                temp_c: 60.0,
                flow_lpm: 0.1 + 0.2,
                torque_nm: None,
            },
            CampaignRecord {
                sample: "N02".into(),
                tip_clearance_drive_um: 0.123_456_789_012_345,
                tip_clearance_driven_um: 31.0,
                bearing_clearance_drive_um: 10.0,
                bearing_clearance_driven_um: 12.5,
                pressure_bar: 10.0,
                speed_rpm: 500.0,
                temp_c: 120.0,
                flow_lpm: 6.0,
                torque_nm: Some(5.25),
            },
        ];
        let text = crate::io::campaign_csv_string(&recs);
        assert!(text.starts_with(HEADER));
        let c = parse_campaign_str("s.csv", &text).unwrap();
        assert_eq!(c.rows[0].sample, "N,01");
        assert_eq!(
            c.rows[0].cells[1].parse::<f64>().unwrap(),
            30.123456789012345
        );
        assert_eq!(c.rows[0].cells[8].parse::<f64>().unwrap(), 0.1 + 0.2);
        assert_eq!(c.rows[0].torque, None);
        assert_eq!(c.rows[1].torque, Some(5.25));
        assert_eq!(c.rows[1].condition.temp_c, 120.0);
    }
}
