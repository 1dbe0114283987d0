//! The pump design: gears, casing, bearings, clearances, oil, losses and
//! numerical settings. Read from a TOML file (the seed pump's is bundled and is
//! the default), overridden by `--set key.path=value`, converted to SI and
//! validated once here: the physics modules trust a [`Design`].
//!
//! Every value the seed paper does not disclose is chosen and justified in
//! `designs/seed_pump.toml`.

use crate::oil::{walther_fit, Oil};
use crate::units::*;
use serde::Deserialize;
use thiserror::Error;

/// The bundled design of the seed paper's pump (seed Table 1).
pub const SEED_PUMP_TOML: &str = include_str!("../../../designs/seed_pump.toml");

#[derive(Debug, Error)]
pub enum DesignError {
    #[error("design file {path}: {message}")]
    Io { path: String, message: String },
    /// A TOML syntax error, where it is (line and column from 1, the
    /// column in characters).
    #[error("{file}: line {line}, column {column}: TOML syntax: {message}")]
    Syntax {
        file: String,
        line: usize,
        column: usize,
        message: String,
    },
    /// Any other error of a design file, with the file named.
    #[error("{file}: {source}")]
    InFile {
        file: String,
        #[source]
        source: Box<DesignError>,
    },
    #[error("design: key `{key}`: {message}")]
    Key { key: String, message: String },
    #[error("override {arg}: {message}")]
    Override { arg: String, message: String },
    #[error("design: key `{key}` = {value}: {message}")]
    Invalid {
        key: String,
        value: String,
        message: String,
    },
}

/// A number as a message shows it: in exponent form when it is very large
/// or very small (`1e-300`, not 300 zeros), as typed otherwise.
fn shown(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-4..1e7).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        v.to_string()
    }
}

/// The option `value` of `key` among its two `choices` (name, option), or
/// an error that names both.
fn one_of<T: Copy>(key: &str, value: &str, choices: [(&str, T); 2]) -> Result<T, DesignError> {
    choices
        .iter()
        .find(|(name, _)| *name == value)
        .map(|&(_, option)| option)
        .ok_or_else(|| {
            invalid(
                key,
                format!("\"{value}\""),
                format!("must be \"{}\" or \"{}\"", choices[0].0, choices[1].0),
            )
        })
}

fn invalid(key: &str, value: impl std::fmt::Display, message: impl Into<String>) -> DesignError {
    DesignError::Invalid {
        key: key.to_string(),
        value: value.to_string(),
        message: message.into(),
    }
}

// ---------------------------------------------------------------- file model

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DesignFile {
    pub gears: GearsFile,
    pub casing: CasingFile,
    pub bearings: BearingsFile,
    pub clearance: ClearanceFile,
    pub oil: OilFile,
    pub losses: LossesFile,
    pub numerics: NumericsFile,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
pub enum AutoOr {
    Value(f64),
    Auto(String),
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GearsFile {
    pub z_drive: u32,
    pub z_driven: u32,
    pub normal_module_mm: f64,
    pub helix_angle_deg: f64,
    pub face_width_mm: f64,
    pub normal_pressure_angle_deg: f64,
    pub profile_shift_drive: f64,
    pub profile_shift_driven: f64,
    pub tip_radius_drive_mm: f64,
    pub tip_radius_driven_mm: f64,
    pub root_radius_drive_mm: f64,
    pub root_radius_driven_mm: f64,
    pub centre_distance_mm: AutoOr,
    pub backlash_normal_mm: f64,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CasingFile {
    pub suction_port_edge_drive_deg: f64,
    pub delivery_port_edge_drive_deg: f64,
    pub suction_port_edge_driven_deg: f64,
    pub delivery_port_edge_driven_deg: f64,
    pub inlet_chamber_volume_cm3: f64,
    pub outlet_chamber_volume_cm3: f64,
    pub port_area_mm2: f64,
    pub port_discharge_coefficient: f64,
    /// A number (mm) or "auto" (the rule of [`relief_groove_edge`]).
    pub delivery_groove_edge_mm: AutoOr,
    pub suction_groove_edge_mm: AutoOr,
    pub groove_width_mm: f64,
    pub groove_depth_mm: f64,
    pub groove_discharge_coefficient: f64,
    pub mesh_discharge_coefficient: f64,
    /// "grooves" (geometric relief grooves) or "ideal" (trapped volume ideally relieved).
    pub relief: String,
    /// "laminar" (the channel along a helical tooth space between its axial
    /// zones) or "none" (each zone on its own); absent = "laminar".
    #[serde(default = "laminar")]
    pub axial_flow: String,
    /// "gap" (a meshing-zone passage opens by the narrowest gap between
    /// the two teeth that bound it; the bundled design's) or "boundary" (by
    /// the length of the boundary between the gears' regions through it);
    /// absent = "boundary", the rule of design files written before
    /// 2026-11-29, whose results it keeps.
    #[serde(default = "boundary_length")]
    pub mesh_passage: String,
}

fn laminar() -> String {
    "laminar".into()
}

fn boundary_length() -> String {
    "boundary".into()
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BearingsFile {
    pub diameter_drive_mm: f64,
    pub diameter_driven_mm: f64,
    pub length_mm: f64,
    /// Section of the by-pass grooves joining each gear's hub to the inlet
    /// (both plates together), mm^2; 0 = none (the hubs drain through the
    /// bearing films alone). Absent: [`DEFAULT_BYPASS_AREA_MM2`].
    #[serde(default = "default_bypass_area")]
    pub bypass_groove_area_mm2: f64,
}

/// By-pass groove section of a design file that does not give one, mm^2:
/// the seed's pump feeds its bearings from suction through by-pass grooves
/// (seed Sec. 3); 1 x 1.5 mm on each plate.
pub const DEFAULT_BYPASS_AREA_MM2: f64 = 3.0;

fn default_bypass_area() -> f64 {
    DEFAULT_BYPASS_AREA_MM2
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClearanceFile {
    pub tip_um: f64,
    pub bearing_um: f64,
    pub lateral_um: f64,
    /// Growth of the clearances with the oil temperature above 20 degC (the
    /// metrology lab), um/K; absent = 0 (docs/model.md section 8).
    #[serde(default)]
    pub thermal_growth_um_per_k: f64,
    /// Where it acts: "tips", "bearings", "lateral", "radial" (tips and
    /// bearings) or "all"; absent = "radial".
    #[serde(default = "radial")]
    pub thermal_growth_on: String,
    /// Growth of the clearances with the delivery gauge pressure, um/bar;
    /// absent = 0.
    #[serde(default)]
    pub pressure_growth_um_per_bar: f64,
    #[serde(default = "radial")]
    pub pressure_growth_on: String,
}

fn radial() -> String {
    "radial".into()
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OilFile {
    pub nu_40c_cst: f64,
    pub nu_100c_cst: f64,
    pub density_20c_kg_m3: f64,
    pub expansion_per_k: f64,
    pub bulk_modulus_gpa: f64,
    pub gas_release_bar_abs: f64,
    pub cavitation_modulus_bar: f64,
    pub t_min_c: f64,
    pub t_max_c: f64,
    /// Factors on the datasheet (Walther) viscosity at 60 and 120 degC,
    /// log-linear in temperature between (an aged or other oil); absent = 1.
    #[serde(default = "unity")]
    pub viscosity_factor_60c: f64,
    #[serde(default = "unity")]
    pub viscosity_factor_120c: f64,
    /// Free air volume fraction at atmospheric pressure; absent = 0.
    #[serde(default)]
    pub air_fraction: f64,
    /// Barus pressure-viscosity coefficient in the gaps, 1/Pa; absent = 0.
    #[serde(default)]
    pub pressure_viscosity_per_pa: f64,
}

fn unity() -> f64 {
    1.0
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LossesFile {
    pub thrust_plate_unbalance: f64,
    pub thrust_plate_friction: f64,
    pub mesh_friction_coefficient: f64,
    pub churning_coefficient: f64,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NumericsFile {
    pub angle_step_deg: f64,
    pub helical_slices: u32,
    /// Axial pressure nodes of every tooth space; absent = 1 (one pressure
    /// over the face width, the layout of designs written before the key).
    #[serde(default = "one")]
    pub axial_nodes: u32,
    pub table_step_deg: f64,
    pub newton_tolerance: f64,
    pub newton_max_iterations: u32,
    pub periodic_tolerance: f64,
    pub max_revolutions: u32,
    pub orifice_transition_bar: f64,
    pub coupling_tolerance: f64,
    pub coupling_max_iterations: u32,
}

// ---------------------------------------------------------------- validated SI model

/// One gear's data, SI.
#[derive(Debug, Clone, PartialEq)]
pub struct GearSpec {
    pub z: u32,
    /// Profile shift coefficient x (dimensionless).
    pub shift: f64,
    /// Tip radius, m.
    pub tip_radius: f64,
    /// Root radius, m.
    pub root_radius: f64,
    /// Transverse circular thinning at the reference circle, m.
    pub thinning: f64,
    /// Casing port edges, rad, on the gear's own angle (0 = towards the mating gear,
    /// positive towards the suction side and in the sense of rotation).
    pub suction_edge: f64,
    pub delivery_edge: f64,
    /// Journal diameter, m.
    pub bearing_diameter: f64,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Clearances {
    /// Tooth tip / casing radial clearance of the driving and driven gear, m.
    pub tip: [f64; 2],
    /// Journal bearing radial clearance of the driving and driven gear, m.
    pub bearing: [f64; 2],
    /// Lateral (axial) clearance on each face, m.
    pub lateral: f64,
    /// How the clearances grow in service (docs/model.md section 8).
    pub growth: ClearanceGrowth,
}

/// Where a clearance law acts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Site {
    Tips,
    Bearings,
    Lateral,
    /// Tips and bearings (a casing and its bearing bores growing together).
    Radial,
    /// Tips, bearings and the lateral gap.
    All,
}

impl Site {
    pub const ALL: [Site; 5] = [
        Site::Tips,
        Site::Bearings,
        Site::Lateral,
        Site::Radial,
        Site::All,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Site::Tips => "tips",
            Site::Bearings => "bearings",
            Site::Lateral => "lateral",
            Site::Radial => "radial",
            Site::All => "all",
        }
    }

    pub fn parse(text: &str) -> Option<Site> {
        Site::ALL.into_iter().find(|s| s.name() == text.trim())
    }
}

/// Clearance growth laws in service: `h = h_meas + k (T - 20 degC)` and
/// `h = h_meas + k p` on the gaps of their site (bearings scaled by
/// R_journal / R_tip: the same differential strain), applied per operating
/// point by the campaign's effect model (docs/model.md section 8).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClearanceGrowth {
    /// m/K.
    pub thermal: f64,
    pub thermal_on: Site,
    /// m/Pa.
    pub pressure: f64,
    pub pressure_on: Site,
}

impl Default for ClearanceGrowth {
    fn default() -> Self {
        ClearanceGrowth {
            thermal: 0.0,
            thermal_on: Site::Radial,
            pressure: 0.0,
            pressure_on: Site::Radial,
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct Casing {
    pub inlet_volume: f64,
    pub outlet_volume: f64,
    pub port_area: f64,
    pub port_cd: f64,
    pub delivery_groove_edge: f64,
    pub suction_groove_edge: f64,
    pub groove_width: f64,
    pub groove_depth: f64,
    pub groove_cd: f64,
    pub mesh_cd: f64,
    /// Trapped-volume relief model.
    pub relief: Relief,
    /// Flow along a helical tooth space between its axial zones.
    pub axial_flow: AxialFlow,
    /// What opens a meshing-zone passage.
    pub mesh_passage: MeshPassage,
}

/// What opens a meshing-zone passage between a driving-gear and a
/// driven-gear pocket (`geometry::tables::Interface`, docs/model.md
/// section 4).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshPassage {
    /// The narrowest gap between the two teeth that bound it: past an end
    /// of the path of contact, the gap between a tip corner and the mating
    /// flank, which grows as the square of the distance past the end. The
    /// rule an independent model of the trapped volume supports
    /// (docs/model.md section 3).
    Gap,
    /// The length of the boundary between the gears' regions (the line of
    /// action and the bores inside the lens) that runs through fluid
    /// between the two pockets. It crosses the gap past an end of the path
    /// of contact obliquely, 1.4-2.2 times its width. The default until
    /// the diagnosis's hand-made references carry what the gap rule adds
    /// (docs/model.md section 3).
    Boundary,
}

/// Whether fluid flows along a tooth space between its axial zones
/// (`hydraulics::steps`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AxialFlow {
    /// Laminar flow along the channel the tooth space forms.
    Laminar,
    /// None: every zone is a space of its own, as in the kinematic closed
    /// form that relieves every section of the face on its own. An
    /// idealisation for kinematic checks.
    None,
}

/// How the trapped volume in the meshing zone is relieved.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Relief {
    /// The relief grooves of the design, by their planform overlap.
    Grooves,
    /// Ideal relief (Foster et al. 1985, cited by the seed): a meshing-zone
    /// fluid region opens wide to the delivery while it shrinks and to the
    /// suction while it grows. An idealisation for kinematic checks.
    Ideal,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Losses {
    /// Unbalanced fraction of the gear face area pressing the thrust plate.
    pub plate_unbalance: f64,
    /// Friction coefficient of the thrust plate on the gear faces.
    pub plate_friction: f64,
    pub mesh_friction: f64,
    pub churning: f64,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Numerics {
    pub angle_step: f64,
    pub slices: usize,
    /// Axial zones of every tooth space (`hydraulics::steps`), 1..=slices.
    pub axial_nodes: usize,
    pub table_step: f64,
    pub newton_tol: f64,
    pub newton_max_iter: usize,
    pub periodic_tol: f64,
    pub max_revolutions: usize,
    pub orifice_dp_t: f64,
    pub coupling_tol: f64,
    pub coupling_max_iter: usize,
}

/// A validated pump design in SI units.
#[derive(Debug, Clone, PartialEq)]
pub struct Design {
    pub gears: [GearSpec; 2],
    /// Normal module, m.
    pub normal_module: f64,
    /// Helix angle, rad (0 = spur).
    pub helix_angle: f64,
    /// Face width, m.
    pub face_width: f64,
    /// Normal pressure angle of the generating rack, rad.
    pub normal_pressure_angle: f64,
    /// Operating centre distance, m.
    pub centre_distance: f64,
    pub casing: Casing,
    /// Bearing length (each of the two bearings of a gear), m.
    pub bearing_length: f64,
    /// By-pass groove section from each hub to the inlet, m^2 (0 = none).
    pub bypass_area: f64,
    pub clearance: Clearances,
    pub oil: Oil,
    pub losses: Losses,
    pub numerics: Numerics,
}

/// Loads a design: the bundled one when `path` is None.
pub fn load(path: Option<&std::path::Path>, sets: &[String]) -> Result<Design, DesignError> {
    match path {
        None => from_toml_str(SEED_PUMP_TOML, sets),
        Some(p) => {
            let text = std::fs::read_to_string(p).map_err(|e| DesignError::Io {
                path: p.display().to_string(),
                message: e.to_string(),
            })?;
            from_toml_file_text(&text, sets, &p.display().to_string())
        }
    }
}

/// A design with the text it loads from: the file's text (or the bundled
/// one), and when `--set` overrides are given the TOML with them applied, so
/// the text alone loads to the same design (what an FMU ships in its
/// `resources/`). Errors as [`load`]'s, naming the file and the key.
pub fn load_with_text(
    path: Option<&std::path::Path>,
    sets: &[String],
) -> Result<(String, Design), DesignError> {
    let (text, file) = match path {
        None => (SEED_PUMP_TOML.to_string(), "design".to_string()),
        Some(p) => (
            std::fs::read_to_string(p).map_err(|e| DesignError::Io {
                path: p.display().to_string(),
                message: e.to_string(),
            })?,
            p.display().to_string(),
        ),
    };
    let design = match path {
        None => from_toml_str(&text, sets)?,
        Some(_) => from_toml_file_text(&text, sets, &file)?,
    };
    if sets.is_empty() {
        return Ok((text, design));
    }
    let mut root: toml::Value = toml::from_str(&text).map_err(|e| DesignError::Io {
        path: file.clone(),
        message: e.to_string(),
    })?;
    for s in sets {
        apply_set(&mut root, s)?;
    }
    let body = toml::to_string(&root).map_err(|e| DesignError::Io {
        path: file.clone(),
        message: format!("writing the design with its overrides: {e}"),
    })?;
    let text = format!(
        "# {file} with {}\n{body}",
        sets.iter()
            .map(|s| format!("--set {s}"))
            .collect::<Vec<_>>()
            .join(" ")
    );
    let again = from_toml_str(&text, &[])?;
    if again != design {
        return Err(DesignError::Io {
            path: file,
            message: "the design with its overrides does not read back as the same design".into(),
        });
    }
    Ok((text, design))
}

/// [`from_toml_str`] for the text of the design file `file`: every error
/// names the file, a syntax error also its line and column.
pub fn from_toml_file_text(text: &str, sets: &[String], file: &str) -> Result<Design, DesignError> {
    parse(text, sets, file).map_err(|e| match e {
        e @ (DesignError::Syntax { .. } | DesignError::Io { .. } | DesignError::InFile { .. }) => e,
        other => DesignError::InFile {
            file: file.to_string(),
            source: Box::new(other),
        },
    })
}

/// Line and column (from 1; the column in characters) of byte `offset` of
/// `text`.
pub fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let mut at = offset.min(text.len());
    while !text.is_char_boundary(at) {
        at -= 1;
    }
    let before = &text[..at];
    let line = before.matches('\n').count() + 1;
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[start..].chars().count() + 1)
}

/// Parses TOML text, applies `key.path=value` overrides, validates.
pub fn from_toml_str(text: &str, sets: &[String]) -> Result<Design, DesignError> {
    parse(text, sets, "design")
}

fn parse(text: &str, sets: &[String], file: &str) -> Result<Design, DesignError> {
    let mut value: toml::Value = toml::from_str(text).map_err(|e| {
        let (line, column) = e.span().map_or((0, 0), |s| line_column(text, s.start));
        DesignError::Syntax {
            file: file.to_string(),
            line,
            column,
            message: e.message().trim().replace('\n', "; "),
        }
    })?;
    for s in sets {
        apply_set(&mut value, s)?;
    }
    let file: DesignFile = serde_path_to_error::deserialize(value).map_err(|e| {
        let key = e.path().to_string();
        // the first line: the toml crate adds "in `table`", the key says it
        let message = e.inner().to_string();
        DesignError::Key {
            key,
            message: message.lines().next().unwrap_or_default().to_string(),
        }
    })?;
    Design::from_file(&file)
}

/// Applies one `key.path=value` override; the key must exist and the new value
/// must have the type of the old one (an integer is accepted where a float is).
pub fn apply_set(root: &mut toml::Value, arg: &str) -> Result<(), DesignError> {
    let err = |m: &str| DesignError::Override {
        arg: arg.to_string(),
        message: m.to_string(),
    };
    let (path, raw) = arg
        .split_once('=')
        .ok_or_else(|| err("expected key.path=value"))?;
    let path = path.trim();
    let raw = raw.trim();
    if path.is_empty() {
        return Err(err("empty key"));
    }
    let mut cur = &mut *root;
    let parts: Vec<&str> = path.split('.').collect();
    for (i, part) in parts.iter().enumerate() {
        let table = cur
            .as_table_mut()
            .ok_or_else(|| err(&format!("`{}` is not a table", parts[..i].join("."))))?;
        cur = table
            .get_mut(*part)
            .ok_or_else(|| err(&format!("unknown key `{path}`")))?;
    }
    let new = match cur {
        toml::Value::Float(_) => raw
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .map(toml::Value::Float)
            .ok_or_else(|| err(&format!("`{path}` takes a number, got `{raw}`")))?,
        toml::Value::Integer(_) => raw
            .parse::<i64>()
            .map(toml::Value::Integer)
            .map_err(|_| err(&format!("`{path}` takes an integer, got `{raw}`")))?,
        toml::Value::Boolean(_) => raw
            .parse::<bool>()
            .map(toml::Value::Boolean)
            .map_err(|_| err(&format!("`{path}` takes true or false, got `{raw}`")))?,
        toml::Value::String(_) => {
            // "auto"-or-number keys: accept a number or a string
            match raw.parse::<f64>() {
                Ok(v) if v.is_finite() => toml::Value::Float(v),
                _ => toml::Value::String(raw.trim_matches('"').to_string()),
            }
        }
        toml::Value::Table(_) | toml::Value::Array(_) | toml::Value::Datetime(_) => {
            return Err(err(&format!("`{path}` is not a scalar value")))
        }
    };
    *cur = new;
    Ok(())
}

fn positive(key: &str, v: f64) -> Result<f64, DesignError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(invalid(key, v, "must be a finite number > 0"))
    }
}

/// A count that must lie in `[1, hi]`.
fn one() -> u32 {
    1
}

fn count_in_range(key: &str, v: u32, hi: u32) -> Result<usize, DesignError> {
    if (1..=hi).contains(&v) {
        Ok(v as usize)
    } else {
        Err(invalid(key, v, format!("must lie in [1, {hi}]")))
    }
}

fn in_range(key: &str, v: f64, lo: f64, hi: f64) -> Result<f64, DesignError> {
    within(key, v, lo, hi, || format!("must lie in [{lo}, {hi}]"))
}

/// `v` if finite and in `[lo, hi]`, else the error naming `key`, the value
/// and `rule` (the range as the caller words it).
fn within(
    key: &str,
    v: f64,
    lo: f64,
    hi: f64,
    rule: impl FnOnce() -> String,
) -> Result<f64, DesignError> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(v)
    } else {
        Err(invalid(key, shown(v), rule()))
    }
}

/// The physical range of a design key in the key's own units, and why it
/// is there: wide enough for any external gear pump (modules 0.5-20 mm,
/// face widths to a few hundred mm, oils from a light fuel to a heavy gear
/// oil), so only absurd magnitudes are refused, before the solver sees them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bound {
    pub lo: f64,
    pub hi: f64,
    pub why: &'static str,
}

impl Bound {
    /// `v` if finite and within; otherwise an error naming `key`, the value,
    /// the range and the reason.
    fn check(&self, key: &str, v: f64) -> Result<f64, DesignError> {
        within(key, v, self.lo, self.hi, || {
            format!("must lie in [{}, {}] ({})", self.lo, self.hi, self.why)
        })
    }
}

/// A range worked out from other keys (mm, shown to 4 decimals): `v` if
/// finite and within, else an error naming `key`, the value, the range and
/// the reason.
fn in_derived_range(key: &str, v: f64, lo: f64, hi: f64, why: &str) -> Result<f64, DesignError> {
    within(key, v, lo, hi, || {
        format!("must lie in [{lo:.4}, {hi:.4}] ({why})")
    })
}

/// `gears.normal_module_mm`.
pub const NORMAL_MODULE_MM: Bound = Bound {
    lo: 0.1,
    hi: 50.0,
    why: "external gear pumps are cut with modules of about 0.5 to 20 mm",
};
/// `gears.face_width_mm`.
pub const FACE_WIDTH_MM: Bound = Bound {
    lo: 0.5,
    hi: 1000.0,
    why: "from a micro pump's gears to the widest industrial pumps' few hundred mm",
};
/// `casing.inlet_chamber_volume_cm3` and `casing.outlet_chamber_volume_cm3`.
pub const CHAMBER_CM3: Bound = Bound {
    lo: 0.01,
    hi: 10_000.0,
    why: "a micro pump's port cavity to a 10 l manifold; a larger volume is a reservoir, not a chamber of the pump",
};
/// `casing.port_area_mm2`.
pub const PORT_AREA_MM2: Bound = Bound {
    lo: 0.5,
    hi: 100_000.0,
    why: "a port of 0.8 mm to 350 mm bore; 1,000 l/min pumps have ports of about 100 mm",
};
/// `casing.groove_depth_mm`.
pub const GROOVE_DEPTH_MM: Bound = Bound {
    lo: 0.0,
    hi: 50.0,
    why: "a recess in a thrust plate, and the largest pumps' plates are a few tens of mm thick; 0 = no passage",
};
/// `oil.nu_40c_cst`.
pub const NU_40C_CST: Bound = Bound {
    lo: 0.5,
    hi: 10_000.0,
    why: "a light fuel (kerosene about 1 cSt) to the heaviest gear oils (ISO VG 3200)",
};
/// `oil.nu_100c_cst`.
pub const NU_100C_CST: Bound = Bound {
    lo: 0.35,
    hi: 2000.0,
    why: "the Walther law's log log(nu + 0.7) needs nu > 0.3 cSt; the heaviest gear oils are about 200 cSt at 100 degC",
};
/// `oil.density_20c_kg_m3`.
pub const DENSITY_KG_M3: Bound = Bound {
    lo: 500.0,
    hi: 2500.0,
    why: "light hydrocarbons (about 500) to fluorinated fluids (about 1,900); mineral oils 850-900",
};
/// `oil.bulk_modulus_gpa`.
pub const BULK_MODULUS_GPA: Bound = Bound {
    lo: 0.05,
    hi: 100.0,
    why: "an aerated oil in a compliant casing to an idealised stiff liquid (kinematic checks use 20); oils are 1-2.5",
};
/// `oil.gas_release_bar_abs` (below atmospheric too).
pub const GAS_RELEASE_BAR_ABS: Bound = Bound {
    lo: 0.001,
    hi: ATMOSPHERE_PA / 1.0e5,
    why: "dissolved air comes out between an oil's vapour pressure (about 1 mbar) and atmospheric",
};
/// `oil.cavitation_modulus_bar` (below the bulk modulus too).
pub const CAVITATION_MODULUS_BAR: Bound = Bound {
    lo: 0.1,
    hi: 1000.0,
    why: "a gas-laden oil is far softer than the liquid; its modulus is of the order of its pressure over its gas fraction",
};
/// `losses.churning_coefficient`.
pub const CHURNING: Bound = Bound {
    lo: 0.0,
    hi: 0.1,
    why: "moment coefficients of enclosed rotating discs are 1e-3 to 1e-2",
};
/// `numerics.orifice_transition_bar`.
pub const ORIFICE_TRANSITION_BAR: Bound = Bound {
    lo: 1.0e-5,
    hi: 1.0,
    why: "a regularisation: below 1 Pa the orifice law's slope at zero is too steep for Newton, above 1 bar it changes real pressure drops",
};

impl Design {
    /// The gear pair's specification for the geometry.
    pub fn pair_spec(&self) -> crate::geometry::pair::PairSpec {
        use crate::geometry::pair::{GearBlank, PairSpec};
        PairSpec {
            normal_module: self.normal_module,
            helix_angle: self.helix_angle,
            normal_pressure_angle: self.normal_pressure_angle,
            centre_distance: self.centre_distance,
            face_width: self.face_width,
            gears: [0, 1].map(|k| {
                let g = &self.gears[k];
                GearBlank {
                    z: g.z as usize,
                    tip_radius: g.tip_radius,
                    root_radius: g.root_radius,
                    shift: g.shift,
                    thinning: g.thinning,
                }
            }),
        }
    }

    /// The gear pair of the design.
    pub fn pair(&self) -> crate::geometry::pair::Pair {
        crate::geometry::pair::Pair::new(&self.pair_spec())
    }

    /// Converts to SI and validates every value and the geometry as a whole.
    pub fn from_file(f: &DesignFile) -> Result<Design, DesignError> {
        let cut = gears_from_file(&f.gears)?;
        let (casing, suction_edge, delivery_edge) = casing_from_file(&f.casing, &cut)?;
        let GearCut {
            mn,
            beta,
            b,
            alpha_n,
            a,
            z,
            x,
            ra,
            rf,
            thinning,
            ..
        } = cut;
        let names = ["drive", "driven"];
        let br = &f.bearings;
        let diameter = [br.diameter_drive_mm, br.diameter_driven_mm];
        let mut bd = [0.0; 2];
        for i in 0..2 {
            let key = format!("bearings.diameter_{}_mm", names[i]);
            let d_root = 2.0 * m_to_mm(rf[i]);
            if diameter[i].is_finite() && diameter[i] >= d_root {
                return Err(invalid(
                    &key,
                    shown(diameter[i]),
                    format!(
                        "journal radius must be below the gear's root radius {:.4} mm",
                        d_root / 2.0
                    ),
                ));
            }
            // below: the gear's pressure load grows with its diameter and a
            // journal a fifth of the root circle could not carry it
            bd[i] = mm_to_m(in_derived_range(
                &key,
                diameter[i],
                0.2 * d_root,
                d_root,
                "a fifth of the gear's root diameter up to the root circle",
            )?);
        }
        let d_mm = [m_to_mm(bd[0]), m_to_mm(bd[1])];
        let bearing_length = mm_to_m(in_derived_range(
            "bearings.length_mm",
            br.length_mm,
            0.05 * d_mm[0].max(d_mm[1]),
            4.0 * d_mm[0].min(d_mm[1]),
            "L/D of both journals 0.05 to 4: pump bushings run 0.3-1.5; shorter is a chamfer, longer the shaft bends away from its ends",
        )?);
        let bypass_area = mm2_to_m2(in_range(
            "bearings.bypass_groove_area_mm2",
            br.bypass_groove_area_mm2,
            0.0,
            100.0,
        )?);
        let cl = &f.clearance;
        let clearance = Clearances {
            tip: [um_to_m(clearance_um("clearance.tip_um", cl.tip_um)?); 2],
            bearing: [um_to_m(clearance_um("clearance.bearing_um", cl.bearing_um)?); 2],
            lateral: um_to_m(clearance_um("clearance.lateral_um", cl.lateral_um)?),
            growth: growth_from_file(cl)?,
        };
        let oil = oil_from_file(&f.oil)?;
        let losses = losses_from_file(&f.losses)?;
        let numerics = numerics_from_file(&f.numerics)?;
        let gears = [0, 1].map(|i| GearSpec {
            z: z[i],
            shift: x[i],
            tip_radius: ra[i],
            root_radius: rf[i],
            thinning: thinning[i],
            suction_edge: suction_edge[i],
            delivery_edge: delivery_edge[i],
            bearing_diameter: bd[i],
        });
        Ok(Design {
            gears,
            normal_module: mn,
            helix_angle: beta,
            face_width: b,
            normal_pressure_angle: alpha_n,
            centre_distance: a,
            casing,
            bearing_length,
            bypass_area,
            clearance,
            oil,
            losses,
            numerics,
        })
    }

    /// The bundled seed-pump design.
    pub fn seed() -> Design {
        from_toml_str(SEED_PUMP_TOML, &[]).expect("the bundled design is valid")
    }
}

/// The gear pair of the `[gears]` section in SI, validated one value at a
/// time and as a pair (tip and root clearances, interference, contact
/// ratio), with the transverse base pitch and working pressure angle the
/// casing's groove rule needs.
struct GearCut {
    /// Normal backlash, m (the driving gear's thinning).
    backlash_n: f64,
    mn: f64,
    beta: f64,
    b: f64,
    alpha_n: f64,
    a: f64,
    z: [u32; 2],
    x: [f64; 2],
    ra: [f64; 2],
    rf: [f64; 2],
    thinning: [f64; 2],
    pbt: f64,
    alpha_w: f64,
}

fn gears_from_file(g: &GearsFile) -> Result<GearCut, DesignError> {
    for (key, z) in [("gears.z_drive", g.z_drive), ("gears.z_driven", g.z_driven)] {
        if !(6..=60).contains(&z) {
            return Err(invalid(key, z, "tooth number must lie in [6, 60]"));
        }
    }
    let mn = mm_to_m(NORMAL_MODULE_MM.check("gears.normal_module_mm", g.normal_module_mm)?);
    let beta = deg_to_rad(in_range(
        "gears.helix_angle_deg",
        g.helix_angle_deg,
        0.0,
        30.0,
    )?);
    let b = mm_to_m(FACE_WIDTH_MM.check("gears.face_width_mm", g.face_width_mm)?);
    let alpha_n = deg_to_rad(in_range(
        "gears.normal_pressure_angle_deg",
        g.normal_pressure_angle_deg,
        10.0,
        30.0,
    )?);
    let x = [
        in_range(
            "gears.profile_shift_drive",
            g.profile_shift_drive,
            -1.0,
            1.5,
        )?,
        in_range(
            "gears.profile_shift_driven",
            g.profile_shift_driven,
            -1.0,
            1.5,
        )?,
    ];
    let ra = [
        mm_to_m(positive(
            "gears.tip_radius_drive_mm",
            g.tip_radius_drive_mm,
        )?),
        mm_to_m(positive(
            "gears.tip_radius_driven_mm",
            g.tip_radius_driven_mm,
        )?),
    ];
    let rf = [
        mm_to_m(positive(
            "gears.root_radius_drive_mm",
            g.root_radius_drive_mm,
        )?),
        mm_to_m(positive(
            "gears.root_radius_driven_mm",
            g.root_radius_driven_mm,
        )?),
    ];
    // bounded against the module before the teeth are checked, so an
    // absurd backlash is named as such (not as a pointed tooth)
    let backlash_n = mm_to_m(in_derived_range(
        "gears.backlash_normal_mm",
        g.backlash_normal_mm,
        0.0,
        m_to_mm(0.5 * mn),
        "0 to half the normal module: pumps run 0.05-0.2 mn, and half a module takes a third of the tooth",
    )?);
    let z = [g.z_drive, g.z_driven];
    let zero_backlash_a =
        crate::geometry::involute::zero_backlash_centre_distance(z, x, mn, beta, alpha_n);
    let a = match &g.centre_distance_mm {
        AutoOr::Auto(s) if s == "auto" => zero_backlash_a,
        AutoOr::Auto(s) => {
            return Err(invalid(
                "gears.centre_distance_mm",
                format!("\"{s}\""),
                "must be a number (mm) or \"auto\"",
            ))
        }
        AutoOr::Value(v) => mm_to_m(positive("gears.centre_distance_mm", *v)?),
    };
    // above: one module over the tight-mesh distance opens a backlash of
    // about 2 mn sin(alpha_w) (0.7 mn), past any pump's
    if a > zero_backlash_a + mn {
        return Err(invalid(
            "gears.centre_distance_mm",
            shown(m_to_mm(a)),
            format!(
                "must lie in [{:.4}, {:.4}] (from the tight-mesh centre distance for these shifts to one normal module more)",
                m_to_mm(zero_backlash_a),
                m_to_mm(zero_backlash_a + mn)
            ),
        ));
    }
    if a < zero_backlash_a * (1.0 - 1e-9) {
        return Err(invalid(
            "gears.centre_distance_mm",
            shown(m_to_mm(a)),
            format!(
                "the teeth interfere: the tight-mesh centre distance for these shifts is {:.4} mm",
                m_to_mm(zero_backlash_a)
            ),
        ));
    }
    // transverse circular thinning of the driving gear giving the normal backlash
    let thinning = [backlash_n / (alpha_n.cos() * beta.cos()), 0.0];
    let mut cut = GearCut {
        backlash_n,
        mn,
        beta,
        b,
        alpha_n,
        a,
        z,
        x,
        ra,
        rf,
        thinning,
        pbt: 0.0,
        alpha_w: 0.0,
    };
    cut.check_teeth()?;
    (cut.pbt, cut.alpha_w) = cut.check_mesh()?;
    Ok(cut)
}

impl GearCut {
    /// Each gear on its own: a tooth left at the tip, no undercut.
    fn check_teeth(&self) -> Result<(), DesignError> {
        let GearCut {
            mn,
            beta,
            z,
            ra,
            rf,
            ..
        } = *self;
        let mt = mn / beta.cos();
        let alpha_t = (self.alpha_n.tan() / beta.cos()).atan();
        let (x, thinning, alpha_n) = (self.x, self.thinning, self.alpha_n);
        let r = [z[0] as f64 * mt / 2.0, z[1] as f64 * mt / 2.0];
        let names = ["drive", "driven"];
        for i in 0..2 {
            let rb = r[i] * alpha_t.cos();
            // the tip first, so a tip radius out of all proportion is named
            // as such (not as a root above it)
            if ra[i] <= rb {
                return Err(invalid(
                    &format!("gears.tip_radius_{}_mm", names[i]),
                    shown(m_to_mm(ra[i])),
                    format!(
                        "tip radius must exceed the base radius {:.4} mm",
                        m_to_mm(rb)
                    ),
                ));
            }
            in_derived_range(
                &format!("gears.tip_radius_{}_mm", names[i]),
                m_to_mm(ra[i]),
                m_to_mm(rb),
                m_to_mm(r[i] + 3.0 * mn),
                "above the base circle, at most 3 modules over the reference circle: an addendum of 1 + a profile shift of 1.5 mn leaves 2.5",
            )?;
            if rf[i] >= ra[i] {
                return Err(invalid(
                    &format!("gears.root_radius_{}_mm", names[i]),
                    shown(m_to_mm(rf[i])),
                    format!(
                        "root radius must be below the tip radius {:.4} mm",
                        m_to_mm(ra[i])
                    ),
                ));
            }
            let st = crate::geometry::involute::tooth_thickness(
                r[i],
                mt,
                x[i],
                alpha_n,
                alpha_t,
                thinning[i],
                ra[i],
            );
            if st.is_nan() || st <= 0.0 {
                // the backlash's thinning alone makes the tooth pointed: name it
                let unthinned = crate::geometry::involute::tooth_thickness(
                    r[i], mt, x[i], alpha_n, alpha_t, 0.0, ra[i],
                );
                if thinning[i] > 0.0 && unthinned > 0.0 {
                    return Err(invalid(
                        "gears.backlash_normal_mm",
                        shown(m_to_mm(self.backlash_n)),
                        format!(
                            "thins the driving gear's tooth tip to {:.3} mm <= 0 (pointed teeth; without backlash its tip land is {:.3} mm)",
                            m_to_mm(st),
                            m_to_mm(unthinned)
                        ),
                    ));
                }
                return Err(invalid(
                    &format!("gears.tip_radius_{}_mm", names[i]),
                    shown(m_to_mm(ra[i])),
                    format!(
                        "tooth tip thickness {:.3} mm <= 0 (pointed teeth): lower the tip radius or raise gears.profile_shift_{} = {}",
                        m_to_mm(st),
                        names[i],
                        x[i]
                    ),
                ));
            }
            // undercut: the generating rack's addendum line, r - rf - 0.25 mn below the
            // reference circle (= (ha_tool - x) mn), must not pass the interference
            // point r sin^2(alpha_t)
            let rack_line = r[i] - rf[i] - 0.25 * mn;
            let limit = r[i] * alpha_t.sin().powi(2);
            if rack_line > limit + 1e-9 {
                return Err(invalid(
                    &format!("gears.root_radius_{}_mm", names[i]),
                    shown(m_to_mm(rf[i])),
                    format!(
                        "the generating rack undercuts the teeth (root radius must be at least {:.3} mm)",
                        m_to_mm(r[i] - 0.25 * mn - limit)
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The pair in mesh: tips clear of the mating base circle and root, a
    /// total contact ratio of at least 1. Returns the transverse base pitch
    /// and the working pressure angle.
    fn check_mesh(&self) -> Result<(f64, f64), DesignError> {
        let GearCut {
            mn,
            beta,
            b,
            a,
            z,
            ra,
            rf,
            ..
        } = *self;
        let mt = mn / beta.cos();
        let alpha_t = (self.alpha_n.tan() / beta.cos()).atan();
        let r = [z[0] as f64 * mt / 2.0, z[1] as f64 * mt / 2.0];
        let names = ["drive", "driven"];
        // mesh: tips must not reach below the mating base circle along the line of action
        let alpha_w = ((r[0] + r[1]) * alpha_t.cos() / a).acos();
        let rb = [r[0] * alpha_t.cos(), r[1] * alpha_t.cos()];
        for i in 0..2 {
            if (ra[i] * ra[i] - rb[i] * rb[i]).sqrt() > a * alpha_w.sin() {
                return Err(invalid(
                    &format!("gears.tip_radius_{}_mm", names[i]),
                    shown(m_to_mm(ra[i])),
                    "tip interference: the tip contacts the mating flank below its base circle",
                ));
            }
            let root_clearance = a - ra[i] - rf[1 - i];
            if root_clearance <= 0.0 {
                return Err(invalid(
                    &format!("gears.tip_radius_{}_mm", names[i]),
                    shown(m_to_mm(ra[i])),
                    "the tip touches the mating root circle",
                ));
            }
        }
        let pbt = 2.0 * std::f64::consts::PI * rb[0] / z[0] as f64;
        let eps = ((ra[0].powi(2) - rb[0].powi(2)).sqrt() + (ra[1].powi(2) - rb[1].powi(2)).sqrt()
            - a * alpha_w.sin())
            / pbt;
        let eps_beta = b * beta.sin() / (std::f64::consts::PI * mn);
        if eps + eps_beta < 1.0 {
            return Err(invalid(
                "gears.tip_radius_drive_mm",
                m_to_mm(ra[0]),
                format!(
                    "total contact ratio {:.3} < 1: the gears cannot transmit continuously",
                    eps + eps_beta
                ),
            ));
        }
        Ok((pbt, alpha_w))
    }
}

/// The `[oil]` section in SI, validated.
fn oil_from_file(o: &OilFile) -> Result<Oil, DesignError> {
    let t_min = in_range("oil.t_min_c", o.t_min_c, -60.0, 300.0)?;
    let t_max = in_range("oil.t_max_c", o.t_max_c, -60.0, 300.0)?;
    if t_max <= t_min {
        return Err(invalid("oil.t_max_c", t_max, "must exceed oil.t_min_c"));
    }
    let nu40 = NU_40C_CST.check("oil.nu_40c_cst", o.nu_40c_cst)?;
    let nu100 = NU_100C_CST.check("oil.nu_100c_cst", o.nu_100c_cst)?;
    if nu100 >= nu40 {
        return Err(invalid(
            "oil.nu_100c_cst",
            nu100,
            "must be below oil.nu_40c_cst (viscosity falls with temperature)",
        ));
    }
    let (wa, wb) = walther_fit(
        celsius_to_kelvin(40.0),
        nu40,
        celsius_to_kelvin(100.0),
        nu100,
    );
    let gas =
        bar_to_pa(GAS_RELEASE_BAR_ABS.check("oil.gas_release_bar_abs", o.gas_release_bar_abs)?);
    if gas >= ATMOSPHERE_PA {
        return Err(invalid(
            "oil.gas_release_bar_abs",
            o.gas_release_bar_abs,
            "must be below atmospheric pressure",
        ));
    }
    let bulk_modulus =
        gpa_to_pa(BULK_MODULUS_GPA.check("oil.bulk_modulus_gpa", o.bulk_modulus_gpa)?);
    let cavitation_modulus = bar_to_pa(
        CAVITATION_MODULUS_BAR.check("oil.cavitation_modulus_bar", o.cavitation_modulus_bar)?,
    );
    if cavitation_modulus >= bulk_modulus {
        return Err(invalid(
            "oil.cavitation_modulus_bar",
            o.cavitation_modulus_bar,
            format!(
                "must be below oil.bulk_modulus_gpa = {} GPa (the gas-laden oil is softer than the liquid)",
                o.bulk_modulus_gpa
            ),
        ));
    }
    let oil = Oil {
        walther_a: wa,
        walther_b: wb,
        rho_ref: DENSITY_KG_M3.check("oil.density_20c_kg_m3", o.density_20c_kg_m3)?,
        t_ref_k: celsius_to_kelvin(20.0),
        expansion_per_k: in_range("oil.expansion_per_k", o.expansion_per_k, 0.0, 0.01)?,
        bulk_modulus,
        gas_release_pa: gas,
        cavitation_modulus,
        t_min_k: celsius_to_kelvin(t_min),
        t_max_k: celsius_to_kelvin(t_max),
        nu_factor: (
            in_range(
                "oil.viscosity_factor_60c",
                o.viscosity_factor_60c,
                0.01,
                100.0,
            )?,
            in_range(
                "oil.viscosity_factor_120c",
                o.viscosity_factor_120c,
                0.01,
                100.0,
            )?,
        ),
        nu_factor_t_k: (celsius_to_kelvin(60.0), celsius_to_kelvin(120.0)),
        air_fraction: in_range("oil.air_fraction", o.air_fraction, 0.0, 0.49)?,
        pressure_viscosity: in_range(
            "oil.pressure_viscosity_per_pa",
            o.pressure_viscosity_per_pa,
            0.0,
            1.0e-6,
        )?,
    };
    Ok(oil)
}

/// The clearance growth keys of `[clearance]`, validated.
fn growth_from_file(c: &ClearanceFile) -> Result<ClearanceGrowth, DesignError> {
    let site = |key: &str, v: &str| {
        Site::parse(v).ok_or_else(|| {
            invalid(
                key,
                format!("\"{v}\""),
                "must be \"tips\", \"bearings\", \"lateral\", \"radial\" or \"all\"",
            )
        })
    };
    Ok(ClearanceGrowth {
        thermal: um_to_m(in_range(
            "clearance.thermal_growth_um_per_k",
            c.thermal_growth_um_per_k,
            -10.0,
            10.0,
        )?),
        thermal_on: site("clearance.thermal_growth_on", &c.thermal_growth_on)?,
        pressure: um_to_m(in_range(
            "clearance.pressure_growth_um_per_bar",
            c.pressure_growth_um_per_bar,
            -10.0,
            10.0,
        )?) / bar_to_pa(1.0),
        pressure_on: site("clearance.pressure_growth_on", &c.pressure_growth_on)?,
    })
}

/// The `[losses]` section, validated.
fn losses_from_file(l: &LossesFile) -> Result<Losses, DesignError> {
    let losses = Losses {
        plate_unbalance: in_range(
            "losses.thrust_plate_unbalance",
            l.thrust_plate_unbalance,
            0.0,
            1.0,
        )?,
        plate_friction: in_range(
            "losses.thrust_plate_friction",
            l.thrust_plate_friction,
            0.0,
            0.5,
        )?,
        mesh_friction: in_range(
            "losses.mesh_friction_coefficient",
            l.mesh_friction_coefficient,
            0.0,
            0.5,
        )?,
        churning: CHURNING.check("losses.churning_coefficient", l.churning_coefficient)?,
    };
    Ok(losses)
}

/// The `[numerics]` section in SI, validated (counts refused, not clamped).
fn numerics_from_file(n: &NumericsFile) -> Result<Numerics, DesignError> {
    let numerics = Numerics {
        angle_step: deg_to_rad(in_range(
            "numerics.angle_step_deg",
            n.angle_step_deg,
            0.01,
            5.0,
        )?),
        slices: count_in_range("numerics.helical_slices", n.helical_slices, 64)?,
        axial_nodes: count_in_range("numerics.axial_nodes", n.axial_nodes, 64).and_then(|na| {
            if na as u32 <= n.helical_slices {
                Ok(na)
            } else {
                Err(invalid(
                    "numerics.axial_nodes",
                    na,
                    format!(
                        "must not exceed numerics.helical_slices = {} (a zone holds whole slices)",
                        n.helical_slices
                    ),
                ))
            }
        })?,
        table_step: deg_to_rad(in_range(
            "numerics.table_step_deg",
            n.table_step_deg,
            0.01,
            2.0,
        )?),
        newton_tol: in_range("numerics.newton_tolerance", n.newton_tolerance, 1e-14, 1e-3)?,
        newton_max_iter: count_in_range(
            "numerics.newton_max_iterations",
            n.newton_max_iterations,
            1000,
        )?,
        periodic_tol: in_range(
            "numerics.periodic_tolerance",
            n.periodic_tolerance,
            1e-10,
            1e-2,
        )?,
        max_revolutions: count_in_range("numerics.max_revolutions", n.max_revolutions, 1000)?,
        orifice_dp_t: bar_to_pa(
            ORIFICE_TRANSITION_BAR
                .check("numerics.orifice_transition_bar", n.orifice_transition_bar)?,
        ),
        coupling_tol: in_range(
            "numerics.coupling_tolerance",
            n.coupling_tolerance,
            1e-8,
            0.1,
        )?,
        coupling_max_iter: count_in_range(
            "numerics.coupling_max_iterations",
            n.coupling_max_iterations,
            100,
        )?,
    };
    Ok(numerics)
}

/// A port edge of each gear (local angle, rad).
type PortEdges = [f64; 2];

/// The `[casing]` section in SI, validated: the casing, and the suction and
/// delivery port edges of each gear (rad). `pbt` and `alpha_w` (the pair's
/// transverse base pitch and working pressure angle) place the relief
/// grooves' default edges.
fn casing_from_file(
    c: &CasingFile,
    cut: &GearCut,
) -> Result<(Casing, PortEdges, PortEdges), DesignError> {
    let auto_edge = relief_groove_edge(cut.pbt, cut.alpha_w);
    // the tip circles cross this far from the line of centres: a groove
    // edge beyond meets no pocket of the meshing zone
    let (r1, r2, a) = (cut.ra[0], cut.ra[1], cut.a);
    let cusp_x = (a * a + r1 * r1 - r2 * r2) / (2.0 * a);
    let cusp_mm = m_to_mm((r1 * r1 - cusp_x * cusp_x).max(0.0).sqrt());
    let edge = |key: &str, v: f64, lo: f64, hi: f64| in_range(key, v, lo, hi).map(deg_to_rad);
    let suction_edge = [
        edge(
            "casing.suction_port_edge_drive_deg",
            c.suction_port_edge_drive_deg,
            5.0,
            175.0,
        )?,
        edge(
            "casing.suction_port_edge_driven_deg",
            c.suction_port_edge_driven_deg,
            5.0,
            175.0,
        )?,
    ];
    let delivery_edge = [
        edge(
            "casing.delivery_port_edge_drive_deg",
            c.delivery_port_edge_drive_deg,
            -175.0,
            -5.0,
        )?,
        edge(
            "casing.delivery_port_edge_driven_deg",
            c.delivery_port_edge_driven_deg,
            -175.0,
            -5.0,
        )?,
    ];
    let casing = Casing {
        inlet_volume: cm3_to_m3(CHAMBER_CM3.check(
            "casing.inlet_chamber_volume_cm3",
            c.inlet_chamber_volume_cm3,
        )?),
        outlet_volume: cm3_to_m3(CHAMBER_CM3.check(
            "casing.outlet_chamber_volume_cm3",
            c.outlet_chamber_volume_cm3,
        )?),
        port_area: mm2_to_m2(PORT_AREA_MM2.check("casing.port_area_mm2", c.port_area_mm2)?),
        port_cd: in_range(
            "casing.port_discharge_coefficient",
            c.port_discharge_coefficient,
            0.05,
            1.0,
        )?,
        delivery_groove_edge: groove_edge(
            "casing.delivery_groove_edge_mm",
            &c.delivery_groove_edge_mm,
            auto_edge,
            cusp_mm,
        )?,
        suction_groove_edge: groove_edge(
            "casing.suction_groove_edge_mm",
            &c.suction_groove_edge_mm,
            auto_edge,
            cusp_mm,
        )?,
        // centred on the pitch point along the line of centres: wider than
        // the centre distance it reaches past a shaft
        groove_width: mm_to_m(in_derived_range(
            "casing.groove_width_mm",
            c.groove_width_mm,
            0.0,
            m_to_mm(a),
            "0 (no groove) up to the centre distance: wider, the groove reaches past a shaft",
        )?),
        groove_depth: mm_to_m(GROOVE_DEPTH_MM.check("casing.groove_depth_mm", c.groove_depth_mm)?),
        groove_cd: in_range(
            "casing.groove_discharge_coefficient",
            c.groove_discharge_coefficient,
            0.05,
            1.0,
        )?,
        mesh_cd: in_range(
            "casing.mesh_discharge_coefficient",
            c.mesh_discharge_coefficient,
            0.05,
            1.0,
        )?,
        relief: one_of(
            "casing.relief",
            &c.relief,
            [("grooves", Relief::Grooves), ("ideal", Relief::Ideal)],
        )?,
        axial_flow: one_of(
            "casing.axial_flow",
            &c.axial_flow,
            [("laminar", AxialFlow::Laminar), ("none", AxialFlow::None)],
        )?,
        mesh_passage: one_of(
            "casing.mesh_passage",
            &c.mesh_passage,
            [
                ("boundary", MeshPassage::Boundary),
                ("gap", MeshPassage::Gap),
            ],
        )?,
    };
    Ok((casing, suction_edge, delivery_edge))
}

/// The default edge of each relief groove, m from the pitch point along the
/// common tangent (the normal to the line of centres): half the projected
/// distance of two consecutive contact points, `pbt cos(alpha_w) / 2`.
///
/// The rule. Two tooth pairs in contact are one transverse base pitch `pbt`
/// apart along the line of action, which makes the angle `alpha_w` with the
/// common tangent; so the trapped volume between them spans
/// `pbt cos(alpha_w)` across the tangent, whatever the phase. A sealed band
/// between the grooves at least that wide keeps every pocket from touching
/// both grooves at once (no short circuit delivery -> trapped volume ->
/// suction at any angle); a wider band seals the trapped volume completely
/// for a while, and it is then compressed or expanded with no outlet. The
/// trapped volume is smallest when its contacts sit symmetrically about the
/// pitch point (its rate of change is proportional to `l1^2 - l2^2` with
/// `l2 = l1 - pbt`, Manring & Kasaragadda 2003), so a band of exactly
/// `pbt cos(alpha_w)` centred on the pitch point joins the trapped volume to
/// the delivery groove while it shrinks and hands it to the suction groove at
/// its minimum, while it starts to grow: the lowest trapped-pressure peak a
/// bridge-free layout allows. Helical gears: the grooves of each plate are
/// offset by the helix so that both faces of a pocket open and close
/// together (`hydraulics::steps`), which makes this the mid-face rule.
///
/// Measured on the seed pump at 1000 rpm / 30 bar / 60 degC (`simulate
/// --trace`, `trapped_volume.svg`): near the switch both grooves touch the
/// trapped volume only through the thin wedges beside the contacts, so it is
/// nearly sealed for a few degrees and its pressure peaks at 48.6 bar gauge.
/// Shifting the band towards the suction side (delivery edge nearer the
/// pitch point) by 0.3 / 0.6 mm lowers the peak to 36.6 / 33.0 bar, at
/// eta_v -0.0000 / -0.0014 and a flow ripple +3 / +15 %; by 0.9 mm the
/// layout bridges the ports. The rule keeps the symmetric band, which holds
/// for any gear pair without a search.
pub fn relief_groove_edge(pbt: f64, alpha_w: f64) -> f64 {
    0.5 * pbt * alpha_w.cos()
}

/// A clearance key within the physical range of `crate::limits` (um).
fn clearance_um(key: &str, v: f64) -> Result<f64, DesignError> {
    let r = crate::limits::CLEARANCE_UM;
    in_range(key, v, r.min, r.max)
}

/// A groove edge key: a distance in mm from 0 to `cusp_mm` (where the tip
/// circles cross), or "auto" for `auto` (m).
fn groove_edge(key: &str, v: &AutoOr, auto: f64, cusp_mm: f64) -> Result<f64, DesignError> {
    match v {
        AutoOr::Auto(s) if s == "auto" => Ok(auto),
        AutoOr::Auto(s) => Err(invalid(
            key,
            format!("\"{s}\""),
            "must be a number (mm) or \"auto\"",
        )),
        AutoOr::Value(v) => Ok(mm_to_m(in_derived_range(
            key,
            *v,
            0.0,
            cusp_mm,
            "from the pitch point to where the tip circles cross: beyond, the groove meets no pocket of the meshing zone",
        )?)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bundled_design_loads() {
        let d = Design::seed();
        assert_eq!(d.gears[0].z, 14);
        assert_eq!(d.gears[1].z, 9);
        assert!(
            (d.centre_distance - 28.508e-3).abs() < 5e-6,
            "a = {}",
            d.centre_distance
        );
    }

    #[test]
    fn set_overrides_and_type_errors() {
        let d = from_toml_str(SEED_PUMP_TOML, &["clearance.lateral_um=12".into()]).unwrap();
        assert!((d.clearance.lateral - 12e-6).abs() < 1e-15);
        let e = from_toml_str(SEED_PUMP_TOML, &["clearance.nope=1".into()]).unwrap_err();
        assert!(e.to_string().contains("clearance.nope"), "{e}");
        let e = from_toml_str(SEED_PUMP_TOML, &["oil.nu_40c_cst=abc".into()]).unwrap_err();
        assert!(e.to_string().contains("oil.nu_40c_cst"), "{e}");
        let e = from_toml_str(SEED_PUMP_TOML, &["gears.z_drive=1.5".into()]).unwrap_err();
        assert!(e.to_string().contains("gears.z_drive"), "{e}");
    }

    /// Iteration and slice counts out of range are refused naming the key
    /// (they were once clamped silently); the bounds themselves load.
    #[test]
    fn counts_out_of_range_are_refused_not_clamped() {
        for (key, bad, good) in [
            ("numerics.newton_max_iterations", 5000, 1000),
            ("numerics.coupling_max_iterations", 0, 100),
            ("numerics.helical_slices", 65, 2),
            ("numerics.max_revolutions", 0, 1000),
            ("numerics.axial_nodes", 0, 1),
        ] {
            let e = from_toml_str(SEED_PUMP_TOML, &[format!("{key}={bad}")]).unwrap_err();
            let text = e.to_string();
            assert!(
                text.contains(key) && text.contains("must lie in [1, "),
                "{text}"
            );
            from_toml_str(SEED_PUMP_TOML, &[format!("{key}={good}")]).unwrap();
        }
    }

    /// More axial zones than slices is refused naming both keys.
    #[test]
    fn axial_zones_hold_whole_slices() {
        let e = from_toml_str(
            SEED_PUMP_TOML,
            &[
                "numerics.helical_slices=4".into(),
                "numerics.axial_nodes=5".into(),
            ],
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("numerics.axial_nodes") && e.contains("numerics.helical_slices = 4"),
            "{e}"
        );
        let d = from_toml_str(SEED_PUMP_TOML, &["numerics.axial_nodes=8".into()]).unwrap();
        assert_eq!(d.numerics.axial_nodes, 8);
        let e = from_toml_str(SEED_PUMP_TOML, &["casing.axial_flow=open".into()])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("casing.axial_flow") && e.contains("\"laminar\""),
            "{e}"
        );
        // the meshing-zone passages: the gap in the bundled design, the
        // boundary on request and where a file leaves the key out
        assert_eq!(
            from_toml_str(SEED_PUMP_TOML, &[])
                .unwrap()
                .casing
                .mesh_passage,
            MeshPassage::Gap
        );
        let d = from_toml_str(SEED_PUMP_TOML, &["casing.mesh_passage=boundary".into()]).unwrap();
        assert_eq!(d.casing.mesh_passage, MeshPassage::Boundary);
        let without = SEED_PUMP_TOML.replace("mesh_passage = \"gap\"", "");
        assert_ne!(without, SEED_PUMP_TOML);
        let d = from_toml_str(&without, &[]).unwrap();
        assert_eq!(d.casing.mesh_passage, MeshPassage::Boundary);
        let e = from_toml_str(SEED_PUMP_TOML, &["casing.mesh_passage=narrow".into()])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("casing.mesh_passage") && e.contains("\"narrow\"") && e.contains("\"gap\""),
            "{e}"
        );
    }

    #[test]
    fn missing_key_wrong_type_and_bad_geometry_name_the_key() {
        let text = SEED_PUMP_TOML.replace("face_width_mm = 26.0", "");
        let e = from_toml_str(&text, &[]).unwrap_err();
        assert!(e.to_string().contains("face_width_mm"), "{e}");
        let text = SEED_PUMP_TOML.replace("face_width_mm = 26.0", "face_width_mm = \"wide\"");
        let e = from_toml_str(&text, &[]).unwrap_err();
        assert!(e.to_string().contains("gears.face_width_mm"), "{e}");
        let e = from_toml_str(SEED_PUMP_TOML, &["clearance.tip_um=-3".into()]).unwrap_err();
        assert!(e.to_string().contains("clearance.tip_um"), "{e}");
        // pointed teeth
        let e =
            from_toml_str(SEED_PUMP_TOML, &["gears.tip_radius_driven_mm=14.4".into()]).unwrap_err();
        assert!(e.to_string().contains("tip_radius_driven_mm"), "{e}");
        // interference: centre distance too small
        let e =
            from_toml_str(SEED_PUMP_TOML, &["gears.centre_distance_mm=28.0".into()]).unwrap_err();
        assert!(e.to_string().contains("centre_distance_mm"), "{e}");
        // undercut of the 9-tooth gear by a deep root
        let e =
            from_toml_str(SEED_PUMP_TOML, &["gears.root_radius_driven_mm=7.5".into()]).unwrap_err();
        assert!(e.to_string().contains("root_radius_driven_mm"), "{e}");
    }

    /// Every numeric key of the bundled design, as `(key, value)`, walked
    /// from the bundled TOML itself, so a key added later is covered.
    fn bundled_numeric_keys() -> Vec<(String, toml::Value)> {
        fn walk(prefix: &str, v: &toml::Value, out: &mut Vec<(String, toml::Value)>) {
            match v {
                toml::Value::Table(t) => {
                    for (k, v) in t {
                        let key = if prefix.is_empty() {
                            k.clone()
                        } else {
                            format!("{prefix}.{k}")
                        };
                        walk(&key, v, out);
                    }
                }
                toml::Value::Integer(_) | toml::Value::Float(_) => {
                    out.push((prefix.to_string(), v.clone()))
                }
                _ => {}
            }
        }
        let root: toml::Value = toml::from_str(SEED_PUMP_TOML).unwrap();
        let mut out = vec![];
        walk("", &root, &mut out);
        out
    }

    /// The error of the bundled design with `key=value`, or None if it loads.
    fn refusal(key: &str, value: &str) -> Option<String> {
        from_toml_str(SEED_PUMP_TOML, &[format!("{key}={value}")])
            .err()
            .map(|e| e.to_string())
    }

    /// Every numeric key of the bundled design set to 1e9 and 1e-9 times its
    /// value (1e9 and -1e9 where it is 0) is refused naming the key, except
    /// the values listed here: physically legitimate ones, which load, and
    /// ones legitimate on their own but not with the bundled design's other
    /// keys, refused by a check between keys that names the other key.
    #[test]
    fn absurd_magnitudes_of_every_key_are_refused_naming_it() {
        // (key, why 1e-9 times its bundled value is legitimate)
        let tiny_is_legitimate: &[(&str, &str)] = &[
            ("gears.backlash_normal_mm", "a tight mesh (0 is allowed)"),
            (
                "casing.groove_width_mm",
                "a groove of no width: no relief passage",
            ),
            (
                "casing.groove_depth_mm",
                "a groove of no depth: no relief passage",
            ),
            (
                "bearings.bypass_groove_area_mm2",
                "no by-pass grooves (0 is allowed)",
            ),
            (
                "oil.expansion_per_k",
                "a density independent of temperature",
            ),
            ("oil.t_min_c", "a viscosity fit trusted from 0 degC"),
            (
                "oil.t_max_c",
                "a fit trusted from -20 to 0 degC (hotter points are then refused)",
            ),
            (
                "losses.mesh_friction_coefficient",
                "frictionless flanks (0 is allowed)",
            ),
            ("losses.churning_coefficient", "no churning (0 is allowed)"),
            (
                "losses.thrust_plate_unbalance",
                "a fully balanced plate (0 is allowed)",
            ),
            (
                "losses.thrust_plate_friction",
                "a frictionless plate (0 is allowed)",
            ),
        ];
        // (key, the key its refusal names, why): a spur gear or a gear with
        // no profile shift is an ordinary gear, but the bundled tip radii
        // were cut for a 6 deg helix and shifts of 0.8 / 0.7
        let tiny_is_inconsistent: &[(&str, &str, &str)] = &[
            (
                "gears.helix_angle_deg",
                "gears.tip_radius_drive_mm",
                "a spur pair has smaller reference circles: the tip reaches the mating root",
            ),
            (
                "gears.profile_shift_drive",
                "gears.tip_radius_drive_mm",
                "unshifted, the tooth is pointed at the bundled tip radius",
            ),
            (
                "gears.profile_shift_driven",
                "gears.tip_radius_driven_mm",
                "unshifted, the tooth is pointed at the bundled tip radius",
            ),
        ];
        let keys = bundled_numeric_keys();
        assert!(keys.len() > 60, "{} numeric keys", keys.len());
        for key in tiny_is_legitimate
            .iter()
            .map(|e| e.0)
            .chain(tiny_is_inconsistent.iter().map(|e| e.0))
        {
            assert!(keys.iter().any(|(k, _)| k == key), "{key} is not a key");
        }
        let mut wrong = vec![];
        for (key, value) in &keys {
            // each value to try, and None if it must load, else the key its
            // refusal must name
            let own = Some(key.as_str());
            let tries: Vec<(String, Option<&str>)> = match value {
                toml::Value::Integer(i) => vec![
                    ((*i as f64 * 1e9).round().to_string(), own),
                    ((*i as f64 * 1e-9).round().to_string(), own),
                ],
                toml::Value::Float(f) if *f == 0.0 => {
                    vec![("1e9".into(), own), ("-1e9".into(), own)]
                }
                toml::Value::Float(f) => {
                    let tiny = if tiny_is_legitimate.iter().any(|e| e.0 == key) {
                        None
                    } else {
                        tiny_is_inconsistent
                            .iter()
                            .find(|e| e.0 == key)
                            .map_or(own, |e| Some(e.1))
                    };
                    vec![((f * 1e9).to_string(), own), ((f * 1e-9).to_string(), tiny)]
                }
                _ => unreachable!(),
            };
            for (v, named) in tries {
                match (refusal(key, &v), named) {
                    (None, None) => {}
                    (None, Some(_)) => wrong.push(format!("{key} = {v} loads")),
                    (Some(e), None) => {
                        wrong.push(format!("{key} = {v} is legitimate but refused: {e}"))
                    }
                    (Some(e), Some(name)) if !e.contains(&format!("`{name}`")) => {
                        wrong.push(format!("{key} = {v} should name {name}: {e}"))
                    }
                    (Some(_), Some(_)) => {}
                }
            }
        }
        assert!(wrong.is_empty(), "{}", wrong.join("\n"));
        // the keys the bundled design gives as "auto", with numbers
        for (key, tiny_ok) in [
            ("gears.centre_distance_mm", false),
            // 0: the edge at the pitch point (a bridging layout, warned about)
            ("casing.delivery_groove_edge_mm", true),
            ("casing.suction_groove_edge_mm", true),
        ] {
            for v in ["1e9", "-1e9"] {
                let e = refusal(key, v).unwrap_or_else(|| panic!("{key} = {v} loads"));
                assert!(e.contains(&format!("`{key}`")), "{key} = {v}: {e}");
            }
            match (refusal(key, "1e-9"), tiny_ok) {
                (None, true) => {}
                (Some(e), false) => assert!(e.contains(&format!("`{key}`")), "{key}: {e}"),
                (r, _) => panic!("{key} = 1e-9: {r:?}"),
            }
        }
    }

    /// The three values that once passed the design and failed in the solver
    /// ("Newton did not converge", "non-finite residual") are refused on
    /// load, naming the key, the value and the range.
    #[test]
    fn values_that_reached_the_solver_are_refused_on_load() {
        for (key, v, range) in [
            ("oil.density_20c_kg_m3", "1e300", "[500, 2500]"),
            ("oil.bulk_modulus_gpa", "1e-300", "[0.05, 100]"),
            ("oil.nu_40c_cst", "1e-9", "[0.5, 10000]"),
        ] {
            let e = refusal(key, v).unwrap_or_else(|| panic!("{key} = {v} loads"));
            assert!(
                e.contains(&format!("key `{key}` = {v}"))
                    && e.contains(&format!("must lie in {range}")),
                "{e}"
            );
        }
    }

    /// The values an independent bad-input check found accepted and run
    /// (exit 0) are refused naming their key.
    #[test]
    fn values_once_accepted_are_refused_naming_the_key() {
        for (key, v) in [
            ("gears.face_width_mm", "1e9"),
            ("gears.face_width_mm", "1e300"),
            ("gears.face_width_mm", "1e-9"),
            ("oil.bulk_modulus_gpa", "1e9"),
            ("oil.nu_40c_cst", "1e12"),
            ("oil.nu_40c_cst", "1e15"),
            ("oil.density_20c_kg_m3", "1e-9"),
            ("losses.churning_coefficient", "1e9"),
            ("casing.port_area_mm2", "1e12"),
            ("casing.port_area_mm2", "1e-12"),
            ("casing.outlet_chamber_volume_cm3", "1e12"),
            ("casing.inlet_chamber_volume_cm3", "1e15"),
            ("casing.inlet_chamber_volume_cm3", "1e-15"),
            ("casing.delivery_groove_edge_mm", "1e6"),
            ("casing.groove_width_mm", "1e9"),
            ("casing.groove_depth_mm", "1e9"),
            ("bearings.length_mm", "1e9"),
            ("bearings.diameter_drive_mm", "1e-9"),
            ("oil.cavitation_modulus_bar", "1e12"),
            ("oil.gas_release_bar_abs", "1e-300"),
        ] {
            let e = refusal(key, v).unwrap_or_else(|| panic!("{key} = {v} loads"));
            assert!(
                e.contains(&format!("`{key}`")) && e.contains("must lie in ["),
                "{key} = {v}: {e}"
            );
        }
    }

    /// An absurd backlash is named as the backlash, not as a pointed tip
    /// (it was "tip_radius_drive_mm ... tooth tip thickness -130 mm"); one
    /// within half a module that still leaves no tip land is named too.
    #[test]
    fn a_backlash_that_eats_the_tooth_is_named() {
        let e = refusal("gears.backlash_normal_mm", "100").unwrap();
        assert!(
            e.contains("`gears.backlash_normal_mm` = 100")
                && e.contains("must lie in [0.0000, 1.1250]"),
            "{e}"
        );
        let e = refusal("gears.backlash_normal_mm", "1.1").unwrap();
        assert!(
            e.contains("`gears.backlash_normal_mm` = 1.1") && e.contains("pointed"),
            "{e}"
        );
        // a pointed tip by the tip radius names the profile shift as a remedy
        let e = refusal("gears.tip_radius_driven_mm", "14.4").unwrap();
        assert!(
            e.contains("`gears.tip_radius_driven_mm`") && e.contains("gears.profile_shift_driven"),
            "{e}"
        );
    }

    /// A TOML syntax error names the file, the line and the column (issue
    /// 18 point 8: it said only "design: TOML syntax: invalid string").
    #[test]
    fn a_syntax_error_names_file_line_and_column() {
        let text = "[gears]\nz_drive = 12\nname = \"unterminated\n";
        let e = from_toml_file_text(text, &[], "pump.toml").unwrap_err();
        assert_eq!(
            e.to_string().split(": TOML syntax").next().unwrap(),
            "pump.toml: line 3, column 21",
            "{e}"
        );
        let e = from_toml_file_text("[gears]\n\n  z_drive = = 12\n", &[], "p.toml").unwrap_err();
        assert!(
            e.to_string()
                .starts_with("p.toml: line 3, column 13: TOML syntax: "),
            "{e}"
        );
        // a key error in a file names the file too
        let e = from_toml_file_text(SEED_PUMP_TOML, &["clearance.nope=1".into()], "pump.toml")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("pump.toml: ") && e.contains("clearance.nope"),
            "{e}"
        );
        assert_eq!(line_column("ab\ncdé f", 8), (2, 5));
        assert_eq!(line_column("x", 0), (1, 1));
    }
}
