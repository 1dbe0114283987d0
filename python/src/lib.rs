//! The Python extension `gearpump._gearpump` (PyO3, abi3): `simulate` (one
//! operating point, the keys of `gearpump simulate --json`) and
//! `simulate_batch` (rows of operating points run in parallel with rayon).
//!
//! The checks and their messages are those of the CLI (src/bin/gearpump.rs,
//! `simulate`): the same library ranges (`gearpump::limits`), the design
//! through `gearpump::design::load`, the design's per-test keys through the
//! campaigns' `EffectModel`. The physics runs with the GIL released. No
//! panic crosses the boundary: a panic becomes a RuntimeError (simulate) or
//! a failed row (simulate_batch).

use gearpump::campaign::effects::EffectModel;
use gearpump::campaign::point::{point_json, PointSpec, PointTimes};
use gearpump::design::Design;
use gearpump::model::{Inputs, Options, Pump, SampleClearances};
use gearpump::units::*;
use numpy::{IntoPyArray, PyReadonlyArray1};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use rayon::prelude::*;
use serde_json::Value;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

/// The names of a sample's four clearances, as the CLI says them.
const SAMPLE_NAMES: [&str; 4] = ["TIP1", "TIP2", "BRG1", "BRG2"];
/// The batch columns of the four clearances, um.
const SAMPLE_COLUMNS: [&str; 4] = ["tip1_um", "tip2_um", "bearing1_um", "bearing2_um"];

/// A bad input: the Python argument (or batch column) and the CLI's text.
struct Bad {
    arg: &'static str,
    message: String,
}

fn bad(arg: &'static str, message: String) -> Bad {
    Bad { arg, message }
}

/// The design of `design`/`set` and its pump (tables from the table cache
/// as the CLI does), with the effect model of the design's keys.
fn prepare(design: Option<PathBuf>, set: Option<Vec<String>>) -> PyResult<(EffectModel, String)> {
    let sets = set.unwrap_or_default();
    let d = gearpump::design::load(design.as_deref(), &sets)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    // the table cache as the CLI uses it (no note on stderr)
    let (pump, source) = Pump::with_env_cache(d);
    let tables = source.label();
    let pump = Arc::new(pump);
    let model = EffectModel::on(&pump, &[]).map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok((model, tables))
}

/// One operating point as given (speed rpm, pressure bar gauge, temperature
/// degC, inlet bar absolute, clearances um, each optional).
struct Point {
    speed: f64,
    pressure: f64,
    temp: f64,
    p_in: f64,
    clearances: [Option<f64>; 4],
}

/// The checked point: the simulation's inputs and the sample, with the
/// values as given (for the output). The messages are the CLI's.
fn check_point(design: &Design, p: &Point) -> Result<(Inputs, SampleClearances), Bad> {
    let limit = |arg: &'static str, flag: &str, range: gearpump::limits::Range, v: f64| {
        range
            .check(v)
            .map_err(|e| bad(arg, format!("--{flag}: {e}")))
    };
    let speed = limit("speed_rpm", "speed", gearpump::limits::SPEED_RPM, p.speed)?;
    let pressure = limit(
        "pressure_bar",
        "pressure",
        gearpump::limits::PRESSURE_BAR,
        p.pressure,
    )?;
    let temp = p.temp;
    if !temp.is_finite() {
        return Err(bad(
            "temp_c",
            format!("--temp: must be a finite number, got {temp}"),
        ));
    }
    let t_k = celsius_to_kelvin(temp);
    if !design.oil.in_range(t_k) {
        return Err(bad(
            "temp_c",
            format!(
                "--temp: {temp} degC is outside the oil model's range [{}, {}] degC",
                kelvin_to_celsius(design.oil.t_min_k),
                kelvin_to_celsius(design.oil.t_max_k)
            ),
        ));
    }
    let p_in = limit(
        "inlet_pressure_bar",
        "inlet-pressure",
        gearpump::limits::INLET_BAR_ABS,
        p.p_in,
    )?;
    let mut sample = SampleClearances::nominal(design);
    for (i, x) in p.clearances.iter().enumerate() {
        let Some(x) = *x else { continue };
        let arg = SAMPLE_COLUMNS[i];
        if !(x.is_finite() && x > 0.0) {
            return Err(bad(
                arg,
                format!(
                    "--sample-clearances: {} must be > 0 um, got {x}",
                    SAMPLE_NAMES[i]
                ),
            ));
        }
        limit(
            arg,
            "sample-clearances",
            gearpump::limits::clearance(SAMPLE_NAMES[i]),
            x,
        )?;
        match i {
            0 | 1 => sample.tip[i] = um_to_m(x),
            _ => sample.bearing[i - 2] = um_to_m(x),
        }
    }
    let inputs = Inputs {
        omega: rpm_to_rad_s(speed),
        p_suction: bar_to_pa(p_in),
        p_delivery: bar_to_pa(p_in + pressure),
        temp_k: t_k,
        measured_torque: None,
    };
    Ok((inputs, sample))
}

/// The figures of one run (the batch's columns).
#[derive(Clone, Copy)]
struct Figures {
    eta_v: f64,
    flow_lpm: f64,
    torque_nm: f64,
    eta_hm: f64,
    flow_ripple_lpm: f64,
    converged: bool,
}

/// Runs one point: the figures, or the error's text. A panic is an error.
fn run_row(
    model: &EffectModel,
    inputs: Inputs,
    sample: SampleClearances,
    options: Options,
) -> Result<Figures, String> {
    let run = || -> Result<Figures, String> {
        let mut sim = model
            .simulation(inputs, sample, options)
            .map_err(|e| e.to_string())?;
        let s = sim.run_periodic().map_err(|e| e.to_string())?;
        Ok(Figures {
            eta_v: s.eta_v,
            flow_lpm: m3_s_to_lpm(s.flow),
            torque_nm: s.torque,
            eta_hm: s.eta_hm,
            flow_ripple_lpm: m3_s_to_lpm(s.flow_ripple),
            converged: s.converged,
        })
    };
    catch_unwind(AssertUnwindSafe(run)).unwrap_or_else(|p| Err(panic_text(p)))
}

fn panic_text(p: Box<dyn std::any::Any + Send>) -> String {
    let what = p
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| p.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into());
    format!("internal error (panic): {what}")
}

/// The CLI's `simulate --json` object for one point (without the trace):
/// the same record the command line writes (`campaign::point`).
fn simulate_json(
    model: &EffectModel,
    tables: &str,
    inputs: Inputs,
    sample: SampleClearances,
    point: &Point,
    micromotion: bool,
    start: Instant,
) -> Result<Value, String> {
    let mut sim = model
        .simulation(inputs, sample, Options { micromotion })
        .map_err(|e| e.to_string())?;
    let setup_ms = start.elapsed().as_secs_f64() * 1e3;
    let summary = sim.run_periodic().map_err(|e| e.to_string())?;
    let solve_ms = start.elapsed().as_secs_f64() * 1e3 - setup_ms;
    let warnings = summary.warnings(sim.unconverged_coupling_steps(), sim.bearing_overload());
    let spec = PointSpec {
        speed_rpm: point.speed,
        pressure_bar: point.pressure,
        temp_c: point.temp,
        inlet_pressure_bar_abs: point.p_in,
        micromotion,
    };
    let times = PointTimes {
        wall_ms: start.elapsed().as_secs_f64() * 1e3,
        setup_ms,
        solve_ms,
        tables: tables.to_string(),
    };
    Ok(point_json(
        model.pump(),
        &sim,
        &summary,
        &sample,
        &spec,
        &warnings,
        &times,
    ))
}

/// A JSON value as a Python object (null -> None, objects -> dict).
fn to_py<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => b.into_pyobject(py)?.to_owned().into_any(),
        Value::Number(n) => {
            if let Some(i) = n.as_i64() {
                i.into_pyobject(py)?.into_any()
            } else if let Some(u) = n.as_u64() {
                u.into_pyobject(py)?.into_any()
            } else {
                n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any()
            }
        }
        Value::String(s) => s.into_pyobject(py)?.into_any(),
        Value::Array(a) => {
            let items = a
                .iter()
                .map(|x| to_py(py, x))
                .collect::<PyResult<Vec<_>>>()?;
            PyList::new(py, items)?.into_any()
        }
        Value::Object(m) => {
            let d = PyDict::new(py);
            for (k, x) in m {
                d.set_item(k, to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}

/// simulate(speed_rpm, pressure_bar, temp_c, *, design=None, set=None,
/// inlet_pressure_bar=1.01325, sample_clearances_um=None, micromotion=True)
#[pyfunction]
#[pyo3(signature = (speed_rpm, pressure_bar, temp_c, *, design=None, set=None,
                    inlet_pressure_bar=1.01325, sample_clearances_um=None, micromotion=true))]
#[allow(clippy::too_many_arguments)]
fn simulate<'py>(
    py: Python<'py>,
    speed_rpm: f64,
    pressure_bar: f64,
    temp_c: f64,
    design: Option<PathBuf>,
    set: Option<Vec<String>>,
    inlet_pressure_bar: f64,
    sample_clearances_um: Option<Vec<f64>>,
    micromotion: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let start = Instant::now();
    let clearances = match &sample_clearances_um {
        None => [None; 4],
        Some(v) if v.len() == 4 => [Some(v[0]), Some(v[1]), Some(v[2]), Some(v[3])],
        Some(v) => {
            return Err(PyValueError::new_err(format!(
                "sample_clearances_um: --sample-clearances: expected four values TIP1,TIP2,BRG1,BRG2 in um, got {} values",
                v.len()
            )))
        }
    };
    let point = Point {
        speed: speed_rpm,
        pressure: pressure_bar,
        temp: temp_c,
        p_in: inlet_pressure_bar,
        clearances,
    };
    let out = py.detach(|| -> PyResult<Value> {
        let (model, tables) = prepare(design, set)?;
        let (inputs, sample) = check_point(&model.pump().design, &point).map_err(|b| {
            let arg = if b.arg.ends_with("_um") {
                "sample_clearances_um"
            } else {
                b.arg
            };
            PyValueError::new_err(format!("{arg}: {}", b.message))
        })?;
        let run = || simulate_json(&model, &tables, inputs, sample, &point, micromotion, start);
        catch_unwind(AssertUnwindSafe(run))
            .unwrap_or_else(|p| Err(panic_text(p)))
            .map_err(PyRuntimeError::new_err)
    })?;
    to_py(py, &out)
}

/// The batch's known columns.
const COLUMNS: [&str; 8] = [
    "speed_rpm",
    "pressure_bar",
    "temp_c",
    "tip1_um",
    "tip2_um",
    "bearing1_um",
    "bearing2_um",
    "inlet_pressure_bar",
];

/// simulate_batch(conditions, *, design=None, set=None, micromotion=True, jobs=None)
///
/// `conditions`: a dict of 1-D float64 numpy arrays (the Python wrapper
/// converts lists and DataFrames).
#[pyfunction]
#[pyo3(signature = (conditions, *, design=None, set=None, micromotion=true, jobs=None))]
fn simulate_batch<'py>(
    py: Python<'py>,
    conditions: &Bound<'py, PyDict>,
    design: Option<PathBuf>,
    set: Option<Vec<String>>,
    micromotion: bool,
    jobs: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut cols: Vec<Option<Vec<f64>>> = vec![None; COLUMNS.len()];
    for (k, v) in conditions.iter() {
        let key: String = k
            .extract()
            .map_err(|_| PyValueError::new_err("conditions: column names must be strings"))?;
        let Some(i) = COLUMNS.iter().position(|c| *c == key) else {
            return Err(PyValueError::new_err(format!(
                "conditions: unknown column {key:?} (known: {})",
                COLUMNS.join(", ")
            )));
        };
        let a: PyReadonlyArray1<f64> = v.extract().map_err(|_| {
            PyValueError::new_err(format!(
                "conditions: column {key:?} must be a 1-D array of floats"
            ))
        })?;
        cols[i] = Some(a.as_array().to_vec());
    }
    for c in &COLUMNS[..3] {
        if cols[COLUMNS.iter().position(|x| x == c).unwrap_or(0)].is_none() {
            return Err(PyValueError::new_err(format!(
                "conditions: missing column {c:?}"
            )));
        }
    }
    let n = cols[0].as_ref().map_or(0, Vec::len);
    for (c, v) in COLUMNS.iter().zip(&cols) {
        if let Some(v) = v {
            if v.len() != n {
                return Err(PyValueError::new_err(format!(
                    "conditions: column {c:?} has {} rows, speed_rpm has {n}",
                    v.len()
                )));
            }
        }
    }
    if jobs == Some(0) {
        return Err(PyValueError::new_err("jobs: must be at least 1"));
    }
    let results = py.detach(|| -> PyResult<Vec<Result<Figures, String>>> {
        let (model, _) = prepare(design, set)?;
        let get = |j: usize, i: usize| cols[j].as_ref().map(|v| v[i]);
        let mut rows = Vec::with_capacity(n);
        for i in 0..n {
            let point = Point {
                speed: get(0, i).unwrap_or(f64::NAN),
                pressure: get(1, i).unwrap_or(f64::NAN),
                temp: get(2, i).unwrap_or(f64::NAN),
                p_in: get(7, i).unwrap_or(1.01325),
                clearances: [get(3, i), get(4, i), get(5, i), get(6, i)],
            };
            let r = check_point(&model.pump().design, &point).map_err(|b| {
                PyValueError::new_err(format!("row {i}, column {}: {}", b.arg, b.message))
            })?;
            rows.push(r);
        }
        let options = Options { micromotion };
        let run = || -> Vec<Result<Figures, String>> {
            rows.par_iter()
                .map(|&(inputs, sample)| run_row(&model, inputs, sample, options))
                .collect()
        };
        match jobs {
            None => Ok(run()),
            Some(j) => {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(j)
                    .build()
                    .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
                Ok(pool.install(run))
            }
        }
    })?;
    let pick = |f: fn(&Figures) -> f64| -> Vec<f64> {
        results
            .iter()
            .map(|r| r.as_ref().map_or(f64::NAN, f))
            .collect()
    };
    let out = PyDict::new(py);
    out.set_item("eta_v", pick(|f| f.eta_v).into_pyarray(py))?;
    out.set_item("flow_lpm", pick(|f| f.flow_lpm).into_pyarray(py))?;
    out.set_item("torque_nm", pick(|f| f.torque_nm).into_pyarray(py))?;
    out.set_item("eta_hm", pick(|f| f.eta_hm).into_pyarray(py))?;
    out.set_item(
        "flow_ripple_lpm",
        pick(|f| f.flow_ripple_lpm).into_pyarray(py),
    )?;
    let converged: Vec<bool> = results
        .iter()
        .map(|r| r.as_ref().is_ok_and(|f| f.converged))
        .collect();
    out.set_item("converged", converged.into_pyarray(py))?;
    let errors: Vec<Option<String>> = results.into_iter().map(|r| r.err()).collect();
    out.set_item("errors", errors)?;
    Ok(out)
}

/// The extension module `gearpump._gearpump`.
#[pymodule]
fn _gearpump(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(simulate_batch, m)?)?;
    Ok(())
}
