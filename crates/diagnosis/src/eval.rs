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

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

use super::diagnose::{run_diagnosis, DiagnoseOptions};
use gearpump_campaign::effects::{Effect, EFFECT_NAMES};
use gearpump_campaign::io::atomic_write_text;
use gearpump_campaign::run::{DesignSource, RunError, Setting, Silent};
use gearpump_campaign::synth::{paper_conditions, synthesize_with, Noise, SynthOptions};
use gearpump_core::model::Pump;

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

/// Options of an evaluation.
#[derive(Debug, Clone)]
pub struct EvalOptions {
    /// Trials per effect (and without effect).
    pub trials: usize,
    pub seed: u64,
    /// The effects to evaluate (names of `EFFECT_NAMES` and/or "none").
    pub effects: Vec<String>,
    pub samples: usize,
    pub jobs: Option<usize>,
    pub micromotion: bool,
}

/// One trial.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Trial {
    pub effect: String,
    pub truth: Option<String>,
    pub synth_seed: u64,
    pub cause: Option<String>,
    pub ambiguous_with: Vec<String>,
    pub unexplained: bool,
    pub rmse_ratio: Option<f64>,
    pub wall_s: f64,
    pub dir: String,
    /// The trial could not be run (synth or diagnosis failed): the reason.
    #[serde(default)]
    pub error: Option<String>,
}

impl Trial {
    pub fn correct(&self) -> bool {
        if self.error.is_some() {
            false
        } else if self.effect == NO_EFFECT {
            self.cause.is_none()
        } else {
            self.cause.as_deref() == Some(self.effect.as_str())
        }
    }
}

/// Per-effect summary.
#[derive(Debug, Clone, Serialize)]
pub struct EffectSummary {
    pub effect: String,
    pub range: String,
    pub trials: usize,
    /// Named correctly (with an effect) / cause null (without).
    pub correct: usize,
    pub rate: f64,
    pub other_cause: usize,
    pub null_cause: usize,
    pub ambiguous: usize,
    /// Trials that could not be run (counted as not correct).
    pub errors: usize,
    pub mean_rmse_ratio: Option<f64>,
    pub worst_rmse_ratio: Option<f64>,
}

fn validate(options: &EvalOptions) -> Result<(), RunError> {
    if options.trials == 0 {
        return Err(RunError::Setting {
            setting: Setting::Trials,
            message: "must be >= 1".into(),
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
    if options.samples < 4 {
        return Err(RunError::Setting {
            setting: Setting::Samples,
            message: "a diagnosis needs at least 4 pumps".into(),
        });
    }
    Ok(())
}

/// Runs the trials; writes `DIR/trials/<effect>-<k>/` (campaign.csv and the
/// diagnosis), `DIR/eval.json` and `DIR/eval.md`; returns the JSON object.
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
    let start = Instant::now();
    let pump = Arc::new(Pump::new(source.design.clone()));
    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    let mut plan: Vec<(String, Option<Effect>, u64)> = Vec::new();
    for k in 0..options.trials {
        for e in &options.effects {
            let effect = if e == NO_EFFECT {
                None
            } else {
                Some(draw_effect(e, &mut rng).ok_or_else(|| RunError::Setting {
                    setting: Setting::Effects,
                    message: format!("{e}: no detectable range"),
                })?)
            };
            let _ = k;
            plan.push((e.clone(), effect, rng.gen::<u64>() % 1_000_000));
        }
    }
    let total = plan.len();
    let mut trials = Vec::with_capacity(total);
    let mut counter: std::collections::HashMap<String, usize> = Default::default();
    for (i, (name, effect, seed)) in plan.into_iter().enumerate() {
        let k = counter.entry(name.clone()).or_insert(0);
        let dir: PathBuf = out.join("trials").join(format!("{name}-{k}"));
        *k += 1;
        std::fs::create_dir_all(&dir).map_err(|source| RunError::Io {
            path: dir.clone(),
            source,
        })?;
        let t0 = Instant::now();
        let run = || -> Result<super::diagnose::Diagnosis, RunError> {
            let synth = SynthOptions {
                samples: options.samples,
                seed,
                effects: effect.into_iter().collect(),
                noise: Noise::RIG,
                conditions: paper_conditions(),
                conditions_label: "paper".into(),
                micromotion: options.micromotion,
                jobs: options.jobs,
            };
            let data = synthesize_with(&pump, &synth, &Silent)?;
            let csv = dir.join("campaign.csv");
            atomic_write_text(&csv, &data.csv())?;
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
        };
        let mut trial = Trial {
            effect: name,
            truth: effect.map(|e| e.to_string()),
            synth_seed: seed,
            cause: None,
            ambiguous_with: vec![],
            unexplained: false,
            rmse_ratio: None,
            wall_s: 0.0,
            dir: dir.display().to_string(),
            error: None,
        };
        match run() {
            Ok(d) => {
                trial.cause = d.cause.map(str::to_string);
                trial.ambiguous_with = d.ambiguous_with.iter().map(|s| s.to_string()).collect();
                trial.unexplained = d.unexplained;
                trial.rmse_ratio = d.extended_rmse.map(|r| r / d.baseline_rmse);
            }
            Err(e) => trial.error = Some(e.to_string()),
        }
        trial.wall_s = t0.elapsed().as_secs_f64();
        progress(i + 1, total, &trial);
        trials.push(trial);
    }
    let summaries = summarize_trials(&options.effects, &trials);
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
        "summary": summaries,
        "detection_rate_min": detection_min,
        "false_alarm_rate": false_alarm,
        "trials": trials,
        "wall_s": start.elapsed().as_secs_f64(),
    });
    atomic_write_text(
        &out.join("eval.json"),
        &(serde_json::to_string_pretty(&v).unwrap_or_default() + "\n"),
    )?;
    atomic_write_text(&out.join("eval.md"), &eval_markdown(&v, &summaries))?;
    Ok(v)
}

pub fn summarize_trials(effects: &[String], trials: &[Trial]) -> Vec<EffectSummary> {
    effects
        .iter()
        .map(|e| {
            let t: Vec<&Trial> = trials.iter().filter(|t| &t.effect == e).collect();
            let n = t.len();
            let correct = t.iter().filter(|x| x.correct()).count();
            let ratios: Vec<f64> = t
                .iter()
                .filter(|x| x.correct())
                .filter_map(|x| x.rmse_ratio)
                .collect();
            EffectSummary {
                effect: e.clone(),
                range: range_text(e),
                trials: n,
                correct,
                rate: if n > 0 {
                    correct as f64 / n as f64
                } else {
                    f64::NAN
                },
                other_cause: t
                    .iter()
                    .filter(|x| x.cause.is_some() && x.cause.as_deref() != Some(e.as_str()))
                    .count(),
                null_cause: t
                    .iter()
                    .filter(|x| x.cause.is_none() && x.error.is_none())
                    .count(),
                errors: t.iter().filter(|x| x.error.is_some()).count(),
                ambiguous: t.iter().filter(|x| !x.ambiguous_with.is_empty()).count(),
                mean_rmse_ratio: (!ratios.is_empty())
                    .then(|| ratios.iter().sum::<f64>() / ratios.len() as f64),
                worst_rmse_ratio: ratios.iter().copied().reduce(f64::max),
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
        "| hidden effect | range | trials | named correctly | other cause | cause null | ambiguous | errors | mean RMSE ratio | worst |\n|---|---|---|---|---|---|---|---|---|---|\n",
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
        } else {
            format!("{}/{} ({:.0} %)", x.correct, x.trials, 100.0 * x.rate)
        };
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            x.effect,
            x.range,
            x.trials,
            correct,
            x.other_cause,
            x.null_cause,
            x.ambiguous,
            x.errors,
            f(x.mean_rmse_ratio),
            f(x.worst_rmse_ratio)
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
    fn bad_options_are_refused() {
        let mut o = EvalOptions {
            trials: 0,
            seed: 1,
            effects: vec![NO_EFFECT.into()],
            samples: 20,
            jobs: None,
            micromotion: false,
        };
        assert!(validate(&o).unwrap_err().to_string().contains("trials"));
        o.trials = 1;
        o.effects = vec!["bogus".into()];
        assert!(validate(&o).unwrap_err().to_string().contains("bogus"));
    }
}
