//! Campaigns whose truth is made by *another mechanism* than the candidates'
//! own code, for `eval-diagnosis` and the hidden-effect tests.
//!
//! `synth` plants an effect with the very code (`campaign::effects`) the
//! diagnosis fits as a candidate, so a perfect fit is possible by
//! construction. Real pumps are not so kind. The plants here change what the
//! model is given by other routes, as nature would:
//!
//! | plant | mechanism | expected cause |
//! |---|---|---|
//! | `tips_thermal` | each test's *tip* clearances opened by `k_T (T - 20 degC)` in the inputs, bearings untouched (the candidate opens both) | thermal_clearance |
//! | `tips_pressure` | each test's tip clearances opened by `k_p p`, bearings untouched | pressure_clearance |
//! | `bearings_pressure` | each test's *bearing* clearances opened by `k_p p`, tips untouched | pressure_clearance |
//! | `lateral` | the design's `clearance.lateral_um` changed through the design keys | lateral_clearance |
//! | `oil` | the oil's datasheet viscosities `oil.nu_40c_cst`, `oil.nu_100c_cst` changed (a Walther curve of another shape than the candidate's factors at 60 and 120 degC) | viscosity_shift |
//! | `face_width` | the design's `gears.face_width_mm` changed (the rig keeps the drawing's displacement) | displacement_error |
//! | `filling` | incomplete filling at high speed: every test's true flow times `1 - L (n / 4000 rpm)^2`, a loss no candidate models | none: unexplained |
//! | `effects` | `synth`'s own effects (one or two at once) | those effects |
//!
//! Any plant may add an **out-of-family pump**: one pump whose recorded tip
//! clearances are smaller than its true ones by a factor (a mis-measured
//! pump: it leaks more than the model of its record).
//!
//! The population, conditions, noise and order of random draws are those of
//! `synth` (its module doc), so the same seed gives the same pumps.

use std::sync::Arc;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use gearpump_campaign::data::parse_campaign_str;
use gearpump_campaign::effects::{Effect, EffectModel, T_MEASURE_C};
use gearpump_campaign::io::campaign_csv_string;
use gearpump_campaign::run::{DesignSource, RunError, Silent};
use gearpump_campaign::synth::{
    draw_noise, draw_population, paper_conditions, population_records, record_measurements,
    truth_runs, Noise, SEED_CLEARANCE_STATS,
};
use gearpump_core::model::Pump;
use gearpump_core::units::{celsius_to_kelvin, um_to_m};

/// What the truth of a planted campaign is.
#[derive(Debug, Clone, PartialEq)]
pub enum Plant {
    /// Tip clearances opened with temperature in the inputs, um/K.
    TipsThermal { k_t_um_per_k: f64 },
    /// Tip clearances opened with delivery pressure in the inputs, um/bar.
    TipsPressure { k_p_um_per_bar: f64 },
    /// Bearing clearances opened with delivery pressure in the inputs, um/bar.
    BearingsPressure { k_p_um_per_bar: f64 },
    /// Design keys changed (`key=value`, as `--set`), and the cause expected.
    Design {
        sets: Vec<String>,
        expect: &'static str,
    },
    /// Incomplete filling: relative flow loss at 4000 rpm.
    Filling { loss_at_4000: f64 },
    /// `synth`'s own effects.
    Effects(Vec<Effect>),
    /// No effect.
    None,
}

impl Plant {
    /// The causes a correct diagnosis names (empty: none, or unexplained).
    pub fn expected(&self) -> Vec<&'static str> {
        match self {
            Plant::TipsThermal { .. } => vec!["thermal_clearance"],
            Plant::TipsPressure { .. } | Plant::BearingsPressure { .. } => {
                vec!["pressure_clearance"]
            }
            Plant::Design { expect, .. } => vec![expect],
            Plant::Effects(e) => e.iter().map(|x| x.name()).collect(),
            Plant::Filling { .. } | Plant::None => vec![],
        }
    }

    /// The truth as text (for the trial records).
    pub fn describe(&self) -> String {
        match self {
            Plant::TipsThermal { k_t_um_per_k } => {
                format!("tips_thermal k_T={k_t_um_per_k:.4} um/K (inputs)")
            }
            Plant::TipsPressure { k_p_um_per_bar } => {
                format!("tips_pressure k_p={k_p_um_per_bar:.4} um/bar (inputs)")
            }
            Plant::BearingsPressure { k_p_um_per_bar } => {
                format!("bearings_pressure k_p={k_p_um_per_bar:.4} um/bar (inputs)")
            }
            Plant::Design { sets, .. } => format!("design {}", sets.join(" ")),
            Plant::Filling { loss_at_4000 } => {
                format!("filling loss {:.1} % at 4000 rpm", 100.0 * loss_at_4000)
            }
            Plant::Effects(e) => e
                .iter()
                .map(|x| x.to_string())
                .collect::<Vec<_>>()
                .join(" + "),
            Plant::None => "none".into(),
        }
    }
}

/// A planted campaign's settings.
#[derive(Debug, Clone)]
pub struct PlantOptions {
    pub samples: usize,
    pub seed: u64,
    pub noise: Noise,
    pub micromotion: bool,
    pub jobs: Option<usize>,
    /// An out-of-family pump: (its index, factor of its true tip clearances
    /// over the recorded ones).
    pub out_of_family: Option<(usize, f64)>,
}

/// The campaign CSV of `plant` on the base design of `source` (module doc).
pub fn planted_csv(
    source: &DesignSource,
    plant: &Plant,
    opts: &PlantOptions,
) -> Result<String, RunError> {
    let (truth_design, effects) = match plant {
        Plant::Design { sets, .. } => {
            let mut all = source.sets.clone();
            all.extend(sets.iter().cloned());
            (DesignSource::load(None, &all)?.design, vec![])
        }
        Plant::Effects(e) => (source.design.clone(), e.clone()),
        _ => (source.design.clone(), vec![]),
    };
    let pump = Arc::new(Pump::new(truth_design));
    let truth = EffectModel::on(&pump, &effects)?;
    let base = &source.design;
    let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
    let population = draw_population(base, opts.samples, &SEED_CLEARANCE_STATS, &mut rng);
    let mut records = population_records(&population, &paper_conditions());
    let noise = draw_noise(&mut rng, records.len());
    // the truth rows: what the pump really had at each test
    let mut rows = parse_campaign_str("plant", &campaign_csv_string(&records))?.rows;
    let ooff_id = opts
        .out_of_family
        .map(|(i, _)| population[i.min(population.len() - 1)].id.clone());
    for r in rows.iter_mut() {
        let dt = r.temp - celsius_to_kelvin(T_MEASURE_C);
        let p_bar = r.pressure / 1e5;
        match *plant {
            Plant::TipsThermal { k_t_um_per_k } => {
                for h in r.tip_clearance.iter_mut() {
                    *h += um_to_m(k_t_um_per_k * dt);
                }
            }
            Plant::TipsPressure { k_p_um_per_bar } => {
                for h in r.tip_clearance.iter_mut() {
                    *h += um_to_m(k_p_um_per_bar * p_bar);
                }
            }
            Plant::BearingsPressure { k_p_um_per_bar } => {
                for h in r.bearing_clearance.iter_mut() {
                    *h += um_to_m(k_p_um_per_bar * p_bar);
                }
            }
            _ => {}
        }
        if let (Some(id), Some((_, factor))) = (&ooff_id, opts.out_of_family) {
            if &r.sample == id {
                for h in r.tip_clearance.iter_mut() {
                    *h *= factor;
                }
            }
        }
    }
    let mut sims = truth_runs(&truth, &rows, opts.micromotion, opts.jobs, &Silent)?;
    if let Plant::Filling { loss_at_4000 } = *plant {
        for ((q, _), rec) in sims.iter_mut().zip(&records) {
            *q *= 1.0 - loss_at_4000 * (rec.speed_rpm / 4000.0).powi(2);
        }
    }
    record_measurements(&mut records, &sims, &noise, opts.noise);
    Ok(campaign_csv_string(&records))
}

/// How much `plant` moves the shaft torque: the RMS over the tests of the
/// relative change of the noise-free truth torque of its campaign (with its
/// out-of-family pump, if any) against the same population with nothing
/// planted. Two truth runs of every test.
pub fn planted_torque_change(
    source: &DesignSource,
    plant: &Plant,
    opts: &PlantOptions,
) -> Result<f64, RunError> {
    let quiet = PlantOptions {
        noise: Noise::NONE,
        ..opts.clone()
    };
    let torques = |plant: &Plant, opts: &PlantOptions| -> Result<Vec<f64>, RunError> {
        Ok(
            parse_campaign_str("plant", &planted_csv(source, plant, opts)?)?
                .rows
                .iter()
                .map(|r| r.torque.unwrap_or(f64::NAN))
                .collect(),
        )
    };
    let t = torques(plant, &quiet)?;
    let base = torques(
        &Plant::None,
        &PlantOptions {
            out_of_family: None,
            ..quiet.clone()
        },
    )?;
    let n = t.len().max(1) as f64;
    Ok((t
        .iter()
        .zip(&base)
        .map(|(a, b)| ((a - b) / b).powi(2))
        .sum::<f64>()
        / n)
        .sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opts() -> PlantOptions {
        PlantOptions {
            samples: 2,
            seed: 5,
            noise: Noise::NONE,
            micromotion: false,
            jobs: Some(1),
            out_of_family: None,
        }
    }

    fn flows(csv: &str) -> Vec<f64> {
        parse_campaign_str("t", csv)
            .unwrap()
            .rows
            .iter()
            .map(|r| r.flow)
            .collect()
    }

    /// The "inputs only" plant is a plain run of the base model with the
    /// clearances opened by hand, and records the measured clearances: the
    /// tips-only thermal plant at 0 is the base campaign, and at k_T > 0 it
    /// lowers the flow at 120 degC more than at 60 degC (the leakage grows
    /// with the gap), and leaves the recorded clearances alone.
    #[test]
    fn tips_thermal_opens_the_tips_in_the_inputs_only() {
        let source = DesignSource::load(None, &[]).unwrap();
        let base = planted_csv(&source, &Plant::None, &opts()).unwrap();
        let zero =
            planted_csv(&source, &Plant::TipsThermal { k_t_um_per_k: 0.0 }, &opts()).unwrap();
        assert_eq!(base, zero);
        let hot =
            planted_csv(&source, &Plant::TipsThermal { k_t_um_per_k: 0.06 }, &opts()).unwrap();
        let (b, h) = (flows(&base), flows(&hot));
        let rows = parse_campaign_str("t", &hot).unwrap().rows;
        let rows0 = parse_campaign_str("t", &base).unwrap().rows;
        let (mut loss60, mut loss120) = (0.0, 0.0);
        for ((r, r0), (qb, qh)) in rows.iter().zip(&rows0).zip(b.iter().zip(&h)) {
            assert_eq!(r.tip_clearance, r0.tip_clearance);
            assert!(qh < qb, "row {}", r.row);
            if r.condition.temp_c < 90.0 {
                loss60 += qb - qh;
            } else {
                loss120 += qb - qh;
            }
        }
        assert!(loss120 > 2.0 * loss60, "{loss60} {loss120}");
    }

    /// The filling loss is the closed form `1 - L (n / 4000)^2` of the
    /// truth flow, exactly.
    #[test]
    fn filling_is_the_closed_form_loss() {
        let source = DesignSource::load(None, &[]).unwrap();
        let base = flows(&planted_csv(&source, &Plant::None, &opts()).unwrap());
        let csv = planted_csv(&source, &Plant::Filling { loss_at_4000: 0.05 }, &opts()).unwrap();
        let rows = parse_campaign_str("t", &csv).unwrap().rows;
        for (r, q0) in rows.iter().zip(&base) {
            let want = q0 * (1.0 - 0.05 * (r.condition.speed_rpm / 4000.0).powi(2));
            assert!((r.flow - want).abs() <= 1e-12 * want, "row {}", r.row);
        }
    }
}
