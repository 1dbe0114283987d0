//! Screening every pair of candidates on their first-step linearisations.
//!
//! Forward selection fits each cause on top of the ones before it, and the
//! refinement refits one slot at a time with the others held. With two
//! effects at once this can stop at a pair that only mimics the truth: a
//! first pick that absorbed part of both effects (a viscosity curve standing
//! in for a clearance opening plus a displacement error) keeps its partner
//! fitted to its own shape, and no single-slot refit can move both at once.
//!
//! Every candidate of the first step was fitted from the base model, so its
//! linearisation `eta_k(v) = eta_k(u_k) + J_k (v - u_k)` holds its effect on
//! every test near its fitted point. Effects of different mechanisms add to
//! first order (each changes its own leakage path, fluid property or
//! displacement), so a pair is modelled as
//!
//! `eta_ab(v_a, v_b) = eta_a(v_a) + eta_b(v_b) - eta_base`,
//!
//! a linearisation in the concatenated parameters. Each pair is fitted
//! within the candidates' bounds and cross-validated over the same folds as
//! the candidates, at no cost in model runs. The screen ranks the pairs; the
//! diagnosis then fits the best pair (and the one it has) on the real model
//! before it decides between them (`diagnose`, "pair check").

use super::candidates::{cross_validate, pump_mse, rmse, CandidateSpec, Linearisation};
use nalgebra::DMatrix;

/// One screened pair: candidate indices, fitted parameters (in u, `a`'s
/// then `b`'s), held-out RMSE and held-out mean squared error per fold.
#[derive(Debug, Clone)]
pub struct PairScreen {
    pub a: usize,
    pub b: usize,
    pub u: Vec<f64>,
    pub cv_rmse: f64,
    pub fold_mse: Vec<f64>,
    pub n_params: usize,
}

/// The pair's candidate (parameters of `a` then of `b`) and its additive
/// linearisation about `base`.
pub fn pair_model(
    a: (&CandidateSpec, &Linearisation),
    b: (&CandidateSpec, &Linearisation),
    base: &[f64],
) -> (CandidateSpec, Linearisation) {
    let (sa, la) = a;
    let (sb, lb) = b;
    let n = base.len();
    let (pa, pb) = (la.u.len(), lb.u.len());
    let spec = CandidateSpec {
        effect: "pair",
        params: sa.params.iter().chain(&sb.params).cloned().collect(),
    };
    let lin = Linearisation {
        u: la.u.iter().chain(&lb.u).copied().collect(),
        eta_u: (0..n)
            .map(|i| la.eta_u[i] + lb.eta_u[i] - base[i])
            .collect(),
        jac: DMatrix::from_fn(n, pa + pb, |i, j| {
            if j < pa {
                la.jac[(i, j)]
            } else {
                lb.jac[(i, j - pa)]
            }
        }),
    };
    (spec, lin)
}

/// Every pair `(a, b)`, `a < b`, of `cands` that `allowed(a, b)` admits
/// (candidates of different kinds), fitted and cross-validated on the
/// additive linearisation; sorted by held-out RMSE.
pub fn screen_pairs(
    cands: &[(&CandidateSpec, &Linearisation)],
    base: &[f64],
    meas: &[f64],
    folds: &[Vec<usize>],
    allowed: impl Fn(usize, usize) -> bool,
) -> Vec<PairScreen> {
    let all: Vec<usize> = (0..meas.len()).collect();
    let mut out = Vec::new();
    for a in 0..cands.len() {
        for b in a + 1..cands.len() {
            if !allowed(a, b) {
                continue;
            }
            let (spec, lin) = pair_model(cands[a], cands[b], base);
            let lower: Vec<f64> = spec.params.iter().map(|q| q.lower_u).collect();
            let upper: Vec<f64> = spec.params.iter().map(|q| q.upper_u).collect();
            let u = lin.bounded_fit(meas, &all, &lower, &upper);
            let cv = cross_validate(&spec, &lin, meas, folds);
            let cv_rmse = rmse(&cv.residual);
            if !cv_rmse.is_finite() {
                continue;
            }
            out.push(PairScreen {
                a,
                b,
                u,
                cv_rmse,
                fold_mse: pump_mse(&cv.residual, folds),
                n_params: spec.params.len(),
            });
        }
    }
    out.sort_by(|x, y| x.cv_rmse.total_cmp(&y.cv_rmse));
    out
}

#[cfg(test)]
mod tests {
    use super::super::candidates::{ParamSpec, Transform};
    use super::*;

    fn spec(name: &'static str, p: usize) -> CandidateSpec {
        CandidateSpec {
            effect: name,
            params: (0..p)
                .map(|_| ParamSpec {
                    name: "x",
                    neutral: 0.0,
                    step_u: 0.1,
                    lower_u: -10.0,
                    upper_u: 10.0,
                    transform: Transform::Identity,
                })
                .collect(),
        }
    }

    /// Three linear effects on 20 pumps x 12 conditions: A a slope in
    /// condition, B a level, C a mimic of A + B fitted alone (the
    /// combination at one magnitude). The truth is A = 1.5, B = -0.8 with
    /// a deterministic small scatter; a single-candidate fit favours C, but
    /// the screen ranks (A, B) first with their magnitudes, and (A, C),
    /// (B, C) behind it.
    #[test]
    fn the_true_pair_ranks_first_with_its_magnitudes() {
        let (pumps, conds) = (20, 12);
        let n = pumps * conds;
        let base = vec![0.9; n];
        let col_a: Vec<f64> = (0..n).map(|i| 0.002 * (i % conds) as f64).collect();
        let col_b: Vec<f64> = (0..n).map(|i| 0.01 + 0.0005 * (i / conds) as f64).collect();
        // C follows A + B in a fixed ratio with a curvature of its own
        let col_c: Vec<f64> = (0..n)
            .map(|i| {
                let c = (i % conds) as f64;
                col_a[i] * 1.5 - col_b[i] * 0.8 + 1e-4 * (c - 5.5).powi(2)
            })
            .collect();
        // a deterministic scatter of RMS about 1e-4
        let noise = |i: usize| 1e-4 * ((i as f64 * 12.9898).sin() * 43758.5453).fract();
        let meas: Vec<f64> = (0..n)
            .map(|i| base[i] + 1.5 * col_a[i] - 0.8 * col_b[i] + noise(i))
            .collect();
        let lin = |col: &Vec<f64>| Linearisation {
            u: vec![0.0],
            eta_u: base.clone(),
            jac: DMatrix::from_fn(n, 1, |i, _| col[i]),
        };
        let (la, lb, lc) = (lin(&col_a), lin(&col_b), lin(&col_c));
        let (sa, sb, sc) = (spec("a", 1), spec("b", 1), spec("c", 1));
        let cands = [(&sa, &la), (&sb, &lb), (&sc, &lc)];
        let folds: Vec<Vec<usize>> = (0..pumps)
            .map(|p| (p * conds..(p + 1) * conds).collect())
            .collect();
        let screen = screen_pairs(&cands, &base, &meas, &folds, |_, _| true);
        assert_eq!(screen.len(), 3);
        let best = &screen[0];
        assert_eq!((best.a, best.b), (0, 1), "{screen:?}");
        assert!((best.u[0] - 1.5).abs() < 0.02, "{:?}", best.u);
        assert!((best.u[1] + 0.8).abs() < 0.02, "{:?}", best.u);
        assert!(best.cv_rmse < 2e-4, "{}", best.cv_rmse);
        assert!(screen[1].cv_rmse > 1.5 * best.cv_rmse, "{screen:?}");
        // a pair the caller rules out is not screened
        let none = screen_pairs(&cands, &base, &meas, &folds, |a, b| (a, b) != (0, 1));
        assert!(none.iter().all(|s| (s.a, s.b) != (0, 1)));
    }
}
