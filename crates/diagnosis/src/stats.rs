//! Statistics of the diagnosis that respect the seed's point (Sec. 4): the
//! tests of one pump are not independent across working conditions, the
//! pumps are. Every test here therefore reduces the data to one number per
//! pump before testing.
//!
//! * [`within_association`]: a feature that varies across the conditions of a
//!   pump (pressure, speed, temperature, viscosity, dp/(mu n), torque
//!   residual): the least-squares slope of the residual d on the standardised
//!   feature is computed for each pump, and the pumps' slopes are tested
//!   against zero with Student's t (n_pumps - 1 degrees of freedom).
//! * [`between_association`]: a feature fixed per pump (a measured
//!   clearance): the pumps' mean residuals are correlated with it, Pearson's
//!   r tested with t = r sqrt((n-2)/(1-r^2)) (n_pumps - 2 degrees of freedom).
//! * [`holm`]: Holm's step-down adjustment of p-values for trying many
//!   features or candidates (family-wise error rate).
//! * [`paired_improvement`]: one-sided paired t-test that a per-pump error
//!   reduction is positive (candidate vs baseline, or winner vs runner-up).
//! * [`folds_by_sample`]: cross-validation folds that keep each pump whole.

use statrs::distribution::{ContinuousCDF, StudentsT};

/// Result of an association test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Association {
    /// Mean per-pump slope of d per standard deviation of the feature (within),
    /// or Pearson's r (between).
    pub effect: f64,
    /// Student's t statistic.
    pub statistic: f64,
    /// Two-sided p-value.
    pub p_value: f64,
    /// Pumps that entered the test.
    pub n_samples: usize,
}

fn t_two_sided(t: f64, dof: f64) -> f64 {
    if !t.is_finite() {
        return if t.is_nan() { 1.0 } else { 0.0 };
    }
    match StudentsT::new(0.0, 1.0, dof) {
        Ok(d) => (2.0 * (1.0 - d.cdf(t.abs()))).clamp(0.0, 1.0),
        Err(_) => 1.0,
    }
}

fn t_upper(t: f64, dof: f64) -> f64 {
    if t.is_nan() {
        return 1.0;
    }
    match StudentsT::new(0.0, 1.0, dof) {
        Ok(d) => (1.0 - d.cdf(t)).clamp(0.0, 1.0),
        Err(_) => 1.0,
    }
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

fn std(v: &[f64]) -> f64 {
    let m = mean(v);
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() as f64 - 1.0)).sqrt()
}

/// Student's one-sample t-test of `v` (one value per pump) against zero,
/// two-sided; `effect` is the mean. A zero spread gives t = 0 (mean 0) or
/// an infinite t.
fn one_sample_t(v: &[f64]) -> Association {
    let n = v.len();
    let (m, s) = (mean(v), std(v));
    let t = if s > 0.0 {
        m / (s / (n as f64).sqrt())
    } else if m == 0.0 {
        0.0
    } else {
        f64::INFINITY * m.signum()
    };
    Association {
        effect: m,
        statistic: t,
        p_value: t_two_sided(t, n as f64 - 1.0),
        n_samples: n,
    }
}

/// Groups row indices by pump id, in order of first appearance.
pub fn groups(sample: &[usize]) -> Vec<Vec<usize>> {
    let mut ids: Vec<usize> = Vec::new();
    let mut out: Vec<Vec<usize>> = Vec::new();
    for (row, &s) in sample.iter().enumerate() {
        match ids.iter().position(|&x| x == s) {
            Some(i) => out[i].push(row),
            None => {
                ids.push(s);
                out.push(vec![row]);
            }
        }
    }
    out
}

/// Within-pump association of `d` with a condition-varying feature `x`;
/// `sample[i]` is the pump of row i. None when fewer than 3 pumps have a
/// non-constant feature.
pub fn within_association(d: &[f64], x: &[f64], sample: &[usize]) -> Option<Association> {
    let sx = std(x);
    if sx.is_nan() || sx <= 0.0 {
        return None;
    }
    let mut slopes = Vec::new();
    for g in groups(sample) {
        let xs: Vec<f64> = g.iter().map(|&i| x[i] / sx).collect();
        let ds: Vec<f64> = g.iter().map(|&i| d[i]).collect();
        if xs.len() < 2 {
            continue;
        }
        let (mx, md) = (mean(&xs), mean(&ds));
        let sxx: f64 = xs.iter().map(|v| (v - mx).powi(2)).sum();
        if sxx < 1e-12 {
            continue;
        }
        let sxd: f64 = xs.iter().zip(&ds).map(|(a, b)| (a - mx) * (b - md)).sum();
        slopes.push(sxd / sxx);
    }
    let n = slopes.len();
    if n < 3 {
        return None;
    }
    Some(one_sample_t(&slopes))
}

/// Between-pump association of the pumps' mean residual with a per-pump
/// feature `x` (its mean over the pump's rows).
pub fn between_association(d: &[f64], x: &[f64], sample: &[usize]) -> Option<Association> {
    let g = groups(sample);
    let n = g.len();
    if n < 4 {
        return None;
    }
    let dm: Vec<f64> = g
        .iter()
        .map(|r| mean(&r.iter().map(|&i| d[i]).collect::<Vec<_>>()))
        .collect();
    let xm: Vec<f64> = g
        .iter()
        .map(|r| mean(&r.iter().map(|&i| x[i]).collect::<Vec<_>>()))
        .collect();
    let (a, b) = (mean(&dm), mean(&xm));
    let sab: f64 = dm.iter().zip(&xm).map(|(p, q)| (p - a) * (q - b)).sum();
    let saa: f64 = dm.iter().map(|p| (p - a).powi(2)).sum();
    let sbb: f64 = xm.iter().map(|q| (q - b).powi(2)).sum();
    if saa <= 0.0 || sbb <= 0.0 {
        return None;
    }
    let r = (sab / (saa * sbb).sqrt()).clamp(-1.0, 1.0);
    let t = r * ((n as f64 - 2.0) / (1.0 - r * r).max(1e-300)).sqrt();
    Some(Association {
        effect: r,
        statistic: t,
        p_value: t_two_sided(t, n as f64 - 2.0),
        n_samples: n,
    })
}

/// Level of the residual: the pumps' mean residuals tested against zero
/// with Student's t (n_pumps - 1 degrees of freedom); `effect` is the mean of
/// the pump means. A bias common to all conditions (a displacement error, a
/// flowmeter offset) shows here and in no slope.
pub fn level_association(d: &[f64], sample: &[usize]) -> Option<Association> {
    let dm: Vec<f64> = groups(sample)
        .iter()
        .map(|r| mean(&r.iter().map(|&i| d[i]).collect::<Vec<_>>()))
        .collect();
    let n = dm.len();
    if n < 3 {
        return None;
    }
    Some(one_sample_t(&dm))
}

/// The slope of `d` on `x` with a level per pump, tested over the tests
/// (for fewer pumps than a population): `effect` is the slope per standard
/// deviation of `x`, t with n - pumps - 1 degrees of freedom. None when the
/// feature does not vary within any pump or too few tests remain.
pub fn pooled_slope(d: &[f64], x: &[f64], sample: &[usize]) -> Option<Association> {
    let sx = std(x);
    if sx.is_nan() || sx <= 0.0 {
        return None;
    }
    let g = groups(sample);
    let (mut sxx, mut sxy) = (0.0, 0.0);
    let mut centred = vec![(0.0, 0.0); d.len()];
    for rows in &g {
        let mx = mean(&rows.iter().map(|&i| x[i] / sx).collect::<Vec<_>>());
        let md = mean(&rows.iter().map(|&i| d[i]).collect::<Vec<_>>());
        for &i in rows {
            let (a, b) = (x[i] / sx - mx, d[i] - md);
            sxx += a * a;
            sxy += a * b;
            centred[i] = (a, b);
        }
    }
    let dof = d.len() as f64 - g.len() as f64 - 1.0;
    if sxx < 1e-12 || dof < 2.0 {
        return None;
    }
    let b = sxy / sxx;
    let rss: f64 = centred.iter().map(|(a, y)| (y - b * a).powi(2)).sum();
    let se = (rss / dof / sxx).sqrt();
    let t = if se > 0.0 {
        b / se
    } else {
        f64::INFINITY * b.signum()
    };
    Some(Association {
        effect: b,
        statistic: t,
        p_value: t_two_sided(t, dof),
        n_samples: g.len(),
    })
}

/// The tests' mean residual against zero (for fewer pumps than a
/// population), Student's t with n - 1 degrees of freedom.
pub fn pooled_level(d: &[f64]) -> Option<Association> {
    (d.len() >= 3).then(|| one_sample_t(d))
}

/// Holm's step-down adjusted p-values (same order as the input).
pub fn holm(p: &[f64]) -> Vec<f64> {
    let m = p.len();
    let mut idx: Vec<usize> = (0..m).collect();
    idx.sort_by(|&a, &b| p[a].total_cmp(&p[b]));
    let mut out = vec![1.0; m];
    let mut running: f64 = 0.0;
    for (rank, &i) in idx.iter().enumerate() {
        let adj = ((m - rank) as f64 * p[i]).min(1.0);
        running = running.max(adj);
        out[i] = running;
    }
    out
}

/// One-sided paired test that the per-pump improvements `diff` (e.g. baseline
/// error minus candidate error on held-out pumps) are positive on average.
/// Returns (t, p).
pub fn paired_improvement(diff: &[f64]) -> (f64, f64) {
    let n = diff.len();
    if n < 2 {
        return (f64::NAN, 1.0);
    }
    let m = mean(diff);
    let s = std(diff);
    let t = if s > 0.0 {
        m / (s / (n as f64).sqrt())
    } else if m > 0.0 {
        f64::INFINITY
    } else {
        0.0
    };
    (t, t_upper(t, n as f64 - 1.0))
}

/// `k` cross-validation folds over the distinct pumps (deterministic: pumps
/// dealt round-robin in order of first appearance); each fold lists the
/// row indices of its pumps.
pub fn folds_by_sample(sample: &[usize], k: usize) -> Vec<Vec<usize>> {
    let g = groups(sample);
    let k = k.clamp(2, g.len().max(2));
    let mut folds = vec![Vec::new(); k];
    for (i, rows) in g.into_iter().enumerate() {
        folds[i % k].extend(rows);
    }
    folds.retain(|f| !f.is_empty());
    folds
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn within_association_finds_a_common_slope_and_ignores_pump_offsets() {
        // 10 pumps, 4 conditions; d = 0.01 x + pump offset + small noise
        let mut d = Vec::new();
        let mut x = Vec::new();
        let mut s = Vec::new();
        for p in 0..10 {
            for c in 0..4 {
                let xv = c as f64 * 10.0;
                let noise = ((p * 7 + c * 3) % 5) as f64 * 1e-4;
                d.push(0.001 * xv + 0.05 * p as f64 + noise);
                x.push(xv);
                s.push(p);
            }
        }
        let a = within_association(&d, &x, &s).unwrap();
        assert!(a.p_value < 1e-6 && a.effect > 0.0 && a.n_samples == 10);
        // no relation: d independent of x (only pump offsets)
        let d0: Vec<f64> = s.iter().map(|&p| 0.05 * p as f64).collect();
        let a0 = within_association(&d0, &x, &s).unwrap();
        assert!(a0.p_value > 0.9, "{a0:?}");
    }

    #[test]
    fn between_association_matches_a_hand_computed_correlation() {
        // pumps' mean d and clearance: r computed by hand = 1 for a line
        let x: Vec<f64> = (0..8)
            .flat_map(|p| std::iter::repeat_n(p as f64, 3))
            .collect();
        let s: Vec<usize> = (0..8).flat_map(|p| std::iter::repeat_n(p, 3)).collect();
        let d: Vec<f64> = x.iter().map(|v| -0.002 * v + 0.01).collect();
        let a = between_association(&d, &x, &s).unwrap();
        assert!((a.effect + 1.0).abs() < 1e-12 && a.p_value < 1e-9);
        // r = 0.5 with n = 10: t = 0.5 sqrt(8/0.75) = 1.633, two-sided p = 0.141 (t table)
        let t = 0.5 * (8.0f64 / 0.75).sqrt();
        assert!((t_two_sided(t, 8.0) - 0.141).abs() < 2e-3);
    }

    #[test]
    fn holm_matches_the_textbook_example() {
        // p = (0.01, 0.04, 0.03, 0.005): sorted 0.005*4=0.02, 0.01*3=0.03, 0.03*2=0.06, 0.04*1=0.04->0.06
        let adj = holm(&[0.01, 0.04, 0.03, 0.005]);
        let want = [0.03, 0.06, 0.06, 0.02];
        for (a, w) in adj.iter().zip(want) {
            assert!((a - w).abs() < 1e-12, "{adj:?}");
        }
    }

    #[test]
    fn paired_improvement_is_one_sided() {
        let better = [0.02, 0.03, 0.01, 0.025, 0.015, 0.02];
        let (t, p) = paired_improvement(&better);
        assert!(t > 0.0 && p < 0.001);
        let worse: Vec<f64> = better.iter().map(|v| -v).collect();
        assert!(paired_improvement(&worse).1 > 0.99);
        // t_0.95,19 = 1.729: a statistic right at it gives p = 0.05
        assert!((t_upper(1.729, 19.0) - 0.05).abs() < 1e-3);
    }

    #[test]
    fn folds_keep_pumps_whole() {
        let s: Vec<usize> = (0..20).flat_map(|p| std::iter::repeat_n(p, 14)).collect();
        let f = folds_by_sample(&s, 5);
        assert_eq!(f.len(), 5);
        assert_eq!(f.iter().map(|x| x.len()).sum::<usize>(), 280);
        for fold in &f {
            let pumps: std::collections::BTreeSet<usize> = fold.iter().map(|&i| s[i]).collect();
            assert_eq!(pumps.len(), 4);
            for other in &f {
                if !std::ptr::eq(fold, other) {
                    assert!(other.iter().all(|i| !pumps.contains(&s[*i])));
                }
            }
        }
    }
}
