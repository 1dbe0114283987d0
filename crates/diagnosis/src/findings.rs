//! "What is wrong": the structure of the residuals d = eta_v,meas -
//! eta_v,sim of a trace-driven campaign, feature by feature.
//!
//! Features a physicist would suspect, each tested at the level of pumps
//! (`stats`): within pumps (varying across a pump's conditions) the delivery
//! pressure, the speed, the oil temperature, the viscosity, the slip group
//! dp / (mu n) of laminar leakage and the torque residual (measured minus
//! simulated, where measured); between pumps the four measured clearances;
//! and the level of the residual (`offset`: the pumps' mean residuals against
//! zero, a bias common to every condition).
//! p-values are adjusted with Holm's method over the whole family, so a
//! finding is significant when its adjusted p is below alpha.

use super::stats::{
    between_association, holm, level_association, pooled_level, pooled_slope, within_association,
    Association,
};
use gearpump_campaign::run::CampaignResult;
use gearpump_core::oil::Oil;
use serde::Serialize;

/// One test of a campaign with its residual and features, SI.
#[derive(Debug, Clone, Copy)]
pub struct ResidualRow {
    /// Index of the pump the test belongs to.
    pub sample: usize,
    /// Delivery gauge pressure, Pa.
    pub pressure: f64,
    /// Driving speed, rad/s.
    pub speed: f64,
    /// Oil temperature, K.
    pub temp: f64,
    /// Dynamic viscosity at the test's temperature, Pa s.
    pub viscosity: f64,
    /// Measured clearances: tip (driving, driven), bearing (driving, driven), m.
    pub tip: [f64; 2],
    pub bearing: [f64; 2],
    /// Measured minus simulated shaft torque, N m (None without a measurement).
    pub torque_residual: Option<f64>,
    /// Residual of the volumetric efficiency.
    pub d: f64,
}

/// A named feature of a residual row.
type Feature = (&'static str, fn(&ResidualRow) -> f64);

/// The residual rows of a trace-driven campaign (failed rows, whose residual
/// is not finite, are left out); `oil` gives the viscosity at each test's
/// temperature.
pub fn rows_from_campaign(result: &CampaignResult, oil: &Oil) -> Vec<ResidualRow> {
    let mut ids: Vec<&str> = Vec::new();
    let mut out = Vec::new();
    for (row, o) in result.campaign.rows.iter().zip(&result.outcomes) {
        if !o.d.is_finite() {
            continue;
        }
        let sample = match ids.iter().position(|s| *s == row.sample.as_str()) {
            Some(i) => i,
            None => {
                ids.push(row.sample.as_str());
                ids.len() - 1
            }
        };
        out.push(ResidualRow {
            sample,
            pressure: row.pressure,
            speed: row.speed,
            temp: row.temp,
            viscosity: oil.dynamic_viscosity(row.temp),
            tip: row.tip_clearance,
            bearing: row.bearing_clearance,
            torque_residual: row.torque.map(|t| t - o.torque_nm_sim),
            d: o.d,
        });
    }
    out
}

/// The association of the residual with one feature.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Finding {
    pub feature: &'static str,
    /// "within" (slopes per pump), "between" (pump means against a per-pump
    /// feature) or "level" (pump means against zero: `offset`).
    pub kind: &'static str,
    /// Mean per-pump slope per standard deviation of the feature (within),
    /// Pearson's r of the pump means (between), or the mean residual (level).
    pub effect: f64,
    pub statistic: f64,
    pub p_value: f64,
    /// Holm-adjusted p-value over all features tested.
    pub p_adjusted: f64,
    pub n_samples: usize,
}

/// The features tested within pumps (varying across a pump's conditions).
const WITHIN: [Feature; 5] = [
    ("pressure_bar", |r| r.pressure),
    ("speed_rpm", |r| r.speed),
    ("temp_c", |r| r.temp),
    ("viscosity", |r| r.viscosity),
    ("slip_group", |r| r.pressure / (r.viscosity * r.speed)),
];

/// The features tested between pumps (fixed per pump).
const BETWEEN: [Feature; 4] = [
    ("tip_clearance_drive_um", |r| r.tip[0]),
    ("tip_clearance_driven_um", |r| r.tip[1]),
    ("bearing_clearance_drive_um", |r| r.bearing[0]),
    ("bearing_clearance_driven_um", |r| r.bearing[1]),
];

/// The values of feature `name` on every row (zeros for the level
/// `offset`, and for a missing torque residual).
pub fn feature_values(rows: &[ResidualRow], name: &str) -> Vec<f64> {
    let f = WITHIN
        .iter()
        .chain(&BETWEEN)
        .find(|(n, _)| *n == name)
        .map(|(_, f)| *f);
    rows.iter()
        .map(|r| match (name, f) {
            ("torque_residual_nm", _) => r.torque_residual.unwrap_or(0.0),
            (_, Some(f)) => f(r),
            _ => 0.0,
        })
        .collect()
}

/// Attaches Holm-adjusted p-values and sorts (most significant first).
fn adjusted(raw: Vec<(&'static str, &'static str, Association)>) -> Vec<Finding> {
    let p: Vec<f64> = raw.iter().map(|(_, _, a)| a.p_value).collect();
    let adj = holm(&p);
    let mut out: Vec<Finding> = raw
        .into_iter()
        .zip(adj)
        .map(|((feature, kind, a), p_adjusted)| Finding {
            feature,
            kind,
            effect: a.effect,
            statistic: a.statistic,
            p_value: a.p_value,
            p_adjusted,
            n_samples: a.n_samples,
        })
        .collect();
    out.sort_by(|a, b| a.p_adjusted.total_cmp(&b.p_adjusted));
    out
}

/// Tests every feature; findings sorted by adjusted p-value (most
/// significant first). Features that cannot be tested (constant, or fewer
/// than the pumps a test needs) are left out.
pub fn findings(rows: &[ResidualRow]) -> Vec<Finding> {
    let d: Vec<f64> = rows.iter().map(|r| r.d).collect();
    let s: Vec<usize> = rows.iter().map(|r| r.sample).collect();
    let mut raw: Vec<(&'static str, &'static str, Association)> = Vec::new();
    for (name, f) in WITHIN {
        let x: Vec<f64> = rows.iter().map(f).collect();
        if let Some(a) = within_association(&d, &x, &s) {
            raw.push((name, "within", a));
        }
    }
    // torque residual: only the rows that have a measured torque
    let with_torque: Vec<&ResidualRow> = rows
        .iter()
        .filter(|r| r.torque_residual.is_some())
        .collect();
    if !with_torque.is_empty() {
        let dt: Vec<f64> = with_torque.iter().map(|r| r.d).collect();
        let xt: Vec<f64> = with_torque
            .iter()
            .map(|r| r.torque_residual.unwrap_or(0.0))
            .collect();
        let st: Vec<usize> = with_torque.iter().map(|r| r.sample).collect();
        if let Some(a) = within_association(&dt, &xt, &st) {
            raw.push(("torque_residual_nm", "within", a));
        }
    }
    for (name, f) in BETWEEN {
        let x: Vec<f64> = rows.iter().map(f).collect();
        if let Some(a) = between_association(&d, &x, &s) {
            raw.push((name, "between", a));
        }
    }
    if let Some(a) = level_association(&d, &s) {
        raw.push(("offset", "level", a));
    }
    adjusted(raw)
}

/// The findings of a campaign of fewer pumps than a population (one to
/// three): the within-pump features only, each tested over the *tests* by
/// the least-squares slope of d on the feature with a level per pump
/// (Student's t, n - pumps - 1 degrees of freedom), and the level by the
/// tests' mean (n - 1). Tests of one pump share its clearance errors, so
/// these p-values speak of these pumps, not of a population; the between-
/// pump features cannot be tested at all.
pub fn findings_pooled(rows: &[ResidualRow]) -> Vec<Finding> {
    let d: Vec<f64> = rows.iter().map(|r| r.d).collect();
    let s: Vec<usize> = rows.iter().map(|r| r.sample).collect();
    let mut raw = Vec::new();
    for (name, f) in WITHIN {
        let x: Vec<f64> = rows.iter().map(f).collect();
        if let Some(a) = pooled_slope(&d, &x, &s) {
            raw.push((name, "within", a));
        }
    }
    if let Some(a) = pooled_level(&d) {
        raw.push(("offset", "level", a));
    }
    adjusted(raw)
}

#[cfg(test)]
mod pooled_tests {
    use super::*;

    fn row(sample: usize, pressure: f64, d: f64) -> ResidualRow {
        ResidualRow {
            sample,
            pressure,
            speed: 104.7,
            temp: 333.15,
            viscosity: 0.0155,
            tip: [30e-6; 2],
            bearing: [12e-6; 2],
            torque_residual: None,
            d,
        }
    }

    #[test]
    fn one_pump_finds_a_pressure_slope_and_no_population_features() {
        // d = 1e-8 p (Pa) with a +-2e-4 alternation: slope by hand is 1e-8
        let rows: Vec<ResidualRow> = (0..14)
            .map(|i| {
                let p = 1e5 * (5 + 5 * (i % 7)) as f64;
                row(0, p, 1e-8 * p + if i % 2 == 0 { 2e-4 } else { -2e-4 })
            })
            .collect();
        let f = findings_pooled(&rows);
        let p = f.iter().find(|x| x.feature == "pressure_bar").unwrap();
        assert!(p.p_adjusted < 1e-6, "{p:?}");
        assert!(f.iter().all(|x| x.kind != "between"));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 20 pumps x the 14 conditions of seed Table 2, clearances spread per
    /// pump, a deterministic pseudo-noise of 0.004 on d, and `truth` giving
    /// the systematic part of d.
    fn campaign(truth: impl Fn(&ResidualRow) -> f64) -> Vec<ResidualRow> {
        let mut rows = Vec::new();
        let mut state: u64 = 0x2545_f491_4f6c_dd1d;
        let mut noise = move || {
            // xorshift, mapped to a roughly normal value by summing uniforms
            let mut acc = 0.0;
            for _ in 0..12 {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                acc += (state >> 11) as f64 / (1u64 << 53) as f64;
            }
            acc - 6.0
        };
        for p in 0..20 {
            let tip = 30e-6 * (1.0 + 0.06 * (((p * 7) % 11) as f64 / 5.0 - 1.0));
            let brg = 12e-6 * (1.0 + 0.06 * (((p * 3) % 7) as f64 / 3.0 - 1.0));
            for t in [333.15, 393.15] {
                let mu = if t < 350.0 { 0.0155 } else { 0.0042 };
                let conds = [
                    (104.7, 10e5),
                    (104.7, 20e5),
                    (104.7, 30e5),
                    (104.7, 40e5),
                    (52.4, 30e5),
                    (209.4, 30e5),
                    (418.9, 30e5),
                ];
                for (w, dp) in conds {
                    let mut r = ResidualRow {
                        sample: p,
                        pressure: dp,
                        speed: w,
                        temp: t,
                        viscosity: mu,
                        tip: [tip, tip * 1.01],
                        bearing: [brg, brg * 1.02],
                        torque_residual: Some(0.01 * noise()),
                        d: 0.0,
                    };
                    r.d = truth(&r) + 0.004 * noise();
                    rows.push(r);
                }
            }
        }
        rows
    }

    fn get<'a>(f: &'a [Finding], name: &str) -> &'a Finding {
        f.iter().find(|x| x.feature == name).unwrap()
    }

    #[test]
    fn a_temperature_effect_is_found_with_temperature_and_viscosity() {
        let f = findings(&campaign(|r| -0.0004 * (r.temp - 333.15)));
        assert!(get(&f, "temp_c").p_adjusted < 1e-6);
        assert!(get(&f, "temp_c").effect < 0.0);
        assert!(get(&f, "viscosity").p_adjusted < 1e-6);
        for c in [
            "tip_clearance_drive_um",
            "bearing_clearance_driven_um",
            "speed_rpm",
        ] {
            assert!(get(&f, c).p_adjusted > 0.05, "{c}: {:?}", get(&f, c));
        }
    }

    #[test]
    fn a_clearance_effect_is_found_between_pumps() {
        let f = findings(&campaign(|r| -800.0 * (r.tip[0] - 30e-6)));
        let tip = get(&f, "tip_clearance_drive_um");
        assert!(
            tip.kind == "between" && tip.p_adjusted < 0.01 && tip.effect < 0.0,
            "{tip:?}"
        );
        assert!(get(&f, "pressure_bar").p_adjusted > 0.05);
    }

    #[test]
    fn a_common_bias_is_found_as_an_offset_and_nothing_else() {
        let f = findings(&campaign(|_| -0.01));
        let o = get(&f, "offset");
        assert!(
            o.kind == "level" && o.p_adjusted < 1e-6 && (o.effect + 0.01).abs() < 0.002,
            "{o:?}"
        );
        for x in f.iter().filter(|x| x.feature != "offset") {
            assert!(x.p_adjusted > 0.05, "{x:?}");
        }
    }

    #[test]
    fn pure_noise_gives_no_significant_finding() {
        let f = findings(&campaign(|_| 0.0));
        assert_eq!(f.len(), 11);
        for x in &f {
            assert!(x.p_adjusted > 0.05, "{x:?}");
            assert!(x.p_adjusted >= x.p_value);
        }
    }
}
