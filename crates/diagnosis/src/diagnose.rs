//! `gearpump diagnose`: the baseline campaign, what is wrong, why, the
//! extended model and its gain, written to `diagnosis.json`, `report.md` and
//! plots.
//!
//! # Decision rule
//! 1. Every candidate of [`super::candidates`] is fitted to all tests and
//!    scored by leave-one-pump-out cross-validation. Its p-value is the
//!    one-sided paired t-test over pumps that its held-out mean squared
//!    residual is below the base model's; the p-values are Holm-adjusted over
//!    the candidates (trying seven explanations must not make one look good by
//!    chance).
//! 2. The *winner* is the significant candidate (adjusted p < alpha) with the
//!    lowest cross-validated RMSE. Another significant candidate that the
//!    winner does not beat significantly (paired one-sided test of their
//!    held-out errors over pumps, p >= alpha) is *indistinguishable* from it on
//!    these data. Among the winner and the indistinguishable ones the cause is
//!    the one with the fewest parameters (then the lowest CV RMSE), and the
//!    others are listed in `ambiguous_with`, each with the measurement that
//!    would tell them apart: the working condition (within and around the
//!    measured ones) where their fitted models differ most, found by running
//!    both on a median pump.
//! 3. The cause is *accepted* only if it leaves no significant structure:
//!    the residual findings of the extended model (a real run at the fitted
//!    parameters) are tested again, Holm-adjusted, at the stricter level
//!    alpha / 5 (a confirmation, not a search). If structure remains, `cause`
//!    is null, `unexplained` is true and `partial` names the candidate and its
//!    gain: an honest "not explained" rather than a wrong name.
//! 4. With no significant candidate, `cause` is null; `unexplained` is true
//!    when the baseline's findings are significant (structure that no
//!    candidate explains), and the significant features are named.
//!
//! # Runs
//! The baseline is the campaign (resumable, journaled in the output
//! folder). Every other run simulates all tests in parallel on the same
//! thread pool; a candidate that has no chance after its first step (its
//! linearised cross-validation p > 0.5, or a cross-validated RMSE above 1.5
//! times the best candidate's so far; 2 times on the sensitivities alone,
//! before its first step) is not refined further.

use std::fs;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use rayon::prelude::*;
use serde_json::{json, Map, Value};

use super::candidates::{
    candidate_specs, cross_validate, fit_candidate, fmt_params, jackknife_se, pump_mse, rmse,
    CandidateScore, CandidateSpec, Fit, FitOptions,
};
use super::findings::{findings, rows_from_campaign, Finding, ResidualRow};
use super::stats::{groups, holm, paired_improvement};
pub use super::verdict::{Diagnosis, DIAGNOSIS_JSON, EXTENDED_DIR};
use gearpump_campaign::effects::{Effect, EffectModel};
use gearpump_campaign::io::{
    atomic_write_text, write_conditions_csv, write_tests_csv, TestOutcome, LOSS_COLUMNS,
};
use gearpump_campaign::run::{
    run_campaign_staged, simulate_test, with_pool, CampaignOptions, CampaignResult, DesignSource,
    Observer, RunError, Setting,
};
use gearpump_campaign::stats::{eta_v, summarize, ConditionSummary, ALPHA};
use gearpump_campaign::{group_by_condition, Condition, TestRow};
use gearpump_core::model::{Pump, SampleClearances};
use gearpump_core::units::{bar_to_pa, celsius_to_kelvin, m3_s_to_lpm, rpm_to_rad_s};

/// A candidate whose held-out error is not below the base model's with at
/// least this p after a step is not refined further.
const HOPELESS_P: f64 = 0.5;
/// A candidate whose cross-validated RMSE after a step is above this multiple
/// of the best candidate's so far is not refined further (it can neither win
/// nor be indistinguishable from the winner).
const OUTCLASSED: f64 = 1.5;
/// The same before any step, judged on the sensitivities alone (a wider
/// margin: the linear prediction can underrate a non-linear candidate).
const OUTCLASSED_LINEAR: f64 = 2.0;

/// Options of a diagnosis.
#[derive(Debug, Clone, Copy)]
pub struct DiagnoseOptions {
    pub jobs: Option<usize>,
    pub micromotion: bool,
    /// Significance level of every decision.
    pub alpha: f64,
    /// Print one line per stage and model run on stderr.
    pub verbose: bool,
}

impl Default for DiagnoseOptions {
    fn default() -> Self {
        DiagnoseOptions {
            jobs: None,
            micromotion: true,
            alpha: ALPHA,
            verbose: false,
        }
    }
}

/// What [`decide`] needs of a scored candidate.
#[derive(Debug, Clone, Copy)]
pub struct CandidateRank<'a> {
    pub n_params: usize,
    pub cv_rmse: f64,
    /// Holm-adjusted p of the improvement over the base model.
    pub p_adjusted: f64,
    /// Held-out mean squared residual per pump.
    pub pump_mse: &'a [f64],
}

/// The outcome of the decision rule (indices into the candidates).
#[derive(Debug, Clone, PartialEq)]
pub struct Decision {
    /// The significant candidate with the lowest CV RMSE.
    pub winner: Option<usize>,
    /// The cause proposed: the most parsimonious among the winner and the
    /// candidates indistinguishable from it.
    pub chosen: Option<usize>,
    /// The other indistinguishable candidates, with the one-sided p that the
    /// chosen one's held-out error is lower.
    pub ambiguous: Vec<(usize, f64)>,
}

/// Steps 1-2 of the decision rule in the module doc.
pub fn decide(c: &[CandidateRank<'_>], alpha: f64) -> Decision {
    let better_p = |a: usize, b: usize| {
        // one-sided p that a's held-out error is below b's
        let diff: Vec<f64> = c[b]
            .pump_mse
            .iter()
            .zip(c[a].pump_mse)
            .map(|(x, y)| x - y)
            .collect();
        paired_improvement(&diff).1
    };
    let significant: Vec<usize> = (0..c.len()).filter(|&i| c[i].p_adjusted < alpha).collect();
    let winner = significant
        .iter()
        .copied()
        .min_by(|&a, &b| c[a].cv_rmse.total_cmp(&c[b].cv_rmse));
    let Some(w) = winner else {
        return Decision {
            winner: None,
            chosen: None,
            ambiguous: vec![],
        };
    };
    let mut set = vec![w];
    set.extend(
        significant
            .iter()
            .copied()
            .filter(|&k| k != w && better_p(w, k) >= alpha),
    );
    let pick = set
        .iter()
        .copied()
        .min_by(|&a, &b| {
            c[a].n_params
                .cmp(&c[b].n_params)
                .then(c[a].cv_rmse.total_cmp(&c[b].cv_rmse))
        })
        .unwrap_or(w);
    let ambiguous = set
        .iter()
        .copied()
        .filter(|&k| k != pick)
        .map(|k| (k, better_p(pick, k)))
        .collect();
    Decision {
        winner: Some(w),
        chosen: Some(pick),
        ambiguous,
    }
}

/// One run of every (used) test: eta_v, flow (l/min), torque (N m).
#[derive(Debug, Clone)]
struct RunOut {
    eta: Vec<f64>,
    flow_lpm: Vec<f64>,
    torque: Vec<f64>,
}

/// Simulates every row of `rows` with `effects`; None when a row fails.
fn run_rows(
    pump: &Arc<Pump>,
    effects: &[Effect],
    rows: &[&TestRow],
    micromotion: bool,
    displacement: f64,
) -> Option<RunOut> {
    let model = EffectModel::on(pump, effects).ok()?;
    // longest first (high speed takes more revolutions to the periodic state)
    let mut order: Vec<usize> = (0..rows.len()).collect();
    order.sort_by(|&a, &b| rows[b].speed.total_cmp(&rows[a].speed));
    let res: Vec<(usize, Option<(f64, f64)>)> = order
        .par_iter()
        .with_max_len(1)
        .map(|&k| {
            let row = rows[k];
            let s = simulate_test(&model, row, row.torque, micromotion).ok();
            (k, s.map(|s| (s.flow, s.torque)))
        })
        .collect();
    let mut out = RunOut {
        eta: vec![f64::NAN; rows.len()],
        flow_lpm: vec![f64::NAN; rows.len()],
        torque: vec![f64::NAN; rows.len()],
    };
    for (k, r) in res {
        let (flow, torque) = r?;
        if !flow.is_finite() {
            return None;
        }
        out.eta[k] = eta_v(flow, displacement, rows[k].speed);
        out.flow_lpm[k] = m3_s_to_lpm(flow);
        out.torque[k] = torque;
    }
    Some(out)
}

fn conditions_json(summaries: &[ConditionSummary]) -> Value {
    Value::Array(
        summaries
            .iter()
            .map(|s| {
                json!({
                    "pressure_bar": s.condition.pressure_bar,
                    "speed_rpm": s.condition.speed_rpm,
                    "temp_c": s.condition.temp_c,
                    "n_samples": s.stats.n_samples,
                    "d_mean": s.stats.d_mean,
                    "d_std": s.stats.d_std,
                    "ci_low": s.stats.ci_low,
                    "ci_high": s.stats.ci_high,
                    "delta_nu": s.stats.delta_nu,
                })
            })
            .collect(),
    )
}

fn delta_nu_max(summaries: &[ConditionSummary]) -> Option<f64> {
    summaries
        .iter()
        .filter_map(|s| s.stats.delta_nu)
        .fold(None, |m: Option<f64>, x| Some(m.map_or(x, |m| m.max(x))))
}

fn findings_json(f: &[Finding], alpha: f64) -> Value {
    Value::Array(
        f.iter()
            .map(|x| {
                let mut v = serde_json::to_value(x).unwrap_or(Value::Null);
                if let Value::Object(m) = &mut v {
                    m.insert("significant".into(), json!(x.p_adjusted < alpha));
                }
                v
            })
            .collect(),
    )
}

/// A candidate after fitting and cross-validation.
struct Scored {
    spec: CandidateSpec,
    fit: Fit,
    /// The run at the fitted parameters (None when the fit stayed at the
    /// base model).
    at_fit: Option<RunOut>,
    /// Held-out mean squared residual per pump.
    pump_mse: Vec<f64>,
    score: CandidateScore,
}

/// The measurement that would separate two fitted candidates.
#[derive(Debug, Clone)]
pub struct Separation {
    pub condition: Condition,
    /// Predicted eta_v of (cause, other) there, on a median pump.
    pub eta: (f64, f64),
    pub text: String,
}

/// The extended model of the chosen candidate `s` and its gain: a real run
/// at the fitted parameters (the fit's last accepted point when it was one,
/// else a new run, counted in the runs returned).
fn extend_with(
    s: &Scored,
    ctx: &CandidateContext<'_>,
    jobs: Option<usize>,
    baseline: &CampaignResult,
    used: &[usize],
    residual_rows: &[ResidualRow],
) -> Result<(Option<ExtendedRun>, usize), RunError> {
    let effect = s
        .spec
        .effect_at(&s.fit.lin.u)
        .map_err(|message| RunError::Setting {
            setting: Setting::Data,
            message: format!("fitted {}: {message}", s.spec.effect),
        })?;
    // the fit's last accepted point is a real run of the extended model
    let (run, runs) = match &s.at_fit {
        Some(r) => (Some(r.clone()), 0),
        None => (
            with_pool(jobs, || {
                run_rows(
                    ctx.pump,
                    &[effect],
                    ctx.rows,
                    ctx.micromotion,
                    ctx.displacement,
                )
            })?,
            1,
        ),
    };
    let Some(run) = run else {
        return Ok((None, runs));
    };
    let groups_all = group_by_condition(&baseline.campaign.rows);
    let e = extended_run(
        baseline,
        used,
        ctx.meas,
        &run,
        effect,
        residual_rows,
        &groups_all,
    )?;
    Ok((Some(e), runs))
}

/// The extended model's record in `diagnosis.json`: the effect, its
/// parameters and their jackknife standard errors, its error and what it
/// still leaves (findings at `strict`).
fn extended_json(e: &ExtendedRun, scored: &[Scored], strict: f64) -> Value {
    json!({
        "effect": e.effect.name(),
        "params": e.effect.params_edge().into_iter().map(|(k, v)| (k.to_string(), json!(v))).collect::<Map<String, Value>>(),
        // jackknife (leave one pump out) standard errors of the fit
        "params_se": scored
            .iter()
            .find(|s| s.spec.effect == e.effect.name())
            .map(|s| Value::Object(s.score.params_se.clone()))
            .unwrap_or(Value::Null),
        "rmse": e.rmse,
        "delta_nu_max": delta_nu_max(&e.summaries),
        "conditions": conditions_json(&e.summaries),
        "remaining_findings": findings_json(&e.findings, strict),
    })
}

/// The extension's gain over the baseline in `diagnosis.json`.
fn gain_json(e: &ExtendedRun, base_rmse: f64, base_summaries: &[ConditionSummary]) -> Value {
    json!({
        "rmse_ratio": e.rmse / base_rmse,
        "delta_nu_max_before": delta_nu_max(base_summaries),
        "delta_nu_max_after": delta_nu_max(&e.summaries),
    })
}

/// Writes the extended model's campaign files (into `extended/`, when a
/// candidate was chosen and run) and `diagnosis.json` beside the
/// baseline's files; returns every file of the result so far.
fn write_files(
    dir: &Path,
    baseline: &CampaignResult,
    extended: Option<&ExtendedRun>,
    v: &Value,
) -> Result<Vec<PathBuf>, RunError> {
    let mut files = baseline.files.clone();
    if let Some(e) = extended {
        let ext = dir.join(EXTENDED_DIR);
        fs::create_dir_all(&ext).map_err(|source| RunError::Io {
            path: ext.clone(),
            source,
        })?;
        files.push(write_tests_csv(&ext, &baseline.campaign, &e.outcomes)?);
        files.push(write_conditions_csv(&ext, &e.summaries)?);
    }
    let json_path = dir.join(DIAGNOSIS_JSON);
    let text = serde_json::to_string_pretty(v).map_err(|e| RunError::Setting {
        setting: Setting::Output,
        message: format!("diagnosis.json: {e}"),
    })?;
    atomic_write_text(&json_path, &(text + "\n"))?;
    files.push(json_path);
    Ok(files)
}

/// The verdict (step 3 of the decision rule in the module doc): the cause
/// (the chosen candidate, when its extended model leaves no structure at
/// Holm-adjusted p < alpha/5), whether something stays unexplained, and
/// the features that do.
fn verdict(
    chosen: Option<usize>,
    extended: Option<&ExtendedRun>,
    base_findings: &[Finding],
    alpha: f64,
) -> (Option<usize>, bool, Vec<&'static str>) {
    let strict = alpha / 5.0;
    let remaining: &[Finding] = extended.map(|e| &e.findings[..]).unwrap_or_default();
    let structure_remains = remaining.iter().any(|f| f.p_adjusted < strict);
    let base_structure: Vec<&Finding> = base_findings
        .iter()
        .filter(|f| f.p_adjusted < alpha)
        .collect();
    match chosen {
        Some(c) if extended.is_some() && !structure_remains => (Some(c), false, vec![]),
        Some(_) if extended.is_some() => (
            None,
            true,
            remaining
                .iter()
                .filter(|f| f.p_adjusted < strict)
                .map(|f| f.feature)
                .collect(),
        ),
        _ => (
            None,
            !base_structure.is_empty(),
            base_structure.iter().map(|f| f.feature).collect(),
        ),
    }
}

/// What scoring a candidate needs of the diagnosis.
struct CandidateContext<'a> {
    pump: &'a Arc<Pump>,
    rows: &'a [&'a TestRow],
    micromotion: bool,
    displacement: f64,
    meas: &'a [f64],
    base: &'a [f64],
    pumps: &'a [Vec<usize>],
    base_pump_mse: &'a [f64],
    base_rmse: f64,
}

impl CandidateContext<'_> {
    /// The held-out mean squared residual per pump of a candidate's
    /// cross-validated `residual`, and the paired test of its improvement
    /// over the base model's (statistic, p).
    fn improvement(&self, residual: &[f64]) -> (Vec<f64>, (f64, f64)) {
        let m = pump_mse(residual, self.pumps);
        let diff: Vec<f64> = self
            .base_pump_mse
            .iter()
            .zip(&m)
            .map(|(a, b)| a - b)
            .collect();
        let test = paired_improvement(&diff);
        (m, test)
    }
}

/// Fits one candidate (few model runs), cross-validates it over the pumps
/// and scores its improvement over the base model; `best_cv` is the best
/// held-out RMSE so far (a candidate far behind it stops early).
fn score_candidate(
    spec: CandidateSpec,
    ctx: &CandidateContext<'_>,
    best_cv: f64,
    say: &dyn Fn(String),
) -> Scored {
    let mut cache: Vec<(Vec<f64>, RunOut)> = Vec::new();
    let mut run = |u: &[f64]| -> Option<Vec<f64>> {
        let effect = spec.effect_at(u).ok()?;
        let t = Instant::now();
        let r = run_rows(
            ctx.pump,
            &[effect],
            ctx.rows,
            ctx.micromotion,
            ctx.displacement,
        );
        say(format!(
            "  run {} ({:.1} s){}",
            effect,
            t.elapsed().as_secs_f64(),
            if r.is_none() { ": failed" } else { "" }
        ));
        let r = r?;
        let eta = r.eta.clone();
        cache.push((u.to_vec(), r));
        Some(eta)
    };
    let mut keep_going = |lin: &super::candidates::Linearisation, steps: usize| {
        let cv = cross_validate(&spec, lin, ctx.meas, ctx.pumps);
        let (_, (_, p)) = ctx.improvement(&cv.residual);
        p <= HOPELESS_P
            && rmse(&cv.residual)
                <= if steps == 0 {
                    OUTCLASSED_LINEAR
                } else {
                    OUTCLASSED
                } * best_cv
    };
    say(format!("candidate {}", spec.effect));
    let fit = fit_candidate(
        &spec,
        ctx.meas,
        ctx.base,
        &mut run,
        FitOptions::default(),
        &mut keep_going,
    );
    let at_fit = cache
        .into_iter()
        .rev()
        .find(|(u, _)| *u == fit.lin.u)
        .map(|(_, r)| r);
    let cv = cross_validate(&spec, &fit.lin, ctx.meas, ctx.pumps);
    let (m, (t, p)) = ctx.improvement(&cv.residual);
    let se = jackknife_se(&spec, &cv.fold_u);
    // a fit that stopped before converging reports the optimum its
    // linearisation predicts (what its CV score measured), flagged
    let predicted = !fit.converged;
    let u_report = if predicted {
        let lower: Vec<f64> = spec.params.iter().map(|q| q.lower_u).collect();
        let upper: Vec<f64> = spec.params.iter().map(|q| q.upper_u).collect();
        let all: Vec<usize> = (0..ctx.meas.len()).collect();
        fit.lin.bounded_fit(ctx.meas, &all, &lower, &upper)
    } else {
        fit.lin.u.clone()
    };
    let mut params = Map::new();
    let mut params_se = Map::new();
    for ((name, v), s) in spec.edge_params(&u_report).into_iter().zip(se) {
        params.insert(name.into(), json!(v));
        params_se.insert(name.into(), json!(s));
    }
    let fit_resid: Vec<f64> = (0..ctx.meas.len())
        .map(|i| ctx.meas[i] - fit.lin.predict(i, &u_report))
        .collect();
    let score = CandidateScore {
        effect: spec.effect,
        params,
        params_se,
        cv_rmse: rmse(&cv.residual),
        fit_rmse: rmse(&fit_resid),
        statistic: t,
        p_value: p,
        p_adjusted: 1.0,
        runs: fit.runs,
        converged: fit.converged,
        params_predicted: predicted,
        note: fit.note.clone(),
    };
    say(format!(
        "  {}: {} cv_rmse {:.5} (base {:.5}) p {:.2e} [{} runs]",
        spec.effect,
        fmt_params(&spec.edge_params(&u_report)),
        score.cv_rmse,
        ctx.base_rmse,
        p,
        fit.runs
    ));
    Scored {
        spec,
        fit,
        at_fit,
        pump_mse: m,
        score,
    }
}

/// Runs the diagnosis (see the module doc); writes the campaign's files plus
/// `diagnosis.json`, `report.md` (replacing the campaign's), the extended
/// model's `extended/tests.csv` and `extended/conditions.csv`, and plots.
pub fn run_diagnosis(
    source: &DesignSource,
    data: &Path,
    out: &Path,
    options: DiagnoseOptions,
    observer: &dyn Observer,
) -> Result<Diagnosis, RunError> {
    let start = Instant::now();
    if options.jobs == Some(0) {
        return Err(RunError::Setting {
            setting: Setting::Jobs,
            message: "must be >= 1".into(),
        });
    }
    // narration goes to the observer (the library never prints)
    let say = |msg: String| {
        if options.verbose {
            observer.message(&format!("diagnose: {msg}"));
        }
    };
    // the whole result (the campaign's files, the diagnosis's) is written
    // into one staging folder and moved into `out` at the end: a run that
    // fails half-way leaves `out` as it was, and the commit removes an
    // earlier result's files the new one lacks (campaign::io, "Output
    // folders")
    let (baseline, journal, stage) = run_campaign_staged(
        source,
        data,
        out,
        CampaignOptions {
            jobs: options.jobs,
            micromotion: options.micromotion,
        },
        observer,
    )?;
    let dir = stage.path().to_path_buf();
    say(format!(
        "baseline campaign: {} tests ({} simulated, {} reused) in {:.1} s",
        baseline.outcomes.len(),
        baseline.simulated,
        baseline.reused,
        start.elapsed().as_secs_f64()
    ));
    let design = &source.design;
    // the tests with a baseline result
    let used: Vec<usize> = (0..baseline.outcomes.len())
        .filter(|&i| baseline.outcomes[i].d.is_finite())
        .collect();
    let rows: Vec<&TestRow> = used.iter().map(|&i| &baseline.campaign.rows[i]).collect();
    let meas: Vec<f64> = used
        .iter()
        .map(|&i| baseline.outcomes[i].eta_v_meas)
        .collect();
    let base: Vec<f64> = used
        .iter()
        .map(|&i| baseline.outcomes[i].eta_v_sim)
        .collect();
    let residual_rows = rows_from_campaign(&baseline, &design.oil);
    debug_assert_eq!(residual_rows.len(), used.len());
    let sample: Vec<usize> = residual_rows.iter().map(|r| r.sample).collect();
    let pumps = groups(&sample);
    if pumps.len() < 4 {
        return Err(RunError::Setting {
            setting: Setting::Data,
            message: format!(
                "a diagnosis needs at least 4 pump samples with results (pumps are the \
                 independent units of every test), got {}",
                pumps.len()
            ),
        });
    }
    let base_findings = findings(&residual_rows);
    let d_base: Vec<f64> = meas.iter().zip(&base).map(|(m, s)| m - s).collect();
    let base_rmse = rmse(&d_base);
    let base_pump_mse = pump_mse(&d_base, &pumps);

    // ---- candidates
    let t_cand = Instant::now();
    let pump = Arc::new(Pump::new(design.clone()));
    let displacement = baseline.displacement;
    let specs = candidate_specs(design);
    let mut total_runs = 0usize;
    let ctx = CandidateContext {
        pump: &pump,
        rows: &rows,
        micromotion: options.micromotion,
        displacement,
        meas: &meas,
        base: &base,
        pumps: &pumps,
        base_pump_mse: &base_pump_mse,
        base_rmse,
    };
    let scored: Vec<Scored> = with_pool(options.jobs, || {
        let mut scored = Vec::new();
        let mut best_cv = f64::INFINITY;
        for spec in specs {
            let s = score_candidate(spec, &ctx, best_cv, &say);
            best_cv = best_cv.min(s.score.cv_rmse);
            scored.push(s);
        }
        scored
    })?;
    let mut scored = scored;
    let adj = holm(&scored.iter().map(|s| s.score.p_value).collect::<Vec<_>>());
    for (s, a) in scored.iter_mut().zip(adj) {
        s.score.p_adjusted = a;
        total_runs += s.fit.runs;
    }
    let alpha = options.alpha;

    // ---- decision
    let decision = decide(
        &scored
            .iter()
            .map(|s| CandidateRank {
                n_params: s.spec.params.len(),
                cv_rmse: s.score.cv_rmse,
                p_adjusted: s.score.p_adjusted,
                pump_mse: &s.pump_mse,
            })
            .collect::<Vec<_>>(),
        alpha,
    );
    let chosen = decision.chosen;
    let ambiguous = decision.ambiguous;

    // ---- extension and gain: a real run at the fitted parameters
    let extended = match chosen {
        Some(c) => {
            let (e, runs) = extend_with(
                &scored[c],
                &ctx,
                options.jobs,
                &baseline,
                &used,
                &residual_rows,
            )?;
            total_runs += runs;
            e
        }
        None => None,
    };
    let strict = alpha / 5.0;
    let (cause, unexplained, unexplained_features) =
        verdict(chosen, extended.as_ref(), &base_findings, alpha);

    // ---- what would separate the ambiguous candidates
    let mut separations: Vec<(usize, f64, Option<Separation>)> = Vec::new();
    if let Some(c) = chosen {
        for &(o, p) in &ambiguous {
            let sep = with_pool(options.jobs, || {
                let effect = |s: &Scored| s.spec.effect_at(&s.fit.lin.u).ok();
                separating_measurement(
                    &pump,
                    effect(&scored[c])?,
                    effect(&scored[o])?,
                    &rows,
                    displacement,
                    options.micromotion,
                    design,
                )
            })?;
            separations.push((o, p, sep));
        }
    }

    let base_summaries = &baseline.summaries;
    let mut candidates_sorted: Vec<&Scored> = scored.iter().collect();
    candidates_sorted.sort_by(|a, b| a.score.cv_rmse.total_cmp(&b.score.cv_rmse));
    let ext_json = |e: &ExtendedRun| extended_json(e, &scored, strict);
    let gain_json = |e: &ExtendedRun| gain_json(e, base_rmse, base_summaries);
    let cause_name = cause.map(|c| scored[c].spec.effect);
    let partial = match (cause, chosen, &extended) {
        (None, Some(c), Some(e)) => json!({
            "effect": scored[c].spec.effect,
            "extended": ext_json(e),
            "gain": gain_json(e),
            "why_not_cause": format!(
                "its extended model still leaves significant structure (Holm-adjusted p < {strict}) in: {}",
                unexplained_features.join(", ")
            ),
        }),
        _ => Value::Null,
    };
    let wall_s = start.elapsed().as_secs_f64();
    let v = json!({
        "data": data.display().to_string(),
        "design": source.label,
        "sets": source.sets,
        "tests": used.len(),
        "failed_rows": baseline.failed.len(),
        "pumps": pumps.len(),
        "micromotion": options.micromotion,
        "alpha": alpha,
        "baseline": {
            "rmse": base_rmse,
            "delta_nu_max": delta_nu_max(base_summaries),
            "conditions": conditions_json(base_summaries),
        },
        "findings": findings_json(&base_findings, alpha),
        "candidates": candidates_sorted.iter().map(|s| serde_json::to_value(&s.score).unwrap_or(Value::Null)).collect::<Vec<_>>(),
        "cause": cause_name,
        "ambiguous_with": separations.iter().map(|(o, p, sep)| json!({
            "effect": scored[*o].spec.effect,
            "p_cause_better": p,
            "cv_rmse": scored[*o].score.cv_rmse,
            "measurement": sep.as_ref().map(|s| s.text.clone()),
            "condition": sep.as_ref().map(|s| json!({
                "pressure_bar": s.condition.pressure_bar,
                "speed_rpm": s.condition.speed_rpm,
                "temp_c": s.condition.temp_c,
                "eta_v_cause": s.eta.0,
                "eta_v_other": s.eta.1,
            })),
        })).collect::<Vec<_>>(),
        "unexplained": unexplained,
        "unexplained_features": unexplained_features,
        "partial": partial,
        "extended": match (cause, &extended) { (Some(_), Some(e)) => ext_json(e), _ => Value::Null },
        "gain": match (cause, &extended) { (Some(_), Some(e)) => gain_json(e), _ => Value::Null },
        "runs": total_runs,
        "candidate_stage_s": t_cand.elapsed().as_secs_f64(),
        "wall_s": wall_s,
    });

    // ---- files
    let files = write_files(
        &dir,
        &baseline,
        extended.as_ref().filter(|_| chosen.is_some()),
        &v,
    )?;
    let diagnosis = Diagnosis {
        cause: cause_name,
        unexplained,
        ambiguous_with: separations
            .iter()
            .map(|(o, _, _)| scored[*o].spec.effect)
            .collect(),
        baseline_rmse: base_rmse,
        extended_rmse: extended
            .as_ref()
            .filter(|_| chosen.is_some())
            .map(|e| e.rmse),
        findings: base_findings,
        candidates: candidates_sorted.iter().map(|s| s.score.clone()).collect(),
        runs: total_runs,
        json: v,
        files,
    };
    let extra = super::report::write_report(
        &dir,
        &baseline,
        &diagnosis,
        extended.as_ref().map(|e| &e.outcomes[..]),
        &residual_rows,
        extended.as_ref().map(|e| &e.rows[..]),
    )?;
    let mut diagnosis = diagnosis;
    diagnosis.files.extend(extra);
    diagnosis.files = diagnosis
        .files
        .iter()
        .map(|f| stage.final_path(f))
        .collect();
    stage.commit()?;
    journal.finish()?;
    Ok(diagnosis)
}

/// The extended model's run over the whole campaign.
pub struct ExtendedRun {
    pub effect: Effect,
    pub outcomes: Vec<TestOutcome>,
    pub summaries: Vec<ConditionSummary>,
    pub rmse: f64,
    pub findings: Vec<Finding>,
    /// The residual rows with the extended model's residuals.
    pub rows: Vec<ResidualRow>,
}

fn extended_run(
    baseline: &CampaignResult,
    used: &[usize],
    meas: &[f64],
    run: &RunOut,
    effect: Effect,
    residual_rows: &[ResidualRow],
    groups_all: &[gearpump_campaign::ConditionGroup],
) -> Result<ExtendedRun, RunError> {
    let mut outcomes: Vec<TestOutcome> = baseline
        .outcomes
        .iter()
        .map(|o| TestOutcome {
            flow_lpm_sim: f64::NAN,
            eta_v_sim: f64::NAN,
            d: f64::NAN,
            torque_nm_sim: f64::NAN,
            losses: [f64::NAN; LOSS_COLUMNS],
            ..*o
        })
        .collect();
    let mut rr: Vec<ResidualRow> = residual_rows.to_vec();
    let mut d = Vec::with_capacity(used.len());
    for (k, &i) in used.iter().enumerate() {
        let o = &mut outcomes[i];
        o.flow_lpm_sim = run.flow_lpm[k];
        o.eta_v_sim = run.eta[k];
        o.d = meas[k] - run.eta[k];
        o.torque_nm_sim = run.torque[k];
        rr[k].d = o.d;
        if let (Some(t), Some(m)) = (
            rr[k].torque_residual.as_mut(),
            baseline.campaign.rows[i].torque,
        ) {
            *t = m - run.torque[k];
        }
        d.push(o.d);
    }
    let all_d: Vec<f64> = outcomes.iter().map(|o| o.d).collect();
    let summaries = summarize(groups_all, &all_d, ALPHA)?;
    Ok(ExtendedRun {
        effect,
        outcomes,
        summaries,
        rmse: rmse(&d),
        findings: findings(&rr),
        rows: rr,
    })
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The lowest eta_v (either model) at a condition proposed as a separating
/// measurement: below, the pump delivers too little for a meaningful test.
pub const MIN_SEPARATION_ETA: f64 = 0.5;

/// Runs both fitted candidates on a median pump over the measured (pressure,
/// speed) pairs and, for each measured speed, 1.5 times the highest measured
/// pressure, each at the measured temperatures and at new ones (between the
/// measured ones, 20 K below and above, within the oil model's range), and
/// returns the condition where their eta_v differ most among those where
/// both have the pump deliver at least [`MIN_SEPARATION_ETA`] of its
/// displacement.
pub fn separating_measurement(
    pump: &Arc<Pump>,
    ea: Effect,
    eb: Effect,
    rows: &[&TestRow],
    displacement: f64,
    micromotion: bool,
    design: &gearpump_core::design::Design,
) -> Option<Separation> {
    let ma = EffectModel::on(pump, &[ea]).ok()?;
    let mb = EffectModel::on(pump, &[eb]).ok()?;
    let uniq = |f: &dyn Fn(&TestRow) -> f64| {
        let mut v: Vec<f64> = rows.iter().map(|r| f(r)).collect();
        v.sort_by(f64::total_cmp);
        v.dedup_by(|a, b| (*a - *b).abs() < 1e-9 * b.abs().max(1.0));
        v
    };
    let temps_c = uniq(&|r| r.condition.temp_c);
    let press = uniq(&|r| r.condition.pressure_bar);
    let speeds = uniq(&|r| r.condition.speed_rpm);
    let (tmin, tmax) = (*temps_c.first()?, *temps_c.last()?);
    let mut t_try = temps_c.clone();
    for t in [0.5 * (tmin + tmax), tmin - 20.0, tmax + 20.0] {
        if design.oil.in_range(celsius_to_kelvin(t)) && !t_try.iter().any(|x| (x - t).abs() < 1.0) {
            t_try.push(t);
        }
    }
    let pmax = *press.last()?;
    // the measured (pressure, speed) pairs, and each measured speed at a
    // pressure 1.5 times the highest measured
    let mut ps: Vec<(f64, f64)> = Vec::new();
    for r in rows {
        let k = (r.condition.pressure_bar, r.condition.speed_rpm);
        if !ps.contains(&k) {
            ps.push(k);
        }
    }
    for &s in &speeds {
        ps.push((1.5 * pmax, s));
    }
    let clear = SampleClearances {
        tip: [
            median(rows.iter().map(|r| r.tip_clearance[0]).collect()),
            median(rows.iter().map(|r| r.tip_clearance[1]).collect()),
        ],
        bearing: [
            median(rows.iter().map(|r| r.bearing_clearance[0]).collect()),
            median(rows.iter().map(|r| r.bearing_clearance[1]).collect()),
        ],
        lateral: design.clearance.lateral,
    };
    let grid: Vec<(f64, f64, f64)> = t_try
        .iter()
        .flat_map(|&t| ps.iter().map(move |&(p, s)| (p, s, t)))
        .collect();
    let eval = |m: &EffectModel, (p, s, t): (f64, f64, f64)| -> Option<f64> {
        let inputs = gearpump_core::model::Inputs {
            omega: rpm_to_rad_s(s),
            p_suction: gearpump_core::units::ATMOSPHERE_PA,
            p_delivery: gearpump_core::units::ATMOSPHERE_PA + bar_to_pa(p),
            temp_k: celsius_to_kelvin(t),
            measured_torque: None,
        };
        let mut sim = m
            .simulation(inputs, clear, gearpump_core::model::Options { micromotion })
            .ok()?;
        let sum = sim.run_periodic().ok()?;
        Some(eta_v(sum.flow, displacement, inputs.omega))
    };
    type Point = (f64, f64, f64);
    // a test a rig would run: both models have the pump deliver at least
    // half its displacement there
    let res: Vec<Option<(f64, f64, Point)>> = grid
        .par_iter()
        .map(|&g| Some((eval(&ma, g)?, eval(&mb, g)?, g)))
        .map(|r| r.filter(|&(a, b, _)| a.min(b) >= MIN_SEPARATION_ETA))
        .collect();
    let best = res
        .into_iter()
        .flatten()
        .max_by(|a, b| (a.0 - a.1).abs().total_cmp(&(b.0 - b.1).abs()))?;
    let (ea_v, eb_v, (p, s, t)) = best;
    let mut novelty = Vec::new();
    if !temps_c.iter().any(|x| (x - t).abs() < 1.0) {
        novelty.push(if temps_c.len() == 2 {
            "a third oil temperature".to_string()
        } else {
            "another oil temperature".to_string()
        });
    }
    if !press.iter().any(|x| (x - p).abs() < 1e-6) {
        novelty.push("a higher delivery pressure".to_string());
    }
    let what = if novelty.is_empty() {
        "more tests at a measured condition".to_string()
    } else {
        novelty.join(" and ")
    };
    Some(Separation {
        condition: Condition {
            pressure_bar: p,
            speed_rpm: s,
            temp_c: t,
        },
        eta: (ea_v, eb_v),
        text: format!(
            "{what}: at {p:.0} bar, {s:.0} rpm, {t:.0} degC the fitted {} and {} predict eta_v {:.4} and {:.4} ({:+.4})",
            ea,
            eb,
            ea_v,
            eb_v,
            ea_v - eb_v
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Per-pump MSEs: `level` plus a deterministic spread.
    fn mse(level: f64, spread: f64) -> Vec<f64> {
        (0..20)
            .map(|i| level + spread * (((i * 7) % 11) as f64 / 10.0 - 0.5))
            .collect()
    }

    #[test]
    fn a_clear_winner_is_chosen_alone() {
        let a = mse(1.0e-5, 2e-6);
        let b = mse(4.0e-5, 2e-6);
        let base = mse(9.0e-5, 2e-6);
        let c = [
            CandidateRank {
                n_params: 1,
                cv_rmse: 0.0032,
                p_adjusted: 1e-9,
                pump_mse: &a,
            },
            CandidateRank {
                n_params: 1,
                cv_rmse: 0.0063,
                p_adjusted: 1e-6,
                pump_mse: &b,
            },
            CandidateRank {
                n_params: 1,
                cv_rmse: 0.0095,
                p_adjusted: 0.8,
                pump_mse: &base,
            },
        ];
        let d = decide(&c, 0.05);
        assert_eq!((d.winner, d.chosen), (Some(0), Some(0)));
        assert!(d.ambiguous.is_empty());
    }

    #[test]
    fn indistinguishable_candidates_prefer_fewer_parameters_and_are_reported() {
        // the 2-parameter one is marginally better on average but not
        // significantly (noisy per-pump differences)
        let two = mse(1.00e-5, 4e-6);
        let one: Vec<f64> = two
            .iter()
            .enumerate()
            .map(|(i, x)| x + if i % 2 == 0 { 3e-6 } else { -2.8e-6 })
            .collect();
        let c = [
            CandidateRank {
                n_params: 2,
                cv_rmse: 0.00316,
                p_adjusted: 1e-9,
                pump_mse: &two,
            },
            CandidateRank {
                n_params: 1,
                cv_rmse: 0.00317,
                p_adjusted: 1e-9,
                pump_mse: &one,
            },
        ];
        let d = decide(&c, 0.05);
        assert_eq!(d.winner, Some(0));
        assert_eq!(d.chosen, Some(1));
        assert_eq!(d.ambiguous.len(), 1);
        assert_eq!(d.ambiguous[0].0, 0);
        assert!(d.ambiguous[0].1 >= 0.05);
    }

    #[test]
    fn nothing_significant_gives_no_cause() {
        let a = mse(1.0e-5, 2e-6);
        let c = [CandidateRank {
            n_params: 1,
            cv_rmse: 0.003,
            p_adjusted: 0.2,
            pump_mse: &a,
        }];
        let d = decide(&c, 0.05);
        assert_eq!(
            d,
            Decision {
                winner: None,
                chosen: None,
                ambiguous: vec![]
            }
        );
    }
}
