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
use pyo3::exceptions::{PyRuntimeError, PyTypeError, PyUserWarning, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyList};
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

/// A whole number argument (`jobs`, `chunk`, `start`, ...): a Python int
/// (or anything with `__index__`, numpy's ints) that is not a bool, and at
/// least `least`. Refused naming the argument: TypeError for the type,
/// ValueError for the value (a negative int was the conversion's
/// OverflowError). Above `usize::MAX` it saturates (every caller clamps or
/// bounds it further).
fn count(name: &str, v: &Bound<'_, PyAny>, least: usize) -> PyResult<usize> {
    let i = whole(name, v)?;
    if i.lt(least)? {
        return Err(PyValueError::new_err(format!(
            "{name}: must be >= {least}, got {i}"
        )));
    }
    Ok(i.extract::<u64>()
        .map_or(usize::MAX, |u| usize::try_from(u).unwrap_or(usize::MAX)))
}

/// The Python int of a whole number argument (see [`count`]): TypeError
/// naming `name` for a bool or a non-integer.
fn whole<'py>(name: &str, v: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    let not_int = || {
        let t = v
            .get_type()
            .name()
            .map_or_else(|_| "?".to_string(), |n| n.to_string());
        PyTypeError::new_err(format!("{name}: must be an integer, not {t}"))
    };
    if v.is_instance_of::<PyBool>() {
        return Err(not_int());
    }
    v.py()
        .import("operator")?
        .call_method1("index", (v,))
        .map_err(|_| not_int())
}

/// `jobs`: None (all cores), or an integer >= 1; more than the cores
/// available is clamped to them with a warning (Python's `warnings`; the
/// CLI's note on stderr), as `gearpump::campaign::run::pool_size` does
/// for the CLI's `--jobs`: 100000 threads hung the machine.
fn jobs_arg(py: Python<'_>, jobs: Option<&Bound<'_, PyAny>>) -> PyResult<Option<usize>> {
    let Some(v) = jobs.filter(|v| !v.is_none()) else {
        return Ok(None);
    };
    let asked = count("jobs", v, 1)?;
    let (n, more) = gearpump::campaign::run::pool_size(Some(asked))
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    if more.is_some() {
        let text = format!("jobs: {v} is more than the {n} cores available: using {n}");
        let text = std::ffi::CString::new(text).unwrap_or_default();
        PyErr::warn(py, py.get_type::<PyUserWarning>().as_any(), &text, 1)?;
    }
    Ok(Some(n))
}

/// An output folder checked before any work, as the CLI's `check_out`
/// (`gearpump::campaign::io::check_out`): ValueError naming `name`.
fn out_arg(name: &str, out: &std::path::Path) -> PyResult<()> {
    gearpump::campaign::io::check_out(out, false)
        .map_err(|why| PyValueError::new_err(format!("{name}: {why}")))
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
    gearpump::limits::delivery_bar_abs(p_in, pressure).map_err(|e| {
        bad(
            "pressure_bar",
            format!("--pressure with --inlet-pressure: {e}"),
        )
    })?;
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
    jobs: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let jobs = jobs_arg(py, jobs)?;
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

// ------------------------------------------------------------ montecarlo

use gearpump::campaign::montecarlo::{
    self as mc, MonteCarloError, Outputs, Population, RunOptions, Spec, Study,
};
use gearpump::campaign::run::{DesignSource, RunError};
use std::sync::{Mutex, OnceLock};

/// A study's error as a Python exception: ValueError for bad input (the
/// message names the key of the study dict), RuntimeError otherwise.
fn mc_err(key: &str, e: MonteCarloError) -> PyErr {
    let text = match &e {
        MonteCarloError::Setting { .. } | MonteCarloError::Run(_) => e.to_string(),
        _ => format!("{key}: {e}"),
    };
    if e.is_bad_input() {
        PyValueError::new_err(text)
    } else {
        PyRuntimeError::new_err(text)
    }
}

fn run_err(e: RunError) -> PyErr {
    if e.is_bad_input() {
        PyValueError::new_err(e.to_string())
    } else {
        PyRuntimeError::new_err(e.to_string())
    }
}

/// A value of the study dict, if present and not None.
fn item<'py, T: pyo3::conversion::FromPyObjectOwned<'py>>(
    d: &Bound<'py, PyDict>,
    key: &str,
) -> PyResult<Option<T>> {
    match d.get_item(key)? {
        None => Ok(None),
        Some(v) if v.is_none() => Ok(None),
        Some(v) => v
            .extract::<T>()
            .map(Some)
            .map_err(|_| PyTypeError::new_err(format!("{key}: wrong type ({})", v.get_type()))),
    }
}

/// The keys a study dict may hold (python/gearpump/__init__.py documents them).
const STUDY_KEYS: [&str; 10] = [
    "design",
    "set",
    "pumps",
    "seed",
    "fit",
    "distributions",
    "conditions",
    "spec",
    "sensitivity",
    "micromotion",
];

/// The design and the study of a study dict, checked as the CLI checks
/// `gearpump montecarlo`'s flags.
fn study_of(d: &Bound<'_, PyDict>) -> PyResult<(DesignSource, Study)> {
    for k in d.keys() {
        let k: String = k.extract()?;
        if !STUDY_KEYS.contains(&k.as_str()) {
            return Err(PyValueError::new_err(format!(
                "study: unknown key {k:?} (known: {})",
                STUDY_KEYS.join(", ")
            )));
        }
    }
    let design: Option<PathBuf> = item(d, "design")?;
    let sets: Vec<String> = item(d, "set")?.unwrap_or_default();
    let source = DesignSource::load(design.as_deref(), &sets).map_err(run_err)?;
    let fit: Option<PathBuf> = item(d, "fit")?;
    let dists: Option<PathBuf> = item(d, "distributions")?;
    let population = match (fit, dists) {
        (Some(_), Some(_)) => {
            return Err(PyValueError::new_err(
                "fit, distributions: give one population, not both",
            ))
        }
        (Some(csv), None) => {
            let c = gearpump::campaign::read_campaign(&csv)
                .map_err(|e| PyValueError::new_err(format!("fit: {e}")))?;
            Population::fitted(&c).map_err(|e| mc_err("fit", e))?
        }
        (None, Some(toml)) => Population::from_toml_file(&source.design, &toml)
            .map_err(|e| mc_err("distributions", e))?,
        (None, None) => Population::paper(&source.design),
    };
    let conditions = match d.get_item("conditions")? {
        None => gearpump::campaign::synth::paper_conditions(),
        Some(v) if v.is_none() => gearpump::campaign::synth::paper_conditions(),
        Some(v) => {
            if let Ok(text) = v.extract::<String>() {
                gearpump::campaign::synth::conditions_from_arg(&text)
                    .map_err(|e| PyValueError::new_err(format!("conditions: {e}")))?
            } else {
                let rows: Vec<(f64, f64, f64)> = v.extract().map_err(|_| {
                    PyValueError::new_err(
                        "conditions: expected \"paper\", a CSV path or a list of (pressure_bar, speed_rpm, temp_c)",
                    )
                })?;
                rows.into_iter()
                    .map(|(p, n, t)| gearpump::campaign::Condition {
                        pressure_bar: p,
                        speed_rpm: n,
                        temp_c: t,
                    })
                    .collect()
            }
        }
    };
    let specs = item::<Vec<String>>(d, "spec")?
        .unwrap_or_default()
        .iter()
        .map(|s| Spec::parse(s).map_err(|e| PyValueError::new_err(format!("spec: {e}"))))
        .collect::<PyResult<Vec<_>>>()?;
    let sensitivity: bool = item(d, "sensitivity")?.unwrap_or(true);
    let pumps = match d.get_item("pumps")?.filter(|v| !v.is_none()) {
        None => 200,
        Some(v) => {
            // the range of Study::new, said before the conversion to usize
            // can fail (a negative or huge int is a wrong value, not type)
            let least = if sensitivity { 4 } else { 1 };
            let n = whole("pumps", &v)?
                .extract::<usize>()
                .ok()
                .filter(|n| (least..=mc::MAX_PUMPS).contains(n));
            let Some(n) = n else {
                return Err(PyValueError::new_err(format!(
                    "pumps: must be in [{least}, {}]{}, got {}",
                    mc::MAX_PUMPS,
                    if sensitivity {
                        " (the sensitivity indices need two pairs)"
                    } else {
                        ""
                    },
                    v
                )));
            };
            n
        }
    };
    let seed = match d.get_item("seed")?.filter(|v| !v.is_none()) {
        None => 1,
        Some(v) => whole("seed", &v)?.extract::<u64>().map_err(|_| {
            PyValueError::new_err(format!("seed: must be in [0, {}], got {v}", u64::MAX))
        })?,
    };
    let micromotion: bool = item(d, "micromotion")?.unwrap_or(true);
    let study = Study::new(
        &source.design,
        population,
        conditions,
        pumps,
        seed,
        sensitivity,
        specs,
        micromotion,
    )
    .map_err(|e| mc_err("study", e))?;
    Ok((source, study))
}

/// The model of a design, built once per process (a Dask worker runs
/// many chunks of one study): keyed by the design text and `set` list.
fn cached_model(source: &DesignSource) -> PyResult<Arc<EffectModel>> {
    type Cache = Mutex<Vec<(String, Arc<EffectModel>)>>;
    static CACHE: OnceLock<Cache> = OnceLock::new();
    let key = format!("{}\u{0}{}", source.text, source.sets.join("\u{0}"));
    let cache = CACHE.get_or_init(|| Mutex::new(Vec::new()));
    if let Some((_, m)) = cache
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .iter()
        .find(|(k, _)| *k == key)
    {
        return Ok(Arc::clone(m));
    }
    let (pump, _) = Pump::with_env_cache(source.design.clone());
    let model = Arc::new(
        EffectModel::on(&Arc::new(pump), &[]).map_err(|e| PyValueError::new_err(e.to_string()))?,
    );
    let mut c = cache.lock().unwrap_or_else(|e| e.into_inner());
    if c.len() >= 4 {
        c.remove(0);
    }
    c.push((key, Arc::clone(&model)));
    Ok(model)
}

fn with_jobs<T: Send>(jobs: Option<usize>, f: impl FnOnce() -> T + Send) -> PyResult<T> {
    match jobs {
        None => Ok(f()),
        Some(j) => rayon::ThreadPoolBuilder::new()
            .num_threads(j)
            .build()
            .map(|p| p.install(f))
            .map_err(|e| PyRuntimeError::new_err(e.to_string())),
    }
}

fn outputs_dict<'py>(py: Python<'py>, o: Outputs) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("eta_v", o.eta_v.into_pyarray(py))?;
    d.set_item("flow_lpm", o.flow_lpm.into_pyarray(py))?;
    d.set_item("torque_nm", o.torque_nm.into_pyarray(py))?;
    d.set_item("errors", o.errors)?;
    Ok(d)
}

/// montecarlo_plan(study, chunk): the study's size and its fingerprint.
#[pyfunction]
fn montecarlo_plan<'py>(
    py: Python<'py>,
    study: &Bound<'py, PyDict>,
    chunk: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let chunk = count("chunk", chunk, 1)?;
    let (source, s) = study_of(study)?;
    let v = serde_json::json!({
        "items": s.items(),
        "rows": s.rows(),
        "pumps": s.pumps,
        "pairs": s.pairs(),
        "conditions": s.conditions,
        "chunks": s.chunks(chunk),
        "fingerprint": format!("{:016x}", mc::study_fingerprint(&source, &s, chunk)),
    });
    to_py(py, &v)
}

/// montecarlo_chunk(study, start, end, jobs=None): the rows of items
/// start..end (every condition), run in parallel with the GIL released.
#[pyfunction]
#[pyo3(signature = (study, start, end, jobs=None))]
fn montecarlo_chunk<'py>(
    py: Python<'py>,
    study: &Bound<'py, PyDict>,
    start: &Bound<'py, PyAny>,
    end: &Bound<'py, PyAny>,
    jobs: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let start = count("start", start, 0)?;
    let end = count("end", end, 0)?;
    let jobs = jobs_arg(py, jobs)?;
    let (source, s) = study_of(study)?;
    if start > end || end > s.items() {
        return Err(PyValueError::new_err(format!(
            "start, end: {start}..{end} is not a range of the study's {} items",
            s.items()
        )));
    }
    let o = py.detach(|| -> PyResult<Outputs> {
        let model = cached_model(&source)?;
        with_jobs(jobs, || mc::run_items(&model, &s, start..end, &|| {}))
    })?;
    outputs_dict(py, o)
}

/// A column of results: a 1-D float64 array (integer arrays converted);
/// another dtype or shape refused naming the argument.
fn column_of(name: &str, a: &Bound<'_, PyAny>, rows: usize) -> PyResult<Vec<f64>> {
    let v = match a.extract::<PyReadonlyArray1<f64>>() {
        Ok(a) => a.as_array().to_vec(),
        Err(_) => {
            let kind: Option<String> = a
                .getattr("dtype")
                .and_then(|d| d.getattr("kind"))
                .and_then(|k| k.extract())
                .ok();
            let ints = matches!(kind.as_deref(), Some("i" | "u"));
            let floats = if ints {
                a.call_method1("astype", ("float64",))
                    .and_then(|f| f.extract::<PyReadonlyArray1<f64>>())
                    .ok()
            } else {
                None
            };
            let Some(floats) = floats else {
                let what = match a.getattr("dtype") {
                    Ok(d) => format!(
                        "a {}-D array of {d}",
                        a.getattr("ndim")
                            .map_or_else(|_| "?".into(), |n| n.to_string())
                    ),
                    Err(_) => a
                        .get_type()
                        .name()
                        .map_or_else(|_| "?".to_string(), |n| n.to_string()),
                };
                return Err(PyTypeError::new_err(format!(
                    "{name}: expected a 1-D numpy array of floats, not {what}"
                )));
            };
            floats.as_array().to_vec()
        }
    };
    if v.len() != rows {
        return Err(PyValueError::new_err(format!(
            "{name}: {} values for the study's {rows} rows",
            v.len()
        )));
    }
    Ok(v)
}

/// montecarlo_summarize(study, eta_v, flow_lpm, torque_nm): the summary of
/// every row's results (the record of montecarlo.json).
#[pyfunction]
fn montecarlo_summarize<'py>(
    py: Python<'py>,
    study: &Bound<'py, PyDict>,
    eta_v: &Bound<'py, PyAny>,
    flow_lpm: &Bound<'py, PyAny>,
    torque_nm: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let (source, s) = study_of(study)?;
    let rows = s.rows();
    let o = Outputs {
        eta_v: column_of("eta_v", eta_v, rows)?,
        flow_lpm: column_of("flow_lpm", flow_lpm, rows)?,
        torque_nm: column_of("torque_nm", torque_nm, rows)?,
        errors: Vec::new(),
    };
    let summary = mc::summarize(&s, &o);
    to_py(
        py,
        &mc::study_json(&source.label, &source.sets, &s, &summary),
    )
}

/// montecarlo_run(study, out, chunk=8, jobs=None): the command line's
/// study (journaled in `out`, resumable, the files written there).
#[pyfunction]
#[pyo3(signature = (study, out, chunk=None, jobs=None))]
fn montecarlo_run<'py>(
    py: Python<'py>,
    study: &Bound<'py, PyDict>,
    out: PathBuf,
    chunk: Option<&Bound<'py, PyAny>>,
    jobs: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let chunk = match chunk {
        Some(c) if !c.is_none() => count("chunk", c, 1)?,
        _ => 8,
    };
    let jobs = jobs_arg(py, jobs)?;
    let (source, s) = study_of(study)?;
    out_arg("out", &out)?;
    let r = py.detach(|| {
        let run = || {
            mc::run_study(
                &source,
                &s,
                &out,
                RunOptions { jobs, chunk },
                &gearpump::campaign::run::Silent,
            )
        };
        catch_unwind(AssertUnwindSafe(run))
            .unwrap_or_else(|p| Err(MonteCarloError::Run(RunError::Pool(panic_text(p)))))
    });
    let r = r.map_err(|e| mc_err("study", e))?;
    let d = PyDict::new(py);
    let v = mc::study_json(&source.label, &source.sets, &s, &r.summary);
    d.set_item("record", to_py(py, &v)?)?;
    d.set_item("simulated", r.simulated)?;
    d.set_item("reused", r.reused)?;
    d.set_item(
        "files",
        r.files
            .iter()
            .map(|f| f.display().to_string())
            .collect::<Vec<_>>(),
    )?;
    d.set_item("runs", outputs_dict(py, r.outputs)?)?;
    Ok(d)
}

// ------------------------------------------------------ campaign, diagnose

/// A panic inside a run as a RunError (nothing panics across the boundary).
fn guarded<T>(f: impl FnOnce() -> Result<T, RunError>) -> Result<T, RunError> {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|p| Err(RunError::Pool(panic_text(p))))
}

/// campaign(data, out, *, design=None, set=None, jobs=None, micromotion=True):
/// `gearpump campaign`; returns the object of its `--json`.
#[pyfunction]
#[pyo3(signature = (data, out, *, design=None, set=None, jobs=None, micromotion=true))]
fn campaign<'py>(
    py: Python<'py>,
    data: PathBuf,
    out: PathBuf,
    design: Option<PathBuf>,
    set: Option<Vec<String>>,
    jobs: Option<&Bound<'py, PyAny>>,
    micromotion: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let jobs = jobs_arg(py, jobs)?;
    out_arg("out", &out)?;
    gearpump::campaign::io::result_places_free(&out)
        .map_err(|e| PyValueError::new_err(format!("out: {e}")))?;
    use gearpump::campaign::run::{run_campaign, CampaignOptions, Silent};
    let start = Instant::now();
    let v = py.detach(|| {
        guarded(|| {
            let source = DesignSource::load(design.as_deref(), &set.unwrap_or_default())?;
            let options = CampaignOptions { jobs, micromotion };
            let r = run_campaign(&source, &data, &out, options, &Silent)?;
            Ok(r.to_json(&out, start.elapsed().as_secs_f64() * 1e3))
        })
    });
    to_py(py, &v.map_err(run_err)?)
}

/// diagnose(data, out, *, design=None, set=None, jobs=None, micromotion=True):
/// `gearpump diagnose`; returns the object of its `--json` (diagnosis.json).
#[pyfunction]
#[pyo3(signature = (data, out, *, design=None, set=None, jobs=None, micromotion=true))]
fn diagnose<'py>(
    py: Python<'py>,
    data: PathBuf,
    out: PathBuf,
    design: Option<PathBuf>,
    set: Option<Vec<String>>,
    jobs: Option<&Bound<'py, PyAny>>,
    micromotion: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let jobs = jobs_arg(py, jobs)?;
    out_arg("out", &out)?;
    gearpump::campaign::io::result_places_free(&out)
        .map_err(|e| PyValueError::new_err(format!("out: {e}")))?;
    use gearpump::diagnosis::diagnose::{run_diagnosis, DiagnoseOptions};
    let v = py.detach(|| {
        guarded(|| {
            let source = DesignSource::load(design.as_deref(), &set.unwrap_or_default())?;
            let options = DiagnoseOptions {
                jobs,
                micromotion,
                ..DiagnoseOptions::default()
            };
            let d = run_diagnosis(
                &source,
                &data,
                &out,
                options,
                &gearpump::campaign::run::Silent,
            )?;
            let mut v = d.json;
            if let Some(m) = v.as_object_mut() {
                m.insert("out".into(), serde_json::json!(out.display().to_string()));
            }
            Ok(v)
        })
    });
    to_py(py, &v.map_err(run_err)?)
}

/// The extension module `gearpump._gearpump`.
#[pymodule]
fn _gearpump(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(simulate_batch, m)?)?;
    m.add_function(wrap_pyfunction!(montecarlo_plan, m)?)?;
    m.add_function(wrap_pyfunction!(montecarlo_chunk, m)?)?;
    m.add_function(wrap_pyfunction!(montecarlo_summarize, m)?)?;
    m.add_function(wrap_pyfunction!(montecarlo_run, m)?)?;
    m.add_function(wrap_pyfunction!(campaign, m)?)?;
    m.add_function(wrap_pyfunction!(diagnose, m)?)?;
    Ok(())
}
