//! The statistics of a Monte Carlo study, free of the model: percentiles,
//! yield with its confidence interval, and first-order and total Sobol
//! indices by pick-freeze.
//!
//! # Percentiles
//! Linear interpolation between order statistics (Hyndman & Fan 1996,
//! definition 7; the default of numpy's `percentile` and R's `quantile`):
//! with the `n` finite values sorted, `x_(1) <= ... <= x_(n)`, the `p`-th
//! percentile is `x_(k) + f (x_(k+1) - x_(k))` with `h = (n - 1) p / 100`,
//! `k = floor(h) + 1`, `f = h - floor(h)`.
//!
//! # Yield
//! The share of pumps meeting the specification, with the Wilson score
//! interval at 95 % (`z = 1.959964`): for `k` of `n`,
//! `(p + z^2/2n -+ z sqrt(p (1 - p)/n + z^2/4n^2)) / (1 + z^2/n)`, `p = k/n`.
//! It stays inside [0, 1] and is not degenerate at a yield of 0 or 1, where
//! the normal approximation is.
//!
//! # Variance-based sensitivity (Sobol indices)
//! For an output `Y = f(X_1, ..., X_k)` of independent inputs, the
//! first-order index of `X_i` is the share of `Var(Y)` its own variation
//! explains, `S_i = Var(E[Y | X_i]) / Var(Y)`, and the total index the share
//! in which it takes part at all, `S_Ti = E[Var(Y | X_~i)] / Var(Y)`.
//! Estimated by pick-freeze (Saltelli et al. 2010, Comput. Phys. Commun.
//! 181, 259-270, their Table 2 (b) and (f)): two independent samples `A` and
//! `B` of `N` input vectors, and for each `i` the matrix `A_B^i`, `A` with
//! its `i`-th column taken from `B`. Then
//!
//! * `S_i  = (1/N) sum_j f(B)_j (f(A_B^i)_j - f(A)_j) / V` (Saltelli 2010),
//! * `S_Ti = (1/2N) sum_j (f(A)_j - f(A_B^i)_j)^2 / V` (Jansen 1999),
//!
//! with `V` the variance of the `2N` outputs of `A` and `B` together
//! (divisor `2N - 1`) and `f(B)` centred by their mean (`f(B)_j - f_0`
//! in the first sum, `f_0` the mean of the `2N` outputs). Centring leaves
//! the estimator's expectation unchanged (`f(A_B^i) - f(A)` has mean
//! zero) but not its spread, which grows with `f_0^2 / V`: the pumps'
//! eta_v of 0.96 +- 0.003 gave first-order indices of +-100 from 8 pairs
//! uncentred, within [-0.4, 1.5] centred (and near the indices of 200
//! pairs: 0.26, 0.79, 0.01, 0.03 at 1000 rpm, 30 bar, 60 degC). Cost: `N (k + 2)` model runs. Both estimators are
//! unbiased for independent inputs; the first-order one can come out
//! slightly negative for an input that does nothing (its standard error is
//! of order `1/sqrt(N)`). A pair with a non-finite output anywhere is left
//! out. Tested against the Ishigami function and a linear model, whose
//! indices are known in closed form (tests below).

use serde::Serialize;

/// The percentiles every quantity is summarised by.
pub const PERCENTILES: [f64; 5] = [1.0, 5.0, 50.0, 95.0, 99.0];

/// The `p`-th percentile (0..=100) of the finite values (definition 7 in
/// the module doc); None when there are none.
pub fn percentile(values: &[f64], p: f64) -> Option<f64> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() || !(0.0..=100.0).contains(&p) {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(percentile_sorted(&v, p))
}

/// [`percentile`] of values already sorted and finite (not empty).
pub fn percentile_sorted(sorted: &[f64], p: f64) -> f64 {
    let h = (sorted.len() - 1) as f64 * p / 100.0;
    let lo = h.floor() as usize;
    let f = h - h.floor();
    match sorted.get(lo + 1) {
        Some(&next) if f > 0.0 => sorted[lo] + f * (next - sorted[lo]),
        _ => sorted[lo],
    }
}

/// Mean and sample standard deviation (divisor n - 1) of the finite values.
pub fn mean_std(values: &[f64]) -> (Option<f64>, Option<f64>) {
    let v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return (None, None);
    }
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let s =
        (v.len() > 1).then(|| (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt());
    (Some(m), s)
}

/// The distribution of one quantity at one condition.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Distribution {
    /// Finite values (failed simulations left out).
    pub n: usize,
    pub mean: Option<f64>,
    pub std: Option<f64>,
    pub min: Option<f64>,
    pub max: Option<f64>,
    /// The [`PERCENTILES`], in order.
    pub percentiles: Vec<Option<f64>>,
}

/// [`Distribution`] of the finite values.
pub fn distribution(values: &[f64]) -> Distribution {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    let (mean, std) = mean_std(&v);
    Distribution {
        n: v.len(),
        mean,
        std,
        min: v.first().copied(),
        max: v.last().copied(),
        percentiles: PERCENTILES
            .iter()
            .map(|&p| (!v.is_empty()).then(|| percentile_sorted(&v, p)))
            .collect(),
    }
}

/// A yield: `pass` of `n` pumps, with the Wilson 95 % interval.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Yield {
    pub pass: usize,
    pub n: usize,
    pub share: Option<f64>,
    pub ci95: Option<[f64; 2]>,
}

/// The standard normal quantile at 0.975.
const Z95: f64 = 1.959_963_984_540_054;

/// `pass` of `n` with the Wilson score interval (module doc).
pub fn yield_of(pass: usize, n: usize) -> Yield {
    if n == 0 {
        return Yield {
            pass,
            n,
            share: None,
            ci95: None,
        };
    }
    let nf = n as f64;
    let p = pass as f64 / nf;
    let z2 = Z95 * Z95;
    let centre = p + z2 / (2.0 * nf);
    let half = Z95 * (p * (1.0 - p) / nf + z2 / (4.0 * nf * nf)).sqrt();
    let d = 1.0 + z2 / nf;
    Yield {
        pass,
        n,
        share: Some(p),
        // at k = 0 (k = n) the bound is 0 (1) exactly; rounding would miss it
        ci95: Some([
            if pass == 0 {
                0.0
            } else {
                ((centre - half) / d).max(0.0)
            },
            if pass == n {
                1.0
            } else {
                ((centre + half) / d).min(1.0)
            },
        ]),
    }
}

/// First-order and total indices of one input.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SobolIndex {
    /// First-order index `S_i` (Saltelli 2010).
    pub first: f64,
    /// Total index `S_Ti` (Jansen 1999).
    pub total: f64,
}

/// The indices of every input from the outputs of `A`, `B` and each
/// `A_B^i` (`ab[i][j]`: pair `j` with input `i` from `B`), by the
/// estimators of the module doc; None when fewer than two pairs are
/// finite or the outputs do not vary. Also returns the pairs used.
pub fn sobol_indices(ya: &[f64], yb: &[f64], ab: &[Vec<f64>]) -> (Option<Vec<SobolIndex>>, usize) {
    let n = ya.len().min(yb.len());
    let ok: Vec<usize> = (0..n)
        .filter(|&j| {
            ya[j].is_finite()
                && yb[j].is_finite()
                && ab.iter().all(|c| c.get(j).is_some_and(|x| x.is_finite()))
        })
        .collect();
    let m = ok.len();
    if m < 2 {
        return (None, m);
    }
    let all: Vec<f64> = ok.iter().flat_map(|&j| [ya[j], yb[j]]).collect();
    let (Some(mean), Some(sd)) = mean_std(&all) else {
        return (None, m);
    };
    let v = sd * sd;
    if v.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return (None, m);
    }
    let mf = m as f64;
    let idx = ab
        .iter()
        .map(|c| {
            let mut first = 0.0;
            let mut total = 0.0;
            for &j in &ok {
                first += (yb[j] - mean) * (c[j] - ya[j]);
                total += (ya[j] - c[j]).powi(2);
            }
            SobolIndex {
                first: first / mf / v,
                total: total / (2.0 * mf) / v,
            }
        })
        .collect();
    (Some(idx), m)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution as _, StandardNormal};

    #[test]
    fn percentiles_by_hand() {
        let v = [5.0, 1.0, 4.0, 2.0, 3.0, f64::NAN];
        // sorted 1 2 3 4 5; h = 4 p / 100
        assert_eq!(percentile(&v, 50.0), Some(3.0));
        assert_eq!(percentile(&v, 25.0), Some(2.0));
        assert_eq!(percentile(&v, 0.0), Some(1.0));
        assert_eq!(percentile(&v, 100.0), Some(5.0));
        // h = 0.4 -> 1 + 0.4 (2 - 1)
        assert!((percentile(&v, 10.0).unwrap() - 1.4).abs() < 1e-15);
        // h = 3.96 -> 4 + 0.96
        assert!((percentile(&v, 99.0).unwrap() - 4.96).abs() < 1e-15);
        assert_eq!(percentile(&[7.0], 95.0), Some(7.0));
        assert_eq!(percentile(&[f64::NAN], 50.0), None);
        let d = distribution(&[2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0]);
        assert_eq!(
            (d.n, d.mean, d.min, d.max),
            (8, Some(5.0), Some(2.0), Some(9.0))
        );
        // sum of squares 32, divisor 7
        assert!((d.std.unwrap() - (32.0f64 / 7.0).sqrt()).abs() < 1e-15);
        // h = 3.5 -> 4 + 0.5 (5 - 4)
        assert_eq!(d.percentiles[2], Some(4.5));
    }

    #[test]
    fn yield_and_its_wilson_interval_by_hand() {
        let y = yield_of(3, 4);
        assert_eq!(y.share, Some(0.75));
        // Wilson, z = 1.96: centre (0.75 + 0.4802) / 1.9604, half
        // 1.96 sqrt(0.046875 + 0.0600) / 1.9604
        let z: f64 = 1.959963984540054;
        let c = (0.75 + z * z / 8.0) / (1.0 + z * z / 4.0);
        let h = z * (0.75f64 * 0.25 / 4.0 + z * z / 64.0).sqrt() / (1.0 + z * z / 4.0);
        let [lo, hi] = y.ci95.unwrap();
        assert!((lo - (c - h)).abs() < 1e-12 && (hi - (c + h)).abs() < 1e-12);
        assert!(
            (lo - 0.3006).abs() < 1e-3 && (hi - 0.9544).abs() < 1e-3,
            "{lo} {hi}"
        );
        let all = yield_of(10, 10);
        assert_eq!(all.share, Some(1.0));
        assert!(all.ci95.unwrap()[1] == 1.0 && all.ci95.unwrap()[0] < 1.0);
        assert_eq!(yield_of(0, 0).share, None);
    }

    fn ishigami(x: [f64; 3]) -> f64 {
        let (a, b) = (7.0, 0.1);
        x[0].sin() + a * x[1].sin().powi(2) + b * x[2].powi(4) * x[0].sin()
    }

    /// The Ishigami function on U(-pi, pi)^3 (a = 7, b = 0.1) has
    /// V = a^2/8 + b pi^4/5 + b^2 pi^8/18 + 1/2, V1 = (1 + b pi^4/5)^2 / 2,
    /// V2 = a^2/8, V3 = 0, V13 = b^2 pi^8 (1/18 - 1/50): closed forms
    /// (Ishigami & Homma 1990; Sobol & Levitan 1999).
    #[test]
    fn sobol_indices_of_the_ishigami_function() {
        let pi = std::f64::consts::PI;
        let (a, b) = (7.0f64, 0.1f64);
        let v1 = (1.0 + b * pi.powi(4) / 5.0).powi(2) / 2.0;
        let v2 = a * a / 8.0;
        let v13 = b * b * pi.powi(8) * (1.0 / 18.0 - 1.0 / 50.0);
        let v = v1 + v2 + v13;
        let exact_first = [v1 / v, v2 / v, 0.0];
        let exact_total = [(v1 + v13) / v, v2 / v, v13 / v];
        let n = 40_000;
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut draw = || [0; 3].map(|_| rng.gen_range(-pi..pi));
        let a_m: Vec<[f64; 3]> = (0..n).map(|_| draw()).collect();
        let b_m: Vec<[f64; 3]> = (0..n).map(|_| draw()).collect();
        let ya: Vec<f64> = a_m.iter().map(|x| ishigami(*x)).collect();
        let yb: Vec<f64> = b_m.iter().map(|x| ishigami(*x)).collect();
        let ab: Vec<Vec<f64>> = (0..3)
            .map(|i| {
                (0..n)
                    .map(|j| {
                        let mut x = a_m[j];
                        x[i] = b_m[j][i];
                        ishigami(x)
                    })
                    .collect()
            })
            .collect();
        let (idx, used) = sobol_indices(&ya, &yb, &ab);
        let idx = idx.unwrap();
        assert_eq!(used, n);
        for i in 0..3 {
            // standard errors at N = 40000 are about 0.005-0.008
            assert!(
                (idx[i].first - exact_first[i]).abs() < 0.025,
                "S{i} {:?} vs {}",
                idx[i],
                exact_first[i]
            );
            assert!(
                (idx[i].total - exact_total[i]).abs() < 0.025,
                "ST{i} {:?} vs {}",
                idx[i],
                exact_total[i]
            );
        }
        // the exact values themselves, as published: 0.3139, 0.4424, 0
        assert!((exact_first[0] - 0.3139).abs() < 1e-4 && (exact_first[1] - 0.4424).abs() < 1e-4);
    }

    /// A linear model of independent normals, Y = sum c_i X_i: S_i = S_Ti =
    /// c_i^2 s_i^2 / sum_k c_k^2 s_k^2. A pair with a NaN is left out.
    #[test]
    fn sobol_indices_of_a_linear_model() {
        let c = [1.0, -2.0, 0.5, 0.0];
        let s = [1.0, 0.5, 2.0, 3.0];
        let f = |x: [f64; 4]| (0..4).map(|i| c[i] * x[i]).sum::<f64>();
        let var: f64 = (0..4).map(|i| (c[i] * s[i]).powi(2)).sum();
        let n = 20_000;
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut draw = || {
            let mut x = [0.0; 4];
            for i in 0..4 {
                let z: f64 = StandardNormal.sample(&mut rng);
                x[i] = 10.0 + s[i] * z;
            }
            x
        };
        let a_m: Vec<[f64; 4]> = (0..n).map(|_| draw()).collect();
        let b_m: Vec<[f64; 4]> = (0..n).map(|_| draw()).collect();
        let mut ya: Vec<f64> = a_m.iter().map(|x| f(*x)).collect();
        let yb: Vec<f64> = b_m.iter().map(|x| f(*x)).collect();
        ya[5] = f64::NAN;
        let ab: Vec<Vec<f64>> = (0..4)
            .map(|i| {
                (0..n)
                    .map(|j| {
                        let mut x = a_m[j];
                        x[i] = b_m[j][i];
                        f(x)
                    })
                    .collect()
            })
            .collect();
        let (idx, used) = sobol_indices(&ya, &yb, &ab);
        assert_eq!(used, n - 1);
        let idx = idx.unwrap();
        for i in 0..4 {
            let exact = (c[i] * s[i]).powi(2) / var;
            assert!(
                (idx[i].first - exact).abs() < 0.03,
                "S{i} {} vs {exact}",
                idx[i].first
            );
            assert!(
                (idx[i].total - exact).abs() < 0.03,
                "ST{i} {} vs {exact}",
                idx[i].total
            );
        }
        // an input that does nothing: total exactly 0
        assert_eq!(idx[3].total, 0.0);
        // no variation: no indices
        let flat = vec![1.0; 10];
        assert!(sobol_indices(&flat, &flat, std::slice::from_ref(&flat))
            .0
            .is_none());
    }
}
