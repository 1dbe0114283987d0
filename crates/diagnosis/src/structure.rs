//! Practical significance: how much *structure* a residual has, in
//! efficiency points, against a noise floor estimated from the data itself.
//!
//! With 280 tests and a flowmeter of 0.5 %, any small difference of form
//! between nature and a candidate is statistically significant; whether it
//! matters is a question of size. This module measures the size.
//!
//! # The structure model
//! The residual `d` of every test is projected on a linear model that can
//! follow any systematic pattern the campaign lets one tell from noise:
//! * with a population (at least [`POPULATION`] pumps): the **two-way
//!   additive model** `d = a_pump + b_condition`, a level per pump (whatever
//!   makes one pump differ from another: its clearances, an offset) plus a
//!   level per working condition (whatever the conditions do to every pump:
//!   pressure, speed, temperature and any form of their combination);
//! * with fewer pumps: a straight line per pump in the delivery pressure,
//!   the speed and the temperature (a per-condition level would leave no
//!   degrees of freedom for the noise).
//!
//! What the model does not follow (pump-by-condition interaction) is taken
//! as noise: the **noise floor** `sigma` is the root mean square of the
//! residual of that projection, `sqrt(RSS / (n - rank))`. Interaction that is
//! real (an effect whose size differs from pump to pump) inflates it
//! slightly; the diagnosis therefore keeps the smallest floor over the
//! residuals it examines (the baseline's and the extended models').
//!
//! The **structure** `S` is the root mean square of the projection's fitted
//! values, corrected for the noise the projection itself picks up (a
//! projection of pure noise on `k` directions keeps `k sigma^2` of it):
//! `S^2 = max(0, (|fitted|^2 - rank sigma^2) / n)`. For pure noise `S` is
//! close to zero whatever `n`; it does not grow with the number of tests as
//! a t statistic does.
//!
//! # The effect-size rule (docs/diagnosis.md, "Decision rule")
//! Structure is **material** when `S >= max(sigma, E0 / 4)`, with `E0` the
//! base model's RMSE of `d`: at least as large as the scatter of a single
//! test (below it, one measurement cannot resolve it), and at least a quarter
//! of the error the diagnosis set out to explain (below it, the extended
//! model removed more than 15/16 of the error's variance).
//! What the causes leave is also material **by its share** of a material
//! discrepancy: when the baseline's structure `S0` was material, and the
//! causes leave at least a quarter of it (`S >= S0 / 4`, [`SHARE_LEFT`]: the
//! same quarter, of what could be explained, noise removed) that the
//! structure model resolves (its F test, `p <` [`RESOLVABLE_P`]). A
//! mechanism of the right kind removes a discrepancy up to small differences
//! of form: over the hand-planted and model-planted evaluations
//! (docs/diagnosis.md) the named causes left at most a tenth of `S0`. One
//! of another kind that stands in for it leaves more: a lateral gap or a
//! thermal opening fitted to a flowmeter's slip (`hand_planted_eval`,
//! family `meter_slip`) left 0.26-0.36 of it, below one test's scatter
//! because the slip itself was only one or two scatters.
//!
//! A candidate's **gain is material** when it at least halves the structure
//! it is added to (`S_after <= S_before / 2`: three quarters of the
//! structured variance removed).
//!
//! Each feature's share (`feature_size`) is the root mean square of the part
//! of `d` a single least-squares slope on that feature explains (within
//! pumps: one slope common to all pumps on the feature centred per pump;
//! between pumps: the pump means on the feature; the level: the mean).

use nalgebra::{DMatrix, DVector};
use serde::Serialize;
use statrs::distribution::{ContinuousCDF, FisherSnedecor};

/// Pumps from which the two-way (pump x condition) model is used.
pub const POPULATION: usize = 4;

/// Smallest residual degrees of freedom for a noise floor.
pub const MIN_DOF: usize = 5;

/// The projection of a residual on the structure model.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Structure {
    /// Root mean square of the residual (the error itself).
    pub rmse: f64,
    /// Noise-corrected root mean square of the structure, in eta units.
    pub structure: f64,
    /// Noise floor of this residual: RMS of what the model does not follow.
    pub noise: f64,
    /// Residual degrees of freedom behind `noise`.
    pub dof: usize,
    /// "pump + condition levels" or "per-pump lines in p, n, T".
    pub model: &'static str,
    /// Whether the model follows anything at all: the p-value of the F
    /// test of its fitted values against this residual's own noise,
    /// `F = (|fitted|^2 / rank) / sigma^2` on `(rank, dof)` degrees of
    /// freedom (NaN without a noise floor).
    pub p: f64,
}

/// Least squares of `y` on the columns of `x` (SVD, rank-revealing):
/// fitted values and the rank.
fn project(x: &DMatrix<f64>, y: &[f64]) -> (Vec<f64>, usize) {
    let svd = x.clone().svd(true, true);
    let smax = svd.singular_values.max();
    let tol = smax * 1e-10 * (x.nrows().max(x.ncols()) as f64);
    let rank = svd.singular_values.iter().filter(|s| **s > tol).count();
    let b = DVector::from_column_slice(y);
    let coef = match svd.solve(&b, tol) {
        Ok(c) => c,
        Err(_) => return (vec![0.0; y.len()], 0),
    };
    let fitted = x * coef;
    (fitted.iter().copied().collect(), rank)
}

/// Index of each row's group (equal keys share an index), in order of first
/// appearance.
pub fn group_index<K: PartialEq>(keys: &[K]) -> Vec<usize> {
    let mut seen: Vec<&K> = Vec::new();
    keys.iter()
        .map(|k| match seen.iter().position(|s| *s == k) {
            Some(i) => i,
            None => {
                seen.push(k);
                seen.len() - 1
            }
        })
        .collect()
}

/// The structure model's design matrix (see the module doc); `x[i]` are the
/// test's delivery pressure, speed and temperature (any units).
fn design_matrix(pump: &[usize], cond: &[usize], x: &[[f64; 3]]) -> (DMatrix<f64>, &'static str) {
    let n = pump.len();
    let np = pump.iter().max().map_or(0, |m| m + 1);
    let nc = cond.iter().max().map_or(0, |m| m + 1);
    if np >= POPULATION {
        let m = DMatrix::from_fn(n, np + nc, |i, j| {
            let hit = if j < np {
                pump[i] == j
            } else {
                cond[i] == j - np
            };
            if hit {
                1.0
            } else {
                0.0
            }
        });
        return (m, "pump + condition levels");
    }
    // standardised features so the SVD's tolerance is meaningful
    let scale: Vec<(f64, f64)> = (0..3)
        .map(|k| {
            let v: Vec<f64> = x.iter().map(|r| r[k]).collect();
            let m = v.iter().sum::<f64>() / n as f64;
            let s = (v.iter().map(|a| (a - m).powi(2)).sum::<f64>() / n as f64).sqrt();
            (m, if s > 0.0 { s } else { 1.0 })
        })
        .collect();
    let m = DMatrix::from_fn(n, 4 * np, |i, j| {
        let (p, k) = (j / 4, j % 4);
        if pump[i] != p {
            0.0
        } else if k == 0 {
            1.0
        } else {
            (x[i][k - 1] - scale[k - 1].0) / scale[k - 1].1
        }
    });
    (m, "per-pump lines in p, n, T")
}

/// The structure of residual `d` (module doc). `pump[i]`, `cond[i]`: group
/// indices of row i; `x[i]`: its pressure, speed and temperature.
pub fn structure(d: &[f64], pump: &[usize], cond: &[usize], x: &[[f64; 3]]) -> Structure {
    let n = d.len();
    let rmse = (d.iter().map(|v| v * v).sum::<f64>() / n.max(1) as f64).sqrt();
    let (m, model) = design_matrix(pump, cond, x);
    let (fitted, rank) = project(&m, d);
    let dof = n.saturating_sub(rank);
    let rss: f64 = d.iter().zip(&fitted).map(|(a, f)| (a - f).powi(2)).sum();
    let noise = if dof >= MIN_DOF {
        (rss / dof as f64).sqrt()
    } else {
        f64::NAN
    };
    let fit2: f64 = fitted.iter().map(|f| f * f).sum();
    let s2 = if noise.is_finite() {
        (fit2 - rank as f64 * noise * noise) / n as f64
    } else {
        fit2 / n as f64
    };
    let p = match FisherSnedecor::new(rank as f64, dof as f64) {
        Ok(f) if noise.is_finite() && noise > 0.0 && rank > 0 => {
            1.0 - f.cdf(fit2 / rank as f64 / (noise * noise))
        }
        _ => f64::NAN,
    };
    Structure {
        rmse,
        structure: s2.max(0.0).sqrt(),
        noise,
        dof,
        model,
        p,
    }
}

/// The effect-size threshold of material structure: `max(sigma, e0 / 4)`
/// (a noise floor that could not be estimated leaves `e0 / 4`).
pub fn material_threshold(sigma: f64, e0: f64) -> f64 {
    if sigma.is_finite() {
        sigma.max(0.25 * e0)
    } else {
        0.25 * e0
    }
}

/// Below this p-value the structure model follows something in a residual
/// ([`Structure::p`]): strong evidence, since it is asked of structure
/// smaller than one test's scatter, and on a campaign without any
/// discrepancy a residual of pure noise passes it once in a thousand.
pub const RESOLVABLE_P: f64 = 1e-3;

/// Share of the baseline's structure at and above which what the causes
/// leave is not explained (see [`not_explained`]).
pub const SHARE_LEFT: f64 = 0.25;

/// Whether the structure `last` left by the causes is material (module
/// doc, "The effect-size rule"), `tau` the size threshold of
/// [`material_threshold`]: by its size, `S >= tau`; or by its share of a
/// material discrepancy: the baseline's structure was material
/// (`S_0 >= tau`), the causes leave at least a quarter of it
/// (`S >= S_0 / 4`, [`SHARE_LEFT`]), and what they leave is resolvable
/// (`p < RESOLVABLE_P`).
pub fn not_explained(baseline: &Structure, last: &Structure, tau: f64) -> bool {
    last.structure >= tau
        || (baseline.structure >= tau
            && last.structure >= SHARE_LEFT * baseline.structure
            && last.p < RESOLVABLE_P)
}

/// A candidate's gain is material when it at least halves the structure.
pub fn gain_is_material(before: f64, after: f64) -> bool {
    after <= 0.5 * before
}

/// The RMS of the part of `d` explained by one slope on feature `x` of the
/// given kind ("within", "between" or "level"); `pump[i]` the pump of row i.
pub fn feature_size(kind: &str, d: &[f64], x: &[f64], pump: &[usize]) -> f64 {
    let n = d.len();
    if n == 0 {
        return 0.0;
    }
    let np = pump.iter().max().map_or(0, |m| m + 1);
    let pump_mean = |v: &[f64]| -> Vec<f64> {
        let mut s = vec![0.0; np];
        let mut c = vec![0usize; np];
        for (i, &p) in pump.iter().enumerate() {
            s[p] += v[i];
            c[p] += 1;
        }
        s.iter()
            .zip(&c)
            .map(|(a, k)| a / (*k).max(1) as f64)
            .collect()
    };
    let slope_rms = |xc: &[f64], yc: &[f64]| -> f64 {
        let sxx: f64 = xc.iter().map(|a| a * a).sum();
        if sxx <= 0.0 {
            return 0.0;
        }
        let b = xc.iter().zip(yc).map(|(a, y)| a * y).sum::<f64>() / sxx;
        (b * b * sxx / n as f64).sqrt()
    };
    match kind {
        "level" => (d.iter().sum::<f64>() / n as f64).abs(),
        "within" => {
            let (mx, md) = (pump_mean(x), pump_mean(d));
            let xc: Vec<f64> = (0..n).map(|i| x[i] - mx[pump[i]]).collect();
            let yc: Vec<f64> = (0..n).map(|i| d[i] - md[pump[i]]).collect();
            slope_rms(&xc, &yc)
        }
        _ => {
            let (mx, md) = (pump_mean(x), pump_mean(d));
            let gx = mx.iter().sum::<f64>() / np as f64;
            let gd = md.iter().sum::<f64>() / np as f64;
            let xc: Vec<f64> = (0..n).map(|i| mx[pump[i]] - gx).collect();
            let yc: Vec<f64> = (0..n).map(|i| md[pump[i]] - gd).collect();
            slope_rms(&xc, &yc)
        }
    }
}

/// Robust z-scores of the pumps' mean residuals (modified z of Iglewicz and
/// Hoaglin: `0.6745 (m - median) / MAD`); a pump with `|z| > 3.5` stands
/// apart from the population.
pub fn robust_z(means: &[f64]) -> Vec<f64> {
    let med = median(means);
    let mad = median(&means.iter().map(|m| (m - med).abs()).collect::<Vec<_>>());
    means
        .iter()
        .map(|m| {
            if mad > 0.0 {
                0.6745 * (m - med) / mad
            } else {
                0.0
            }
        })
        .collect()
}

/// Threshold of [`robust_z`] for an out-of-family pump (Iglewicz and
/// Hoaglin's recommendation).
pub const OUT_OF_FAMILY_Z: f64 = 3.5;

pub fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use crate::testing::normal;

    /// 20 pumps x 14 conditions; `truth(pump, cond)` plus noise `sigma`.
    fn campaign(
        sigma: f64,
        truth: impl Fn(usize, usize) -> f64,
        seed: u64,
    ) -> (Vec<f64>, Vec<usize>, Vec<usize>, Vec<[f64; 3]>) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let (mut d, mut p, mut c, mut x) = (vec![], vec![], vec![], vec![]);
        for pump in 0..20 {
            for cond in 0..14 {
                d.push(truth(pump, cond) + sigma * normal(&mut rng));
                p.push(pump);
                c.push(cond);
                x.push([
                    (cond % 4) as f64 * 10.0,
                    (cond / 4) as f64 * 1000.0,
                    if cond < 7 { 60.0 } else { 120.0 },
                ]);
            }
        }
        (d, p, c, x)
    }

    #[test]
    fn pure_noise_has_its_own_sigma_as_floor_and_no_structure() {
        let (d, p, c, x) = campaign(0.004, |_, _| 0.0, 1);
        let s = structure(&d, &p, &c, &x);
        // the residual dof: 280 - (20 + 14 - 1) = 247
        assert_eq!(s.dof, 247);
        assert!((s.noise - 0.004).abs() < 0.0004, "{s:?}");
        assert!(s.structure < 0.001, "{s:?}");
        assert!(s.structure < material_threshold(s.noise, s.rmse));
    }

    #[test]
    fn a_known_pattern_is_measured_at_its_size() {
        // a condition pattern of RMS 0.01 (+-0.01 square wave) and a pump
        // level of RMS 0.005: S = sqrt(0.01^2 + 0.005^2) by hand
        let truth = |pump: usize, cond: usize| {
            (if cond % 2 == 0 { 0.01 } else { -0.01 }) + if pump % 2 == 0 { 0.005 } else { -0.005 }
        };
        let (d, p, c, x) = campaign(0.003, truth, 2);
        let s = structure(&d, &p, &c, &x);
        let want = (0.01f64.powi(2) + 0.005f64.powi(2)).sqrt();
        assert!((s.structure - want).abs() < 0.0007, "{s:?} vs {want}");
        assert!((s.noise - 0.003).abs() < 0.0004, "{s:?}");
    }

    /// On residuals of pure noise the structure's F test is what its
    /// distribution says: p below 0.05 in about one campaign in twenty,
    /// below RESOLVABLE_P in hardly any.
    #[test]
    fn the_structure_test_of_pure_noise_holds_its_level() {
        let ps: Vec<f64> = (0..300)
            .map(|seed| {
                let (d, p, c, x) = campaign(0.005, |_, _| 0.0, 1000 + seed);
                structure(&d, &p, &c, &x).p
            })
            .collect();
        assert!(ps.iter().all(|p| (0.0..=1.0).contains(p)), "{ps:?}");
        let share = |a: f64| ps.iter().filter(|&&p| p < a).count() as f64 / ps.len() as f64;
        // binomial(300, 0.05): 15 +- 3.8
        assert!((0.02..=0.09).contains(&share(0.05)), "{}", share(0.05));
        assert!(share(RESOLVABLE_P) <= 0.01, "{}", share(RESOLVABLE_P));
        // a condition pattern of 0.4 noise scatters is resolved: by hand
        // F = 1 + n S^2 / (rank sigma^2) = 1 + 280 x 0.16 / 33 = 2.4 on
        // (33, 247) degrees of freedom, p about 1e-5
        let (d, p, c, x) = campaign(
            0.005,
            |_, cond| if cond % 2 == 0 { 0.002 } else { -0.002 },
            7,
        );
        let s = structure(&d, &p, &c, &x);
        assert!(s.p < RESOLVABLE_P && s.structure < s.noise, "{s:?}");
    }

    /// The share rule against hand-built residuals: a condition pattern of
    /// 1.5 noise scatters (a material discrepancy, baseline) of which the
    /// causes leave 30 % (a mechanism of another kind), 5 % (one of the
    /// right kind, its form a little off) or all of a pattern that was
    /// never material.
    #[test]
    fn a_quarter_left_of_a_material_discrepancy_is_not_explained() {
        let sigma = 0.005;
        let pattern = |scale: f64| {
            move |pump: usize, cond: usize| {
                scale * sigma * (if cond % 2 == 0 { 1.0 } else { -1.0 })
                    + 0.2 * scale * sigma * (if pump % 2 == 0 { 1.0 } else { -1.0 })
            }
        };
        let st = |scale: f64, seed: u64| {
            let (d, p, c, x) = campaign(sigma, pattern(scale), seed);
            structure(&d, &p, &c, &x)
        };
        let base = st(1.5, 11);
        let tau = material_threshold(base.noise, base.rmse);
        assert!(base.structure >= tau, "{base:?} {tau}");
        let left = st(0.3 * 1.5, 12);
        // below one test's scatter, so the size rule alone misses it
        assert!(left.structure < tau, "{left:?}");
        assert!(left.structure >= SHARE_LEFT * base.structure, "{left:?}");
        assert!(not_explained(&base, &left, tau));
        let nearly_all_removed = st(0.05 * 1.5, 13);
        assert!(
            !not_explained(&base, &nearly_all_removed, tau),
            "{nearly_all_removed:?}"
        );
        // no material discrepancy to begin with: nothing is "not explained"
        let small = st(0.5, 14);
        let tau_small = material_threshold(small.noise, small.rmse);
        assert!(
            small.structure < tau_small && small.p < RESOLVABLE_P,
            "{small:?}"
        );
        assert!(!not_explained(&small, &small, tau_small));
    }

    #[test]
    fn one_pump_uses_lines_and_keeps_degrees_of_freedom() {
        let (d, p, c, x) = campaign(0.002, |_, cond| 0.001 * (cond % 4) as f64, 3);
        let one: Vec<usize> = (0..14).collect();
        let pick = |v: &[f64]| one.iter().map(|&i| v[i]).collect::<Vec<_>>();
        let s = structure(
            &pick(&d),
            &one.iter().map(|&i| p[i]).collect::<Vec<_>>(),
            &one.iter().map(|&i| c[i]).collect::<Vec<_>>(),
            &one.iter().map(|&i| x[i]).collect::<Vec<_>>(),
        );
        assert_eq!(s.model, "per-pump lines in p, n, T");
        assert_eq!(s.dof, 10);
        // the pattern 0.001 (cond % 4) is a line in p: RMS over the 14 tests
        let pattern: Vec<f64> = (0..14).map(|c| 0.001 * (c % 4) as f64).collect();
        let rms = (pattern.iter().map(|v| v * v).sum::<f64>() / 14.0).sqrt();
        assert!((s.structure - rms).abs() < 0.0012, "{s:?} vs {rms}");
    }

    #[test]
    fn feature_sizes_match_hand_slopes() {
        // d = 0.002 * (x - pump mean of x) exactly: within size = 0.002 RMS(xc)
        let pump: Vec<usize> = (0..30).map(|i| i / 10).collect();
        let x: Vec<f64> = (0..30).map(|i| (i % 10) as f64).collect();
        let d: Vec<f64> = x.iter().map(|v| 0.002 * (v - 4.5)).collect();
        let rms_xc = (x.iter().map(|v| (v - 4.5).powi(2)).sum::<f64>() / 30.0).sqrt();
        assert!((feature_size("within", &d, &x, &pump) - 0.002 * rms_xc).abs() < 1e-12);
        assert!(feature_size("between", &d, &x, &pump) < 1e-12);
        assert!((feature_size("level", &[0.01, 0.03], &[0.0, 0.0], &[0, 1]) - 0.02).abs() < 1e-15);
    }

    #[test]
    fn one_pump_apart_is_out_of_family() {
        let mut means: Vec<f64> = (0..20).map(|i| 0.001 * ((i * 7) % 5) as f64).collect();
        means[13] = 0.03;
        let z = robust_z(&means);
        let flagged: Vec<usize> = (0..20).filter(|&i| z[i].abs() > OUT_OF_FAMILY_Z).collect();
        assert_eq!(flagged, vec![13]);
    }
}
