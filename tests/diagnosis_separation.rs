//! The measurement that tells two indistinguishable candidates apart
//! (`ambiguous_with` in diagnosis.json), for two oils that agree at 120 degC
//! and differ elsewhere: the proposed condition separates them at least as
//! well as every measured condition, the pump still delivers there, a new
//! temperature is named as such, and the efficiencies reported are those of
//! the two models run at that condition.

use gearpump::campaign::effects::{Effect, EffectModel};
use gearpump::campaign::parse_campaign_str;
use gearpump::campaign::run::simulate_test;
use gearpump::campaign::stats::eta_v;
use gearpump::campaign::synth::paper_conditions;
use gearpump::design::Design;
use gearpump::diagnosis::diagnose::{separating_measurement, MIN_SEPARATION_ETA};
use gearpump::model::Pump;
use std::sync::Arc;

#[test]
fn two_oils_that_agree_when_hot_are_separated_where_they_differ_most() {
    let pump = Arc::new(Pump::new(Design::seed()));
    let mut csv = String::from(
        "sample,tip_clearance_drive_um,tip_clearance_driven_um,bearing_clearance_drive_um,\
         bearing_clearance_driven_um,pressure_bar,speed_rpm,temp_c,flow_lpm,torque_nm\n",
    );
    for c in paper_conditions() {
        csv.push_str(&format!(
            "N01,30.8,31.1,13.2,14.0,{},{},{},10,\n",
            c.pressure_bar, c.speed_rpm, c.temp_c
        ));
    }
    let campaign = parse_campaign_str("one-pump.csv", &csv).unwrap();
    let rows: Vec<_> = campaign.rows.iter().collect();
    // factors on the datasheet viscosity at 60 and 120 degC: equal when hot
    let a = Effect::ViscosityShift {
        factors: (0.7, 0.7),
    };
    let b = Effect::ViscosityShift {
        factors: (1.0, 0.7),
    };
    let sep = separating_measurement(&pump, a, b, &rows, pump.displacement, false, &pump.design)
        .expect("a separating condition");
    println!("{}", sep.text);
    let c = sep.condition;
    assert!((sep.eta.0 - sep.eta.1).abs() > 0.005, "{:?}", sep.eta);
    assert!(
        sep.eta.0.min(sep.eta.1) >= MIN_SEPARATION_ETA,
        "{:?}",
        sep.eta
    );
    // at least as discriminating as every measured condition where the pump
    // still delivers
    let model_a = EffectModel::on(&pump, &[a]).unwrap();
    let model_b = EffectModel::on(&pump, &[b]).unwrap();
    for row in &rows {
        let ea = simulate_test(&model_a, row, None, false).unwrap().flow;
        let eb = simulate_test(&model_b, row, None, false).unwrap().flow;
        let (ea, eb) = (
            eta_v(ea, pump.displacement, row.speed),
            eta_v(eb, pump.displacement, row.speed),
        );
        if ea.min(eb) >= MIN_SEPARATION_ETA {
            assert!(
                (sep.eta.0 - sep.eta.1).abs() >= (ea - eb).abs() - 1e-12,
                "{:?} separates less than the measured {:?}",
                c,
                row.condition
            );
        }
    }
    // the new temperature is named as such
    if ![60.0, 120.0].contains(&c.temp_c) {
        assert!(
            sep.text.starts_with("a third oil temperature"),
            "{}",
            sep.text
        );
    }
    // the reported efficiencies are the models' at that condition
    let text = format!(
        "sample,tip_clearance_drive_um,tip_clearance_driven_um,bearing_clearance_drive_um,\
         bearing_clearance_driven_um,pressure_bar,speed_rpm,temp_c,flow_lpm,torque_nm\n\
         N01,30.8,31.1,13.2,14.0,{},{},{},10,\n",
        c.pressure_bar, c.speed_rpm, c.temp_c
    );
    let one = parse_campaign_str("at.csv", &text).unwrap();
    let row = &one.rows[0];
    for (effect, reported) in [(a, sep.eta.0), (b, sep.eta.1)] {
        let model = EffectModel::on(&pump, &[effect]).unwrap();
        let s = simulate_test(&model, row, None, false).unwrap();
        let e = eta_v(s.flow, pump.displacement, row.speed);
        assert!((e - reported).abs() < 1e-9, "{effect}: {e} vs {reported}");
    }
}
