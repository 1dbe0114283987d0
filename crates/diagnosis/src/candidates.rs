//! "Why": every effect of docs/model.md section 8 as a candidate extension of the
//! model, fitted to the measured data and scored by cross-validation over
//! pumps.
//!
//! # Fitting with few model runs
//! A model evaluation simulates every test of the campaign (a few seconds for
//! 280 tests), so a candidate is fitted by Gauss-Newton on the *real* model
//! with Broyden's update of the sensitivities rather than by a blind search:
//! 1. sensitivities by one forward difference per parameter (one run each)
//!    around the base model (the neutral parameter values, whose run is the
//!    baseline campaign itself);
//! 2. a bounded linear least-squares step on those sensitivities, one run at
//!    the new point, Broyden's rank-one update (in one dimension: the secant),
//!    repeated until the step is below 1 % of the parameter's scale or the
//!    iteration budget is spent; a step that raises the error is halved once.
//!
//! Parameters are fitted in a transformed coordinate in which laminar
//! leakage is close to linear (the inverse of a viscosity factor, the cube of
//! the lateral gap relative to the nominal one), so the secant converges in
//! two or three runs. The physical bounds of each parameter (e.g. an air
//! fraction is not negative, a casing bore does not shrink with pressure)
//! are kept by the bounded step.
//!
//! # Cross-validation
//! Leave one pump out: the candidate is refitted on the other pumps with the
//! linearisation at the full-data fit (exact at the fit, whose run is known;
//! the folds' parameters lie close to it) and predicts the left-out pump.
//! Each pump gets its held-out mean squared residual; the base model has no
//! parameter, so its held-out residual is its residual. The leave-one-out
//! parameters also give the jackknife standard error of the fit.

use nalgebra::{DMatrix, DVector};
use serde::Serialize;

use gearpump_campaign::effects::{split_site, Effect, EFFECT_NAMES, LOCATED};
use gearpump_core::design::Design;
use gearpump_core::units::m_to_um;

/// How a parameter's edge value maps to the fitted coordinate `u`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Transform {
    /// u = edge value.
    Identity,
    /// u = edge value / scale (keeps u of order one).
    Scale(f64),
    /// u = 1 / edge value (laminar leakage is proportional to 1 / viscosity).
    Inverse,
    /// u = (edge value / nominal)^3 (laminar leakage grows with the gap cubed).
    CubeRatio(f64),
}

impl Transform {
    pub fn to_u(self, edge: f64) -> f64 {
        match self {
            Transform::Identity => edge,
            Transform::Scale(s) => edge / s,
            Transform::Inverse => 1.0 / edge,
            Transform::CubeRatio(n) => (edge / n).powi(3),
        }
    }

    pub fn to_edge(self, u: f64) -> f64 {
        match self {
            Transform::Identity => u,
            Transform::Scale(s) => u * s,
            Transform::Inverse => 1.0 / u,
            Transform::CubeRatio(n) => n * u.cbrt(),
        }
    }
}

/// One parameter of a candidate, in the units of `--effect` (see
/// `campaign::effects`).
#[derive(Debug, Clone, PartialEq)]
pub struct ParamSpec {
    /// Name as in `Effect::params_edge` (e.g. `k_t_um_per_k`).
    pub name: &'static str,
    /// The value at which the candidate is the base model.
    pub neutral: f64,
    /// Forward-difference step and scale of the parameter, in u.
    pub step_u: f64,
    /// Physical bounds, in u (lower < upper).
    pub lower_u: f64,
    pub upper_u: f64,
    pub transform: Transform,
}

/// A candidate extension: one effect of docs/model.md section 8 with its
/// parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct CandidateSpec {
    pub effect: &'static str,
    pub params: Vec<ParamSpec>,
}

impl CandidateSpec {
    /// The effect at fitted coordinates `u`.
    pub fn effect_at(&self, u: &[f64]) -> Result<Effect, String> {
        let edge: Vec<f64> = self
            .params
            .iter()
            .zip(u)
            .map(|(p, &x)| p.transform.to_edge(x))
            .collect();
        Effect::from_edge(self.effect, &edge)
    }

    /// Edge values of the parameters at `u`.
    pub fn edge_params(&self, u: &[f64]) -> Vec<(&'static str, f64)> {
        self.params
            .iter()
            .zip(u)
            .map(|(p, &x)| (p.name, p.transform.to_edge(x)))
            .collect()
    }

    pub fn neutral_u(&self) -> Vec<f64> {
        self.params
            .iter()
            .map(|p| p.transform.to_u(p.neutral))
            .collect()
    }
}

/// The candidates, one per effect, with documented steps and bounds:
///
/// | effect | parameter | fitted as | step | bounds (edge units) | why the bounds |
/// |---|---|---|---|---|---|
/// | thermal_clearance | k_T, um/K | k_T | 0.03 | -0.15 .. 0.5 | cast-iron casings close slightly (-0.02), aluminium ones open (+0.2); beyond, gaps would close at 120 degC or triple |
/// | pressure_clearance | k_p, um/bar | k_p | 0.15 | 0 .. 2 | pressure opens bores, never closes them |
/// | lateral_clearance | h_lat, um | (h/h_nom)^3 | 0.3 | 0.46 .. 2 h_nom | leakage ~ h^3 |
/// | viscosity_shift | f1, f2 | 1/f | 0.2 | 0.25 .. 4 | an aged or other oil, within a factor 4 |
/// | entrained_air | x0 | x0 | 0.02 | 0 .. 0.06 | more free air than 6 % at suction is foam: a rig's flowmeter reading means little, and the model's periodic state takes tens of periods to settle (each pocket carries its compressible charge round the casing), so runs become 10-100 times slower |
/// | displacement_error | relative | relative | 0.02 | -0.2 .. 0.2 | a machining error, not another pump |
/// | pressure_viscosity | alpha, 1/Pa | alpha / 1e-8 | 1.5 | 0 .. 2e-7 | mineral oils 1e-8..3e-8; detectable on this rig from 5e-8; twice the top of that range because the model's gears, pressed towards the suction, seal the tip chain and leave the model's leak 31 % less sensitive to the films' viscosity than concentric films (eta_v +0.0057 against +0.0083 at 7e-8, 1000 rpm / 40 bar / 60 degC; the hand's concentric chain +0.0082): a fluid of 1e-7 needs about 1.45e-7 in the model |
pub fn candidate_specs(design: &Design) -> Vec<CandidateSpec> {
    let id = |name, step, lo, hi| ParamSpec {
        name,
        neutral: 0.0,
        step_u: step,
        lower_u: lo,
        upper_u: hi,
        transform: Transform::Identity,
    };
    let h_nom = m_to_um(design.clearance.lateral);
    let cube = Transform::CubeRatio(h_nom);
    let inv = |name| ParamSpec {
        name,
        neutral: 1.0,
        step_u: 0.2,
        lower_u: 0.25,
        upper_u: 4.0,
        transform: Transform::Inverse,
    };
    let specs = vec![
        CandidateSpec {
            effect: EFFECT_NAMES[0],
            params: vec![id("k_t_um_per_k", 0.03, -0.15, 0.5)],
        },
        CandidateSpec {
            effect: EFFECT_NAMES[1],
            params: vec![id("k_p_um_per_bar", 0.15, 0.0, 2.0)],
        },
        CandidateSpec {
            effect: EFFECT_NAMES[2],
            params: vec![ParamSpec {
                name: "h_lat_um",
                neutral: h_nom,
                step_u: 0.3,
                lower_u: cube.to_u(0.46 * h_nom),
                upper_u: cube.to_u(2.0 * h_nom),
                transform: cube,
            }],
        },
        CandidateSpec {
            effect: EFFECT_NAMES[3],
            params: vec![inv("factor_t1"), inv("factor_t2")],
        },
        CandidateSpec {
            effect: EFFECT_NAMES[4],
            params: vec![id("air_fraction", 0.02, 0.0, 0.06)],
        },
        CandidateSpec {
            effect: EFFECT_NAMES[5],
            params: vec![id("relative", 0.02, -0.2, 0.2)],
        },
        CandidateSpec {
            effect: EFFECT_NAMES[6],
            params: vec![ParamSpec {
                name: "alpha_per_pa",
                neutral: 0.0,
                step_u: 1.5,
                lower_u: 0.0,
                upper_u: 20.0,
                transform: Transform::Scale(1e-8),
            }],
        },
    ];
    debug_assert!(specs.iter().map(|s| s.effect).eq(EFFECT_NAMES));
    // the clearance effects at every other site: the data choose where an
    // effect acts (tips, bearings, lateral faces, all)
    let mut located: Vec<CandidateSpec> = LOCATED
        .iter()
        .map(|name| {
            let base = split_site(name).0;
            let mut s = specs
                .iter()
                .find(|s| s.effect == base)
                .expect("a base spec for every located effect")
                .clone();
            s.effect = name;
            s
        })
        .collect();
    let mut all = specs;
    all.append(&mut located);
    all
}

/// The mechanism of a candidate, whatever its site.
pub fn kind(effect: &str) -> &str {
    split_site(effect).0
}

/// The linear model of the simulated efficiencies around a point `u`:
/// `eta(v) = eta_u + jac (v - u)`.
#[derive(Debug, Clone)]
pub struct Linearisation {
    pub u: Vec<f64>,
    pub eta_u: Vec<f64>,
    /// rows x parameters
    pub jac: DMatrix<f64>,
}

impl Linearisation {
    pub fn predict(&self, i: usize, v: &[f64]) -> f64 {
        let mut e = self.eta_u[i];
        for (j, (vj, uj)) in v.iter().zip(&self.u).enumerate() {
            e += self.jac[(i, j)] * (vj - uj);
        }
        e
    }

    /// Least squares of `meas - eta(v)` over `rows` with `lower <= v <=
    /// upper`: every combination of free and bound-fixed parameters is solved
    /// (3^p small systems; p <= 2 here) and the best feasible one is kept.
    pub fn bounded_fit(
        &self,
        meas: &[f64],
        rows: &[usize],
        lower: &[f64],
        upper: &[f64],
    ) -> Vec<f64> {
        let p = self.u.len();
        let mut best: Option<(f64, Vec<f64>)> = None;
        let combos = 3usize.pow(p as u32);
        for c in 0..combos {
            // state of parameter j: 0 free, 1 at lower, 2 at upper
            let mut code = c;
            let mut state = vec![0u8; p];
            for s in state.iter_mut() {
                *s = (code % 3) as u8;
                code /= 3;
            }
            let mut v = self.u.clone();
            for j in 0..p {
                match state[j] {
                    1 => v[j] = lower[j],
                    2 => v[j] = upper[j],
                    _ => {}
                }
            }
            let free: Vec<usize> = (0..p).filter(|&j| state[j] == 0).collect();
            if !free.is_empty() {
                // residual with the fixed ones applied and the free ones at u
                let a =
                    DMatrix::from_fn(rows.len(), free.len(), |r, k| self.jac[(rows[r], free[k])]);
                let b = DVector::from_fn(rows.len(), |r, _| {
                    let i = rows[r];
                    meas[i] - self.predict(i, &v)
                });
                let ata = a.transpose() * &a;
                let atb = a.transpose() * b;
                let Some(delta) = ata.lu().solve(&atb) else {
                    continue;
                };
                if delta.iter().any(|x| !x.is_finite()) {
                    continue;
                }
                for (k, &j) in free.iter().enumerate() {
                    v[j] += delta[k];
                }
            }
            let feasible = (0..p).all(|j| v[j] >= lower[j] - 1e-12 && v[j] <= upper[j] + 1e-12);
            if !feasible {
                continue;
            }
            let sse: f64 = rows
                .iter()
                .map(|&i| (meas[i] - self.predict(i, &v)).powi(2))
                .sum();
            if best.as_ref().is_none_or(|(s, _)| sse < *s) {
                best = Some((sse, v));
            }
        }
        best.map(|(_, v)| v).unwrap_or_else(|| self.u.clone())
    }

    /// Broyden's rank-one update after a run at `v` gave `eta_v`; the
    /// linearisation moves to `v`.
    pub fn update(&mut self, v: &[f64], eta_v: Vec<f64>) {
        let du = DVector::from_iterator(v.len(), v.iter().zip(&self.u).map(|(a, b)| a - b));
        let norm2 = du.norm_squared();
        if norm2 > 0.0 {
            let n = self.eta_u.len();
            let pred = &self.jac * &du;
            let miss = DVector::from_fn(n, |i, _| (eta_v[i] - self.eta_u[i]) - pred[i]);
            self.jac += miss * du.transpose() / norm2;
        }
        self.u = v.to_vec();
        self.eta_u = eta_v;
    }
}

/// Sum of squared residuals `meas - eta` over all rows.
pub fn sse(meas: &[f64], eta: &[f64]) -> f64 {
    meas.iter().zip(eta).map(|(m, e)| (m - e).powi(2)).sum()
}

/// The full-data fit of one candidate.
#[derive(Debug, Clone)]
pub struct Fit {
    pub effect: &'static str,
    /// Linearisation at the fitted point (its `eta_u` is an exact run).
    pub lin: Linearisation,
    /// The sensitivities the fit started from (rows x parameters, at the
    /// neutral parameters).
    pub sensitivities: DMatrix<f64>,
    /// Model runs spent (forward differences and steps).
    pub runs: usize,
    /// The last step was below 1 % of the parameters' scale.
    pub converged: bool,
    /// Why the fit stopped early, if it did (a failed run, the budget, ...).
    pub note: Option<String>,
}

/// Fitting controls.
#[derive(Debug, Clone, Copy)]
pub struct FitOptions {
    /// Gauss-Newton steps after the forward differences.
    pub max_steps: usize,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions { max_steps: 4 }
    }
}

/// Fits `spec` to the measured efficiencies `meas` (all rows). `base` is the
/// base model's run (the candidate at its neutral parameters). `run(u)`
/// simulates every row at coordinates `u` (None: some row failed).
/// `keep_going(&lin, steps)` is asked after the sensitivities (steps = 0)
/// and after every accepted step: false stops the fit (used to drop
/// candidates that cannot compete).
pub fn fit_candidate(
    spec: &CandidateSpec,
    meas: &[f64],
    base: &[f64],
    run: &mut dyn FnMut(&[f64]) -> Option<Vec<f64>>,
    options: FitOptions,
    keep_going: &mut dyn FnMut(&Linearisation, usize) -> bool,
) -> Fit {
    fit_candidate_from(spec, meas, base, None, run, options, keep_going)
}

/// [`fit_candidate`] starting from known sensitivities `start` (rows x
/// parameters, at the neutral parameters) instead of forward differences:
/// the first step is taken on them and Broyden's updates correct them as
/// the runs come (exact secants for one parameter). Used for a candidate
/// fitted again on top of other effects, whose sensitivities differ from
/// those on the base model only by what the other effects change.
pub fn fit_candidate_from(
    spec: &CandidateSpec,
    meas: &[f64],
    base: &[f64],
    start: Option<&DMatrix<f64>>,
    run: &mut dyn FnMut(&[f64]) -> Option<Vec<f64>>,
    options: FitOptions,
    keep_going: &mut dyn FnMut(&Linearisation, usize) -> bool,
) -> Fit {
    let p = spec.params.len();
    let n = meas.len();
    let u0 = spec.neutral_u();
    let lower: Vec<f64> = spec.params.iter().map(|q| q.lower_u).collect();
    let upper: Vec<f64> = spec.params.iter().map(|q| q.upper_u).collect();
    let mut runs = 0;
    let mut jac = DMatrix::zeros(n, p);
    let mut note = None;
    let start = start.filter(|j| j.nrows() == n && j.ncols() == p);
    if let Some(j0) = start {
        jac.copy_from(j0);
    }
    for (j, q) in spec.params.iter().enumerate() {
        if start.is_some() {
            break;
        }
        let mut h = q.step_u;
        if u0[j] + h > q.upper_u {
            h = -h;
        }
        let mut v = u0.clone();
        v[j] += h;
        runs += 1;
        match run(&v) {
            Some(eta) => {
                for i in 0..n {
                    jac[(i, j)] = (eta[i] - base[i]) / h;
                }
            }
            None => {
                note = Some(format!(
                    "the model failed at {}; sensitivity left at zero",
                    fmt_params(&spec.edge_params(&v))
                ));
            }
        }
    }
    let sensitivities = jac.clone();
    let mut lin = Linearisation {
        u: u0,
        eta_u: base.to_vec(),
        jac,
    };
    let all: Vec<usize> = (0..n).collect();
    let mut sse_u = sse(meas, &lin.eta_u);
    let mut converged = false;
    if !keep_going(&lin, 0) {
        return Fit {
            effect: spec.effect,
            lin,
            sensitivities,
            runs,
            converged: false,
            note: Some("stopped after the sensitivities: cannot compete".into()),
        };
    }
    for step in 0..options.max_steps {
        let v = lin.bounded_fit(meas, &all, &lower, &upper);
        let small = spec
            .params
            .iter()
            .enumerate()
            .all(|(j, q)| (v[j] - lin.u[j]).abs() < 0.01 * q.step_u);
        if small {
            converged = true;
            break;
        }
        // the step, then (if it raised the error) its half
        let mut accepted = false;
        for shrink in [1.0, 0.5] {
            let w: Vec<f64> = lin
                .u
                .iter()
                .zip(&v)
                .map(|(a, b)| a + shrink * (b - a))
                .collect();
            runs += 1;
            let Some(eta_w) = run(&w) else {
                note = Some(format!(
                    "the model failed at {}",
                    fmt_params(&spec.edge_params(&w))
                ));
                continue;
            };
            let sse_w = sse(meas, &eta_w);
            if sse_w <= sse_u {
                lin.update(&w, eta_w);
                sse_u = sse_w;
                accepted = true;
                break;
            }
            // keep the information about the slope, stay at u
            let mut probe = lin.clone();
            probe.update(&w, eta_w);
            lin.jac = probe.jac;
        }
        if !accepted {
            // no descent along the step: the current point is the best found
            converged = note.is_none();
            break;
        }
        if !keep_going(&lin, step + 1) {
            note.get_or_insert_with(|| "stopped early: cannot compete".into());
            break;
        }
    }
    if !converged && note.is_none() {
        note = Some(format!("step budget ({}) spent", options.max_steps));
    }
    Fit {
        effect: spec.effect,
        lin,
        sensitivities,
        runs,
        converged,
        note,
    }
}

pub fn fmt_params(p: &[(&'static str, f64)]) -> String {
    p.iter()
        .map(|(k, v)| format!("{k}={v:.4e}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Held-out residuals of a fitted candidate, leave one pump out.
#[derive(Debug, Clone)]
pub struct CrossValidation {
    /// Held-out residual of every row (meas - prediction).
    pub residual: Vec<f64>,
    /// The parameters refitted without each pump (in u), pump order.
    pub fold_u: Vec<Vec<f64>>,
}

/// Leave-one-pump-out cross-validation of the linearised candidate;
/// `pumps` lists each pump's row indices.
pub fn cross_validate(
    spec: &CandidateSpec,
    lin: &Linearisation,
    meas: &[f64],
    pumps: &[Vec<usize>],
) -> CrossValidation {
    let lower: Vec<f64> = spec.params.iter().map(|q| q.lower_u).collect();
    let upper: Vec<f64> = spec.params.iter().map(|q| q.upper_u).collect();
    let mut residual = vec![f64::NAN; meas.len()];
    let mut fold_u = Vec::with_capacity(pumps.len());
    for (k, held) in pumps.iter().enumerate() {
        let train: Vec<usize> = pumps
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != k)
            .flat_map(|(_, r)| r.iter().copied())
            .collect();
        let v = lin.bounded_fit(meas, &train, &lower, &upper);
        for &i in held {
            residual[i] = meas[i] - lin.predict(i, &v);
        }
        fold_u.push(v);
    }
    CrossValidation { residual, fold_u }
}

/// Mean squared residual of each pump.
pub fn pump_mse(residual: &[f64], pumps: &[Vec<usize>]) -> Vec<f64> {
    pumps
        .iter()
        .map(|rows| rows.iter().map(|&i| residual[i].powi(2)).sum::<f64>() / rows.len() as f64)
        .collect()
}

/// Root mean square of all residuals.
pub fn rmse(residual: &[f64]) -> f64 {
    (residual.iter().map(|r| r * r).sum::<f64>() / residual.len() as f64).sqrt()
}

/// Jackknife (leave one pump out) standard error of each parameter, edge
/// units, from the folds' parameters.
pub fn jackknife_se(spec: &CandidateSpec, fold_u: &[Vec<f64>]) -> Vec<f64> {
    let n = fold_u.len() as f64;
    (0..spec.params.len())
        .map(|j| {
            let edge: Vec<f64> = fold_u
                .iter()
                .map(|u| spec.params[j].transform.to_edge(u[j]))
                .collect();
            let m = edge.iter().sum::<f64>() / n;
            ((n - 1.0) / n * edge.iter().map(|x| (x - m).powi(2)).sum::<f64>()).sqrt()
        })
        .collect()
}

/// A candidate's score, as written to `diagnosis.json`.
#[derive(Debug, Clone, Serialize)]
pub struct CandidateScore {
    pub effect: &'static str,
    /// Fitted parameters, edge units.
    pub params: serde_json::Map<String, serde_json::Value>,
    /// Jackknife standard errors, same keys.
    pub params_se: serde_json::Map<String, serde_json::Value>,
    /// Root mean square of the held-out residuals.
    pub cv_rmse: f64,
    /// Root mean square of the residuals of the full-data fit (a real run
    /// when converged; else the linearisation's prediction).
    pub fit_rmse: f64,
    /// One-sided paired t over pumps: held-out error below the base model's.
    pub statistic: f64,
    pub p_value: f64,
    /// Holm-adjusted over all candidates.
    pub p_adjusted: f64,
    pub runs: usize,
    pub converged: bool,
    /// The parameters (and fit RMSE) are the linearisation's prediction: the
    /// fit stopped early (see `note`), not at a model run.
    pub params_predicted: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec1() -> CandidateSpec {
        CandidateSpec {
            effect: "thermal_clearance",
            params: vec![ParamSpec {
                name: "k",
                neutral: 0.0,
                step_u: 0.1,
                lower_u: -1.0,
                upper_u: 1.0,
                transform: Transform::Identity,
            }],
        }
    }

    /// A smooth non-linear "model": eta_i(k) = a_i - b_i (1 + k c_i)^3.
    fn model(k: f64) -> Vec<f64> {
        (0..40)
            .map(|i| {
                let a = 0.95 - 0.001 * (i % 7) as f64;
                let b = 0.03 + 0.002 * (i % 5) as f64;
                let c = 0.5 + 0.1 * (i % 3) as f64;
                a - b * (1.0 + k * c).powi(3)
            })
            .collect()
    }

    #[test]
    fn transforms_round_trip() {
        for t in [
            Transform::Identity,
            Transform::Scale(1e-8),
            Transform::Inverse,
            Transform::CubeRatio(15.0),
        ] {
            for x in [0.3, 1.0, 17.0] {
                assert!(
                    (t.to_edge(t.to_u(x)) - x).abs() < 1e-12 * x.max(1.0),
                    "{t:?}"
                );
            }
        }
    }

    #[test]
    fn the_secant_fit_finds_a_nonlinear_parameter_in_a_few_runs() {
        let truth = 0.37;
        let meas = model(truth);
        let base = model(0.0);
        let mut calls = 0;
        let fit = fit_candidate(
            &spec1(),
            &meas,
            &base,
            &mut |u| {
                calls += 1;
                Some(model(u[0]))
            },
            FitOptions { max_steps: 8 },
            &mut |_, _| true,
        );
        assert!((fit.lin.u[0] - truth).abs() < 1e-3, "{:?}", fit.lin.u);
        assert!(fit.converged);
        assert_eq!(fit.runs, calls);
        assert!(calls <= 7, "{calls} runs");
    }

    #[test]
    fn bounds_are_kept() {
        // the data want k = 0.37 but the candidate may not exceed 0.2
        let mut s = spec1();
        s.params[0].upper_u = 0.2;
        let meas = model(0.37);
        let base = model(0.0);
        let fit = fit_candidate(
            &s,
            &meas,
            &base,
            &mut |u| Some(model(u[0])),
            FitOptions::default(),
            &mut |_, _| true,
        );
        assert!((fit.lin.u[0] - 0.2).abs() < 1e-9, "{:?}", fit.lin.u);
    }

    #[test]
    fn two_parameter_fit_and_cross_validation() {
        // eta_i(u1, u2) linear in two directions, rows of 10 pumps
        let n = 60;
        let f = |u: &[f64]| -> Vec<f64> {
            (0..n)
                .map(|i| {
                    let w = if i % 2 == 0 { 1.0 } else { 0.3 };
                    0.9 - 0.02 * w * (u[0] - 1.0) - 0.01 * (1.0 - w) * (u[1] - 1.0)
                })
                .collect()
        };
        let spec = CandidateSpec {
            effect: "viscosity_shift",
            params: vec![
                ParamSpec {
                    name: "f1",
                    neutral: 1.0,
                    step_u: 0.2,
                    lower_u: 0.25,
                    upper_u: 4.0,
                    transform: Transform::Inverse,
                },
                ParamSpec {
                    name: "f2",
                    neutral: 1.0,
                    step_u: 0.2,
                    lower_u: 0.25,
                    upper_u: 4.0,
                    transform: Transform::Inverse,
                },
            ],
        };
        let meas = f(&[1.5, 0.8]);
        let fit = fit_candidate(
            &spec,
            &meas,
            &f(&[1.0, 1.0]),
            &mut |u| Some(f(u)),
            FitOptions::default(),
            &mut |_, _| true,
        );
        assert!((fit.lin.u[0] - 1.5).abs() < 1e-6 && (fit.lin.u[1] - 0.8).abs() < 1e-6);
        let edge = spec.edge_params(&fit.lin.u);
        assert!((edge[0].1 - 1.0 / 1.5).abs() < 1e-6);
        let pumps: Vec<Vec<usize>> = (0..10).map(|p| (p * 6..p * 6 + 6).collect()).collect();
        let cv = cross_validate(&spec, &fit.lin, &meas, &pumps);
        assert!(rmse(&cv.residual) < 1e-9);
        assert_eq!(cv.fold_u.len(), 10);
        let se = jackknife_se(&spec, &cv.fold_u);
        assert!(se.iter().all(|s| *s < 1e-6));
    }

    #[test]
    fn the_specs_cover_every_effect_and_build_effects() {
        let design = gearpump_core::design::Design::seed();
        let specs = candidate_specs(&design);
        assert_eq!(specs.len(), EFFECT_NAMES.len() + LOCATED.len());
        for s in &specs {
            let u0 = s.neutral_u();
            assert!(s.effect_at(&u0).is_ok(), "{}", s.effect);
            for (p, u) in s.params.iter().zip(&u0) {
                assert!(p.lower_u <= *u && *u <= p.upper_u, "{}", s.effect);
                assert!(p.lower_u < p.upper_u);
            }
            // the neutral effect's edge parameters are the neutral values
            let e = s.effect_at(&u0).unwrap();
            assert_eq!(e.name(), s.effect);
            for ((name, v), p) in e.params_edge().iter().zip(&s.params) {
                assert_eq!(*name, p.name);
                assert!((v - p.neutral).abs() < 1e-9 * p.neutral.abs().max(1.0));
            }
        }
    }
}
