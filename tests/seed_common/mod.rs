//! What the physics tests share: operating inputs in the rig's units and
//! the seed paper's 14 working conditions.
#![allow(dead_code)] // each test file uses a part

use gearpump::design::{from_toml_str, SEED_PUMP_TOML};
use gearpump::model::{Inputs, Pump, SampleClearances};
use std::sync::Arc;

/// Inputs at `rpm`, `bar` gauge above atmospheric suction, `temp_c`, no
/// measured torque.
pub fn inputs(rpm: f64, bar: f64, temp_c: f64) -> Inputs {
    Inputs::rig(rpm, bar, temp_c)
}

/// The 14 working conditions of the seed's Table 2 as (rpm, bar, degC):
/// 1000 rpm at 10-40 bar and 30 bar at 500/2000/4000 rpm, at 60 and 120 degC.
pub fn table2() -> Vec<(f64, f64, f64)> {
    let mut v = Vec::new();
    for t in [60.0, 120.0] {
        for bar in [10.0, 20.0, 30.0, 40.0] {
            v.push((1000.0, bar, t));
        }
        for rpm in [500.0, 2000.0, 4000.0] {
            v.push((rpm, 30.0, t));
        }
    }
    v
}

/// The bundled seed pump with design overrides (`key.path=value`).
pub fn pump(sets: &[&str]) -> Arc<Pump> {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    Arc::new(Pump::new(
        from_toml_str(SEED_PUMP_TOML, &sets).expect("valid design"),
    ))
}

/// Tip and lateral gaps closed, the journal bearings at 1 nm: their leakage
/// scales with c^3, so it is nil (a zero bearing clearance is refused). For
/// the kinematic references.
pub fn zero_clearances() -> SampleClearances {
    SampleClearances {
        tip: [0.0; 2],
        bearing: [1e-9; 2],
        lateral: 0.0,
    }
}
