//! One operating point's result as the JSON object of `gearpump simulate
//! --json` (docs/interfaces.md section 3): written once here for the
//! command line and the Python package, so the two cannot drift apart.

use gearpump_core::losses::LossBudget;
use gearpump_core::model::{Pump, SampleClearances, Simulation, Summary};
use gearpump_core::units::{m3_s_to_lpm, m3_to_cm3, m_to_um};
use serde_json::{json, Value};

/// The operating point as the user gave it (display units).
#[derive(Debug, Clone, Copy)]
pub struct PointSpec {
    pub speed_rpm: f64,
    pub pressure_bar: f64,
    pub temp_c: f64,
    pub inlet_pressure_bar_abs: f64,
    pub micromotion: bool,
}

/// Where the time went, ms, and where the section tables came from.
#[derive(Debug, Clone)]
pub struct PointTimes {
    pub wall_ms: f64,
    pub setup_ms: f64,
    pub solve_ms: f64,
    pub tables: String,
}

/// The loss budget as JSON: its parts by name (shares of Vm n).
pub fn losses_json(b: &LossBudget) -> Value {
    let mut m = serde_json::Map::new();
    for (name, v) in b.parts() {
        m.insert(name.into(), json!(v));
    }
    Value::Object(m)
}

/// The `simulate --json` object of a finished run: `sim` after
/// `run_periodic` gave `summary`; `sample` is the measured sample (the
/// eccentricity ratio divides by its bearing clearances).
pub fn point_json(
    pump: &Pump,
    sim: &Simulation,
    summary: &Summary,
    sample: &SampleClearances,
    point: &PointSpec,
    warnings: &[String],
    times: &PointTimes,
) -> Value {
    let e = summary.eccentricity;
    json!({
        "speed_rpm": point.speed_rpm,
        "pressure_bar": point.pressure_bar,
        "temp_c": point.temp_c,
        "inlet_pressure_bar_abs": point.inlet_pressure_bar_abs,
        "displacement_cm3": m3_to_cm3(pump.displacement),
        "flow_lpm": m3_s_to_lpm(summary.flow),
        "eta_v": summary.eta_v,
        "torque_nm": summary.torque,
        "eta_hm": summary.eta_hm,
        "flow_ripple_lpm": m3_s_to_lpm(summary.flow_ripple),
        "losses": summary.losses.as_ref().map(losses_json),
        "losses_closure": summary.losses.as_ref().map(|b| b.closure),
        "warnings": warnings,
        "eccentricity": {
            "drive": [m_to_um(e[0][0]), m_to_um(e[0][1])],
            "driven": [m_to_um(e[1][0]), m_to_um(e[1][1])],
        },
        "eccentricity_ratio": {
            "drive": e[0][0].hypot(e[0][1]) / sample.bearing[0],
            "driven": e[1][0].hypot(e[1][1]) / sample.bearing[1],
        },
        "micromotion": point.micromotion,
        "coupling_unconverged_steps": sim.unconverged_coupling_steps(),
        "bearing_overload": sim.bearing_overload(),
        "revolutions": summary.revolutions,
        "coupling_iterations_mean": summary.coupling_iterations_mean,
        "converged": summary.converged,
        "mass_imbalance": summary.mass_imbalance,
        "newton_iterations_mean": summary.mean_newton_iterations,
        "steps_per_revolution": pump.steps_per_period() * pump.tables.z[0],
        "wall_ms": times.wall_ms,
        "setup_ms": times.setup_ms,
        "solve_ms": times.solve_ms,
        "tables": times.tables,
    })
}
