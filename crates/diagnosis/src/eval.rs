//! `gearpump eval-diagnosis`: how often the diagnosis names a hidden effect,
//! and how often it names one that is not there.
//!
//! Each trial draws a synthetic 20-pump campaign (`synth`: the seed's
//! population, Table 2 conditions, the rig's noise) with one effect at a
//! magnitude drawn uniformly from its *detectable range* below (or no
//! effect), with its own random seed, and runs the diagnosis blind. A trial
//! with an effect is a detection when `cause` names it; a trial without an
//! effect is a false alarm when `cause` is not null.
//!
//! # Detectable ranges
//! The noise of the rig (flowmeter 0.5 % of reading, one sigma) puts a floor
//! of about 0.0045 under the RMSE of d. For the extended model to cut the
//! RMSE to 0.6 of the baseline, the effect must move eta_v by more than about
//! 1.3 times that floor (RMS over the tests). The ranges are the magnitudes
//! where that holds for the seed pump at the Table 2 conditions, within each
//! effect's physically plausible range where possible. The upper ends are
//! where the pump still delivers at its worst condition (500 rpm, 30 bar,
//! 120 degC, eta_v 0.58 in the base model without micromotion): k_T = 0.15
//! um/K, k_p = 0.5 um/bar or h_lat = 40 um leak more than the gears displace
//! there, a campaign no rig would produce (`campaign` refuses a negative
//! measured flow); k_T = 0.08 already does for the pumps of the population
//! with the widest clearances.
//!
//! | effect | detectable range | plausible range (effects module) | note |
//! |---|---|---|---|
//! | thermal_clearance | k_T 0.04 .. 0.07 um/K | 0.02 .. 0.3 | cast iron on steel (0.02) is below the noise |
//! | pressure_clearance | k_p 0.1 .. 0.3 um/bar | 0.1 .. 0.5 | |
//! | lateral_clearance | h_lat 20 .. 30 um (nominal 15) | 10 .. 40 | a gap closer than nominal leaks less: a few points of eta_v at most |
//! | viscosity_shift | f1, f2 each 0.55 .. 0.8 | 0.7 .. 1.4 | a thinner (aged, sheared or other) oil; 1.25 .. 1.4 only moves eta_v by about the noise |
//! | entrained_air | x0 0.02 .. 0.05 | 0.005 .. 0.05 | free air lowers eta_v by about x0 at every condition; at 0.016 the extended model's RMSE ratio is already 0.59 |
//! | displacement_error | delta 0.015 .. 0.03, either sign | 0.01 .. 0.03 | |
//! | pressure_viscosity | alpha 5e-8 .. 1e-7 1/Pa | 1e-8 .. 3e-8 | at 10-40 bar mineral oils change gap leakage by < 1 %: only a strongly piezoviscous fluid is detectable at these pressures |
//!
//! # The torque verdict
//! The diagnosis gives a torque verdict beside the flow's (module `torque`:
//! a loss coefficient named, or no cause). Each trial is scored on it too.
//! What a plant does to the torque is **measured**, not assumed: the RMS
//! over the tests of the relative change of its noise-free truth torque
//! against the same population with nothing planted
//! ([`planted_torque_change`], two truth runs per trial). The plant *acts on
//! the torque* when that change is at least the torque meter's noise (one
//! sigma of reading: 0.2 % on the rig, 0.6 % in `noise_x3`).
//!
//! The torque causes of a planted mechanism are never false alarms: the
//! film shear (`viscous_friction`) for a viscosity change (the oil's, or a
//! pressure-viscous film's, whose shear takes its Barus factor), a lateral
//! gap, a radial or bearing clearance law and an out-of-family pump's
//! wider tips (the shear of a gap falls about as 1 / h). A displacement
//! error (the hydraulic torque scales with the face width) and free air
//! have no loss coefficient as their mechanism.
//!
//! * **torque false alarm**: the plant does not act on the torque and the
//!   torque verdict names a cause (first or second) not of a planted
//!   mechanism. Measured with two pumps and no noise, at the far end of
//!   each range: radial clearance laws 0.11-0.18 % (below the meter's
//!   noise; their shear may still show over 280 tests, so
//!   `viscous_friction` is tolerated), free air 0.11 %, pressure viscosity
//!   0.13 % (0.02 % before its films' shear took the Barus factor),
//!   incomplete filling and nothing planted 0.
//! * **torque cause right**: the plant acts on the torque through a loss a
//!   candidate models (a thinner oil or a wider lateral gap: 0.3 % at the
//!   near end of their ranges; bearings opened by 0.6 um/bar: 0.34 %) and
//!   the first torque cause is one of its mechanism's, or no torque cause
//!   is named, nothing is left unexplained and the flow's first cause is
//!   right (the torque verdict is taken on the model the flow's causes
//!   extended, which carries the planted effect's losses).
//! * A plant that acts on the torque through no candidate's mechanism (a
//!   displacement error or a face width: 1.3 % at 0.015) is neither: its
//!   torque verdict is recorded, not scored.
//!
//! **`flow_and_torque`** plants a torque loss beside the flow effect
//! (module `plant`: a lip seal's drag, the thrust plate's or the mesh's
//! friction coefficient), so the torque is always acted on (0.5-4 % RMS,
//! test `the_torque_plants_act_beyond_the_meter_noise`) and a torque cause
//! must be named. Its rules replace the two above:
//!
//! * **torque cause right**: the first torque cause is the planted loss's
//!   (constant_drag for the seal). No torque cause, or only the flow
//!   mechanism's film shear, is a miss even when the flow's first cause is
//!   right: the flow's extension does not carry the planted loss. This
//!   holds beside a face width too (its hydraulic torque, unscored in
//!   `mismatched`, is the extended model's when the flow's cause is right).
//! * **torque false alarm**: a torque cause named, first or second, that is
//!   neither the planted loss's nor of the flow's planted mechanism (as
//!   above); every trial of the family is counted among those scored.

use std::path::{Path, PathBuf};
use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

use super::candidates::kind;
use super::diagnose::{run_diagnosis, DiagnoseOptions};
use gearpump_campaign::effects::{Effect, EFFECT_NAMES};
use gearpump_campaign::io::atomic_write_text;
use gearpump_campaign::run::{DesignSource, RunError, Setting, Silent};
use gearpump_campaign::synth::{sample_id, Noise};

use super::plant::{
    planted_csv, planted_flow_factors, planted_torque_change, FlowFactor, Plant, PlantOptions,
    TorquePlant,
};

/// Label of the trials without an effect.
pub const NO_EFFECT: &str = "none";

/// The detectable range of each effect (see the module doc), edge units:
/// (low, high) per parameter and whether the sign is drawn too.
pub fn detectable_range(effect: &str) -> Option<(&'static [(f64, f64)], bool)> {
    let r: &'static [(f64, f64)] = match effect {
        "thermal_clearance" => &[(0.04, 0.07)],
        "pressure_clearance" => &[(0.1, 0.3)],
        "lateral_clearance" => &[(20.0, 30.0)],
        "viscosity_shift" => &[(0.55, 0.8), (0.55, 0.8)],
        "entrained_air" => &[(0.02, 0.05)],
        "displacement_error" => &[(0.015, 0.03)],
        "pressure_viscosity" => &[(5e-8, 1e-7)],
        _ => return None,
    };
    Some((r, effect == "displacement_error"))
}

/// The range as text, for tables.
pub fn range_text(effect: &str) -> String {
    match detectable_range(effect) {
        None => "-".into(),
        Some((r, signed)) => {
            let s: Vec<String> = r
                .iter()
                .map(|(a, b)| {
                    if signed {
                        format!("+-{a}..{b}")
                    } else {
                        format!("{a}..{b}")
                    }
                })
                .collect();
            s.join(", ")
        }
    }
}

/// Draws an effect uniformly from its detectable range.
pub fn draw_effect(effect: &str, rng: &mut impl Rng) -> Option<Effect> {
    let (ranges, signed) = detectable_range(effect)?;
    let sign = if signed && rng.gen_bool(0.5) {
        -1.0
    } else {
        1.0
    };
    let values: Vec<f64> = ranges
        .iter()
        .map(|&(a, b)| sign * rng.gen_range(a..=b))
        .collect();
    // three significant digits, as a user would type it
    let values: Vec<f64> = values
        .iter()
        .map(|v| format!("{v:.3e}").parse().unwrap_or(*v))
        .collect();
    Effect::from_edge(effect, &values).ok()
}

/// The families of campaigns made by other mechanisms than the
/// candidates' code (module `plant`), each run `trials` times.
pub const FAMILIES: [&str; 6] = [
    "mismatched",
    "two_effects",
    "noise_x3",
    "out_of_family",
    "outside",
    "flow_and_torque",
];

/// The pairs of effects of the `two_effects` family, each at a magnitude
/// from its detectable range: effects whose signatures differ (a clearance
/// law in temperature or pressure, a level over all conditions, a viscosity
/// curve). Not paired: two leakage laws driven by the same delivery
/// pressure (a wider lateral gap and a bore opening with pressure change
/// the leakage of 10-40 bar tests almost alike), nor the two level effects
/// (free air and a displacement error both lower eta_v at every condition).
pub const PAIRS: [(&str, &str); 4] = [
    ("thermal_clearance", "displacement_error"),
    ("pressure_clearance", "entrained_air"),
    ("viscosity_shift", "displacement_error"),
    ("lateral_clearance", "entrained_air"),
];

/// Factor of an out-of-family pump's true tip clearances over its recorded
/// ones (a clearance measured 20 % small).
pub const OUT_OF_FAMILY_FACTOR: f64 = 1.25;

/// The torque loss of the `k`-th campaign of `flow_and_torque` (module
/// `plant`, its doc table): a lip seal's drag, or the thrust plate's or the
/// mesh's friction coefficient through the design keys, at a magnitude
/// drawn where it moves the torque by several times the meter's noise and
/// stays physical. The kind turns with `(k + k / 6) mod 3`, so that over
/// twelve campaigns each flow plant of `mismatched` meets two of them.
pub fn draw_torque_plant(k: usize, rng: &mut impl Rng) -> TorquePlant {
    let lower_or_higher = |rng: &mut dyn rand::RngCore, low: (f64, f64), high: (f64, f64)| {
        if rng.gen_bool(0.5) {
            typed(rng.gen_range(low.0..=low.1))
        } else {
            typed(rng.gen_range(high.0..=high.1))
        }
    };
    match (k + k / 6) % 3 {
        0 => TorquePlant::SealDrag {
            a_nm: typed(rng.gen_range(SEAL_A_NM.0..=SEAL_A_NM.1)),
            b_nm: typed(rng.gen_range(SEAL_B_NM.0..=SEAL_B_NM.1)),
        },
        1 => TorquePlant::Coefficient {
            key: "losses.thrust_plate_friction",
            factor: lower_or_higher(rng, PLATE_FACTOR_LOW, PLATE_FACTOR_HIGH),
        },
        _ => TorquePlant::Coefficient {
            key: "losses.mesh_friction_coefficient",
            factor: lower_or_higher(rng, MESH_FACTOR_LOW, MESH_FACTOR_HIGH),
        },
    }
}

/// Ranges of the torque plants of `flow_and_torque` (module `plant`):
/// the seal's constant and speed parts, N m, and the factors on the
/// design's thrust-plate and mesh friction coefficients (a lower or a
/// higher one, drawn with equal odds).
pub const SEAL_A_NM: (f64, f64) = (0.03, 0.08);
pub const SEAL_B_NM: (f64, f64) = (0.02, 0.05);
pub const PLATE_FACTOR_LOW: (f64, f64) = (0.6, 0.9);
pub const PLATE_FACTOR_HIGH: (f64, f64) = (1.15, 1.6);
pub const MESH_FACTOR_LOW: (f64, f64) = (0.25, 0.5);
pub const MESH_FACTOR_HIGH: (f64, f64) = (1.6, 2.2);

/// Options of an evaluation.
#[derive(Debug, Clone)]
pub struct EvalOptions {
    /// Trials per effect (and without effect) and per family.
    pub trials: usize,
    pub seed: u64,
    /// The effects to hide with `synth`'s own code (names of `EFFECT_NAMES`
    /// and/or "none").
    pub effects: Vec<String>,
    /// Families of [`FAMILIES`].
    pub families: Vec<String>,
    pub samples: usize,
    pub jobs: Option<usize>,
    pub micromotion: bool,
    /// Only these trials of the plan, by folder name (`two_effects-8`): the
    /// draws are those of the whole plan, so a trial is the same campaign as
    /// in a full evaluation with the same seed and counts. Empty: every trial.
    pub only: Vec<String>,
}

/// One trial.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Trial {
    /// The group it is summarised in: the hidden effect, `none`, or a family.
    pub effect: String,
    pub truth: Option<String>,
    /// Causes a correct diagnosis names (first: any of them).
    #[serde(default)]
    pub expected: Vec<String>,
    pub synth_seed: u64,
    pub cause: Option<String>,
    #[serde(default)]
    pub causes: Vec<String>,
    pub ambiguous_with: Vec<String>,
    pub unexplained: bool,
    /// The pump planted out of family, and those the diagnosis named.
    #[serde(default)]
    pub out_of_family_planted: Option<String>,
    #[serde(default)]
    pub out_of_family_found: Vec<String>,
    pub rmse_ratio: Option<f64>,
    /// The same ratio against the noise-free truth ([`truth_rmse_ratio`]):
    /// the model error the extension leaves, without the flowmeter's
    /// scatter that no model removes.
    #[serde(default)]
    pub truth_rmse_ratio: Option<f64>,
    /// What the noise-free truth itself scores on the measurements (its
    /// RMSE over the base model's): the flowmeter's share of the data
    /// ratio, which no model of the pump removes, so the floor that
    /// `rmse_ratio` meets when the extension is exact.
    #[serde(default)]
    pub floor_rmse_ratio: Option<f64>,
    pub wall_s: f64,
    pub dir: String,
    /// The trial could not be run (synth or diagnosis failed): the reason.
    #[serde(default)]
    pub error: Option<String>,
    /// Taken from an earlier run of the same trial in the same folder
    /// (`wall_s` is then that run's diagnosis time).
    #[serde(default)]
    pub resumed: bool,
    /// What the planted effects do to the shaft torque ([`torque_truth`]).
    #[serde(default)]
    pub torque_truth: TorqueTruth,
    /// The torque verdict (`diagnosis.json`'s `torque`): its first cause,
    /// every cause, and whether structure is left unexplained.
    #[serde(default)]
    pub torque_cause: Option<String>,
    #[serde(default)]
    pub torque_causes: Vec<String>,
    #[serde(default)]
    pub torque_unexplained: bool,
    /// The measured torque contradicts the flow's causes
    /// (`torque.flow_causes_check.worsened`).
    #[serde(default)]
    pub torque_contradicts: bool,
}

/// What the planted effects of a trial do to the shaft torque (module doc,
/// "The torque verdict").
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TorqueTruth {
    /// The planted torque change, RMS over the tests of the relative change
    /// of the noise-free truth torque ([`planted_torque_change`]).
    pub change_rms: f64,
    /// It is at least the torque meter's noise (one sigma, relative): the
    /// planted effects act on the torque and a torque cause is due.
    pub acts: bool,
    /// The torque causes of the planted mechanisms: naming them is never a
    /// false alarm; when `acts`, the first torque cause is right when it is
    /// one of them. Empty when no loss coefficient is the mechanism.
    pub causes: Vec<String>,
    /// A planted effect moves the torque beyond the meter's noise through
    /// no candidate's mechanism (a displacement error: the hydraulic
    /// torque, 1.3 % at delta 0.015): the first torque cause is not scored.
    #[serde(default)]
    pub unmodelled: bool,
    /// The torque loss planted beside the flow effect (`flow_and_torque`):
    /// its cause must be the first torque cause for the trial to be right,
    /// and any cause named beyond it and `causes` is a false alarm.
    #[serde(default)]
    pub planted: Option<String>,
}

impl TorqueTruth {
    /// A torque loss of cause `cause` planted beside the flow effect: it is
    /// due, and never a false alarm.
    pub fn plant(&mut self, cause: &str) {
        self.planted = Some(cause.to_string());
        if !self.causes.iter().any(|c| c == cause) {
            self.causes.push(cause.to_string());
            self.causes.sort();
        }
    }
}

/// The torque candidate of the loss mechanism the clearance and viscosity
/// effects also change: the film shear.
const VISCOUS: &str = "viscous_friction";

/// What the planted effects `expected` (flow causes, as `Plant::expected`)
/// and an out-of-family pump do to the torque, given the measured planted
/// torque change `change_rms` and the torque meter's noise `meter_rel`
/// (module doc, "The torque verdict").
pub fn torque_truth(
    expected: &[String],
    out_of_family: bool,
    change_rms: f64,
    meter_rel: f64,
) -> TorqueTruth {
    let mut causes: Vec<String> = Vec::new();
    let mut unmodelled = false;
    for e in expected {
        match kind(e) {
            // the film shear of every gap scales with the viscosity and
            // falls as a gap opens (about 1 / h): a viscosity change (the
            // oil's, or the films' Barus factor), a lateral gap, a radial or
            // bearing clearance law
            "viscosity_shift" | "pressure_viscosity" | "lateral_clearance"
            | "thermal_clearance" | "pressure_clearance" => causes.push(VISCOUS.into()),
            // the hydraulic torque scales with the face width
            "displacement_error" => unmodelled = true,
            // free air: no loss coefficient is its mechanism, and it moves
            // the torque by less than the noise
            _ => {}
        }
    }
    if out_of_family {
        // one pump's tips wider than its record: its tip shear is smaller
        causes.push(VISCOUS.into());
    }
    causes.sort();
    causes.dedup();
    TorqueTruth {
        change_rms,
        acts: change_rms >= meter_rel,
        causes,
        unmodelled,
        planted: None,
    }
}

/// The diagnosis in `csv`'s folder when `csv` holds `text` exactly and the
/// folder has a readable `diagnosis.json` written after this program was
/// built (a diagnosis by an earlier build, whose rules may differ, is made
/// again).
fn earlier_diagnosis(csv: &Path, text: &str) -> Option<Value> {
    if std::fs::read_to_string(csv).ok()? != text {
        return None;
    }
    let dir = csv.parent()?;
    let path = dir.join(super::diagnose::DIAGNOSIS_JSON);
    let modified = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    let built = modified(&std::env::current_exe().ok()?)?;
    if modified(&path)? < built {
        return None;
    }
    let j = std::fs::read_to_string(&path).ok()?;
    let v: Value = serde_json::from_str(&j).ok()?;
    v.get("unexplained")?.as_bool()?;
    Some(v)
}

/// The diagnosis time recorded in a trial folder's `diagnosis.json`.
fn v_wall(dir: &str) -> f64 {
    std::fs::read_to_string(Path::new(dir).join(super::diagnose::DIAGNOSIS_JSON))
        .ok()
        .and_then(|j| serde_json::from_str::<Value>(&j).ok())
        .and_then(|v| v["wall_s"].as_f64())
        .unwrap_or(0.0)
}

impl Trial {
    /// The verdict of a diagnosis (its `diagnosis.json`): cause, causes,
    /// ambiguity, unexplained, out-of-family pumps and, when a cause is
    /// named, the RMSE ratio of the extended model over the baseline.
    pub fn read_diagnosis(&mut self, v: &Value) {
        let names = |x: &Value, key: &str| -> Vec<String> {
            x.as_array()
                .map(|a| {
                    a.iter()
                        .filter_map(|e| e[key].as_str().map(str::to_string))
                        .collect()
                })
                .unwrap_or_default()
        };
        self.cause = v["cause"].as_str().map(str::to_string);
        self.causes = names(&v["causes"], "effect");
        self.ambiguous_with = names(&v["ambiguous_with"], "effect");
        self.unexplained = v["unexplained"].as_bool().unwrap_or(false);
        self.out_of_family_found = names(&v["out_of_family"], "sample");
        // the verdict's ratio: over the tests analysed (without the pumps
        // set aside as out of family)
        self.rmse_ratio = match &self.cause {
            Some(_) => v["gain"]["rmse_ratio"].as_f64(),
            None => None,
        };
        let t = &v["torque"];
        self.torque_cause = t["cause"].as_str().map(str::to_string);
        self.torque_causes = t["causes"]
            .as_array()
            .map(|a| {
                a.iter()
                    .filter_map(|c| c.as_str().map(str::to_string))
                    .collect()
            })
            .unwrap_or_default();
        self.torque_unexplained = t["unexplained"].as_bool().unwrap_or(false);
        self.torque_contradicts = t["flow_causes_check"]["worsened"] == Value::Bool(true);
    }

    /// A torque false alarm: nothing planted moves the torque beyond the
    /// meter's noise, yet the torque verdict names a cause that is not of a
    /// planted mechanism.
    ///
    /// With a torque loss planted beside the flow effect (`planted`), any
    /// cause named that is neither it nor of the flow's planted mechanism.
    pub fn torque_false_alarm(&self) -> bool {
        self.error.is_none()
            && (!self.torque_truth.acts || self.torque_truth.planted.is_some())
            && self
                .torque_causes
                .iter()
                .chain(&self.torque_cause)
                .any(|c| !self.torque_truth.causes.contains(c))
    }

    /// Whether the first torque cause is right, for a trial whose planted
    /// effects act on the torque through a loss the candidates model and
    /// through no other (None otherwise). The torque verdict is taken on
    /// the model the flow's causes extended (`diagnose`), so "no cause and
    /// nothing unexplained" is right too when the flow's first cause is:
    /// the planted effect, named for the flow, carries its own losses (a
    /// viscosity shift its film shear).
    ///
    /// With a torque loss planted beside the flow effect (`planted`), the
    /// first torque cause must be the planted loss's: naming no cause, or
    /// only the flow mechanism's, is a miss.
    pub fn torque_right(&self) -> Option<bool> {
        let t = &self.torque_truth;
        if let Some(p) = &t.planted {
            return Some(self.error.is_none() && self.torque_cause.as_ref() == Some(p));
        }
        (t.acts && !t.causes.is_empty() && !t.unmodelled).then(|| {
            self.error.is_none()
                && (self
                    .torque_cause
                    .as_ref()
                    .is_some_and(|c| self.torque_truth.causes.contains(c))
                    || (self.torque_cause.is_none()
                        && !self.torque_unexplained
                        && self.cause.is_some()
                        && self.correct()))
        })
    }

    /// The first cause is right: one of the expected causes; with none
    /// expected, no cause (`none`) or "unexplained" (`outside`).
    pub fn correct(&self) -> bool {
        if self.error.is_some() {
            false
        } else if self.effect == "outside" {
            self.unexplained
        } else if self.expected.is_empty() {
            self.cause.is_none()
        } else {
            self.cause
                .as_ref()
                .is_some_and(|c| self.expected.iter().any(|e| e == kind(c)))
        }
    }

    /// Every expected cause is among the causes named.
    pub fn all_named(&self) -> bool {
        self.error.is_none()
            && self
                .expected
                .iter()
                .all(|e| self.causes.iter().any(|c| kind(c) == e))
    }
}

/// Per-effect or per-family summary.
#[derive(Debug, Clone, Serialize)]
pub struct EffectSummary {
    pub effect: String,
    pub range: String,
    pub trials: usize,
    /// First cause right (with an effect) / cause null (without) /
    /// unexplained (`outside`).
    pub correct: usize,
    pub rate: f64,
    /// Every expected cause named (two effects).
    pub all_named: usize,
    pub other_cause: usize,
    pub null_cause: usize,
    pub unexplained: usize,
    pub ambiguous: usize,
    /// Out-of-family pumps planted and found.
    pub out_of_family_found: usize,
    /// Trials that could not be run (counted as not correct).
    pub errors: usize,
    /// RMSE ratio of the extended model over the trials that name a cause.
    pub mean_rmse_ratio: Option<f64>,
    pub worst_rmse_ratio: Option<f64>,
    /// Trials naming a cause with an RMSE ratio above 0.5.
    pub ratio_above_half: usize,
    /// The same against the noise-free truth ([`truth_rmse_ratio`]).
    pub mean_truth_rmse_ratio: Option<f64>,
    pub worst_truth_rmse_ratio: Option<f64>,
    pub truth_ratio_above_half: usize,
    /// Trials naming a cause whose floor ([`Trial::floor_rmse_ratio`]) is
    /// above 0.5: the flowmeter alone keeps their ratio on the data there.
    pub floor_above_half: usize,
    /// Trials scored for torque false alarms (whose planted effects do not
    /// act on the torque, or with a torque loss planted beside the flow
    /// effect), and those of them whose torque verdict names a cause of no
    /// planted mechanism ([`Trial::torque_false_alarm`]).
    pub torque_quiet: usize,
    pub torque_false_alarms: usize,
    /// Trials whose planted effects act on the torque through a modelled
    /// loss, and those whose first torque cause is right.
    pub torque_due: usize,
    pub torque_right: usize,
    /// Trials whose torque verdict is "unexplained".
    pub torque_unexplained: usize,
    /// Trials whose measured torque contradicts the flow's causes.
    pub torque_contradicts: usize,
}

/// Fails when a folder is where `eval.json` or `eval.md` goes in `out`:
/// one would be written and not the other.
fn check_result_places(out: &Path) -> Result<(), RunError> {
    for name in ["eval.json", "eval.md"] {
        if out.join(name).is_dir() {
            return Err(RunError::Io {
                path: out.join(name),
                source: std::io::Error::other("a folder is where this result file goes; move or rename it (nothing was written)",
                ),
            });
        }
    }
    Ok(())
}

/// The most trials per group an evaluation takes.
pub const MAX_TRIALS: usize = 1000;

/// The most pumps of an evaluation's campaigns ([`gearpump_campaign::synth::MAX_SAMPLES`]).
pub const MAX_SAMPLES: usize = gearpump_campaign::synth::MAX_SAMPLES;

fn validate(options: &EvalOptions) -> Result<(), RunError> {
    if !(1..=MAX_TRIALS).contains(&options.trials) {
        return Err(RunError::Setting {
            setting: Setting::Trials,
            message: format!(
                "{} is outside [1, {MAX_TRIALS}] (each trial plants and diagnoses a whole campaign, a minute or more; the plan's draws are made up front)",
                options.trials
            ),
        });
    }
    for e in &options.effects {
        if e != NO_EFFECT && !EFFECT_NAMES.contains(&e.as_str()) {
            return Err(RunError::Setting {
                setting: Setting::Effects,
                message: format!(
                    "unknown effect `{e}` (effects: {}, {NO_EFFECT})",
                    EFFECT_NAMES.join(", ")
                ),
            });
        }
    }
    for f in &options.families {
        if !FAMILIES.contains(&f.as_str()) {
            return Err(RunError::Setting {
                setting: Setting::Families,
                message: format!("unknown family `{f}` (families: {})", FAMILIES.join(", ")),
            });
        }
    }
    if options.samples < 4 {
        return Err(RunError::Setting {
            setting: Setting::Samples,
            message: "the evaluation draws populations: at least 4 pumps".into(),
        });
    }
    if options.samples > MAX_SAMPLES {
        return Err(RunError::Setting {
            setting: Setting::Samples,
            message: format!(
                "{} pumps is more than {MAX_SAMPLES} (a campaign's pumps are each simulated at every condition, in every trial)",
                options.samples
            ),
        });
    }
    Ok(())
}

/// A drawn effect, refused when its name has no detectable range.
fn drawn(name: &str, rng: &mut ChaCha8Rng) -> Result<Effect, RunError> {
    draw_effect(name, rng).ok_or_else(|| RunError::Setting {
        setting: Setting::Effects,
        message: format!("{name}: no detectable range"),
    })
}

/// Three significant digits, as a user would type it.
fn typed(v: f64) -> f64 {
    format!("{v:.3e}").parse().unwrap_or(v)
}

/// An out-of-family pump: its index and the factor on its true tips.
type OutOfFamily = Option<(usize, f64)>;

/// The `k`-th campaign of a family: its plant, noise and out-of-family
/// pump.
fn family_plant(
    family: &str,
    k: usize,
    samples: usize,
    rng: &mut ChaCha8Rng,
) -> Result<(Plant, Noise, OutOfFamily), RunError> {
    let single = EFFECT_NAMES[k % EFFECT_NAMES.len()];
    Ok(match family {
        "mismatched" => {
            let plant = match k % 6 {
                0 => Plant::TipsThermal {
                    k_t_um_per_k: typed(rng.gen_range(0.04..=0.07)),
                },
                1 => Plant::TipsPressure {
                    k_p_um_per_bar: typed(rng.gen_range(0.1..=0.3)),
                },
                2 => Plant::BearingsPressure {
                    k_p_um_per_bar: typed(rng.gen_range(0.3..=0.6)),
                },
                3 => Plant::Design {
                    sets: vec![format!(
                        "clearance.lateral_um={}",
                        typed(rng.gen_range(20.0..=30.0))
                    )],
                    expect: "lateral_clearance",
                },
                4 => Plant::Design {
                    sets: vec![
                        format!("oil.nu_40c_cst={}", typed(35.0 * rng.gen_range(0.55..=0.8))),
                        format!("oil.nu_100c_cst={}", typed(7.3 * rng.gen_range(0.55..=0.8))),
                    ],
                    expect: "viscosity_shift",
                },
                _ => {
                    let sign = if rng.gen_bool(0.5) { -1.0 } else { 1.0 };
                    Plant::Design {
                        sets: vec![format!(
                            "gears.face_width_mm={}",
                            typed(26.0 * (1.0 + sign * rng.gen_range(0.015..=0.03)))
                        )],
                        expect: "displacement_error",
                    }
                }
            };
            (plant, Noise::RIG, None)
        }
        "two_effects" => {
            let (a, b) = PAIRS[k % PAIRS.len()];
            (
                Plant::Effects(vec![drawn(a, rng)?, drawn(b, rng)?]),
                Noise::RIG,
                None,
            )
        }
        "noise_x3" => (
            Plant::Effects(vec![drawn(single, rng)?]),
            Noise {
                flow_rel: 3.0 * Noise::RIG.flow_rel,
                torque_rel: 3.0 * Noise::RIG.torque_rel,
            },
            None,
        ),
        "out_of_family" => (
            Plant::Effects(vec![drawn(single, rng)?]),
            Noise::RIG,
            Some((rng.gen_range(0..samples), OUT_OF_FAMILY_FACTOR)),
        ),
        "flow_and_torque" => {
            let (flow, _, _) = family_plant("mismatched", k, samples, rng)?;
            (
                Plant::WithTorque {
                    flow: Box::new(flow),
                    torque: draw_torque_plant(k, rng),
                },
                Noise::RIG,
                None,
            )
        }
        _ => (
            Plant::Filling {
                loss_at_4000: typed(rng.gen_range(0.03..=0.06)),
            },
            Noise::RIG,
            None,
        ),
    })
}

/// Runs the trials; writes `DIR/trials/<effect or family>-<k>/` (campaign.csv
/// and the diagnosis), `DIR/eval.json` and `DIR/eval.md`; returns the JSON
/// object.
pub fn run_eval(
    source: &DesignSource,
    out: &Path,
    options: &EvalOptions,
    progress: &mut dyn FnMut(usize, usize, &Trial),
) -> Result<Value, RunError> {
    validate(options)?;
    if out.exists() && !out.is_dir() {
        return Err(RunError::Setting {
            setting: Setting::Output,
            message: format!("{} exists and is not a directory", out.display()),
        });
    }
    check_result_places(out)?;
    let start = Instant::now();
    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    // (group, plant, noise, out-of-family pump, campaign seed)
    type Planned = (String, Plant, Noise, OutOfFamily, u64);
    let mut plan: Vec<Planned> = Vec::new();
    for _ in 0..options.trials {
        for e in &options.effects {
            let plant = if e == NO_EFFECT {
                Plant::None
            } else {
                Plant::Effects(vec![drawn(e, &mut rng)?])
            };
            plan.push((
                e.clone(),
                plant,
                Noise::RIG,
                None,
                rng.gen::<u64>() % 1_000_000,
            ));
        }
    }
    for f in &options.families {
        for k in 0..options.trials {
            let (plant, noise, ooff) = family_plant(f, k, options.samples, &mut rng)?;
            plan.push((f.clone(), plant, noise, ooff, rng.gen::<u64>() % 1_000_000));
        }
    }
    // each trial's folder name: its group and its index in the group
    let mut counter: std::collections::HashMap<String, usize> = Default::default();
    let named: Vec<(String, Planned)> = plan
        .into_iter()
        .map(|p| {
            let k = counter.entry(p.0.clone()).or_insert(0);
            let id = format!("{}-{k}", p.0);
            *k += 1;
            (id, p)
        })
        .collect();
    if let Some(missing) = options
        .only
        .iter()
        .find(|o| !named.iter().any(|(id, _)| id == *o))
    {
        return Err(RunError::Setting {
            setting: Setting::Only,
            message: format!(
                "{missing}: no such trial in this plan (trials are named <group>-<k>, k from 0 to {}: {} ...)",
                options.trials - 1,
                named.iter().take(3).map(|(id, _)| id.as_str()).collect::<Vec<_>>().join(", ")
            ),
        });
    }
    let selected: Vec<(String, Planned)> = named
        .into_iter()
        .filter(|(id, _)| options.only.is_empty() || options.only.contains(id))
        .collect();
    let total = selected.len();
    let mut trials = Vec::with_capacity(total);
    for (i, (id, (name, plant, noise, ooff, seed))) in selected.into_iter().enumerate() {
        let dir: PathBuf = out.join("trials").join(id);
        std::fs::create_dir_all(&dir).map_err(|source| RunError::Io {
            path: dir.clone(),
            source,
        })?;
        let t0 = Instant::now();
        let mut resumed = false;
        let popts = PlantOptions {
            samples: options.samples,
            seed,
            noise,
            micromotion: options.micromotion,
            jobs: options.jobs,
            out_of_family: ooff,
        };
        let mut run = || -> Result<Value, RunError> {
            let csv_text = planted_csv(source, &plant, &popts)?;
            let csv = dir.join("campaign.csv");
            // an earlier run of the same trial (the same campaign, byte for
            // byte, and its diagnosis) is taken as it is: an evaluation
            // stopped half-way resumes where it stopped
            if let Some(v) = earlier_diagnosis(&csv, &csv_text) {
                resumed = true;
                return Ok(v);
            }
            atomic_write_text(&csv, &csv_text)?;
            run_diagnosis(
                source,
                &csv,
                &dir,
                DiagnoseOptions {
                    jobs: options.jobs,
                    micromotion: options.micromotion,
                    ..DiagnoseOptions::default()
                },
                &Silent,
            )
            .map(|d| d.json)
        };
        let mut trial = Trial {
            effect: name,
            truth: (plant != Plant::None).then(|| plant.describe()),
            expected: plant.expected().iter().map(|s| s.to_string()).collect(),
            synth_seed: seed,
            cause: None,
            causes: vec![],
            ambiguous_with: vec![],
            unexplained: false,
            out_of_family_planted: ooff.map(|(p, _)| sample_id(p, options.samples)),
            out_of_family_found: vec![],
            rmse_ratio: None,
            truth_rmse_ratio: None,
            floor_rmse_ratio: None,
            wall_s: 0.0,
            dir: dir.display().to_string(),
            error: None,
            resumed: false,
            torque_truth: TorqueTruth::default(),
            torque_cause: None,
            torque_causes: vec![],
            torque_unexplained: false,
            torque_contradicts: false,
        };
        match run() {
            Ok(v) => trial.read_diagnosis(&v),
            Err(e) => trial.error = Some(e.to_string()),
        }
        trial.wall_s = t0.elapsed().as_secs_f64();
        if resumed {
            trial.resumed = true;
            trial.wall_s = trial.wall_s.max(v_wall(&trial.dir));
        }
        // the verdict's error against the noise-free truth: the campaign's
        // own noise draws, no model run
        if trial.error.is_none() && trial.rmse_ratio.is_some() {
            let factors = planted_flow_factors(source, &popts);
            match truth_rmse_ratio(&dir, &factors) {
                Ok(r) => {
                    // the data's ratio recomputed from the files is the
                    // diagnosis's own, or the files are not what it used
                    let (data, own) = (r.data, trial.rmse_ratio.unwrap_or(f64::NAN));
                    if (data - own).abs() <= 1e-9 * own.abs().max(1.0) {
                        trial.truth_rmse_ratio = Some(r.truth);
                        trial.floor_rmse_ratio = Some(r.floor);
                    } else {
                        trial.error = Some(format!(
                            "the RMSE ratio from tests.csv, {data}, is not the diagnosis's {own}"
                        ));
                    }
                }
                Err(e) => trial.error = Some(format!("the RMSE ratio against the truth: {e}")),
            }
        }
        // what the plant does to the torque, measured on its noise-free
        // truth (not in the diagnosis time)
        if trial.error.is_none() {
            match planted_torque_change(source, &plant, &popts) {
                Ok(change) => {
                    trial.torque_truth =
                        torque_truth(&trial.expected, ooff.is_some(), change, noise.torque_rel);
                    if let Some(p) = plant.torque_expected() {
                        trial.torque_truth.plant(p);
                    }
                }
                Err(e) => trial.error = Some(format!("the planted torque change: {e}")),
            }
        }
        progress(i + 1, total, &trial);
        trials.push(trial);
    }
    let groups: Vec<String> = options
        .effects
        .iter()
        .chain(&options.families)
        .cloned()
        .collect();
    let summaries = summarize_trials(&groups, &trials);
    let detection_min = summaries
        .iter()
        .filter(|s| s.effect != NO_EFFECT)
        .map(|s| s.rate)
        .fold(None, |m: Option<f64>, x| Some(m.map_or(x, |m| m.min(x))));
    let false_alarm = summaries
        .iter()
        .find(|s| s.effect == NO_EFFECT)
        .map(|s| 1.0 - s.rate);
    let v = json!({
        "trials_per_effect": options.trials,
        "seed": options.seed,
        "samples": options.samples,
        "micromotion": options.micromotion,
        "families": options.families,
        "summary": summaries,
        "detection_rate_min": detection_min,
        "false_alarm_rate": false_alarm,
        "trials": trials,
        "wall_s": start.elapsed().as_secs_f64(),
    });
    // both files or neither (checked at the start too: a folder may have
    // been put there since)
    check_result_places(out)?;
    atomic_write_text(
        &out.join("eval.json"),
        &(serde_json::to_string_pretty(&v).unwrap_or_default() + "\n"),
    )?;
    atomic_write_text(&out.join("eval.md"), &eval_markdown(&v, &summaries))?;
    Ok(v)
}

/// The verdict's RMSE ratio (extended model over base model, eta_v) on a
/// diagnosed trial folder, against the measurements and against the
/// noise-free truth: `factors` are the flowmeter's factors of every test
/// ([`planted_flow_factors`]), so a test's true eta_v is its measured one
/// over its factor. Over the tests of the verdict: those of `tests.csv`
/// (the base model) and `extended/tests.csv` (the extended one), without
/// the pumps the diagnosis set aside (`diagnosis.json`'s
/// `gain.pumps_set_aside`).
pub fn truth_rmse_ratio(dir: &Path, factors: &[FlowFactor]) -> Result<Ratios, String> {
    let v: Value = std::fs::read_to_string(dir.join("diagnosis.json"))
        .map_err(|e| format!("diagnosis.json: {e}"))
        .and_then(|t| serde_json::from_str(&t).map_err(|e| format!("diagnosis.json: {e}")))?;
    let set_aside: Vec<&str> = v["gain"]["pumps_set_aside"]
        .as_array()
        .map(|a| a.iter().filter_map(Value::as_str).collect())
        .unwrap_or_default();
    type Key = (String, i64, i64, i64);
    let key = |s: &str, p: f64, n: f64, t: f64| -> Key {
        let q = |x: f64| (x * 1e6).round() as i64;
        (s.to_string(), q(p), q(n), q(t))
    };
    // (key, eta_v measured, eta_v simulated) of every test of a tests.csv
    let read = |path: PathBuf| -> Result<Vec<(Key, f64, f64)>, String> {
        let mut r =
            csv::Reader::from_path(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        let h = r
            .headers()
            .map_err(|e| format!("{}: {e}", path.display()))?
            .clone();
        let col = |name: &str| {
            h.iter()
                .position(|c| c == name)
                .ok_or_else(|| format!("{}: no column {name}", path.display()))
        };
        let c = [
            col("sample")?,
            col("pressure_bar")?,
            col("speed_rpm")?,
            col("temp_c")?,
            col("eta_v_meas")?,
            col("eta_v_sim")?,
        ];
        let mut out = Vec::new();
        for rec in r.records() {
            let rec = rec.map_err(|e| format!("{}: {e}", path.display()))?;
            let num = |k: usize| rec[c[k]].trim().parse::<f64>().unwrap_or(f64::NAN);
            out.push((key(&rec[c[0]], num(1), num(2), num(3)), num(4), num(5)));
        }
        Ok(out)
    };
    let base = read(dir.join("tests.csv"))?;
    let ext: std::collections::HashMap<Key, f64> = read(dir.join("extended").join("tests.csv"))?
        .into_iter()
        .map(|(k, _, sim)| (k, sim))
        .collect();
    let factor: std::collections::HashMap<Key, f64> = factors
        .iter()
        .map(|f| {
            (
                key(&f.sample, f.pressure_bar, f.speed_rpm, f.temp_c),
                f.factor,
            )
        })
        .collect();
    let (mut sums, mut n) = ([0.0; 5], 0usize);
    for (k, meas, sim) in &base {
        if set_aside.contains(&k.0.as_str()) || !(meas.is_finite() && sim.is_finite()) {
            continue;
        }
        let ext_sim = *ext
            .get(k)
            .ok_or_else(|| format!("test {k:?} not in extended/tests.csv"))?;
        let f = *factor
            .get(k)
            .ok_or_else(|| format!("test {k:?} not in the campaign's draws"))?;
        if !ext_sim.is_finite() {
            continue;
        }
        let truth = meas / f;
        for (s, x) in sums.iter_mut().zip([
            sim - meas,
            ext_sim - meas,
            sim - truth,
            ext_sim - truth,
            truth - meas,
        ]) {
            *s += x * x;
        }
        n += 1;
    }
    if n == 0 {
        return Err("no test with finite values".into());
    }
    Ok(Ratios {
        data: (sums[1] / sums[0]).sqrt(),
        truth: (sums[3] / sums[2]).sqrt(),
        floor: (sums[4] / sums[0]).sqrt(),
    })
}

/// The RMSE ratios of one diagnosed trial ([`truth_rmse_ratio`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ratios {
    /// Extended model over base model, against the measurements (the
    /// diagnosis's own `gain.rmse_ratio`).
    pub data: f64,
    /// The same against the noise-free truth.
    pub truth: f64,
    /// The noise-free truth itself against the measurements, over the
    /// base model: the ratio an exact extension would score on the data.
    pub floor: f64,
}

/// What a family or effect group plants, for the table.
fn group_text(g: &str) -> String {
    match g {
        "mismatched" => "other mechanisms: tips-only thermal / pressure in the inputs, bearings-only pressure, lateral gap, oil datasheet, face width through design keys".into(),
        "two_effects" => PAIRS.iter().map(|(a, b)| format!("{a}+{b}")).collect::<Vec<_>>().join(", "),
        "noise_x3" => "one effect, flowmeter noise 1.5 %".into(),
        "out_of_family" => format!("one effect and one pump whose tips are {OUT_OF_FAMILY_FACTOR} x their record"),
        "outside" => "incomplete filling, 3-6 % at 4000 rpm (no candidate)".into(),
        "flow_and_torque" => "a mismatched flow plant and beside it a torque loss: a lip seal's drag a + b sqrt(n/1000), or the thrust-plate or mesh friction coefficient through design keys".into(),
        _ => range_text(g),
    }
}

/// One summary per group that has trials (a group left out by `--only`
/// has no row).
pub fn summarize_trials(effects: &[String], trials: &[Trial]) -> Vec<EffectSummary> {
    effects
        .iter()
        .filter(|e| trials.iter().any(|t| &t.effect == *e))
        .map(|e| {
            let t: Vec<&Trial> = trials.iter().filter(|t| &t.effect == e).collect();
            let n = t.len();
            let correct = t.iter().filter(|x| x.correct()).count();
            let ratios: Vec<f64> = t
                .iter()
                .filter(|x| x.cause.is_some())
                .filter_map(|x| x.rmse_ratio)
                .collect();
            let truth_ratios: Vec<f64> = t
                .iter()
                .filter(|x| x.cause.is_some())
                .filter_map(|x| x.truth_rmse_ratio)
                .collect();
            let floor_above_half = t
                .iter()
                .filter(|x| x.cause.is_some())
                .filter_map(|x| x.floor_rmse_ratio)
                .filter(|r| *r > 0.5)
                .count();
            EffectSummary {
                effect: e.clone(),
                range: group_text(e),
                trials: n,
                correct,
                rate: if n > 0 {
                    correct as f64 / n as f64
                } else {
                    f64::NAN
                },
                all_named: t
                    .iter()
                    .filter(|x| !x.expected.is_empty() && x.all_named())
                    .count(),
                other_cause: t
                    .iter()
                    .filter(|x| {
                        x.cause
                            .as_ref()
                            .is_some_and(|c| !x.expected.iter().any(|e| e == kind(c)))
                    })
                    .count(),
                null_cause: t
                    .iter()
                    .filter(|x| x.cause.is_none() && x.error.is_none())
                    .count(),
                unexplained: t.iter().filter(|x| x.unexplained).count(),
                out_of_family_found: t
                    .iter()
                    .filter(|x| {
                        x.out_of_family_planted
                            .as_ref()
                            .is_some_and(|p| x.out_of_family_found.contains(p))
                    })
                    .count(),
                errors: t.iter().filter(|x| x.error.is_some()).count(),
                ambiguous: t.iter().filter(|x| !x.ambiguous_with.is_empty()).count(),
                mean_rmse_ratio: (!ratios.is_empty())
                    .then(|| ratios.iter().sum::<f64>() / ratios.len() as f64),
                worst_rmse_ratio: ratios.iter().copied().reduce(f64::max),
                ratio_above_half: ratios.iter().filter(|r| **r > 0.5).count(),
                mean_truth_rmse_ratio: (!truth_ratios.is_empty())
                    .then(|| truth_ratios.iter().sum::<f64>() / truth_ratios.len() as f64),
                worst_truth_rmse_ratio: truth_ratios.iter().copied().reduce(f64::max),
                truth_ratio_above_half: truth_ratios.iter().filter(|r| **r > 0.5).count(),
                floor_above_half,
                torque_quiet: t
                    .iter()
                    .filter(|x| {
                        x.error.is_none()
                            && (!x.torque_truth.acts || x.torque_truth.planted.is_some())
                    })
                    .count(),
                torque_false_alarms: t.iter().filter(|x| x.torque_false_alarm()).count(),
                torque_due: t.iter().filter(|x| x.torque_right().is_some()).count(),
                torque_right: t.iter().filter(|x| x.torque_right() == Some(true)).count(),
                torque_unexplained: t.iter().filter(|x| x.torque_unexplained).count(),
                torque_contradicts: t.iter().filter(|x| x.torque_contradicts).count(),
            }
        })
        .collect()
}

fn eval_markdown(v: &Value, s: &[EffectSummary]) -> String {
    let mut md = String::from("# Diagnosis evaluation\n\n");
    md.push_str(&format!(
        "{} trials per effect, {} pumps, micromotion {}, seed {}; {:.0} s.\n\n",
        v["trials_per_effect"],
        v["samples"],
        v["micromotion"],
        v["seed"],
        v["wall_s"].as_f64().unwrap_or(f64::NAN)
    ));
    md.push_str(&table(s));
    md
}

/// The evaluation table (markdown).
pub fn table(s: &[EffectSummary]) -> String {
    let mut md = String::from(
        "| hidden effect / family | what | trials | first cause right | all causes named | other cause | cause null | unexplained | out-of-family found | errors | mean RMSE ratio | worst | ratio > 0.5 (noise alone > 0.5) | against the noise-free truth: mean / worst (> 0.5) | torque false alarms | torque cause right | torque unexplained | torque contradicts the flow's cause |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let f = |x: Option<f64>| x.map_or("-".into(), |x| format!("{x:.2}"));
    for x in s {
        let correct = if x.effect == NO_EFFECT {
            format!(
                "{}/{} null (false alarms {:.0} %)",
                x.correct,
                x.trials,
                100.0 * (1.0 - x.rate)
            )
        } else if x.effect == "outside" {
            format!(
                "{}/{} unexplained ({:.0} %)",
                x.correct,
                x.trials,
                100.0 * x.rate
            )
        } else {
            format!("{}/{} ({:.0} %)", x.correct, x.trials, 100.0 * x.rate)
        };
        let all = if x.effect == "two_effects" {
            format!("{}/{}", x.all_named, x.trials)
        } else {
            "-".into()
        };
        let ooff = if x.effect == "out_of_family" {
            format!("{}/{}", x.out_of_family_found, x.trials)
        } else {
            "-".into()
        };
        let torque_fa = if x.torque_quiet > 0 {
            format!(
                "{}/{} ({:.0} %)",
                x.torque_false_alarms,
                x.torque_quiet,
                100.0 * x.torque_false_alarms as f64 / x.torque_quiet as f64
            )
        } else {
            "-".into()
        };
        let torque_right = if x.torque_due > 0 {
            format!("{}/{}", x.torque_right, x.torque_due)
        } else {
            "-".into()
        };
        let truth = match (x.mean_truth_rmse_ratio, x.worst_truth_rmse_ratio) {
            (Some(m), Some(w)) => format!("{m:.2} / {w:.2} ({})", x.truth_ratio_above_half),
            _ => "-".into(),
        };
        let above_half = format!("{} ({})", x.ratio_above_half, x.floor_above_half);
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            x.effect,
            x.range,
            x.trials,
            correct,
            all,
            x.other_cause,
            x.null_cause,
            x.unexplained,
            ooff,
            x.errors,
            f(x.mean_rmse_ratio),
            f(x.worst_rmse_ratio),
            above_half,
            truth,
            torque_fa,
            torque_right,
            x.torque_unexplained,
            x.torque_contradicts
        ));
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_effect_has_a_range_and_draws_inside_it() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for name in EFFECT_NAMES {
            let (ranges, signed) = detectable_range(name).unwrap();
            for _ in 0..20 {
                let e = draw_effect(name, &mut rng).unwrap();
                assert_eq!(e.name(), name);
                for ((_, v), (a, b)) in e.params_edge().iter().zip(ranges) {
                    let m = if signed { v.abs() } else { *v };
                    assert!(m >= a * 0.999 && m <= b * 1.001, "{name}: {v}");
                }
            }
        }
        assert!(detectable_range(NO_EFFECT).is_none());
    }

    #[test]
    fn a_trial_is_resumed_only_from_the_same_campaign() {
        let dir = std::env::temp_dir().join(format!("gearpump-eval-resume-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let csv = dir.join("campaign.csv");
        std::fs::write(&csv, "sample,flow\nN01,1.0\n").unwrap();
        // no diagnosis yet
        assert!(earlier_diagnosis(&csv, "sample,flow\nN01,1.0\n").is_none());
        let v = json!({
            "cause": "thermal_clearance@tips",
            "causes": [{"effect": "thermal_clearance@tips"}, {"effect": "entrained_air"}],
            "ambiguous_with": [{"effect": "viscosity_shift"}],
            "unexplained": false,
            "out_of_family": [{"sample": "N07"}],
            // over every test, N07 included; the verdict's ratio is over
            // the tests analysed, N07 set aside
            "baseline": {"rmse": 0.04},
            "extended": {"rmse": 0.02},
            "gain": {"rmse_ratio": 0.25, "pumps_set_aside": ["N07"]},
            "wall_s": 12.5,
            "torque": {"cause": "churning", "causes": ["churning"], "unexplained": true,
                       "flow_causes_check": {"worsened": true}},
        });
        std::fs::write(
            dir.join(super::super::diagnose::DIAGNOSIS_JSON),
            v.to_string(),
        )
        .unwrap();
        // another campaign (one reading differs): run again
        assert!(earlier_diagnosis(&csv, "sample,flow\nN01,1.1\n").is_none());
        // a diagnosis older than this build: run again
        let json_path = dir.join(super::super::diagnose::DIAGNOSIS_JSON);
        let old = std::time::SystemTime::UNIX_EPOCH + std::time::Duration::from_secs(1_000_000);
        std::fs::File::options()
            .write(true)
            .open(&json_path)
            .unwrap()
            .set_modified(old)
            .unwrap();
        assert!(earlier_diagnosis(&csv, "sample,flow\nN01,1.0\n").is_none());
        std::fs::File::options()
            .write(true)
            .open(&json_path)
            .unwrap()
            .set_modified(std::time::SystemTime::now())
            .unwrap();
        let got = earlier_diagnosis(&csv, "sample,flow\nN01,1.0\n").unwrap();
        let mut t = Trial {
            effect: "two_effects".into(),
            truth: None,
            expected: vec!["thermal_clearance".into(), "entrained_air".into()],
            synth_seed: 1,
            cause: None,
            causes: vec![],
            ambiguous_with: vec![],
            unexplained: true,
            out_of_family_planted: None,
            out_of_family_found: vec![],
            rmse_ratio: None,
            truth_rmse_ratio: None,
            floor_rmse_ratio: None,
            wall_s: 0.0,
            dir: dir.display().to_string(),
            error: None,
            resumed: true,
            torque_truth: TorqueTruth::default(),
            torque_cause: None,
            torque_causes: vec![],
            torque_unexplained: false,
            torque_contradicts: false,
        };
        t.read_diagnosis(&got);
        assert_eq!(t.cause.as_deref(), Some("thermal_clearance@tips"));
        assert_eq!(t.causes, ["thermal_clearance@tips", "entrained_air"]);
        assert_eq!(t.ambiguous_with, ["viscosity_shift"]);
        assert!(!t.unexplained);
        assert_eq!(t.out_of_family_found, ["N07"]);
        assert!((t.rmse_ratio.unwrap() - 0.25).abs() < 1e-12);
        assert!(t.correct() && t.all_named());
        assert_eq!(t.torque_cause.as_deref(), Some("churning"));
        assert_eq!(t.torque_causes, ["churning"]);
        assert!(t.torque_unexplained);
        assert!(t.torque_contradicts);
        assert_eq!(v_wall(&t.dir), 12.5);
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A trial of group `effect` with the planted causes `expected` whose
    /// planted torque change is `change` (relative RMS, against the rig's
    /// 0.2 % meter), read from a diagnosis whose torque section is `torque`
    /// (flow: no cause).
    fn torque_trial(effect: &str, expected: &[&str], change: f64, torque: Value) -> Trial {
        let expected: Vec<String> = expected.iter().map(|s| s.to_string()).collect();
        let mut t = Trial {
            effect: effect.into(),
            truth: None,
            torque_truth: torque_truth(&expected, false, change, Noise::RIG.torque_rel),
            expected,
            synth_seed: 1,
            cause: None,
            causes: vec![],
            ambiguous_with: vec![],
            unexplained: false,
            out_of_family_planted: None,
            out_of_family_found: vec![],
            rmse_ratio: None,
            truth_rmse_ratio: None,
            floor_rmse_ratio: None,
            wall_s: 0.0,
            dir: String::new(),
            error: None,
            resumed: false,
            torque_cause: None,
            torque_causes: vec![],
            torque_unexplained: false,
            torque_contradicts: false,
        };
        t.read_diagnosis(&json!({
            "cause": null, "causes": [], "ambiguous_with": [], "unexplained": false,
            "torque": torque,
        }));
        t
    }

    fn named(c: &str) -> Value {
        json!({"cause": c, "causes": [c], "unexplained": false})
    }

    fn no_cause() -> Value {
        json!({"cause": null, "causes": [], "unexplained": false})
    }

    /// A torque cause named when nothing planted acts on the torque is a
    /// torque false alarm, "no cause" is not; a cause of a planted
    /// mechanism whose torque change is below the meter's noise (the film
    /// shear of an opened clearance) is tolerated, another is not; where
    /// the torque is acted on through a modelled loss the first torque
    /// cause is scored.
    #[test]
    fn a_torque_cause_with_nothing_planted_on_the_torque_is_a_false_alarm() {
        let alarm = torque_trial(NO_EFFECT, &[], 0.0, named("viscous_friction"));
        assert!(alarm.torque_false_alarm());
        assert_eq!(alarm.torque_right(), None);
        let quiet = torque_trial(NO_EFFECT, &[], 0.0, no_cause());
        assert!(!quiet.torque_false_alarm());
        // no torque section at all (no measured torque): nothing named
        assert!(!torque_trial(NO_EFFECT, &[], 0.0, Value::Null).torque_false_alarm());
        // incomplete filling lowers the flow only
        assert!(torque_trial("outside", &[], 0.0, named("churning")).torque_false_alarm());
        // a second cause outside the planted mechanisms is an alarm too
        let second = json!({"cause": "viscous_friction",
            "causes": ["viscous_friction", "mesh_friction"], "unexplained": false});
        let thermal = &["thermal_clearance@tips"];
        assert!(torque_trial("thermal_clearance", thermal, 0.001, second).torque_false_alarm());
        let clear = torque_trial("mismatched", thermal, 0.001, named("viscous_friction"));
        assert!(!clear.torque_false_alarm());
        assert!(torque_trial("mismatched", thermal, 0.001, named("churning")).torque_false_alarm());
        // a clearance law that moves the torque beyond the meter's noise
        // (bearings opened by 0.6 um/bar) is scored, not an alarm
        let bearings = torque_trial(
            "mismatched",
            &["pressure_clearance@bearings"],
            0.0034,
            named("churning"),
        );
        assert!(!bearings.torque_false_alarm());
        assert_eq!(bearings.torque_right(), Some(false));
        // the oil acts on every film's shear
        let oil = |t| torque_trial("mismatched", &["viscosity_shift"], 0.005, t);
        assert_eq!(oil(named("viscous_friction")).torque_right(), Some(true));
        assert_eq!(oil(named("mesh_friction")).torque_right(), Some(false));
        assert_eq!(oil(no_cause()).torque_right(), Some(false));
        // the same with the flow's cause right: the extended model carries
        // the oil's shear, nothing is left for a loss coefficient
        let mut carried = oil(no_cause());
        carried.cause = Some("viscosity_shift".into());
        carried.causes = vec!["viscosity_shift".into()];
        assert_eq!(carried.torque_right(), Some(true));
        carried.torque_unexplained = true;
        assert_eq!(carried.torque_right(), Some(false));
        assert!(!oil(named("mesh_friction")).torque_false_alarm());
        // a wider face moves the hydraulic torque: no candidate is right,
        // none is a false alarm
        let face = torque_trial(
            "mismatched",
            &["displacement_error"],
            0.02,
            named("mesh_friction"),
        );
        assert_eq!(face.torque_right(), None);
        assert!(!face.torque_false_alarm());
        // a thermal opening (shear tolerated) beside a displacement error
        // that moves the hydraulic torque: not scored either
        let pair = torque_trial(
            "two_effects",
            &["thermal_clearance", "displacement_error"],
            0.02,
            named("thrust_plate_friction"),
        );
        assert_eq!(pair.torque_right(), None);
        assert!(!pair.torque_false_alarm());
        // free air below the meter's noise: no loss is its mechanism
        assert!(torque_trial(
            "entrained_air",
            &["entrained_air"],
            0.001,
            named("constant_drag")
        )
        .torque_false_alarm());

        let trials = vec![alarm, quiet, oil(named("viscous_friction")), face, clear];
        // a group without trials (left out by --only) has no row
        let s = summarize_trials(
            &[NO_EFFECT.into(), "outside".into(), "mismatched".into()],
            &trials,
        );
        assert_eq!(s.len(), 2);
        assert_eq!((s[0].torque_quiet, s[0].torque_false_alarms), (2, 1));
        assert_eq!((s[1].torque_quiet, s[1].torque_false_alarms), (1, 0));
        assert_eq!((s[1].torque_due, s[1].torque_right), (1, 1));
        let md = table(&s);
        assert!(md.contains("torque false alarms"), "{md}");
        assert!(md.contains("| 1/2 (50 %) | - |"), "{md}");
        assert!(md.contains("| 0/1 (0 %) | 1/1 |"), "{md}");
    }

    /// The planted torque change against the physics of each plant
    /// (noise-free campaigns of two pumps at the Table 2 conditions):
    /// nothing planted and incomplete filling (a closed form on the flow)
    /// leave the torque exactly alone; a pressure-viscous film, whose
    /// shear takes its Barus factor on the tip and lateral films only (a
    /// factor of 1.22 at most, at 40 bar, on the 0.4-2 % of the torque
    /// that their shear is), by less
    /// than the meter's noise but more than a quarter of it; a thinner oil
    /// and a wider lateral gap (less film shear) and a wider face (the
    /// hydraulic torque) by more, even at the end of their ranges nearest
    /// the base model.
    /// Two pumps (seed 5), micromotion on, one job: the torque-change tests.
    fn two_pumps() -> PlantOptions {
        PlantOptions {
            samples: 2,
            seed: 5,
            noise: Noise::RIG,
            micromotion: true,
            jobs: Some(1),
            out_of_family: None,
        }
    }

    #[test]
    fn the_planted_torque_change_follows_each_plants_physics() {
        let source = DesignSource::load(None, &[]).unwrap();
        let opts = two_pumps();
        let change = |p: &Plant| planted_torque_change(&source, p, &opts).unwrap();
        let eff = |name: &str, v: &[f64]| Plant::Effects(vec![Effect::from_edge(name, v).unwrap()]);
        let meter = Noise::RIG.torque_rel;
        assert_eq!(change(&Plant::None), 0.0);
        assert_eq!(change(&Plant::Filling { loss_at_4000: 0.06 }), 0.0);
        let pv = change(&eff("pressure_viscosity", &[1e-7]));
        assert!(pv > 0.25 * meter && pv < meter, "{pv}");
        for p in [
            eff("viscosity_shift", &[0.8, 0.8]),
            eff("lateral_clearance", &[20.0]),
            Plant::Design {
                sets: vec![format!("gears.face_width_mm={}", 26.0 * 1.015)],
                expect: "displacement_error",
            },
            // the bearing films shear less when opened by 0.6 um/bar
            Plant::BearingsPressure {
                k_p_um_per_bar: 0.6,
            },
        ] {
            let c = change(&p);
            assert!(c >= meter, "{}: {c}", p.describe());
        }
        // the rest at the far end of their ranges, for docs/diagnosis.md
        // (`-- --nocapture`): below the meter's noise when measured
        for p in [
            eff("thermal_clearance", &[0.07]),
            eff("pressure_clearance", &[0.3]),
            eff("entrained_air", &[0.05]),
            Plant::TipsThermal { k_t_um_per_k: 0.07 },
            Plant::TipsPressure {
                k_p_um_per_bar: 0.3,
            },
        ] {
            eprintln!("{}: {:.3} %", p.describe(), 100.0 * change(&p));
        }
    }

    /// `flow_and_torque`: a torque loss planted beside a flow effect is
    /// right only when its cause is the first torque cause (no cause, or
    /// only the flow mechanism's film shear, is a miss even with the flow's
    /// first cause right); any torque cause named beyond it and the flow
    /// mechanism's is a false alarm, first or second, and those trials
    /// count among those scored for false alarms although the torque is
    /// acted on. The planted cause survives eval.json (serde), and an
    /// eval.json of before the field reads as no torque plant.
    #[test]
    fn flow_and_torque_needs_the_planted_torque_cause_first() {
        let ft = |flow: &[&str], planted: &str, torque: Value| {
            let mut t = torque_trial("flow_and_torque", flow, 0.01, torque);
            t.torque_truth.plant(planted);
            t
        };
        let thermal = &["thermal_clearance"];
        let seal = |t| ft(thermal, "constant_drag", t);
        let right = seal(named("constant_drag"));
        assert_eq!(right.torque_right(), Some(true));
        assert!(!right.torque_false_alarm());
        assert_eq!(
            right.torque_truth.causes,
            ["constant_drag", "viscous_friction"]
        );
        // the flow's first cause right and nothing named for the torque:
        // right for `mismatched`, a miss here
        let mut silent = seal(no_cause());
        silent.cause = Some("thermal_clearance@tips".into());
        silent.causes = vec!["thermal_clearance@tips".into()];
        assert!(silent.correct());
        assert_eq!(silent.torque_right(), Some(false));
        assert!(!silent.torque_false_alarm());
        // the film shear of the thermal opening first: a miss, not an alarm
        let shear = seal(named("viscous_friction"));
        assert_eq!(shear.torque_right(), Some(false));
        assert!(!shear.torque_false_alarm());
        // the planted cause first and the flow mechanism's second: right
        let two = |second: &str| {
            seal(json!({"cause": "constant_drag",
                "causes": ["constant_drag", second], "unexplained": false}))
        };
        assert_eq!(two("viscous_friction").torque_right(), Some(true));
        assert!(!two("viscous_friction").torque_false_alarm());
        // ... or a cause of no planted mechanism second: right, and an alarm
        assert_eq!(two("mesh_friction").torque_right(), Some(true));
        assert!(two("mesh_friction").torque_false_alarm());
        // another loss first
        let wrong = seal(named("mesh_friction"));
        assert_eq!(wrong.torque_right(), Some(false));
        assert!(wrong.torque_false_alarm());
        // a face width moves the hydraulic torque (not scored in
        // `mismatched`): the plate friction planted beside it is scored
        let face = |t| ft(&["displacement_error"], "thrust_plate_friction", t);
        assert!(face(no_cause()).torque_truth.unmodelled);
        assert_eq!(
            face(named("thrust_plate_friction")).torque_right(),
            Some(true)
        );
        assert_eq!(face(named("churning")).torque_right(), Some(false));
        assert!(face(named("viscous_friction")).torque_false_alarm());
        // an error is a miss, never an alarm
        let mut failed = seal(named("constant_drag"));
        failed.error = Some("synth failed".into());
        assert_eq!(failed.torque_right(), Some(false));
        assert!(!failed.torque_false_alarm());

        let trials = vec![right.clone(), silent, wrong, two("mesh_friction"), failed];
        let s = summarize_trials(&["flow_and_torque".into()], &trials);
        assert_eq!((s[0].torque_quiet, s[0].torque_false_alarms), (4, 2));
        assert_eq!((s[0].torque_due, s[0].torque_right), (5, 2));
        assert!(table(&s).contains("| 2/4 (50 %) | 2/5 |"), "{}", table(&s));

        let j = serde_json::to_string(&right).unwrap();
        let back: Trial = serde_json::from_str(&j).unwrap();
        assert_eq!(back.torque_truth.planted.as_deref(), Some("constant_drag"));
        assert_eq!(back.torque_right(), Some(true));
        let mut old: Value = serde_json::from_str(&j).unwrap();
        old["torque_truth"]
            .as_object_mut()
            .unwrap()
            .remove("planted");
        let old: Trial = serde_json::from_value(old).unwrap();
        assert_eq!(old.torque_truth.planted, None);
    }

    /// The family's campaigns: the flow plant of `mismatched`'s same draw
    /// (the same plant and magnitude from the same random state), and
    /// beside it a seal, the plate's or the mesh's friction in turn, each
    /// within its range; twelve campaigns meet every flow plant with two
    /// torque kinds.
    #[test]
    fn flow_and_torque_draws_a_mismatched_flow_plant_and_a_torque_loss() {
        let mut kinds = std::collections::BTreeSet::new();
        for k in 0..12 {
            let mut a = ChaCha8Rng::seed_from_u64(40 + k as u64);
            let mut b = a.clone();
            let (p, noise, ooff) = family_plant("flow_and_torque", k, 20, &mut a).unwrap();
            let (m, _, _) = family_plant("mismatched", k, 20, &mut b).unwrap();
            assert_eq!((noise, ooff), (Noise::RIG, None));
            let Plant::WithTorque { flow, torque } = &p else {
                panic!("{p:?}")
            };
            assert_eq!(flow.as_ref(), &m);
            assert_eq!(p.expected(), m.expected());
            assert_eq!(p.torque_expected(), Some(torque.expected()));
            let inside = |v: f64, r: (f64, f64)| v >= r.0 * 0.999 && v <= r.1 * 1.001;
            match *torque {
                TorquePlant::SealDrag { a_nm, b_nm } => {
                    assert!(inside(a_nm, SEAL_A_NM) && inside(b_nm, SEAL_B_NM), "{p:?}")
                }
                TorquePlant::Coefficient { key, factor } => {
                    let (lo, hi) = if key == "losses.thrust_plate_friction" {
                        (PLATE_FACTOR_LOW, PLATE_FACTOR_HIGH)
                    } else {
                        assert_eq!(key, "losses.mesh_friction_coefficient");
                        (MESH_FACTOR_LOW, MESH_FACTOR_HIGH)
                    };
                    assert!(inside(factor, lo) || inside(factor, hi), "{p:?}");
                }
            }
            let flow_kind = m.describe().split('=').next().unwrap().to_string();
            kinds.insert((flow_kind, torque.expected()));
        }
        assert_eq!(kinds.len(), 12, "{kinds:?}");
    }

    /// The torque plants of `flow_and_torque` at the ends of their ranges
    /// nearest the base model move the noise-free truth torque by more than
    /// twice the meter's noise (RMS over the tests, relative), so a
    /// torque cause is due; the churning coefficient, even four times the
    /// design's (the candidate's physical bound), moves it by less than the
    /// noise: the drag of the submerged gears, `C rho w^2 ra^4 b`, is about
    /// 1.5e-4 N m at 1000 rpm, so it is not planted.
    #[test]
    fn the_torque_plants_act_beyond_the_meter_noise() {
        let source = DesignSource::load(None, &[]).unwrap();
        let opts = two_pumps();
        let meter = Noise::RIG.torque_rel;
        let with = |torque: TorquePlant| Plant::WithTorque {
            flow: Box::new(Plant::None),
            torque,
        };
        let coef = |key: &'static str, factor: f64| with(TorquePlant::Coefficient { key, factor });
        let change = |p: &Plant| planted_torque_change(&source, p, &opts).unwrap();
        for p in [
            with(TorquePlant::SealDrag {
                a_nm: SEAL_A_NM.0,
                b_nm: SEAL_B_NM.0,
            }),
            coef("losses.thrust_plate_friction", PLATE_FACTOR_LOW.1),
            coef("losses.thrust_plate_friction", PLATE_FACTOR_HIGH.0),
            coef("losses.mesh_friction_coefficient", MESH_FACTOR_LOW.1),
            coef("losses.mesh_friction_coefficient", MESH_FACTOR_HIGH.0),
        ] {
            let c = change(&p);
            eprintln!("{}: {:.3} %", p.describe(), 100.0 * c);
            assert!(c >= 2.0 * meter, "{}: {c}", p.describe());
        }
        let churn = change(&coef("losses.churning_coefficient", 4.0));
        eprintln!("churning x 4: {:.4} %", 100.0 * churn);
        assert!(churn > 0.0 && churn < meter, "{churn}");
    }

    /// The flowmeter's factors are the campaign's own: its measured flows
    /// divided by them are, row by row, the flows of the same campaign
    /// planted without noise (a second, independent planting: model runs
    /// of every test), and the keys are its rows'.
    #[test]
    fn the_flow_factors_take_the_noise_out_of_a_planted_campaign() {
        let source = DesignSource::load(None, &[]).unwrap();
        let noisy = PlantOptions {
            noise: Noise {
                flow_rel: 0.015,
                torque_rel: 0.006,
            },
            ..two_pumps()
        };
        let quiet = PlantOptions {
            noise: Noise::NONE,
            ..two_pumps()
        };
        let plant = Plant::TipsThermal { k_t_um_per_k: 0.05 };
        let rows = |opts: &PlantOptions| {
            gearpump_campaign::data::parse_campaign_str(
                "t",
                &planted_csv(&source, &plant, opts).unwrap(),
            )
            .unwrap()
            .rows
        };
        let (a, b) = (rows(&noisy), rows(&quiet));
        let f = planted_flow_factors(&source, &noisy);
        assert_eq!((a.len(), f.len()), (28, 28));
        let mut moved = 0.0_f64;
        use gearpump_core::units::{bar_to_pa, celsius_to_kelvin, rpm_to_rad_s};
        for ((x, y), r) in a.iter().zip(&b).zip(&f) {
            // the factor's row is the campaign's row (compared in SI)
            assert_eq!(x.sample, r.sample);
            assert!((x.pressure - bar_to_pa(r.pressure_bar)).abs() < 1e-6);
            assert!((x.temp - celsius_to_kelvin(r.temp_c)).abs() < 1e-9);
            assert!((x.speed - rpm_to_rad_s(r.speed_rpm)).abs() < 1e-9);
            assert!(((x.flow / r.factor) / y.flow - 1.0).abs() < 1e-12, "{r:?}");
            moved = moved.max((x.flow / y.flow - 1.0).abs());
        }
        // the noise is there to be taken out
        assert!(moved > 0.01, "{moved}");
    }

    /// The ratios by hand on a folder of three tests and a pump set aside:
    /// the base model's errors against the data 0.02, -0.01, 0.02, the
    /// extension's a fifth of them (ratio 0.2); the flowmeter read 1 % high
    /// on the first test and 1 % low on the third, so against the truth
    /// (measured over factor) the ratio is another, computed from the same
    /// numbers.
    #[test]
    fn the_ratios_against_data_and_truth_by_hand() {
        let dir = std::env::temp_dir().join(format!("gp-truth-ratio-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("extended")).unwrap();
        std::fs::write(
            dir.join("diagnosis.json"),
            r#"{"gain": {"pumps_set_aside": ["N02"]}}"#,
        )
        .unwrap();
        let head = "sample,pressure_bar,speed_rpm,temp_c,eta_v_meas,eta_v_sim\n";
        let meas = [0.95, 0.90, 0.80];
        let base = [0.97, 0.89, 0.82];
        let ext = [0.954, 0.898, 0.804];
        let conds = [
            ("10", "1000", "60"),
            ("20", "1000", "60"),
            ("30", "2500", "120"),
        ];
        let file = |sims: &[f64]| {
            let mut t = head.to_string();
            for ((c, m), s) in conds.iter().zip(meas).zip(sims) {
                t += &format!("N01,{},{},{},{m},{s}\n", c.0, c.1, c.2);
            }
            // the pump set aside: far off, and left out
            t += "N02,10,1000,60,0.5,0.9\n";
            t
        };
        std::fs::write(dir.join("tests.csv"), file(&base)).unwrap();
        std::fs::write(dir.join("extended").join("tests.csv"), file(&ext)).unwrap();
        let row = |sample: &str, p: f64, n: f64, t: f64, factor: f64| FlowFactor {
            sample: sample.into(),
            pressure_bar: p,
            speed_rpm: n,
            temp_c: t,
            factor,
        };
        let factors = vec![
            row("N01", 10.0, 1000.0, 60.0, 1.01),
            row("N01", 20.0, 1000.0, 60.0, 1.0),
            row("N01", 30.0, 2500.0, 120.0, 0.99),
            row("N02", 10.0, 1000.0, 60.0, 1.0),
        ];
        let Ratios { data, truth, floor } = truth_rmse_ratio(&dir, &factors).unwrap();
        let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
        let by_hand = |sim: &[f64], truth: &[f64]| {
            rms(&sim
                .iter()
                .zip(truth)
                .map(|(s, t)| s - t)
                .collect::<Vec<_>>())
        };
        let t = [0.95 / 1.01, 0.90, 0.80 / 0.99];
        assert!((data - by_hand(&ext, &meas) / by_hand(&base, &meas)).abs() < 1e-12);
        assert!((data - 0.2).abs() < 1e-12, "{data}");
        assert!((truth - by_hand(&ext, &t) / by_hand(&base, &t)).abs() < 1e-12);
        assert!((truth - data).abs() > 0.01, "{truth} {data}");
        // the truth's own errors on the data: 0.95 - 0.95/1.01, 0, 0.80 -
        // 0.80/0.99, over the base model's 0.02, -0.01, 0.02
        let floor_by_hand = ((0.95f64 - 0.95 / 1.01).powi(2) + (0.80f64 - 0.80 / 0.99).powi(2))
            .sqrt()
            / (0.02f64 * 0.02 + 0.01 * 0.01 + 0.02 * 0.02).sqrt();
        assert!(
            (floor - floor_by_hand).abs() < 1e-12,
            "{floor} {floor_by_hand}"
        );
        // a test missing from the draws is refused, not skipped
        let e = truth_rmse_ratio(&dir, &factors[1..]).unwrap_err();
        assert!(e.contains("draws"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn bad_options_are_refused() {
        let mut o = EvalOptions {
            trials: 0,
            seed: 1,
            effects: vec![NO_EFFECT.into()],
            families: vec![],
            samples: 20,
            jobs: None,
            micromotion: false,
            only: vec![],
        };
        assert!(validate(&o).unwrap_err().to_string().contains("trials"));
        o.trials = 1;
        o.effects = vec!["bogus".into()];
        assert!(validate(&o).unwrap_err().to_string().contains("bogus"));
        // a trial the plan does not hold is refused by name before anything
        // is planted or written
        o.effects = vec![NO_EFFECT.into()];
        o.only = vec!["none-0".into(), "none-3".into()];
        let dir = std::env::temp_dir().join(format!("gp-eval-only-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let source = DesignSource::load(None, &[]).unwrap();
        let e = run_eval(&source, &dir, &o, &mut |_, _, _| {})
            .unwrap_err()
            .to_string();
        assert!(e.contains("none-3") && e.contains("no such trial"), "{e}");
        assert!(!dir.exists(), "{}", dir.display());
    }
}
