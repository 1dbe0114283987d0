//! Hidden-effect tests of the diagnosis (issue "Diagnosis", point 3): for
//! each effect of docs/model.md section 8, a synthetic 20-pump campaign made by
//! `synth` (the seed's population and Table 2 conditions, the rig's noise)
//! with that effect at a magnitude inside its documented detectable range
//! (`gearpump::diagnosis::eval`), diagnosed blind: the diagnosis must name
//! the effect and the extended model must cut the RMSE of d to at most 0.6 of
//! the base model's. A campaign with no effect must give no cause.
//!
//! Seeds and magnitudes are fixed here so CI is reproducible; the magnitudes
//! are drawn once from the detectable ranges (the test checks they lie
//! inside them). `gearpump eval-diagnosis --trials N` measures the rates over
//! random seeds and magnitudes.

mod hand_reference;

use std::path::PathBuf;
use std::sync::Arc;

use gearpump::campaign::effects::{Effect, T_MEASURE_C};
use gearpump::campaign::run::{DesignSource, Silent};
use gearpump::campaign::synth::{synthesize_with, SynthOptions};
use gearpump::campaign::CampaignRecord;
use gearpump::diagnosis::diagnose::{run_diagnosis, DiagnoseOptions, Diagnosis};
use gearpump::diagnosis::eval::detectable_range;
use gearpump::model::Pump;

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("gearpump-hidden-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A synthetic campaign of the seed's population at Table 2 with `effect`
/// hidden (seed `seed`), its records editable by `edit` before writing.
fn synthetic(effect: Option<Effect>, seed: u64, edit: impl Fn(&mut CampaignRecord)) -> String {
    synthetic_of(20, effect, seed, edit)
}

/// [`synthetic`] with `pumps` pumps drawn instead of the seed's 20. Ten
/// are still a population (four or more: cross-validation by pump); the
/// tests whose point needs no more use them, since the candidates' fits
/// cost in proportion to the tests, and a campaign where no candidate fits
/// well takes the longest (every candidate refined, causes taken on trial
/// in every slot): 2-4 minutes at 20 pumps.
fn synthetic_of(
    pumps: usize,
    effect: Option<Effect>,
    seed: u64,
    edit: impl Fn(&mut CampaignRecord),
) -> String {
    let source = DesignSource::load(None, &[]).unwrap();
    let pump = Arc::new(Pump::new(source.design.clone()));
    let mut opts = SynthOptions::paper(seed);
    opts.samples = pumps;
    opts.effects = effect.into_iter().collect();
    let mut data = synthesize_with(&pump, &opts, &Silent).unwrap();
    data.records.iter_mut().for_each(edit);
    data.csv()
}

/// Writes `csv` into a scratch folder and diagnoses it (default options);
/// returns the diagnosis and the folder (outputs in `out/`).
fn diagnose_csv(name: &str, csv: &str) -> (Diagnosis, PathBuf) {
    let source = DesignSource::load(None, &[]).unwrap();
    let dir = scratch(name);
    let path = dir.join("campaign.csv");
    std::fs::write(&path, csv).unwrap();
    let d = run_diagnosis(
        &source,
        &path,
        &dir.join("out"),
        DiagnoseOptions::default(),
        &Silent,
    )
    .unwrap();
    // the file's `runs` is every model run of the diagnosis (the verdict's
    // analysis once overwrote it with its own)
    assert_eq!(d.json["runs"].as_u64(), Some(d.runs as u64));
    (d, dir)
}

/// Synthesizes the campaign with `effect` (seed `seed`) and diagnoses it.
fn diagnose_hidden(name: &str, effect: Option<Effect>, seed: u64) -> Diagnosis {
    let (d, dir) = diagnose_csv(name, &synthetic(effect, seed, |_| {}));
    println!(
        "{name}: cause {:?}, ambiguous {:?}, unexplained {}, base RMSE {:.5}, extended {:?}, {} runs, {:.0} s",
        d.cause,
        d.ambiguous_with,
        d.unexplained,
        d.baseline_rmse,
        d.extended_rmse,
        d.runs,
        d.json["wall_s"].as_f64().unwrap_or(f64::NAN)
    );
    for c in &d.candidates {
        println!(
            "  {:<20} cv_rmse {:.5} p_adj {:.1e} {:?}",
            c.effect, c.cv_rmse, c.p_adjusted, c.params
        );
    }
    assert!(dir.join("out/diagnosis.json").exists());
    assert!(dir.join("out/report.md").exists());
    let _ = std::fs::remove_dir_all(&dir);
    d
}

/// The fitted parameter `param` of the named cause `effect` in `causes`.
fn cause_param(d: &Diagnosis, effect: &str, param: &str) -> f64 {
    d.json["causes"]
        .as_array()
        .expect("causes")
        .iter()
        .find(|c| c["effect"] == effect)
        .and_then(|c| c["params"][param].as_f64())
        .unwrap_or_else(|| panic!("{effect}.{param} not among {}", d.json["causes"]))
}

fn check_found(name: &str, values: &[f64], seed: u64) {
    let (ranges, signed) = detectable_range(name).unwrap();
    for (v, (a, b)) in values.iter().zip(ranges) {
        let m = if signed { v.abs() } else { *v };
        assert!(
            m >= *a && m <= *b,
            "{name}={v} is outside its detectable range"
        );
    }
    let effect = Effect::from_edge(name, values).unwrap();
    let d = diagnose_hidden(name, Some(effect), seed);
    // the mechanism; a clearance law planted radially may be named at a
    // site the data cannot tell from it (`sites` says how close)
    assert_eq!(
        d.cause.map(|c| c.split('@').next().unwrap_or(c)),
        Some(name),
        "hidden {effect}: {:?}",
        d.json["candidates"]
    );
    let ratio = d.extended_rmse.unwrap() / d.baseline_rmse;
    assert!(ratio <= 0.6, "hidden {effect}: RMSE ratio {ratio:.3}");
    assert_eq!(d.json["gain"]["rmse_ratio"].as_f64(), Some(ratio));
    // the planted mechanism moved the torque as the cause's model does, so
    // the measured torque does not contradict it
    let check = &d.json["torque"]["flow_causes_check"];
    assert_eq!(check["worsened"], false, "hidden {effect}: {check}");
    // the fitted parameters are written with their names
    let fitted = &d.json["extended"]["params"];
    assert_eq!(fitted.as_object().unwrap().len(), values.len(), "{fitted}");
}

// thermal_clearance (0.1 um/K, seed 7, the acceptance case) runs
// through the binary in tests/diagnosis_cli.rs.
#[test]
fn hidden_thermal_clearance_at_the_low_end_is_named() {
    check_found("thermal_clearance", &[0.05], 9);
}

#[test]
fn hidden_pressure_clearance_is_named() {
    check_found("pressure_clearance", &[0.3], 21);
}

#[test]
fn hidden_lateral_clearance_is_named() {
    check_found("lateral_clearance", &[24.0], 33);
}

#[test]
fn hidden_viscosity_shift_is_named() {
    check_found("viscosity_shift", &[0.7, 0.6], 45);
}

#[test]
fn hidden_entrained_air_is_named() {
    check_found("entrained_air", &[0.03], 57);
}

#[test]
fn hidden_displacement_error_is_named() {
    check_found("displacement_error", &[-0.02], 69);
}

#[test]
fn hidden_pressure_viscosity_is_named() {
    check_found("pressure_viscosity", &[7e-8], 81);
}

/// Incomplete filling at high speed (the suction cannot fill the tooth
/// spaces in time) is a real loss that no candidate models: the flow of every
/// test loses `4 % (n / 4000 rpm)^2`. The diagnosis must not name a cause and
/// must say that the structure (in speed) is not explained.
///
/// Ten pumps (`synthetic_of`): with the seed's 20 the same verdict took
/// 6.3 minutes against 1.7 on a loaded machine (two causes taken on trial,
/// each refined in every slot, before neither halved the structure). At 10:
/// no cause (`entrained_air` improves the fit, ratio 0.75, but removes too
/// little of the structure), unexplained in `speed_rpm` (1.27 eta_v points),
/// `offset` and `slip_group`; at 20 the same three, speed 1.26 points.
#[test]
fn an_effect_outside_the_candidates_is_reported_unexplained() {
    let csv = synthetic_of(10, None, 105, |r| {
        r.flow_lpm *= 1.0 - 0.04 * (r.speed_rpm / 4000.0).powi(2)
    });
    let (d, dir) = diagnose_csv("filling", &csv);
    println!(
        "filling: cause {:?}, unexplained {} {}, partial {}",
        d.cause, d.unexplained, d.json["unexplained_features"], d.json["partial"]["effect"]
    );
    assert_eq!(d.cause, None, "{:?}", d.json["candidates"]);
    assert!(d.unexplained);
    let features: Vec<&str> = d.json["unexplained_features"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|v| v.as_str())
        .collect();
    assert!(features.contains(&"speed_rpm"), "{features:?}");
    let report = std::fs::read_to_string(dir.join("out/report.md")).unwrap();
    assert!(report.contains("Not explained"), "{report}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn no_hidden_effect_gives_no_cause() {
    let d = diagnose_hidden("none", None, 93);
    assert_eq!(d.cause, None, "{:?}", d.json["candidates"]);
    assert!(d.json["cause"].is_null());
    assert!(!d.unexplained, "{}", d.json["findings"]);
    assert!(d.json["gain"].is_null() && d.json["extended"].is_null());
}

/// A campaign planted by another mechanism than the candidates' code
/// (`gearpump::diagnosis::plant`), written and diagnosed blind.
fn diagnose_planted(
    name: &str,
    plant: &gearpump::diagnosis::plant::Plant,
    seed: u64,
    out_of_family: Option<(usize, f64)>,
) -> Diagnosis {
    use gearpump::campaign::synth::Noise;
    use gearpump::diagnosis::plant::{planted_csv, PlantOptions};
    let source = DesignSource::load(None, &[]).unwrap();
    let csv = planted_csv(
        &source,
        plant,
        &PlantOptions {
            samples: 20,
            seed,
            noise: Noise::RIG,
            micromotion: true,
            jobs: None,
            out_of_family,
        },
    )
    .unwrap();
    let (d, dir) = diagnose_csv(name, &csv);
    println!(
        "{name} ({}): causes {:?}, unexplained {}, out of family {}, RMSE {:.5} -> {:?}\n  remaining {}\n  structure {}",
        plant.describe(),
        d.causes,
        d.unexplained,
        d.json["out_of_family"],
        d.baseline_rmse,
        d.extended_rmse,
        d.json["remaining"],
        d.json["structure"]
    );
    let _ = std::fs::remove_dir_all(&dir);
    d
}

/// The kinds of the causes named (sites dropped), sorted.
fn cause_kinds(d: &Diagnosis) -> Vec<&str> {
    let mut kinds: Vec<&str> = d
        .causes
        .iter()
        .map(|c| c.split('@').next().unwrap_or(c))
        .collect();
    kinds.sort_unstable();
    kinds
}

/// Issue "Diagnosis on real data", point 1 (a mismatched-form case): the tip
/// clearances open with temperature through the measured-clearance inputs
/// alone, bearings unchanged, while the candidate also opens the bearings.
/// The radial candidate removes most of the error but not all of its form:
/// the diagnosis must name the mechanism rather than report "not
/// explained", and let the data say where it acts.
#[test]
fn a_mismatched_form_is_named_with_its_remaining_structure() {
    use gearpump::diagnosis::plant::Plant;
    let d = diagnose_planted(
        "tips-thermal",
        &Plant::TipsThermal { k_t_um_per_k: 0.06 },
        17,
        None,
    );
    // the mechanism; its site is reported with what the data can tell (the
    // bearings' share of the thermal opening changes eta_v little: tips
    // alone and tips with bearings are close, and the default is kept
    // unless the data prefer another site significantly)
    assert_eq!(
        d.cause.map(|c| c.split('@').next().unwrap_or(c)),
        Some("thermal_clearance"),
        "{}",
        d.json["candidates"]
    );
    let sites = d.json["sites"].as_array().unwrap();
    assert_eq!(sites.len(), 5, "{sites:?}");
    assert!(sites
        .iter()
        .any(|x| x["effect"] == "thermal_clearance@tips"));
    assert!(!d.unexplained, "{}", d.json["remaining"]);
    assert!(d.extended_rmse.unwrap() / d.baseline_rmse <= 0.5);
    // the record says how big what remains is, against the noise floor
    let floor = d.json["noise_floor"].as_f64().unwrap();
    assert!(floor > 0.0 && floor < 0.01, "noise floor {floor}");
    assert!(d.json["remaining"].is_array());
}

/// Issue "Diagnosis on real data", point 3: where an effect acts. The
/// bearing bores alone open with delivery pressure (0.45 um/bar, in the
/// inputs; the tips stay as measured): the data must choose the bearings.
#[test]
fn a_bearings_only_opening_is_placed_on_the_bearings() {
    use gearpump::diagnosis::plant::Plant;
    let d = diagnose_planted(
        "bearings",
        &Plant::BearingsPressure {
            k_p_um_per_bar: 0.45,
        },
        23,
        None,
    );
    assert_eq!(
        d.cause,
        Some("pressure_clearance@bearings"),
        "{}",
        d.json["sites"]
    );
    assert_eq!(d.json["causes"][0]["acts_on"], "bearings");
}

/// An oil whose viscosity rises with the film pressure by Barus's law,
/// alpha 8.18e-8 1/Pa, planted by the hand calculation (every film at its
/// own pressures, exactly through the reduced pressure; `plant_barus`),
/// where the candidate scales every gap's viscosity by one factor at half
/// the pressure rise (`hand_planted_eval`'s trial pressure_viscosity-0,
/// seed 20261128). The diagnosis must name the pressure-viscosity law.
///
/// Measured: `pressure_viscosity`, alpha 1.164e-7 (1.42 times the hand's:
/// the model's gears seal the tip chain, and its leak moves 31 % less than
/// concentric films' for the same alpha), RMSE ratio 0.258. With the
/// trapped cavity's work rise in the plant's torque (session 34): alpha
/// 1.166e-7, ratio 0.259, the torque leaves nothing. With the
/// candidate bounded at 1e-7, as before session 28, its fit stopped at the
/// bound and `pressure_clearance@bearings` was named instead (ratio 0.261).
#[test]
fn a_piezoviscous_oil_made_by_the_hand_calculation_is_named() {
    let d = diagnose_by_hand("hand-barus", 442904, |hand, r| {
        hand_reference::plant_barus(hand, r, 8.18e-8)
    });
    assert_eq!(
        d.cause,
        Some("pressure_viscosity"),
        "{}",
        d.json["candidates"]
    );
    let ratio = d.extended_rmse.unwrap() / d.baseline_rmse;
    assert!(ratio <= 0.5, "RMSE ratio {ratio:.3}");
    let alpha = cause_param(&d, "pressure_viscosity", "alpha_per_pa");
    // the hand's value, raised by the model's lower sensitivity, and inside
    // the candidate's bounds (not stopped at the upper one)
    let source = DesignSource::load(None, &[]).unwrap();
    let spec = gearpump::diagnosis::candidates::candidate_specs(&source.design)
        .into_iter()
        .find(|s| s.effect == "pressure_viscosity")
        .unwrap();
    let q = &spec.params[0];
    let upper = q.transform.to_edge(q.upper_u);
    assert!(
        alpha > 8.18e-8 && alpha < 0.95 * upper,
        "alpha {alpha:e} (bound {upper:e})"
    );
    assert_eq!(d.json["torque"]["flow_causes_check"]["worsened"], false);
}

/// The control of the torque's choice of site: every clearance (tips,
/// bearings, faces) opens with the delivery pressure, 0.2 um/bar, planted
/// by the model's own code. The tips alone fit the flow nearly as well
/// (held-out excess below the noise floor, so the torque is consulted);
/// the torque, moved by the bearings' and the faces' films as well as the
/// tips', must not move the cause off `all` (and if the flow alone picked
/// another site, must bring it back).
///
/// Measured: `pressure_clearance@all`, RMSE ratio 0.037; the tips' held-out
/// RMSE 0.00557 against 0.00402, an excess of 0.0038 against a noise floor
/// of 0.0040; the torque did not contradict `all`.
#[test]
fn a_pressure_opening_at_every_site_stays_at_every_site() {
    use gearpump::diagnosis::plant::Plant;
    let plant = Plant::Effects(vec![
        Effect::from_edge("pressure_clearance@all", &[0.2]).unwrap()
    ]);
    let d = diagnose_planted("all-sites", &plant, 31, None);
    println!("sites {}", d.json["sites"]);
    assert_eq!(
        d.cause,
        Some("pressure_clearance@all"),
        "{} {}",
        d.json["sites"],
        d.json["site_by_torque"]
    );
    let site = &d.json["site_by_torque"];
    assert!(
        site.is_null() || site["flow_pick"] != "pressure_clearance@all",
        "{site}"
    );
    // the tips were a contender: the flow preferred every site by less
    // than its noise floor, so the torque was consulted
    let cv = |e: &str| {
        d.json["sites"]
            .as_array()
            .and_then(|a| a.iter().find(|x| x["effect"] == e))
            .and_then(|x| x["cv_rmse"].as_f64())
            .unwrap()
    };
    let excess =
        (cv("pressure_clearance@tips").powi(2) - cv("pressure_clearance@all").powi(2)).sqrt();
    let floor = d.json["noise_floor"].as_f64().unwrap();
    assert!(
        excess < floor,
        "tips' excess {excess} against the floor {floor}"
    );
    assert_eq!(d.json["torque"]["flow_causes_check"]["worsened"], false);
}

/// Issue "Diagnosis on real data", point 2: two effects at once (a wider
/// lateral gap and free air in the oil) are both named, with the second's
/// parameter. (Bores opening with pressure plus free air, seed 29, is named
/// as `pressure_clearance@all` alone since the clearance sites exist: the
/// lateral share of the "all" site takes part of the air's level;
/// `eval-diagnosis --families two_effects` measures the rates; a pair that
/// mimics a single cause is the next test.)
#[test]
fn two_effects_at_once_are_both_named() {
    use gearpump::diagnosis::plant::Plant;
    let plant = Plant::Effects(vec![
        Effect::from_edge("lateral_clearance", &[24.0]).unwrap(),
        Effect::from_edge("entrained_air", &[0.04]).unwrap(),
    ]);
    let d = diagnose_planted("two", &plant, 29, None);
    for e in ["lateral_clearance", "entrained_air"] {
        assert!(d.causes.contains(&e), "{e} not among {:?}", d.causes);
    }
    let causes = d.json["causes"].as_array().unwrap();
    for c in causes {
        // each with its parameters, interval and gain
        assert!(
            c["params"].as_object().is_some_and(|m| !m.is_empty()),
            "{c}"
        );
        assert!(
            c["interval_95"].as_object().is_some_and(|m| !m.is_empty()),
            "{c}"
        );
        assert!(
            c["gain"]["rmse_after"].as_f64().unwrap() < c["gain"]["rmse_before"].as_f64().unwrap()
        );
    }
    let x0 = cause_param(&d, "entrained_air", "air_fraction");
    assert!((x0 - 0.04).abs() < 0.01, "air fraction {x0}");
}

/// Issue "Diagnosis on real data", point 4: one pump whose tip clearances
/// are a quarter larger than its record (the plant scales that pump's true
/// tips; its record keeps the measured ones: a mis-measured clearance)
/// beside a displacement error of +1.58 % in every pump (the draws of the
/// trial folder `out_of_family-5` of docs/diagnosis.md's evaluation e1).
/// The pump is named out of family, and the headline verdict is the
/// analysis with it set aside: with it in, its fold dominates the held-out
/// errors and no cause was named (the rule before this one gave cause null
/// here). The all-pump analysis is kept beside (`with_out_of_family`), and
/// the extended model is still run on the pump set aside.
#[test]
fn an_out_of_family_pump_does_not_bend_the_verdict() {
    use gearpump::diagnosis::plant::Plant;
    let plant = Plant::Effects(vec![
        Effect::from_edge("displacement_error", &[0.01582]).unwrap()
    ]);
    let d = diagnose_planted("ooff", &plant, 591232, Some((8, 1.25)));
    println!(
        "  with the pump: {}\n  gain {}",
        d.json["with_out_of_family"], d.json["gain"]
    );
    assert_eq!(
        d.cause,
        Some("displacement_error"),
        "all pumps: {}",
        d.json["with_out_of_family"]
    );
    assert_eq!(d.out_of_family, vec!["N09".to_string()]);
    assert!(!d.unexplained, "{}", d.json["remaining"]);
    let delta = d.json["causes"][0]["params"]["relative"].as_f64().unwrap();
    assert!(
        (delta - 0.01582).abs() < 0.003,
        "displacement error {delta}"
    );
    // the RMSE ratio of the headline is over the pumps analysed
    let ratio = d.json["gain"]["rmse_ratio"].as_f64().unwrap();
    assert!(ratio <= 0.5, "RMSE ratio {ratio}");
    let w = &d.json["with_out_of_family"];
    assert_eq!(w["pumps"].as_u64(), Some(20), "{w}");
    assert!(
        w.get("cause").is_some() && w["unexplained"].is_boolean(),
        "{w}"
    );
    // every pump's figures under the extended model, the one set aside too:
    // its tips leak more than its record says, so the extension (the same
    // for every pump) leaves it far below the others
    let pumps = d.json["extended"]["pumps"].as_array().unwrap();
    assert_eq!(pumps.len(), 20);
    let n09 = pumps.iter().find(|p| p["sample"] == "N09").unwrap();
    assert_eq!(n09["set_aside"], true, "{n09}");
    assert!(pumps
        .iter()
        .filter(|p| p["sample"] != "N09")
        .all(|p| p["set_aside"] == false
            && p["mean_residual"].as_f64().unwrap().abs()
                < n09["mean_residual"].as_f64().unwrap().abs() / 3.0));
    assert_eq!(
        d.json["extended"]["effects"],
        serde_json::json!(["displacement_error"])
    );
}

/// Issue "Diagnosis on real data", points 2 and 9: two effects whose
/// signatures partly cancel (a thinner oil lowers eta_v most where leakage
/// is largest, a larger displacement raises it everywhere). The first
/// step's pick (a thermal opening mimicking their sum) must not stay the
/// first cause once refitted beside the two: the first cause is pruned like
/// the others. (A campaign drawn for this test, not one of
/// `eval-diagnosis`'s.)
#[test]
fn two_effects_that_partly_cancel_are_both_named() {
    use gearpump::diagnosis::plant::Plant;
    let plant = Plant::Effects(vec![
        Effect::from_edge("viscosity_shift", &[0.7, 0.75]).unwrap(),
        Effect::from_edge("displacement_error", &[0.022]).unwrap(),
    ]);
    let d = diagnose_planted("cancel", &plant, 4242, None);
    assert_eq!(
        cause_kinds(&d),
        ["displacement_error", "viscosity_shift"],
        "{}",
        d.json["causes"]
    );
    let delta = cause_param(&d, "displacement_error", "relative");
    assert!((delta - 0.022).abs() < 0.004, "displacement error {delta}");
    assert!(!d.unexplained, "{}", d.json["remaining"]);
    assert!(d.extended_rmse.unwrap() / d.baseline_rmse <= 0.5);
}

/// Issue "Diagnosis on real data", points 2 and 9: a pair that, at the
/// Table 2 conditions, looks like one cause. A thermal opening of the
/// clearances with a smaller displacement resembles a wider lateral gap: at
/// the first step the lateral gap (and a thinner oil) beat the thermal
/// opening on held-out error, and no second candidate on top of the lateral
/// gap carried a material share, so forward selection alone named
/// `lateral_clearance` by itself (RMSE ratio 0.18). The pair check now
/// also runs when one cause leaves resolvable structure: the pair screened
/// on the first step's linearisations is fitted on the model and replaces
/// the single cause only when its held-out error is significantly lower
/// and each of its two causes carries a material share. The campaign is
/// trial `two_effects-8` of `gearpump eval-diagnosis --trials 10 --seed
/// 2028 --families two_effects` (its draws: k_T 0.06138 um/K,
/// displacement -0.02259, synth seed 442260).
#[test]
fn a_pair_that_looks_like_one_cause_is_named_as_the_pair() {
    use gearpump::diagnosis::plant::Plant;
    let (k_t, delta) = (0.06138, -0.02259);
    let plant = Plant::Effects(vec![
        Effect::from_edge("thermal_clearance", &[k_t]).unwrap(),
        Effect::from_edge("displacement_error", &[delta]).unwrap(),
    ]);
    let d = diagnose_planted("lookalike", &plant, 442260, None);
    assert_eq!(
        cause_kinds(&d),
        ["displacement_error", "thermal_clearance"],
        "{}",
        d.json["causes"]
    );
    // each planted value inside its cause's 95 % interval
    for (effect, param, planted) in [
        ("thermal_clearance", "k_t_um_per_k", k_t),
        ("displacement_error", "relative", delta),
    ] {
        let c = d.json["causes"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["effect"].as_str().unwrap_or("").starts_with(effect))
            .unwrap();
        let iv = &c["interval_95"][param];
        let (lo, hi) = (iv[0].as_f64().unwrap(), iv[1].as_f64().unwrap());
        assert!(
            lo <= planted && planted <= hi,
            "{effect}: {planted} outside {lo} to {hi}"
        );
    }
    assert!(!d.unexplained, "{}", d.json["remaining"]);
    assert!(d.extended_rmse.unwrap() / d.baseline_rmse <= 0.2);
}

/// Issue "Diagnosis on real data", point 9, against a reference the
/// diagnosis never sees: with three times the flowmeter's noise (1.5 %)
/// and a small effect (noise_x3-6 of `eval-diagnosis --trials 10 --seed
/// 2028`: the viscosity's pressure coefficient), the extended model's RMSE
/// ratio on the data can only be as low as the noise-free truth's own on
/// the same data (the flowmeter's scatter, which no model of the pump
/// removes). The cause must be named, its ratio must sit at that floor,
/// and against the noise-free truth (the campaign's own flowmeter draws
/// taken out) the extension must remove most of the model's error.
#[test]
fn with_three_times_the_meter_noise_the_ratio_sits_at_the_truths_own_floor() {
    use gearpump::campaign::synth::Noise;
    use gearpump::diagnosis::eval::{truth_rmse_ratio, Ratios};
    use gearpump::diagnosis::plant::{planted_csv, planted_flow_factors, Plant, PlantOptions};
    let alpha = 5.845e-8;
    let (lo, hi) = detectable_range("pressure_viscosity").unwrap().0[0];
    assert!(lo <= alpha && alpha <= hi, "{alpha} outside {lo} to {hi}");
    let plant = Plant::Effects(vec![
        Effect::from_edge("pressure_viscosity", &[alpha]).unwrap()
    ]);
    let source = DesignSource::load(None, &[]).unwrap();
    let opts = PlantOptions {
        samples: 20,
        seed: 37163,
        noise: Noise {
            flow_rel: 3.0 * Noise::RIG.flow_rel,
            torque_rel: 3.0 * Noise::RIG.torque_rel,
        },
        micromotion: true,
        jobs: None,
        out_of_family: None,
    };
    let csv = planted_csv(&source, &plant, &opts).unwrap();
    let (d, dir) = diagnose_csv("noise-x3", &csv);
    assert_eq!(
        cause_kinds(&d),
        ["pressure_viscosity"],
        "{}",
        d.json["causes"]
    );
    let Ratios { data, truth, floor } =
        truth_rmse_ratio(&dir.join("out"), &planted_flow_factors(&source, &opts)).unwrap();
    println!("RMSE ratio on the data {data:.4}, the truth's own {floor:.4}, against the truth {truth:.4}");
    assert!(
        (data - d.extended_rmse.unwrap() / d.baseline_rmse).abs() < 1e-9,
        "{data}"
    );
    assert!(data <= floor + 0.02, "{data} against the floor {floor}");
    assert!(truth <= 0.25, "{truth}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Two mechanisms with the same eta_v signature, told apart by the torque
/// the rig measured beside the flow: a viscosity rising with pressure
/// (trial `pressure_viscosity-6` of `gearpump eval-diagnosis --trials 10
/// --seed 20261128`: alpha 8.88e-8 1/Pa, synth seed 966489) and bearing
/// bores opening with pressure fit the flow alike (the flow's pick was the
/// bores, the Barus law indistinguishable from it at p 0.35). The Barus
/// law also shears the tip and lateral films harder, so its model's torque
/// is the measurement's and the bores' is not: the torque names the
/// effect, the flow's pick is listed as indistinguishable on eta_v, and
/// the torque verdict finds nothing left (before the torque chose, it
/// named the mesh friction for what the wrong flow cause left).
#[test]
fn the_torque_tells_apart_what_the_flow_cannot() {
    let effect = Effect::from_edge("pressure_viscosity", &[8.88e-8]).unwrap();
    let d = diagnose_hidden("torque-tie", Some(effect), 966489);
    assert_eq!(
        cause_kinds(&d),
        ["pressure_viscosity"],
        "{}",
        d.json["causes"]
    );
    let by_torque = &d.json["chosen_by_torque"];
    assert_eq!(
        by_torque["flow_pick"]
            .as_str()
            .map(|c| c.split('@').next().unwrap_or(c)),
        Some("pressure_clearance"),
        "{by_torque}"
    );
    assert!(
        by_torque["p_torque_better"].as_f64().unwrap() < 1e-3,
        "{by_torque}"
    );
    assert!(d
        .ambiguous_with
        .iter()
        .any(|c| c.starts_with("pressure_clearance")));
    assert!(d.json["torque"]["cause"].is_null(), "{}", d.json["torque"]);
}

/// A campaign of the seed's population (synth seed `seed`, the rig's
/// noise, no effect planted by the model) whose flows and torques are then
/// moved by what the hand calculation gives for the gaps each pump really
/// had, `(tip, lateral)` in um from `actual(record)`, against what it was
/// measured or designed with: the effect made by another mechanism than the
/// candidates' code (concentric gears, incompressible pockets, the chain's
/// steady solution), as nature would make it, and diagnosed blind.
fn diagnose_hand_planted(
    name: &str,
    seed: u64,
    actual: impl Fn(&CampaignRecord) -> (f64, f64),
) -> Diagnosis {
    diagnose_by_hand(name, seed, |hand, r| {
        let (tip, lateral) = actual(r);
        hand_reference::plant_gaps(hand, r, tip, lateral);
    })
}

/// The diagnosis of a synthetic campaign (no effect planted by the model)
/// whose records `plant` then moves by the hand calculation.
fn diagnose_by_hand(
    name: &str,
    seed: u64,
    plant: impl Fn(&hand_reference::Hand, &mut CampaignRecord),
) -> Diagnosis {
    let hand = hand_reference::Hand::seed();
    let csv = synthetic(None, seed, |r| plant(&hand, r));
    let (d, dir) = diagnose_csv(name, &csv);
    println!(
        "{name}: causes {}, sites {}, site by torque {}, unexplained {}, RMSE {:.5} -> {:?}, torque {}\n  remaining {}",
        d.json["causes"],
        d.json["sites"],
        d.json["site_by_torque"],
        d.unexplained,
        d.baseline_rmse,
        d.extended_rmse,
        d.json["torque"],
        d.json["remaining"],
    );
    let _ = std::fs::remove_dir_all(&dir);
    d
}

/// The tip clearances open with temperature (0.05 um/K above the
/// clearances' measurement temperature, inside the candidate's detectable
/// range), the flow and torque moved by the hand calculation's tip chain,
/// not by the model: the diagnosis must name the thermal opening, on the tips, and
/// remove at least half of the model's error.
///
/// Measured: `thermal_clearance@tips`, RMSE of d 0.0697 -> 0.0053 (ratio
/// 0.076), k_T fitted 0.0605 um/K (95 % interval 0.0599-0.0612) against the
/// hand's 0.05: the model's gears, pressed towards the suction side, leak
/// less for the same opening than the hand's concentric ones, and an
/// interval conditional on the model's form does not hold nature's value
/// when the forms differ (docs/diagnosis.md).
#[test]
fn a_thermal_tip_opening_made_by_the_hand_calculation_is_named() {
    let k = 0.05;
    let (lo, hi) = detectable_range("thermal_clearance").unwrap().0[0];
    assert!(lo <= k && k <= hi);
    let lateral = hand_reference::Hand::seed().lateral * 1e6;
    let d = diagnose_hand_planted("hand-thermal", 4242, |r| {
        let tip = 0.5 * (r.tip_clearance_drive_um + r.tip_clearance_driven_um);
        (tip + k * (r.temp_c - T_MEASURE_C), lateral)
    });
    assert_eq!(
        d.cause,
        Some("thermal_clearance@tips"),
        "{} {}",
        d.json["candidates"],
        d.json["sites"]
    );
    assert!(!d.unexplained, "{}", d.json["remaining"]);
    let ratio = d.extended_rmse.unwrap() / d.baseline_rmse;
    assert!(ratio <= 0.5, "RMSE ratio {ratio:.3}");
    let check = &d.json["torque"]["flow_causes_check"];
    assert_eq!(check["worsened"], false, "{check}");
}

/// The lateral gaps at 24 um instead of the design's 15 (inside the
/// candidate's detectable range), the flow and torque moved by the hand
/// calculation's lateral gaps and face shear: the diagnosis must name the
/// lateral clearance and remove at least half of the model's error.
///
/// Measured: `lateral_clearance`, RMSE of d 0.0551 -> 0.0046 (ratio 0.084),
/// h_lat fitted 22.67 um (95 % interval 22.62-22.73) against the hand's 24:
/// at 1000 rpm / 30 bar / 60 degC, concentric, hand and model lose the same
/// to the lateral gaps at 15 and at 24 um (0.633 / 0.639 % and 2.537 /
/// 2.539 % of `Vm n`), but the campaign's gears move: pressed towards the
/// suction side, they seal the chain there, the pockets sit nearer the
/// delivery pressure and the model's lateral loss is 0.80 / 3.12 %, a 22 %
/// larger change for the same opening. The torque verdict is
/// "unexplained" (structure 0.0168 N m against a floor of 0.0147): the
/// hand moves only the face shear, while the model's torque also follows
/// the pockets' pressures that the wider gaps lower (docs/diagnosis.md).
#[test]
fn a_wider_lateral_gap_made_by_the_hand_calculation_is_named() {
    let lateral = 24.0;
    let (lo, hi) = detectable_range("lateral_clearance").unwrap().0[0];
    assert!(lo <= lateral && lateral <= hi);
    let d = diagnose_hand_planted("hand-lateral", 5151, |r| {
        (
            0.5 * (r.tip_clearance_drive_um + r.tip_clearance_driven_um),
            lateral,
        )
    });
    assert_eq!(
        d.cause.map(|c| c.split('@').next().unwrap_or(c)),
        Some("lateral_clearance"),
        "{}",
        d.json["candidates"]
    );
    assert!(!d.unexplained, "{}", d.json["remaining"]);
    let ratio = d.extended_rmse.unwrap() / d.baseline_rmse;
    assert!(ratio <= 0.5, "RMSE ratio {ratio:.3}");
    let check = &d.json["torque"]["flow_causes_check"];
    assert_eq!(check["worsened"], false, "{check}");
}

/// A flowmeter reading 4 % low, an instrument's error: nature made it
/// without any of the model's code, and it moves the flow alone. No
/// candidate is a flowmeter, and on the flow a smaller displacement is the
/// same signature, so `displacement_error` is named (the flow cannot tell
/// them apart; a relative -4 %). But the design key of a displacement
/// error is the real face width, which lowers the hydraulic torque by as
/// much, and the measured torque did not fall: the diagnosis must say that
/// the torque contradicts the flow's cause (`flow_causes_check.worsened`),
/// the model it extends fitting the torque materially worse than the base
/// model, and diagnose the torque on the base model, where nothing is left
/// to explain (on the extended model a thrust-plate friction 65 % higher
/// was fitted to undo the face width's torque).
///
/// The report then gives the instrument's alternative, a flowmeter gain
/// fitted to the base model's eta_v without a model run. Since session 30
/// such a verdict is unexplained (`unexplained_by_torque`): no candidate
/// explains the flow and the torque together.
///
/// Ten pumps (`synthetic_of`): the reconsideration without the
/// displacement error takes entrained air and a thinner oil on trial in
/// every slot, which took 8.6 minutes at the seed's 20 pumps on a loaded
/// machine, 5.5 at 10, with the same verdict.
///
/// Measured at 10 pumps: `displacement_error` relative -0.0415 (95 %
/// interval -0.0421 .. -0.0409); the torque's RMSE 0.0146 N m with the
/// base model against 0.257 N m with the extended one; no torque cause;
/// the flowmeter's gain -0.0404, held-out RMSE 0.00458 against the cause's
/// 0.00465 (at 20: -0.0416, 0.0152 against 0.258 N m, gain -0.0406,
/// 0.00442 against 0.00452).
#[test]
fn a_flowmeter_reading_low_is_not_borne_out_by_the_torque() {
    let csv = synthetic_of(10, None, 8080, |r| r.flow_lpm *= 0.96);
    let (d, dir) = diagnose_csv("flowmeter-low", &csv);
    let check = &d.json["torque"]["flow_causes_check"];
    println!(
        "flowmeter 4 % low: causes {}, torque {}, check {check}, reconsidered {}",
        d.json["causes"], d.json["torque"]["cause"], d.json["reconsidered_by_torque"]
    );
    let _ = std::fs::remove_dir_all(&dir);
    // the torque sent the flow back without the displacement error, and no
    // alternative both fits the flow within its noise floor and leaves the
    // torque as measured: the verdict stays, flagged, and no candidate
    // explains both measurements: not explained
    assert!(d.unexplained, "{}", d.json["structure"]);
    assert_eq!(d.json["unexplained_by_torque"], true);
    let tried = d.json["reconsidered_by_torque"]["tried"]
        .as_array()
        .unwrap();
    assert_eq!(tried.len(), 1, "{tried:?}");
    assert_eq!(tried[0]["excluded"], "displacement_error");
    assert_eq!(tried[0]["adopted"], false);
    assert_eq!(
        d.cause,
        Some("displacement_error"),
        "{}",
        d.json["candidates"]
    );
    let relative = cause_param(&d, "displacement_error", "relative");
    assert!((relative + 0.04).abs() < 0.005, "relative {relative}");
    assert_eq!(check["worsened"], true, "{check}");
    let (base, ext) = (
        check["base_rmse_nm"].as_f64().unwrap(),
        check["extended_rmse_nm"].as_f64().unwrap(),
    );
    assert!(ext > 5.0 * base, "torque RMSE {base} -> {ext} N m");
    assert!(
        d.json["torque"]["cause"].is_null(),
        "{}",
        d.json["torque"]["cause"]
    );
    // the instrument's alternative, fitted without a model run: the gain
    // planted, and a held-out error no worse than the named cause's
    let alt = &check["flowmeter_alternative"];
    let (gain, cv, cause_cv) = (
        alt["gain"].as_f64().unwrap(),
        alt["cv_rmse"].as_f64().unwrap(),
        alt["cause_cv_rmse"].as_f64().unwrap(),
    );
    assert!((gain + 0.04).abs() < 0.002, "flowmeter gain {gain}");
    assert!(
        cv <= 1.02 * cause_cv,
        "held-out RMSE {cv} against the cause's {cause_cv}"
    );
    assert!(
        d.json["torque"]["model"]
            .as_str()
            .is_some_and(|m| m.starts_with("the base model")),
        "{}",
        d.json["torque"]["model"]
    );
}

/// The tips of both gears opened with the delivery pressure, 0.2218 um/bar,
/// by the hand calculation (the campaign of `hand_planted_eval`'s trial
/// pressure_clearance-4, seed 20261128). The flow names the mechanism but
/// prefers the site `all` (it also opens the bearings and the faces, which
/// the hand left shut), by a held-out margin below its own noise floor. The
/// measured torque, which the hand moved through the tips' shear alone,
/// contradicts that site: the diagnosis must name the tips by the torque
/// (`site_by_torque`), and the torque must then bear the cause out, with no
/// loss coefficient named for the torque the opening moved.
///
/// Measured: `pressure_clearance@tips`, k_p 0.263 um/bar (the hand's
/// 0.2218; the model's gears seal the chain, as for the thermal opening),
/// RMSE ratio 0.053; the flow preferred `@all` by 0.0025 against a noise
/// floor of 0.0048, and its model leaves a torque structure of 0.0294 N m
/// against the tips' 0.0035 (material from 0.0135). Before the torque chose
/// the site, `@all` was named (ratio 0.048) and the torque check flagged it.
#[test]
fn the_torque_chooses_the_tips_the_hand_opened_with_pressure() {
    let k = 0.2218;
    let lateral = hand_reference::Hand::seed().lateral * 1e6;
    let d = diagnose_hand_planted("hand-pressure", 17396, |r| {
        let tip = 0.5 * (r.tip_clearance_drive_um + r.tip_clearance_driven_um);
        (tip + k * r.pressure_bar, lateral)
    });
    assert_eq!(
        d.cause,
        Some("pressure_clearance@tips"),
        "{} {}",
        d.json["sites"],
        d.json["site_by_torque"]
    );
    let ratio = d.extended_rmse.unwrap() / d.baseline_rmse;
    assert!(ratio <= 0.5, "RMSE ratio {ratio:.3}");
    let site = &d.json["site_by_torque"];
    assert_eq!(site["flow_pick"], "pressure_clearance@all", "{site}");
    let excess = site["flow_excess"].as_f64().unwrap();
    let floor = site["flow_noise_floor"].as_f64().unwrap();
    assert!(excess < floor, "{site}");
    let check = &d.json["torque"]["flow_causes_check"];
    assert_eq!(check["worsened"], false, "{check}");
    assert!(
        d.json["torque"]["cause"].is_null(),
        "a torque cause {} for a tip opening",
        d.json["torque"]["cause"]
    );
}

/// The diagnosis of a campaign whose tips the hand opened with temperature
/// (`k_t` um/K) and whose lateral gaps it widened to `lateral` um at once.
fn diagnose_two_gaps(name: &str, seed: u64, k_t: f64, lateral: f64) -> Diagnosis {
    diagnose_hand_planted(name, seed, |r| {
        let tip = 0.5 * (r.tip_clearance_drive_um + r.tip_clearance_driven_um);
        (tip + k_t * (r.temp_c - T_MEASURE_C), lateral)
    })
}

/// Two effects made by the hand calculation at once: the tips opening with
/// temperature (0.0495 um/K) and the lateral gaps at 25.55 um instead of
/// 15 (`hand_planted_eval`'s trial two_gaps-3, seed 20261129, rounded).
/// A thinner oil at both temperatures (two free factors) stands in for
/// their sum on the flow, and leaves a residual whose level structure S
/// sits at the noise floor while its pump-by-condition interaction does not
/// (each pump's clearances weigh tips and faces differently): the search
/// for a second cause must ask what is left beyond the floor, not S alone.
///
/// Before (S alone): `viscosity_shift` (0.52, 0.44) named alone, its
/// residual's S 0.00741 against a floor of 0.00745, its own floor 0.0094;
/// a mesh friction +49 % named for the torque its shear lost. After:
/// `lateral_clearance` 24.69 um and `thermal_clearance@tips` 0.0569 um/K,
/// RMSE ratio 0.038, the check quiet.
#[test]
fn two_gap_openings_made_by_the_hand_are_not_taken_for_a_thinner_oil() {
    let d = diagnose_two_gaps("hand-two-gaps", 888946, 0.0495, 25.55);
    assert_eq!(
        cause_kinds(&d),
        ["lateral_clearance", "thermal_clearance"],
        "{}",
        d.json["causes"]
    );
    let ratio = d.json["gain"]["rmse_ratio"].as_f64().unwrap();
    assert!(ratio <= 0.5, "RMSE ratio {ratio:.3}");
    let check = &d.json["torque"]["flow_causes_check"];
    assert_eq!(check["worsened"], false, "{check}");
}

/// The same two hand-made openings on another campaign (0.0566 um/K and
/// 24.52 um; trial two_gaps-1, rounded), where forward selection ends on a
/// wider lateral gap and a thinner oil: the flow fits them as well as the
/// truth, but the oil's shear, the bearings' too, takes torque the hand's
/// gaps do not, and the measured torque contradicts them. The flow is
/// analysed again without each contradicted mechanism in turn; the first
/// alternative that fits the flow within its noise floor and that the
/// torque does not contradict is the verdict (`reconsidered_by_torque`).
///
/// Before: `lateral_clearance` + `viscosity_shift` (0.84, 0.66), torque
/// structure 0.0436 N m against the base model's 0.0175, flagged. After:
/// `thermal_clearance@tips` 0.0651 um/K and `lateral_clearance` 23.83 um,
/// 0.0014 of eta_v beyond the contradicted causes against a floor of
/// 0.0048, torque structure 0.0225 N m (not contradicted), RMSE ratio
/// 0.035.
#[test]
fn the_torque_turns_a_thinner_oil_back_into_the_hands_two_gaps() {
    let d = diagnose_two_gaps("hand-two-gaps-torque", 696075, 0.0566, 24.52);
    let r = &d.json["reconsidered_by_torque"];
    println!("reconsidered by the torque: {r}");
    assert!(
        r["flow_causes"]
            .as_array()
            .is_some_and(|c| c.iter().any(|c| c == "viscosity_shift")),
        "{r}"
    );
    let tried = r["tried"].as_array().unwrap();
    let adopted = tried.iter().find(|t| t["adopted"] == true).unwrap();
    assert_eq!(adopted["excluded"], "viscosity_shift", "{r}");
    // the alternative fits the flow within its noise floor of the causes'
    assert!(
        adopted["flow_excess"].as_f64().unwrap() < adopted["flow_noise_floor"].as_f64().unwrap(),
        "{adopted}"
    );
    assert_eq!(
        cause_kinds(&d),
        ["lateral_clearance", "thermal_clearance"],
        "{}",
        d.json["causes"]
    );
    let check = &d.json["torque"]["flow_causes_check"];
    assert_eq!(check["worsened"], false, "{check}");
    let ratio = d.json["gain"]["rmse_ratio"].as_f64().unwrap();
    assert!(ratio <= 0.5, "RMSE ratio {ratio:.3}");
}

/// A flowmeter that lets a slip past its rotors uncounted, made by a
/// closed form of the meter (`hand_reference::meter_slip_lpm`: the same
/// l/min at every speed and delivery pressure of one temperature, growing
/// as the oil thins), not by any model code and outside every candidate:
/// the pump's own leaks grow with the delivery pressure, free air and a
/// displacement error with the flow. 0.1669 l/min at 120 degC
/// (`hand_planted_eval`'s trial meter_slip-2, seed 20261130), a quarter of
/// it at 60 degC: one or two tests' scatter of eta_v at most conditions.
///
/// A wider lateral gap stands in for it and halves the error, which made
/// it the cause, and what it leaves is smaller than one test's scatter:
/// before the share rule the verdict was `lateral_clearance` (16.65 um),
/// explained. The gap leaves 0.36 of the discrepancy's structure, where a
/// mechanism of the right kind leaves a tenth at most, and what it leaves
/// follows the delivery pressure: the meter's slip does not grow with it,
/// the gap's leak does. Since the torque check also counts what is
/// resolvable, the torque contradicts the gap (its thinner face shear),
/// and without it the flow names the bearings closing with temperature,
/// which leaves 0.39. Either way it is not explained, by its share.
#[test]
fn a_flowmeter_slip_is_not_explained_by_a_gap_that_halves_it() {
    let d = diagnose_by_hand("hand-meter-slip", 793466, |hand, r| {
        r.flow_lpm -= hand_reference::meter_slip_lpm(hand, r.temp_c, 0.1669);
    });
    let st = &d.json["structure"];
    assert!(d.unexplained, "{st}");
    let (left, threshold) = (
        st["final"]["structure"].as_f64().unwrap(),
        st["threshold"].as_f64().unwrap(),
    );
    // the size rule alone would call it explained
    assert!(left < threshold, "{st}");
    assert!(st["share_left"].as_f64().unwrap() >= 0.25, "{st}");
    assert!(st["final"]["p"].as_f64().unwrap() < 1e-3, "{st}");
    let features: Vec<&str> = d.json["unexplained_features"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|f| f.as_str())
        .collect();
    assert!(features.contains(&"pressure_bar"), "{features:?}");
}

/// A relief valve whose seat seeps, made by a closed form of an orifice
/// (`hand_reference::valve_seep_lpm`: inertial, the square root of the
/// delivery pressure, no viscosity in it), not by any model code and
/// outside every candidate. 0.1065 l/min at 30 bar (`hand_planted_eval`'s
/// trial valve_seep-7, seed 20261130).
///
/// On eta_v a thinner oil at both temperatures nearly has its form, and
/// leaves too small a share of the structure to be resolved (0.17, p
/// 0.03): the flow alone names `viscosity_shift`, explained. The torque
/// tells them apart: the thinner oil lowers every film's shear, the valve
/// moves no torque. Its model leaves 0.0138 N m of torque structure where
/// the base model leaves none, below the size threshold (0.0152) but
/// resolvable, so the torque contradicts it; without the oil the flow
/// names nothing, and the verdict is unexplained by the torque. Before
/// the resolvable check and the rule for a contradicted verdict: the
/// thinner oil, explained.
#[test]
fn a_seeping_relief_valve_is_not_taken_for_a_thinner_oil() {
    let d = diagnose_by_hand("hand-valve-seep", 641691, |hand, r| {
        r.flow_lpm -= hand_reference::valve_seep_lpm(hand, r.pressure_bar, r.temp_c, 0.1065);
    });
    let check = &d.json["torque"]["flow_causes_check"];
    assert!(d.unexplained, "{}", d.json["structure"]);
    assert_eq!(d.json["unexplained_by_torque"], true, "{check}");
    // the size rule alone would not contradict it: the resolvable way did
    assert_eq!(check["worsened"], true, "{check}");
    assert_eq!(check["by_size"], false, "{check}");
    assert!(check["extended_p"].as_f64().unwrap() < 1e-3, "{check}");
    // nor would the share rule alone call the flow unexplained
    let st = &d.json["structure"];
    assert!(
        st["share_left"].as_f64().unwrap() < 0.25 || st["final"]["p"].as_f64().unwrap() >= 1e-3,
        "{st}"
    );
}
