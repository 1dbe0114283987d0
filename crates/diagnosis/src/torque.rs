//! The torque residual, treated as the flow residual is: what the shaft
//! torque error follows, which coefficient of the loss model (docs/model.md
//! section 6) explains it, and what stays unexplained.
//!
//! # Candidates
//! The residual of a test is `r = T_meas - T_sim` (N m). Each candidate is
//! one coefficient of the loss model being off by a relative amount theta,
//! which adds `theta C` to the torque, `C` the loss component it scales in
//! the base run of that test:
//!
//! | candidate | component C | coefficient | linear in it |
//! |---|---|---|---|
//! | `viscous_friction` | tip + lateral + bearing shear | the film viscosity (or the films' mean h) | exactly in mu; first order in h |
//! | `mesh_friction` | mesh Coulomb friction | `losses.mesh_friction_coefficient` | exactly |
//! | `thrust_plate_friction` | thrust-plate friction | `losses.thrust_plate_friction` x `thrust_plate_unbalance` | exactly |
//! | `churning` | churning drag | `losses.churning_coefficient` | exactly |
//! | `constant_drag` | 1 N m | a drag the model lacks (a shaft seal), theta in N m | exactly |
//!
//! # Give-back
//! A campaign runs each test given its measured torque, and the model's
//! mesh force takes the measurement less the model's own losses
//! (docs/model.md section 5): a loss the model lacks therefore passes
//! through its mesh force, and its mesh friction gives a share `k` of it
//! back to the simulated torque (about 186 N of mesh force per N m, so `k`
//! is near 0.05 for this pump). A loss `theta C` put into the model is taken
//! off the mesh force again, so the extended model's torque rises by `theta
//! C (1 - k)`, not `theta C`: the residual is fitted on `C (1 - k)`, and
//! `theta` is the loss itself (fitted on `C`, every theta came out 3-10 %
//! low and its 95 % interval missed the planted value in 28 of 30 planted
//! campaigns). `k` of each test is measured, not assumed: the same model run
//! again with every measured torque 2 % higher gives `k = dT_sim /
//! dT_meas` (one more run of the tests). Otherwise a loss coefficient
//! scarcely moves the flow or the pressures, so the components of the run
//! give the fit without further runs.
//!
//! # Newton step
//! The fit is linear in theta; the mesh friction's is not quite (its
//! coefficient scales its own give-back: theta came out 4-5 % low at
//! factors of 2). When the causes are loss-model coefficients (a design
//! key each: mesh, plate, churning), `diagnose` runs the model extended by
//! them at their thetas once more, and [`refine`] fits what that run leaves
//! on the same columns and adds it (`newton` in the JSON). The plate's step
//! is 1e-5, the mesh's 0.04-0.06 at factors of 2.
//!
//! # Decision
//! As for the flow (`diagnose`, module doc): theta by least squares;
//! leave-one-fold-out cross-validation (pumps, or working conditions with
//! fewer than four pumps); significance by the one-sided paired test of the
//! folds' held-out errors against the base model (the nested F test with
//! fewer pumps), Holm-adjusted over the candidates; the cause is the
//! significant candidate with the lowest cross-validated RMSE when it at
//! least halves the residual's structure (module `structure`, in N m
//! against a noise floor from the data); a second cause is fitted jointly
//! with the first and kept by the same rule; `unexplained` when the
//! structure left is material, `>= max(sigma, E0 / 4)`. A fit outside a
//! coefficient's physical bounds ([`THETA_BOUNDS`]) is refused.

use nalgebra::{DMatrix, DVector};
use serde_json::{json, Value};
use statrs::distribution::{ContinuousCDF, FisherSnedecor, StudentsT};

use super::stats::{holm, paired_improvement};
use super::structure::{gain_is_material, material_threshold, structure, Structure};
use gearpump_core::mechanics::torque::Losses;

/// The candidates, in the order of the module doc.
pub const TORQUE_CANDIDATES: [&str; 5] = [
    "viscous_friction",
    "mesh_friction",
    "thrust_plate_friction",
    "churning",
    "constant_drag",
];

/// Physical bounds of each candidate's theta: a loss coefficient stays
/// positive and within a factor four of the design's (mixed-lubrication
/// friction coefficients and drag coefficients are known to that), a
/// constant drag is a drag (0 to 2 N m: a shaft seal of this size). A fit
/// outside them is not a physical explanation and is refused.
pub const THETA_BOUNDS: [(f64, f64); 5] = [
    (-0.75, 3.0),
    (-0.75, 3.0),
    (-0.75, 3.0),
    (-0.75, 3.0),
    (0.0, 2.0),
];

/// The component candidate `k` scales, N m.
fn component(k: usize, l: &Losses) -> f64 {
    match k {
        0 => l.tip + l.lateral + l.bearings,
        1 => l.mesh,
        2 => l.plate,
        3 => l.churning,
        _ => 1.0,
    }
}

/// What each candidate's theta adds to the simulated torque at each test
/// (module doc, "Give-back").
fn columns(d: &TorqueData) -> Vec<Vec<f64>> {
    (0..TORQUE_CANDIDATES.len())
        .map(|k| {
            d.losses
                .iter()
                .zip(&d.give_back)
                .map(|(l, g)| component(k, l) * (1.0 - g))
                .collect()
        })
        .collect()
}

/// The tests a torque diagnosis uses (those with a measured torque).
#[derive(Debug, Clone)]
pub struct TorqueData {
    pub meas: Vec<f64>,
    pub sim: Vec<f64>,
    pub losses: Vec<Losses>,
    /// The share of a loss the model gives back through its measured-torque
    /// input at each test, `dT_sim / dT_meas` (module doc, "Give-back").
    pub give_back: Vec<f64>,
    /// Pump and condition group of each test; pressure, speed, temperature.
    pub pump_of: Vec<usize>,
    pub cond_of: Vec<usize>,
    pub x: Vec<[f64; 3]>,
    /// Cross-validation folds (row indices).
    pub folds: Vec<Vec<usize>>,
    /// Folds are pumps (a population) rather than working conditions.
    pub by_pump: bool,
}

/// Least squares of `r` on the columns `cols` of `c` over `rows`.
fn lsq(r: &[f64], c: &[Vec<f64>], cols: &[usize], rows: &[usize]) -> Option<Vec<f64>> {
    let a = DMatrix::from_fn(rows.len(), cols.len(), |i, j| c[cols[j]][rows[i]]);
    let b = DVector::from_fn(rows.len(), |i, _| r[rows[i]]);
    let sol = (a.transpose() * &a).lu().solve(&(a.transpose() * b))?;
    sol.iter()
        .all(|v| v.is_finite())
        .then(|| sol.iter().copied().collect())
}

struct Fitted {
    cols: Vec<usize>,
    theta: Vec<f64>,
    /// In-sample residual and held-out residual of every row.
    resid: Vec<f64>,
    cv: Vec<f64>,
    fold_theta: Vec<Vec<f64>>,
}

fn fit(r: &[f64], c: &[Vec<f64>], cols: &[usize], d: &TorqueData) -> Option<Fitted> {
    let all: Vec<usize> = (0..r.len()).collect();
    let theta = lsq(r, c, cols, &all)?;
    let pred = |i: usize, th: &[f64]| cols.iter().zip(th).map(|(&k, t)| t * c[k][i]).sum::<f64>();
    let resid: Vec<f64> = (0..r.len()).map(|i| r[i] - pred(i, &theta)).collect();
    let mut cv = vec![0.0; r.len()];
    let mut fold_theta = Vec::new();
    for f in &d.folds {
        let train: Vec<usize> = all.iter().copied().filter(|i| !f.contains(i)).collect();
        let th = lsq(r, c, cols, &train)?;
        for &i in f {
            cv[i] = r[i] - pred(i, &th);
        }
        fold_theta.push(th);
    }
    Some(Fitted {
        cols: cols.to_vec(),
        theta,
        resid,
        cv,
        fold_theta,
    })
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
}

/// The held-out error of each fold (mean square by pumps, RMS by
/// conditions, as for the flow).
fn fold_error(res: &[f64], d: &TorqueData) -> Vec<f64> {
    d.folds
        .iter()
        .map(|f| {
            let m = f.iter().map(|&i| res[i] * res[i]).sum::<f64>() / f.len() as f64;
            if d.by_pump {
                m
            } else {
                m.sqrt()
            }
        })
        .collect()
}

/// p of the candidate's improvement over the model `base_resid` it extends.
fn p_value(f: &Fitted, base_resid: &[f64], base_k: usize, d: &TorqueData) -> f64 {
    if d.by_pump {
        let (b, c) = (fold_error(base_resid, d), fold_error(&f.cv, d));
        let diff: Vec<f64> = b.iter().zip(&c).map(|(x, y)| x - y).collect();
        paired_improvement(&diff).1
    } else {
        let n = base_resid.len();
        let (s0, s1) = (
            base_resid.iter().map(|x| x * x).sum::<f64>(),
            f.resid.iter().map(|x| x * x).sum::<f64>(),
        );
        let k = f.cols.len() - base_k;
        if n <= f.cols.len() + 1 || s1 >= s0 || k == 0 {
            return 1.0;
        }
        let (d1, d2) = (k as f64, (n - f.cols.len()) as f64);
        let stat = ((s0 - s1) / d1) / (s1 / d2).max(f64::MIN_POSITIVE);
        FisherSnedecor::new(d1, d2)
            .map(|dist| 1.0 - dist.cdf(stat))
            .unwrap_or(1.0)
    }
}

fn structure_of(res: &[f64], d: &TorqueData) -> Structure {
    structure(res, &d.pump_of, &d.cond_of, &d.x)
}

/// Each fitted coefficient with its jackknife standard error over the folds
/// and 95 % interval.
fn params_json(f: &Fitted) -> Value {
    let n = f.fold_theta.len() as f64;
    let t = StudentsT::new(0.0, 1.0, (n - 1.0).max(1.0))
        .map(|s| s.inverse_cdf(0.975))
        .unwrap_or(f64::NAN);
    Value::Array(
        f.cols
            .iter()
            .enumerate()
            .map(|(j, &k)| {
                let m = f.fold_theta.iter().map(|v| v[j]).sum::<f64>() / n;
                let se = ((n - 1.0) / n
                    * f.fold_theta.iter().map(|v| (v[j] - m).powi(2)).sum::<f64>())
                .sqrt();
                json!({
                    "candidate": TORQUE_CANDIDATES[k],
                    // relative change of the coefficient (N m for constant_drag)
                    "theta": f.theta[j],
                    "theta_se": se,
                    "interval_95": [f.theta[j] - t * se, f.theta[j] + t * se],
                })
            })
            .collect(),
    )
}

/// The torque diagnosis (module doc) as its `diagnosis.json` record; None
/// with fewer than 3 tests.
pub fn torque_diagnosis(d: &TorqueData, alpha: f64) -> Option<Value> {
    let n = d.meas.len();
    if n < 3 {
        return None;
    }
    let r: Vec<f64> = d.meas.iter().zip(&d.sim).map(|(m, s)| m - s).collect();
    let c = columns(d);
    let base = structure_of(&r, d);
    let mut sigma = base.noise;
    let e0 = base.rmse;
    let mut causes: Vec<Fitted> = Vec::new();
    let mut current_resid = r.clone();
    let mut current = base.clone();
    let mut steps = Vec::new();
    while causes.len() < 2 {
        if !causes.is_empty() && current.structure < sigma.max(0.0) {
            break;
        }
        let held: Vec<usize> = causes.last().map(|f| f.cols.clone()).unwrap_or_default();
        let tried: Vec<(Fitted, f64)> = (0..TORQUE_CANDIDATES.len())
            .filter(|k| !held.contains(k))
            .filter_map(|k| {
                let mut cols = held.clone();
                cols.push(k);
                let f = fit(&r, &c, &cols, d)?;
                let inside = f
                    .cols
                    .iter()
                    .zip(&f.theta)
                    .all(|(&k, t)| (THETA_BOUNDS[k].0..=THETA_BOUNDS[k].1).contains(t));
                let p = if inside {
                    p_value(&f, &current_resid, held.len(), d)
                } else {
                    1.0
                };
                Some((f, p))
            })
            .collect();
        let adj = holm(&tried.iter().map(|t| t.1).collect::<Vec<_>>());
        let record: Vec<Value> = tried
            .iter()
            .zip(&adj)
            .map(|((f, p), a)| {
                json!({
                    "candidate": TORQUE_CANDIDATES[*f.cols.last().unwrap_or(&0)],
                    "theta": f.theta.last(),
                    "cv_rmse_nm": rms(&f.cv),
                    "p_value": p,
                    "p_adjusted": a,
                    "within_bounds": *p < 1.0 || f.cols.iter().zip(&f.theta).all(|(&k, t)| (THETA_BOUNDS[k].0..=THETA_BOUNDS[k].1).contains(t)),
                })
            })
            .collect();
        steps.push(Value::Array(record));
        let best = tried
            .into_iter()
            .zip(adj)
            .filter(|(_, a)| *a < alpha)
            .min_by(|a, b| rms(&a.0 .0.cv).total_cmp(&rms(&b.0 .0.cv)));
        let Some(((f, _), _)) = best else { break };
        let after = structure_of(&f.resid, d);
        if !gain_is_material(current.structure, after.structure) {
            break;
        }
        sigma = sigma.min(after.noise);
        current_resid = f.resid.clone();
        current = after;
        causes.push(f);
    }
    let tau = material_threshold(sigma, e0);
    let last = causes.last();
    Some(json!({
        "tests": n,
        "baseline_rmse_nm": e0,
        "noise_floor_nm": sigma,
        "give_back": {
            "min": d.give_back.iter().copied().fold(f64::INFINITY, f64::min),
            "max": d.give_back.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        },
        "structure_nm": { "baseline": base.structure, "final": current.structure, "threshold": tau },
        "candidates": steps,
        "cause": last.map(|f| TORQUE_CANDIDATES[f.cols[0]]),
        "causes": last.map(|f| f.cols.iter().map(|&k| TORQUE_CANDIDATES[k]).collect::<Vec<_>>()).unwrap_or_default(),
        "params": last.map(params_json),
        "rmse_after_nm": last.map(|f| rms(&f.resid)),
        "unexplained": current.structure >= tau,
    }))
}

/// One Newton step on the torque causes of `t` (a [`torque_diagnosis`] of
/// `d`) from a run of the model extended by them at their thetas:
/// `resid` is that run's `T_meas - T_sim` at each test of `d`. The step
/// fits `resid` on the causes' columns (as the diagnosis did) and adds it
/// to each theta and its interval; `t["newton"]` keeps the thetas of the
/// linear fit, the run's RMSE and the step. It takes what the linear fit
/// misses: a coefficient that feeds its own give-back (the mesh friction:
/// its coefficient scales the share too), and whatever else the run moves.
/// Returns false (and leaves `t`) when the step cannot be fitted.
pub fn refine(t: &mut Value, d: &TorqueData, resid: &[f64]) -> bool {
    let Some(params) = t["params"].as_array() else {
        return false;
    };
    let cols: Vec<usize> = params
        .iter()
        .filter_map(|p| {
            let name = p["candidate"].as_str()?;
            TORQUE_CANDIDATES.iter().position(|c| *c == name)
        })
        .collect();
    if cols.len() != params.len()
        || resid.len() != d.meas.len()
        || resid.iter().any(|r| !r.is_finite())
    {
        return false;
    }
    let c = columns(d);
    let all: Vec<usize> = (0..resid.len()).collect();
    let Some(step) = lsq(resid, &c, &cols, &all) else {
        return false;
    };
    let after: Vec<f64> = (0..resid.len())
        .map(|i| {
            resid[i]
                - cols
                    .iter()
                    .zip(&step)
                    .map(|(&k, s)| s * c[k][i])
                    .sum::<f64>()
        })
        .collect();
    let linear: Vec<Value> = params.iter().map(|p| p["theta"].clone()).collect();
    if let Some(params) = t["params"].as_array_mut() {
        for (p, s) in params.iter_mut().zip(&step) {
            let shift = |v: &Value| v.as_f64().map(|x| json!(x + s)).unwrap_or(Value::Null);
            p["theta"] = shift(&p["theta"]);
            if let Some(iv) = p["interval_95"].as_array_mut() {
                for v in iv.iter_mut() {
                    *v = shift(v);
                }
            }
        }
    }
    t["newton"] = json!({
        "theta_linear": linear,
        "step": step,
        "rmse_run_nm": rms(resid),
        "rmse_after_nm": rms(&after),
    });
    t["rmse_after_nm"] = json!(rms(&after));
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use crate::testing::normal;

    /// A hand-made campaign of 20 pumps at the 14 conditions of seed Table 2
    /// with loss components of the laws' shapes (shear ~ mu n, Coulomb and
    /// plate ~ dp with their own pump spread, churning ~ n^2), and the
    /// measured torque `truth` of the components plus 0.2 % noise.
    fn campaign(truth: impl Fn(&Losses, [f64; 3]) -> f64, seed: u64) -> TorqueData {
        campaign_giving_back(truth, seed, |_| 0.0)
    }

    /// [`campaign`] with a model that gives back the share `give_back(x)`
    /// of what the measured torque exceeds its own (module doc,
    /// "Give-back"): its simulated torque is its own plus that share.
    fn campaign_giving_back(
        truth: impl Fn(&Losses, [f64; 3]) -> f64,
        seed: u64,
        give_back: impl Fn([f64; 3]) -> f64,
    ) -> TorqueData {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let conds: Vec<[f64; 3]> = [60.0, 120.0]
            .iter()
            .flat_map(|&t| {
                [
                    [10.0, 1000.0, t],
                    [20.0, 1000.0, t],
                    [30.0, 1000.0, t],
                    [40.0, 1000.0, t],
                    [30.0, 500.0, t],
                    [30.0, 2000.0, t],
                    [30.0, 4000.0, t],
                ]
            })
            .collect();
        let mut d = TorqueData {
            meas: vec![],
            sim: vec![],
            losses: vec![],
            give_back: vec![],
            pump_of: vec![],
            cond_of: vec![],
            x: vec![],
            folds: vec![],
            by_pump: true,
        };
        for p in 0..20 {
            let spread = 1.0 + 0.05 * (((p * 7) % 11) as f64 / 5.0 - 1.0);
            let mut fold = vec![];
            for (k, x) in conds.iter().enumerate() {
                let mu = if x[2] < 90.0 { 1.0 } else { 0.35 };
                let l = Losses {
                    tip: 0.02 * mu * x[1] / 1000.0 * spread,
                    lateral: 0.03 * mu * x[1] / 1000.0,
                    bearings: 0.05 * mu * x[1] / 1000.0,
                    mesh: 0.012 * x[0] * (1.0 + 0.1 * x[1] / 1000.0),
                    plate: 0.015 * x[0] * spread,
                    churning: 0.02 * (x[1] / 1000.0).powi(2),
                };
                let hyd = 0.2 * x[0];
                let t_sim = hyd + l.total();
                let t_meas = hyd + truth(&l, *x);
                fold.push(d.meas.len());
                let t_meas = t_meas * (1.0 + 0.002 * normal(&mut rng));
                let g = give_back(*x);
                d.meas.push(t_meas);
                d.sim.push(t_sim + g * (t_meas - t_sim));
                d.losses.push(l);
                d.give_back.push(g);
                d.pump_of.push(p);
                d.cond_of.push(k);
                d.x.push(*x);
            }
            d.folds.push(fold);
        }
        d
    }

    #[test]
    fn a_churning_coefficient_off_by_half_is_named_with_its_size() {
        let d = campaign(|l, _| l.total() + 0.5 * l.churning, 1);
        let v = torque_diagnosis(&d, 0.05).unwrap();
        assert_eq!(v["cause"], "churning", "{v}");
        let p = &v["params"][0];
        let (lo, hi) = (
            p["interval_95"][0].as_f64().unwrap(),
            p["interval_95"][1].as_f64().unwrap(),
        );
        assert!(lo <= 0.5 && 0.5 <= hi, "{p}");
        assert_eq!(v["unexplained"], false, "{v}");
    }

    /// A thrust plate 40 % stiffer in friction, on a model that gives back
    /// 3-9 % of a missing loss (more at higher pressure): theta is the
    /// loss's own 0.4, within its interval; read without the give-back the
    /// same data give theta (1 - k) and an interval that misses 0.4.
    #[test]
    fn a_loss_the_model_gives_back_is_fitted_at_its_size() {
        let k = |x: [f64; 3]| 0.03 + 0.06 * x[0] / 40.0;
        let mut d = campaign_giving_back(|l, _| l.total() + 0.4 * l.plate, 4, k);
        let interval = |v: &Value| {
            let p = &v["params"][0];
            assert_eq!(v["cause"], "thrust_plate_friction", "{v}");
            (
                p["interval_95"][0].as_f64().unwrap(),
                p["interval_95"][1].as_f64().unwrap(),
            )
        };
        let (lo, hi) = interval(&torque_diagnosis(&d, 0.05).unwrap());
        assert!(lo <= 0.4 && 0.4 <= hi, "[{lo}, {hi}]");
        d.give_back.iter_mut().for_each(|g| *g = 0.0);
        let (lo, hi) = interval(&torque_diagnosis(&d, 0.05).unwrap());
        assert!(hi < 0.4, "without the give-back: [{lo}, {hi}]");
    }

    /// The Newton step: a run of the extended model that leaves 0.05 of
    /// the cause's column (a coefficient whose effect is not linear in it)
    /// moves theta and its interval by 0.05 and takes that residual away;
    /// a run that leaves nothing moves nothing.
    #[test]
    fn the_newton_step_adds_what_the_run_leaves() {
        let d = campaign(|l, _| l.total() + 0.4 * l.plate, 5);
        let t0 = torque_diagnosis(&d, 0.05).unwrap();
        let theta0 = t0["params"][0]["theta"].as_f64().unwrap();
        let lo0 = t0["params"][0]["interval_95"][0].as_f64().unwrap();
        // the run at theta0 as the fit predicts it, plus 0.05 of the plate
        let fitted: Vec<f64> = (0..d.meas.len())
            .map(|i| d.meas[i] - d.sim[i] - theta0 * d.losses[i].plate)
            .collect();
        for (extra, want) in [(0.05, 0.05), (0.0, 0.0)] {
            let resid: Vec<f64> = (0..d.meas.len())
                .map(|i| fitted[i] + extra * d.losses[i].plate)
                .collect();
            let mut t = t0.clone();
            assert!(refine(&mut t, &d, &resid));
            let theta = t["params"][0]["theta"].as_f64().unwrap();
            let lo = t["params"][0]["interval_95"][0].as_f64().unwrap();
            assert!((theta - theta0 - want).abs() < 1e-9, "{theta} {theta0}");
            assert!((lo - lo0 - want).abs() < 1e-9);
            assert!(t["newton"]["rmse_after_nm"].as_f64().unwrap() <= rms(&fitted) + 1e-12);
            assert_eq!(t["newton"]["theta_linear"][0].as_f64(), Some(theta0));
        }
        // a residual that is not finite leaves it
        let mut t = t0.clone();
        assert!(!refine(&mut t, &d, &vec![f64::NAN; d.meas.len()]));
        assert_eq!(t, t0);
    }

    #[test]
    fn the_model_as_measured_gives_no_cause() {
        let d = campaign(|l, _| l.total(), 2);
        let v = torque_diagnosis(&d, 0.05).unwrap();
        assert!(v["cause"].is_null(), "{v}");
        assert_eq!(v["unexplained"], false, "{v}");
    }

    /// A loss no candidate has is reported unexplained: mixed friction that
    /// grows as the oil thins (Stribeck: boundary contact under a thinner
    /// film), `k p / mu`, 2.9 times larger at 120 than at 60 degC, while the
    /// model's Coulomb coefficients are constant and its shear falls with mu.
    #[test]
    fn a_loss_outside_the_candidates_is_unexplained() {
        let d = campaign(
            |l, x| {
                let thin = if x[2] < 90.0 { 1.0 } else { 1.0 / 0.35 };
                l.total() + 0.01 * x[0] * thin
            },
            3,
        );
        let v = torque_diagnosis(&d, 0.05).unwrap();
        assert_eq!(v["unexplained"], true, "{v}");
    }
}
