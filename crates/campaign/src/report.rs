//! `report.md` of a campaign: what was run, the accuracy per working
//! condition (seed Table 3 and Eqs. 17-20), per-sample residuals, failed
//! rows and the figures.
//!
//! The text depends only on the inputs and results (no dates, wall times,
//! output paths or journal statistics), so an interrupted and resumed run
//! writes the same bytes as an uninterrupted one.

use std::fmt::Write;

use super::data::Campaign;
use super::io::TestOutcome;
use super::plots::Figure;
use super::run::{rms, sample_ids, FailedRow};
use super::stats::{ConditionSummary, ALPHA};
use gearpump_core::units::m3_to_cm3;

/// Everything the report shows.
#[derive(Debug, Clone, Copy)]
pub struct ReportInput<'a> {
    pub campaign: &'a Campaign,
    pub outcomes: &'a [TestOutcome],
    pub summaries: &'a [ConditionSummary],
    pub failed: &'a [FailedRow],
    pub design_label: &'a str,
    pub sets: &'a [String],
    pub micromotion: bool,
    /// Nominal displacement used for eta_v, m^3/rev.
    pub displacement: f64,
    pub figures: &'a [Figure],
}

fn opt(x: Option<f64>, decimals: usize) -> String {
    match x {
        Some(v) => format!("{v:.decimals$}"),
        None => "-".to_string(),
    }
}

/// The Markdown text of `report.md`.
pub fn campaign_report(r: &ReportInput<'_>) -> String {
    let c = r.campaign;
    let samples = sample_ids(&c.rows);
    let mut s = String::new();
    // Writing to a String cannot fail; the results are ignored.
    let _ = writeln!(s, "# Population validation: {}\n", c.file);
    let _ = writeln!(
        s,
        "Trace-driven simulation of every test with its own sample's measured clearances \
         (Battarra & Mucchi 2020, Sec. 4). `d = eta_v,meas - eta_v,sim` per test (Eq. 17); \
         per working condition the two-sided confidence interval of the mean of `d` at \
         alpha = {ALPHA} (Eqs. 18-19) and the closeness to reality \
         `delta_nu = max(|ci_low|, |ci_high|)` (Eq. 20).\n"
    );
    let _ = writeln!(
        s,
        "- data: `{}`: {} tests, {} samples, {} working conditions",
        c.file,
        c.rows.len(),
        samples.len(),
        r.summaries.len()
    );
    let sets = if r.sets.is_empty() {
        "none".to_string()
    } else {
        r.sets
            .iter()
            .map(|x| format!("`{x}`"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let _ = writeln!(s, "- design: {}; overrides: {sets}", r.design_label);
    let _ = writeln!(
        s,
        "- model: gear micromotion {}; suction 1.01325 bar abs; lateral clearance nominal; \
         measured torque used for the mesh force where given",
        if r.micromotion { "on" } else { "off" }
    );
    let _ = writeln!(
        s,
        "- eta_v of measurement and simulation with the nominal displacement {:.4} cm^3/rev\n",
        m3_to_cm3(r.displacement)
    );

    let _ = writeln!(s, "## Accuracy per working condition\n");
    let _ = writeln!(
        s,
        "| p (bar) | n (rpm) | T (degC) | n_s | d_mean | S_d | t_crit | ci_low | ci_high | delta_nu | bias |"
    );
    let _ = writeln!(
        s,
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|:---:|"
    );
    let mut biased = 0usize;
    let mut worst: Option<&ConditionSummary> = None;
    for cs in r.summaries {
        let t = &cs.stats;
        let bias = match (t.ci_low, t.ci_high) {
            (Some(lo), Some(hi)) if lo > 0.0 || hi < 0.0 => {
                biased += 1;
                "yes"
            }
            (Some(_), Some(_)) => "no",
            _ => "-",
        };
        if let Some(dn) = t.delta_nu {
            if worst.and_then(|w| w.stats.delta_nu).is_none_or(|w| dn > w) {
                worst = Some(cs);
            }
        }
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {bias} |",
            cs.condition.pressure_bar,
            cs.condition.speed_rpm,
            cs.condition.temp_c,
            t.n_samples,
            opt(t.d_mean, 4),
            opt(t.d_std, 4),
            opt(t.t_crit, 3),
            opt(t.ci_low, 4),
            opt(t.ci_high, 4),
            opt(t.delta_nu, 4),
        );
    }
    let d: Vec<f64> = r.outcomes.iter().map(|o| o.d).collect();
    let _ = writeln!(s);
    let _ = writeln!(s, "- RMS of d over all tests: {}", opt(rms(&d), 4));
    if let Some(w) = worst {
        let _ = writeln!(
            s,
            "- largest delta_nu: {} at {}",
            opt(w.stats.delta_nu, 4),
            w.condition
        );
    }
    let _ = writeln!(
        s,
        "- conditions whose interval excludes 0 (a significant bias at alpha = {ALPHA}): {biased} of {}",
        r.summaries.len()
    );
    let _ = writeln!(
        s,
        "- `bias = yes`: the model's mean error at that condition is distinguishable from 0; \
         `-`: fewer than two samples\n"
    );

    if r.summaries.iter().any(|c| c.torque.n_torque > 0) {
        let _ = writeln!(s, "## Shaft torque per working condition\n");
        let _ = writeln!(
            s,
            "Error `T_meas - T_sim` over the tests with a measured torque, and of eta_hm = V dp / (2 pi T) (nominal displacement).\n"
        );
        let _ = writeln!(
            s,
            "| p (bar) | n (rpm) | T (degC) | tests | torque error mean (N m) | std (N m) | relative mean | eta_hm error mean | std |"
        );
        let _ = writeln!(s, "|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
        for cs in r.summaries {
            let t = &cs.torque;
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                cs.condition.pressure_bar,
                cs.condition.speed_rpm,
                cs.condition.temp_c,
                t.n_torque,
                opt(t.torque_err_mean_nm, 4),
                opt(t.torque_err_std_nm, 4),
                opt(t.torque_err_rel_mean, 4),
                opt(t.eta_hm_err_mean, 4),
                opt(t.eta_hm_err_std, 4),
            );
        }
        let _ = writeln!(s);
    }

    let _ = writeln!(s, "## Residuals per sample\n");
    let _ = writeln!(s, "| sample | tests | mean d | max abs d |");
    let _ = writeln!(s, "|---|---:|---:|---:|");
    for id in &samples {
        let ds: Vec<f64> = c
            .rows
            .iter()
            .zip(r.outcomes)
            .filter(|(row, o)| row.sample == *id && o.d.is_finite())
            .map(|(_, o)| o.d)
            .collect();
        let n = c.rows.iter().filter(|row| row.sample == *id).count();
        let mean = (!ds.is_empty()).then(|| ds.iter().sum::<f64>() / ds.len() as f64);
        let maxabs = ds.iter().map(|x| x.abs()).reduce(f64::max);
        let _ = writeln!(s, "| {id} | {n} | {} | {} |", opt(mean, 4), opt(maxabs, 4));
    }
    let _ = writeln!(s);

    let _ = writeln!(s, "## Failed simulations\n");
    if r.failed.is_empty() {
        let _ = writeln!(s, "None: every test was simulated.\n");
    } else {
        let _ = writeln!(
            s,
            "{} test(s) have no simulated result and are left out of the statistics:\n",
            r.failed.len()
        );
        for f in r.failed {
            let _ = writeln!(s, "- row {} (sample {}): {}", f.row, f.sample, f.message);
        }
        let _ = writeln!(s);
    }

    let _ = writeln!(s, "## Figures\n");
    for f in r.figures {
        let _ = writeln!(s, "![{}]({})\n", f.caption, f.file);
    }
    let _ = writeln!(
        s,
        "Per-test values: `tests.csv`; per-condition statistics at full precision: `conditions.csv`."
    );
    s
}
