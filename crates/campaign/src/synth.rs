//! Synthetic measured campaigns with known hidden effects (`gearpump synth`).
//!
//! # What is drawn, what is simulated, what is written
//! 1. **Population.** `samples` pumps; each sample's four clearances are drawn
//!    from normal distributions of the normalised deviation
//!    `x* = (h - h_design) / h_design` with the seed paper's statistics
//!    (Sec. 3, Figs. 4-5; docs/model.md section 1): tip clearance mean 0.025
//!    (driving) and 0.035 (driven), bearing clearance mean 0.10 (driving) and
//!    0.17 (driven), standard deviation 0.06 for all four, around the design
//!    values of the design file. A draw that would give a clearance below
//!    10 % of its design value (more than 15 standard deviations out) is
//!    drawn again. Measured clearances are rounded to 0.1 um, the resolution
//!    of a dimensional-metrology report, and the rounded value is the
//!    sample's true clearance (no metrology error).
//! 2. **Conditions.** The 14 working conditions of seed Table 2 (1000 rpm at
//!    10/20/30/40 bar; 30 bar at 500/2000/4000 rpm; each at 60 and 120 degC),
//!    or a CSV file with the columns `pressure_bar`, `speed_rpm`, `temp_c`
//!    (bar gauge, rpm, degC; extra columns ignored). Every sample is tested at
//!    every condition; rows are sample-major.
//! 3. **Truth.** The project's model with the `--effect`s switched on
//!    ([`EffectModel`]), micromotion on. The pump's real shaft torque is the
//!    model's own (run with no measured torque); with micromotion the flow is
//!    then taken from a second run given that torque, exactly as `campaign`
//!    runs a test given its measured torque, so a noise-free campaign with no
//!    effect reproduces itself to rounding.
//! 4. **Measurement.** Gaussian noise, relative to the reading: the flowmeter
//!    (the seed's Kracht VC 5, +-0.5 % of reading, taken as one standard
//!    deviation: default 0.005) and the torque meter (the seed gives no
//!    figure; default 0.002, a typical in-line torque meter class).
//!    `--noise REL` sets both to REL, `--noise FLOW,TORQUE` each.
//! 5. **Output.** Only what a rig records: sample id, the four measured
//!    clearances (um), pressure (bar gauge), speed (rpm), temperature (degC),
//!    flow (l/min), torque (N m), at full precision. The effects are not in
//!    the file.
//!
//! # Reproducibility
//! One ChaCha8 stream seeded with `--seed` (portable and fixed by its
//! specification, unlike `StdRng`): first the clearances, sample by sample
//! (tip driving, tip driven, bearing driving, bearing driven), then two
//! standard normals per row in row order (flow, torque), drawn even when the
//! noise is zero. The same seed therefore gives the same population whatever
//! the noise, effects or thread count, and the same arguments give a
//! byte-identical CSV.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;
use serde::Serialize;
use serde_json::json;

pub use super::conditions::{
    conditions_from_arg, paper_conditions, parse_conditions_str, read_conditions, ConditionsError,
    PAPER_CONDITIONS,
};
use super::data::{parse_campaign_str, CampaignRecord, Condition, TestRow};
use super::effects::{Effect, EffectModel};
use super::io::atomic_write_text;
use super::io::campaign_csv_string;
use super::run::{simulate_test, with_pool, Observer, RunError, Setting};
use gearpump_core::design::Design;
use gearpump_core::model::Pump;
use gearpump_core::units::{m3_s_to_lpm, m_to_um};

/// Normalised clearance deviations `x* = (h - h_d) / h_d` of the seed's
/// population (Sec. 3): mean and standard deviation, in the order tip
/// driving, tip driven, bearing driving, bearing driven.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ClearanceStats {
    pub mean: [f64; 4],
    pub std: [f64; 4],
}

/// The seed paper's clearance statistics (docs/model.md section 1).
pub const SEED_CLEARANCE_STATS: ClearanceStats = ClearanceStats {
    mean: [0.025, 0.035, 0.10, 0.17],
    std: [0.06, 0.06, 0.06, 0.06],
};

/// Resolution of the written measured clearances, um.
pub const CLEARANCE_RESOLUTION_UM: f64 = 0.1;

/// Relative measurement noise (one standard deviation of the reading).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Noise {
    /// Flowmeter, relative to the reading.
    pub flow_rel: f64,
    /// Torque meter, relative to the reading.
    pub torque_rel: f64,
}

impl Noise {
    /// The seed's rig: flowmeter +-0.5 % of reading; torque meter 0.2 %.
    pub const RIG: Noise = Noise {
        flow_rel: 0.005,
        torque_rel: 0.002,
    };
    /// No noise.
    pub const NONE: Noise = Noise {
        flow_rel: 0.0,
        torque_rel: 0.0,
    };

    /// `REL` (both) or `FLOW,TORQUE`; each finite, in [0, 0.5).
    pub fn parse(text: &str) -> Result<Noise, RunError> {
        let bad = |message: String| RunError::Setting {
            setting: Setting::Noise,
            message,
        };
        let v = text
            .split(',')
            .map(|p| {
                p.trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite() && (0.0..0.5).contains(x))
                    .ok_or_else(|| {
                        bad(format!(
                            "`{}` is not a relative noise in [0, 0.5) (e.g. 0.005 for 0.5 %)",
                            p.trim()
                        ))
                    })
            })
            .collect::<Result<Vec<f64>, _>>()?;
        match v[..] {
            [r] => Ok(Noise {
                flow_rel: r,
                torque_rel: r,
            }),
            [f, t] => Ok(Noise {
                flow_rel: f,
                torque_rel: t,
            }),
            _ => Err(bad(format!("expected REL or FLOW,TORQUE, got `{text}`"))),
        }
    }
}

/// One drawn pump sample: measured clearances, um.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SampleDraw {
    pub id: String,
    pub tip_um: [f64; 2],
    pub bearing_um: [f64; 2],
}

/// Sample ids `N01`, `N02`, ... (at least two digits, more when needed).
pub fn sample_id(i: usize, n: usize) -> String {
    let width = n.to_string().len().max(2);
    format!("N{:0width$}", i + 1)
}

/// Draws `n` samples' clearances around the design values (see module doc).
pub fn draw_population(
    design: &Design,
    n: usize,
    stats: &ClearanceStats,
    rng: &mut ChaCha8Rng,
) -> Vec<SampleDraw> {
    let d = &design.clearance;
    let nominal_um = [
        m_to_um(d.tip[0]),
        m_to_um(d.tip[1]),
        m_to_um(d.bearing[0]),
        m_to_um(d.bearing[1]),
    ];
    (0..n)
        .map(|i| {
            let mut h = [0.0; 4];
            for k in 0..4 {
                h[k] = loop {
                    let z: f64 = StandardNormal.sample(rng);
                    let x = stats.mean[k] + stats.std[k] * z;
                    if x > -0.9 {
                        let v = nominal_um[k] * (1.0 + x);
                        break (v / CLEARANCE_RESOLUTION_UM).round() * CLEARANCE_RESOLUTION_UM;
                    }
                };
                // shortest text of the rounded value (30.700000000000003 -> 30.7)
                h[k] = format!("{:.1}", h[k]).parse().unwrap_or(h[k]);
            }
            SampleDraw {
                id: sample_id(i, n),
                tip_um: [h[0], h[1]],
                bearing_um: [h[2], h[3]],
            }
        })
        .collect()
}

/// Options of `gearpump synth`.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthOptions {
    pub samples: usize,
    pub seed: u64,
    pub effects: Vec<Effect>,
    pub noise: Noise,
    pub conditions: Vec<Condition>,
    /// Label of the conditions' source, for the JSON summary.
    pub conditions_label: String,
    pub micromotion: bool,
    /// Threads; None = all cores.
    pub jobs: Option<usize>,
}

impl SynthOptions {
    /// The seed's campaign: 20 samples, Table 2, rig noise, no effect.
    pub fn paper(seed: u64) -> Self {
        SynthOptions {
            samples: 20,
            seed,
            effects: Vec::new(),
            noise: Noise::RIG,
            conditions: paper_conditions(),
            conditions_label: "paper".into(),
            micromotion: true,
            jobs: None,
        }
    }
}

/// A synthetic campaign.
#[derive(Debug, Clone)]
pub struct SynthResult {
    pub population: Vec<SampleDraw>,
    pub records: Vec<CampaignRecord>,
    /// The noise-free truth flow of every row, l/min (not written).
    pub true_flow_lpm: Vec<f64>,
}

impl SynthResult {
    /// The campaign CSV text.
    pub fn csv(&self) -> String {
        campaign_csv_string(&self.records)
    }
}

/// The largest synthetic population: more pumps than any rig campaign
/// tests (the seed's has 20); at 14 conditions it is 140,000 periodic
/// runs, hours on a workstation.
pub const MAX_SAMPLES: usize = 10_000;

/// Refuses an empty or absurdly large population (checked before the pump
/// is built).
fn check_samples(opts: &SynthOptions) -> Result<(), RunError> {
    if !(1..=MAX_SAMPLES).contains(&opts.samples) {
        return Err(RunError::Setting {
            setting: Setting::Samples,
            message: format!(
                "{} is outside [1, {MAX_SAMPLES}] pumps (more than any rig campaign tests; each pump is simulated at every condition)",
                opts.samples
            ),
        });
    }
    Ok(())
}

/// One record per sample and condition (sample-major), flow and torque
/// still to be filled in.
pub fn population_records(
    population: &[SampleDraw],
    conditions: &[Condition],
) -> Vec<CampaignRecord> {
    let mut records = Vec::with_capacity(population.len() * conditions.len());
    for s in population {
        for c in conditions {
            records.push(CampaignRecord {
                sample: s.id.clone(),
                tip_clearance_drive_um: s.tip_um[0],
                tip_clearance_driven_um: s.tip_um[1],
                bearing_clearance_drive_um: s.bearing_um[0],
                bearing_clearance_driven_um: s.bearing_um[1],
                pressure_bar: c.pressure_bar,
                speed_rpm: c.speed_rpm,
                temp_c: c.temp_c,
                flow_lpm: 0.0,
                torque_nm: None,
            });
        }
    }
    records
}

/// Two standard normals per row (flow, torque), in row order.
pub fn draw_noise(rng: &mut ChaCha8Rng, rows: usize) -> Vec<(f64, f64)> {
    (0..rows)
        .map(|_| {
            let a: f64 = StandardNormal.sample(rng);
            let b: f64 = StandardNormal.sample(rng);
            (a, b)
        })
        .collect()
}

/// The true flow (l/min) and shaft torque (N m) of every row under
/// `truth`: one run with no measured torque.
///
/// Why that agrees with `campaign`, which runs a test given its measured
/// torque: a real pump's mesh force is set by its own shaft torque. The
/// model without a measurement takes its own (`model::net_torque`: the
/// shaft torque less friction is the hydraulic torque of the last mesh
/// period), with one the measurement less the model's losses; given the
/// model's own torque, both reach the same periodic state
/// (`tests/mechanics.rs`: flow within 4e-7, torque within 1e-5 at 1000
/// and 4000 rpm). Until 2026-11-27 the model without a measurement took the
/// ideal torque `Vm dp / (2 pi)` (6 % below the hydraulic torque at 4000
/// rpm / 30 bar) and the truth was first one run without a torque, whose
/// torque `campaign` then simulated 0.004-0.036 N m short of (`diagnose`
/// named `viscous_friction` -8 % for the torque of a campaign with nothing
/// hidden), and then a second run given that torque, one step of the fixed
/// point the model now reaches by itself.
pub fn truth_runs(
    truth: &EffectModel,
    rows: &[TestRow],
    micromotion: bool,
    jobs: Option<usize>,
    observer: &dyn Observer,
) -> Result<Vec<(f64, f64)>, RunError> {
    observer.begin(rows.len(), 0);
    let sims = with_pool(jobs, || {
        rows.par_iter()
            .map(|row| {
                let fail = |source| RunError::Model {
                    row: row.row,
                    source,
                };
                let run = simulate_test(truth, row, None, micromotion).map_err(fail)?;
                observer.advance();
                Ok((m3_s_to_lpm(run.flow), run.torque))
            })
            .collect::<Result<Vec<_>, RunError>>()
    })??;
    observer.end();
    Ok(sims)
}

/// What the rig records: the true flow and torque times `1 + noise`.
pub fn record_measurements(
    records: &mut [CampaignRecord],
    truth: &[(f64, f64)],
    normals: &[(f64, f64)],
    noise: Noise,
) {
    for ((rec, (q, t)), (nq, nt)) in records.iter_mut().zip(truth).zip(normals) {
        rec.flow_lpm = q * (1.0 + noise.flow_rel * nq);
        rec.torque_nm = Some(t * (1.0 + noise.torque_rel * nt));
    }
}

/// Simulates a synthetic campaign with a pump already built for `design`
/// (see the module doc). `pump.design` is the base design.
pub fn synthesize_with(
    pump: &Arc<Pump>,
    opts: &SynthOptions,
    observer: &dyn Observer,
) -> Result<SynthResult, RunError> {
    check_samples(opts)?;
    let design = &pump.design;
    let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
    let population = draw_population(design, opts.samples, &SEED_CLEARANCE_STATS, &mut rng);
    let mut records = population_records(&population, &opts.conditions);
    // The rows exactly as `campaign` will read them back; sample-major, so
    // a condition out of range shows first at its own row of the
    // conditions (the first sample's rows)
    let label = format!("conditions {}", opts.conditions_label);
    let campaign = parse_campaign_str(&label, &campaign_csv_string(&records))?;
    super::run::check_rows_in_range(&campaign, design)?;
    let noise = draw_noise(&mut rng, records.len());
    let truth = EffectModel::on(pump, &opts.effects)?;
    let sims = truth_runs(
        &truth,
        &campaign.rows,
        opts.micromotion,
        opts.jobs,
        observer,
    )?;
    record_measurements(&mut records, &sims, &noise, opts.noise);
    let true_flow_lpm = sims.iter().map(|s| s.0).collect();
    Ok(SynthResult {
        population,
        records,
        true_flow_lpm,
    })
}

/// [`synthesize_with`] building the pump (about half a second) first.
pub fn synthesize(
    design: &Design,
    opts: &SynthOptions,
    observer: &dyn Observer,
) -> Result<SynthResult, RunError> {
    check_samples(opts)?;
    let pump = Arc::new(Pump::new(design.clone()));
    synthesize_with(&pump, opts, observer)
}

/// `gearpump synth`: synthesizes and writes the CSV to `out` atomically
/// (creating its folder); returns the `--json` object.
pub fn run_synth(
    design: &Design,
    opts: &SynthOptions,
    out: &Path,
    observer: &dyn Observer,
) -> Result<serde_json::Value, RunError> {
    if let Some(dir) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|source| RunError::Io {
            path: PathBuf::from(dir),
            source,
        })?;
    }
    let result = synthesize(design, opts, observer)?;
    atomic_write_text(out, &result.csv())?;
    Ok(json!({
        "out": out.display().to_string(),
        "samples": opts.samples,
        "tests": result.records.len(),
        "conditions": opts.conditions.len(),
        "conditions_source": opts.conditions_label,
        "seed": opts.seed,
        "noise": opts.noise,
        "effects": opts.effects.iter().map(|e| e.to_string()).collect::<Vec<_>>(),
        "micromotion": opts.micromotion,
        "clearance_stats": SEED_CLEARANCE_STATS,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn campaign_synth_noise_parse() {
        assert_eq!(
            Noise::parse("0.005").unwrap(),
            Noise {
                flow_rel: 0.005,
                torque_rel: 0.005
            }
        );
        assert_eq!(
            Noise::parse("0.005, 0.002").unwrap(),
            Noise {
                flow_rel: 0.005,
                torque_rel: 0.002
            }
        );
        for bad in ["", "x", "-0.1", "0.6", "1,2,3", "NaN", "0.1,0.1,0.1"] {
            let e = Noise::parse(bad).unwrap_err();
            assert!(
                e.is_bad_input() && e.to_string().starts_with("noise: "),
                "{bad}: {e}"
            );
        }
    }

    #[test]
    fn campaign_synth_conditions_file() {
        let c = parse_conditions_str(
            "k.csv",
            "note,temp_c,speed_rpm,pressure_bar\na,60,1000,30\nb,120,500,10\n",
        )
        .unwrap();
        assert_eq!(c.len(), 2);
        assert_eq!(c[1].speed_rpm, 500.0);
        let e = parse_conditions_str(
            "k.csv",
            "pressure_bar,speed_rpm,temp_c\n30,1000,60\n30,-1,60\n",
        )
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "k.csv: row 2, column speed_rpm: must be > 0, got -1"
        );
        let e = parse_conditions_str("k.csv", "pressure_bar,speed_rpm\n30,1000\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "k.csv: header, column temp_c: required column is missing"
        );
        let e = parse_conditions_str(
            "k.csv",
            "pressure_bar,speed_rpm,temp_c\n30,1000,60\n30,1000,60\n",
        )
        .unwrap_err();
        assert!(
            matches!(
                e,
                ConditionsError::Duplicate {
                    row: 2,
                    first: 1,
                    ..
                }
            ),
            "{e}"
        );
        let e = parse_conditions_str("k.csv", "pressure_bar,speed_rpm,temp_c\n30,abc,60\n")
            .unwrap_err();
        assert!(
            e.to_string()
                .starts_with("k.csv: row 1, column speed_rpm: not a number"),
            "{e}"
        );
        assert!(matches!(
            parse_conditions_str("k.csv", "pressure_bar,speed_rpm,temp_c\n"),
            Err(ConditionsError::Empty { .. })
        ));
    }

    #[test]
    fn campaign_synth_paper_conditions_are_table_2() {
        let c = paper_conditions();
        assert_eq!(c.len(), 14);
        assert_eq!(c.iter().filter(|x| x.temp_c == 60.0).count(), 7);
        assert_eq!(
            c.iter()
                .filter(|x| x.speed_rpm == 1000.0 && x.temp_c == 120.0)
                .count(),
            4
        );
        assert_eq!(sample_id(0, 20), "N01");
        assert_eq!(sample_id(99, 100), "N100");
        assert_eq!(sample_id(4, 5), "N05");
    }

    #[test]
    fn campaign_synth_population_matches_seed_statistics() {
        let design = Design::seed();
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let n = 4000;
        let pop = draw_population(&design, n, &SEED_CLEARANCE_STATS, &mut rng);
        let nominal = [
            m_to_um(design.clearance.tip[0]),
            m_to_um(design.clearance.tip[1]),
            m_to_um(design.clearance.bearing[0]),
            m_to_um(design.clearance.bearing[1]),
        ];
        for (k, nominal_k) in nominal.into_iter().enumerate() {
            let x: Vec<f64> = pop
                .iter()
                .map(|s| {
                    let h = if k < 2 {
                        s.tip_um[k]
                    } else {
                        s.bearing_um[k - 2]
                    };
                    // written at 0.1 um resolution
                    assert_eq!(format!("{h}"), format!("{h:.1}").trim_end_matches(".0"));
                    (h - nominal_k) / nominal_k
                })
                .collect();
            let m = x.iter().sum::<f64>() / n as f64;
            let s = (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt();
            // standard error of the mean 0.06/sqrt(4000) ~ 1e-3; rounding adds < 0.002
            assert!(
                (m - SEED_CLEARANCE_STATS.mean[k]).abs() < 0.006,
                "{k}: mean {m}"
            );
            assert!((s - 0.06).abs() < 0.006, "{k}: std {s}");
        }
        // Same seed, same population.
        let again = draw_population(
            &design,
            n,
            &SEED_CLEARANCE_STATS,
            &mut ChaCha8Rng::seed_from_u64(7),
        );
        assert_eq!(pop, again);
    }
}
