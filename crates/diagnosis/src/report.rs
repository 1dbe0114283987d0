//! The diagnosis' `report.md` (it replaces the campaign's report in the
//! output folder and links the campaign's figures) and its figures:
//! * `diagnosis.svg`: left, the per-condition mean residual with its 95 %
//!   confidence interval before (grey) and after (blue) the extension; right,
//!   the candidates' cross-validated RMSE against the base model's.
//! * `diagnosis_features.svg`: d against every feature the findings test
//!   (pressure, speed, temperature, viscosity, slip group, torque residual,
//!   the four clearances), base model grey, extended blue.
//! * `extended/residuals.svg`, `extended/curves_*.svg`: the campaign figures
//!   of the extended model.

use std::path::{Path, PathBuf};

use plotters::prelude::*;
use serde_json::Value;

use super::findings::ResidualRow;
use super::verdict::{Diagnosis, EXTENDED_DIR};
use gearpump_campaign::io::{atomic_write_text, TestOutcome};
use gearpump_campaign::plots::write_plots;
use gearpump_campaign::run::REPORT_MD;
use gearpump_campaign::run::{CampaignResult, RunError};
use gearpump_core::units::{kelvin_to_celsius, m_to_um, pa_s_to_mpa_s, pa_to_bar, rad_s_to_rpm};

const FONT: &str = "sans-serif";
pub const DIAGNOSIS_SVG: &str = "diagnosis.svg";
pub const FEATURES_SVG: &str = "diagnosis_features.svg";

fn num(v: &Value) -> String {
    match v.as_f64() {
        Some(x) if x != 0.0 && (x.abs() < 1e-3 || x.abs() >= 1e5) => format!("{x:.3e}"),
        Some(x) => format!("{x:.4}"),
        None => "-".into(),
    }
}

fn conditions_table(md: &mut String, before: &Value, after: Option<&Value>) {
    let empty = Vec::new();
    let b = before.as_array().unwrap_or(&empty);
    let a = after.and_then(Value::as_array);
    if a.is_some() {
        md.push_str("| p (bar) | n (rpm) | T (degC) | n_s | d_mean before | S_d before | Delta_nu before | d_mean after | S_d after | Delta_nu after |\n|---|---|---|---|---|---|---|---|---|---|\n");
    } else {
        md.push_str("| p (bar) | n (rpm) | T (degC) | n_s | d_mean | S_d | CI low | CI high | Delta_nu |\n|---|---|---|---|---|---|---|---|---|\n");
    }
    for (k, c) in b.iter().enumerate() {
        let mut line = format!(
            "| {} | {} | {} | {} |",
            c["pressure_bar"], c["speed_rpm"], c["temp_c"], c["n_samples"]
        );
        match a.and_then(|a| a.get(k)) {
            Some(x) => line.push_str(&format!(
                " {} | {} | {} | {} | {} | {} |",
                num(&c["d_mean"]),
                num(&c["d_std"]),
                num(&c["delta_nu"]),
                num(&x["d_mean"]),
                num(&x["d_std"]),
                num(&x["delta_nu"])
            )),
            None => line.push_str(&format!(
                " {} | {} | {} | {} | {} |",
                num(&c["d_mean"]),
                num(&c["d_std"]),
                num(&c["ci_low"]),
                num(&c["ci_high"]),
                num(&c["delta_nu"])
            )),
        }
        md.push_str(&line);
        md.push('\n');
    }
}

/// ", over the pumps analysed: N09 set aside" when out-of-family pumps were
/// set aside (the gain is over the others), else nothing.
fn set_aside_note(gain: &Value) -> String {
    let aside: Vec<&str> = gain["pumps_set_aside"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(Value::as_str)
        .collect();
    if aside.is_empty() {
        String::new()
    } else {
        format!(", over the pumps analysed: {} set aside", aside.join(", "))
    }
}

fn report_text(v: &Value, figures: &[(String, String)]) -> String {
    let mut md = String::new();
    md.push_str("# Diagnosis\n\n");
    md.push_str(&format!(
        "Data `{}`, design `{}`, {} tests on {} pumps ({} rows without a simulated result), micromotion {}, alpha {}.\n\n",
        v["data"].as_str().unwrap_or("?"),
        v["design"].as_str().unwrap_or("?"),
        v["tests"],
        v["pumps"],
        v["failed_rows"],
        v["micromotion"],
        v["alpha"]
    ));
    // verdict
    md.push_str("## Verdict\n\n");
    let causes = v["causes"].as_array().cloned().unwrap_or_default();
    let unexplained = v["unexplained"].as_bool() == Some(true);
    let named = |x: &Value| -> Vec<String> {
        x.as_array()
            .map(|a| {
                a.iter()
                    .filter_map(Value::as_str)
                    .map(str::to_string)
                    .collect()
            })
            .unwrap_or_default()
    };
    if !causes.is_empty() {
        md.push_str(&format!(
            "**Cause{}: {}**. The extended model cuts the RMSE of d from {} to {} (ratio {}{}); Delta_nu max {} -> {}.\n\n",
            if causes.len() > 1 { "s" } else { "" },
            causes
                .iter()
                .map(|c| format!("`{}`", c["effect"].as_str().unwrap_or("?")))
                .collect::<Vec<_>>()
                .join(" then "),
            num(&v["gain"]["rmse_before"]),
            num(&v["gain"]["rmse_after"]),
            num(&v["gain"]["rmse_ratio"]),
            set_aside_note(&v["gain"]),
            num(&v["gain"]["delta_nu_max_before"]),
            num(&v["gain"]["delta_nu_max_after"]),
        ));
        md.push_str("| # | cause | parameters (95 % interval) | Holm p | structure before -> after |\n|---|---|---|---|---|\n");
        for (k, c) in causes.iter().enumerate() {
            let params: Vec<String> = c["params"]
                .as_object()
                .map(|m| {
                    m.iter()
                        .map(|(name, x)| {
                            let iv = &c["interval_95"][name];
                            format!("{name} = {} ({} .. {})", num(x), num(&iv[0]), num(&iv[1]))
                        })
                        .collect()
                })
                .unwrap_or_default();
            md.push_str(&format!(
                "| {} | `{}` | {} | {} | {} -> {} |\n",
                k + 1,
                c["effect"].as_str().unwrap_or("?"),
                params.join(", "),
                num(&c["p_adjusted"]),
                num(&c["gain"]["structure_before"]),
                num(&c["gain"]["structure_after"]),
            ));
        }
        md.push('\n');
    } else if let Some(p) = v["partial"]["effect"].as_str() {
        md.push_str(&format!(
            "**No cause.** `{p}` improves the fit significantly (RMSE ratio {}{}) but {}.\n\n",
            num(&v["partial"]["gain"]["rmse_ratio"]),
            set_aside_note(&v["partial"]["gain"]),
            v["partial"]["why_not_cause"].as_str().unwrap_or("")
        ));
    } else if unexplained {
        md.push_str("**No cause**: no candidate extension improves the fit significantly.\n\n");
    } else {
        md.push_str(
            "**No significant discrepancy that a candidate explains**: no extension improves the base model significantly, and its residuals show no material structure.\n\n",
        );
    }
    let st = &v["structure"];
    md.push_str(&format!(
        "Structure of the residual (RMS of what pump and condition levels follow, noise removed): {} before, {} after ({} of it left; F test of what is left p = {}); noise floor estimated from the data {}; material from {} (max of the noise floor and a quarter of the baseline RMSE), or, when the structure before was material, from a quarter of it if resolvable (p < 0.001).\n\n",
        num(&st["baseline"]["structure"]),
        num(&st["final"]["structure"]),
        num(&st["share_left"]),
        num(&st["final"]["p"]),
        num(&v["noise_floor"]),
        num(&st["threshold"]),
    ));
    if v["unexplained_by_torque"] == true {
        md.push_str("**Not explained**: the measured torque contradicts the causes, and no alternative fits eta_v that it does not contradict (below): no candidate explains both measurements.\n\n");
    } else if unexplained {
        let by_share = st["final"]["structure"].as_f64() < st["threshold"].as_f64();
        md.push_str(&format!(
            "**Not explained**: material structure remains ({}){}.\n\n",
            named(&v["unexplained_features"]).join(", "),
            if by_share {
                ": smaller than one test's scatter, but a quarter or more of the discrepancy the causes set out to explain, which a mechanism of the right kind removes up to small differences of form; the causes may stand in for an effect of another kind"
            } else {
                ""
            }
        ));
    }
    if let Some(r) = v["remaining"].as_array().filter(|a| !a.is_empty()) {
        md.push_str("What the model still leaves (significant features, largest first):\n\n| feature | kind | effect, eta_v points | Holm p | material |\n|---|---|---|---|---|\n");
        for x in r {
            md.push_str(&format!(
                "| {} | {} | {} | {} | {} |\n",
                x["feature"].as_str().unwrap_or("?"),
                x["kind"].as_str().unwrap_or("?"),
                num(&x["effect_points"]),
                num(&x["p_adjusted"]),
                if x["material"].as_bool() == Some(true) {
                    "yes"
                } else {
                    "no"
                },
            ));
        }
        md.push('\n');
    }
    if let Some(o) = v["out_of_family"].as_array().filter(|a| !a.is_empty()) {
        md.push_str(&format!(
            "**Out-of-family pumps** (mean residual apart from the population, robust z beyond 3.5): {}. ",
            o.iter()
                .map(|x| format!(
                    "{} (mean d {}, z {})",
                    x["sample"].as_str().unwrap_or("?"),
                    num(&x["mean_residual"]),
                    num(&x["robust_z"])
                ))
                .collect::<Vec<_>>()
                .join(", ")
        ));
        let w = &v["with_out_of_family"];
        md.push_str(&format!(
            "A residual level that stands apart is a fact about that pump (a mis-measured clearance, a damaged pump), not about the model: the verdict above is the analysis with them set aside. With them in, the analysis of every pump gives: cause {}, unexplained {} (RMSE ratio {}).\n\n",
            w["cause"].as_str().unwrap_or("none"),
            w["unexplained"],
            num(&w["rmse_ratio"]),
        ));
        let aside: Vec<&Value> = v["extended"]["pumps"]
            .as_array()
            .or(v["partial"]["extended"]["pumps"].as_array())
            .into_iter()
            .flatten()
            .filter(|p| p["set_aside"].as_bool() == Some(true))
            .collect();
        if !aside.is_empty() {
            md.push_str("The pumps set aside under the extended model:\n\n| pump | tests | mean d before | RMSE before | mean d after | RMSE after |\n|---|---|---|---|---|---|\n");
            for p in aside {
                md.push_str(&format!(
                    "| {} | {} | {} | {} | {} | {} |\n",
                    p["sample"].as_str().unwrap_or("?"),
                    p["tests"],
                    num(&p["baseline_mean_residual"]),
                    num(&p["baseline_rmse"]),
                    num(&p["mean_residual"]),
                    num(&p["rmse"]),
                ));
            }
            md.push('\n');
        }
    }
    let tq = &v["torque"];
    if tq.is_object() {
        md.push_str(&format!(
            "**Torque** ({} tests with a measured torque; T_sim of {}; RMSE of T_meas - T_sim {} N m, noise floor {} N m): ",
            tq["tests"],
            tq["model"].as_str().unwrap_or("the base model"),
            num(&tq["baseline_rmse_nm"]),
            num(&tq["noise_floor_nm"]),
        ));
        match tq["params"].as_array() {
            Some(p) if !p.is_empty() => md.push_str(&format!(
                "{} (theta: relative change of the loss coefficient, N m for a constant drag), RMSE after {} N m{}.\n\n",
                p.iter()
                    .map(|x| format!(
                        "`{}` theta = {} ({} .. {})",
                        x["candidate"].as_str().unwrap_or("?"),
                        num(&x["theta"]),
                        num(&x["interval_95"][0]),
                        num(&x["interval_95"][1])
                    ))
                    .collect::<Vec<_>>()
                    .join(" then "),
                num(&tq["rmse_after_nm"]),
                if tq["unexplained"] == true { "; material structure remains: not explained" } else { "" }
            )),
            _ if tq["withheld"].is_object() => md.push_str(&format!(
                "not explained: no loss coefficient is named while the torque contradicts the flow's causes (below); on the base model {} would have been fitted.\n\n",
                tq["withheld"]["causes"]
                    .as_array()
                    .map(|c| c
                        .iter()
                        .filter_map(Value::as_str)
                        .map(|c| format!("`{c}`"))
                        .collect::<Vec<_>>()
                        .join(" then "))
                    .unwrap_or_default()
            )),
            _ => md.push_str(if tq["unexplained"] == true {
                "no loss-model candidate explains it: not explained.\n\n"
            } else {
                "no material discrepancy.\n\n"
            }),
        }
        let check = &tq["flow_causes_check"];
        if check["worsened"] == true {
            md.push_str(&format!(
                "**The measured torque contradicts the flow's causes**: the model they extend fits the torque worse than the base model (structure {} N m against {} N m, RMSE {} against {} N m; {}). No flow candidate is fitted to the torque, so a true flow cause leaves it as it was or mends it; the torque above is therefore taken on the base model, and no loss coefficient is named. Suspect a flow deficit the candidates do not hold that leaves the torque alone, such as the flowmeter's calibration, before the named cause.\n\n",
                num(&check["extended_structure_nm"]),
                num(&check["base_structure_nm"]),
                num(&check["extended_rmse_nm"]),
                num(&check["base_rmse_nm"]),
                if check["by_size"] == false {
                    format!(
                        "more than twice as much, resolvable: F test p = {}, below one test's scatter, {} N m",
                        num(&check["extended_p"]),
                        num(&check["material_nm"])
                    )
                } else {
                    format!("material from {} N m", num(&check["material_nm"]))
                },
            ));
            let alt = &check["flowmeter_alternative"];
            if alt.is_object() {
                md.push_str(&format!(
                    "The instrument's alternative: a flowmeter reading {:+.2} % of the flow would leave a cross-validated RMSE of eta_v of {} (the first cause's {}) and the torque as measured.\n\n",
                    100.0 * alt["gain"].as_f64().unwrap_or(f64::NAN),
                    num(&alt["cv_rmse"]),
                    num(&alt["cause_cv_rmse"]),
                ));
            }
        }
    }
    let reconsidered = &v["reconsidered_by_torque"];
    if let Some(tried) = reconsidered["tried"].as_array() {
        let adopted = tried.iter().find(|t| t["adopted"] == true);
        let leaves = reconsidered["why"] == "leaves_structure";
        md.push_str(&format!(
            "**The torque reconsidered the flow's causes**: the model of {} {}, so the flow was analysed again without each of their mechanisms in turn.{}\n\n",
            named(&reconsidered["flow_causes"]).join(" + "),
            if leaves {
                "leaves material structure in the measured torque"
            } else {
                "fits the measured torque materially worse than the base model"
            },
            match adopted {
                Some(t) => format!(
                    " Without `{}` the flow names {}, whose eta_v error leaves {} beyond theirs (RMSE {} against {}), below the noise floor {}, and the torque {}: they are the causes above.",
                    t["excluded"].as_str().unwrap_or("?"),
                    named(&t["causes"]).join(" + "),
                    num(&t["flow_excess"]),
                    num(&t["rmse"]),
                    num(&reconsidered["rmse"]),
                    num(&t["flow_noise_floor"]),
                    if leaves {
                        format!(
                            "structure they leave is materially smaller ({} N m against {})",
                            num(&t["torque_check"]["extended_structure_nm"]),
                            num(&reconsidered["torque_structure_nm"]),
                        )
                    } else {
                        "does not contradict them".to_string()
                    },
                ),
                None if leaves => " No alternative both fits eta_v within the noise floor of the flow's causes and leaves materially less in the torque; the causes stay.".to_string(),
                None => " No alternative both fits eta_v within the noise floor of the flow's causes and leaves the torque as measured; the causes stay, contradicted.".to_string(),
            }
        ));
    }
    let site = &v["site_by_torque"];
    if site.is_object() {
        md.push_str(&format!(
            "**The torque chose the site**: `{}` was preferred on eta_v, but the held-out error `{}` leaves beyond it, {}, is below the noise floor {}; the model of `{}` leaves a torque structure of {} N m against {} N m (material from {} N m), so the cause acts where the torque agrees.\n\n",
            site["flow_pick"].as_str().unwrap_or("?"),
            v["cause"].as_str().unwrap_or("?"),
            num(&site["flow_excess"]),
            num(&site["flow_noise_floor"]),
            site["flow_pick"].as_str().unwrap_or("?"),
            num(&site["torque_structure_nm"]["flow_pick"]),
            num(&site["torque_structure_nm"]["chosen"]),
            num(&site["material_nm"]),
        ));
    }
    let cannot = named(&v["population"]["cannot_tell"]);
    if !cannot.is_empty() {
        md.push_str(&format!(
            "**{} pump(s) only**: cross-validated over working conditions. Without a population this diagnosis cannot tell:\n\n",
            v["pumps"]
        ));
        for c in cannot {
            md.push_str(&format!("- {c}\n"));
        }
        md.push('\n');
    }
    if let Some(a) = v["ambiguous_with"].as_array().filter(|a| !a.is_empty()) {
        match v["chosen_by_torque"].as_object() {
            Some(t) => md.push_str(&format!(
                "Indistinguishable on eta_v; the torque chose the cause: its model's torque error is below that of `{}`, which the flow alone would have named (one-sided p {}):\n\n",
                t.get("flow_pick").and_then(Value::as_str).unwrap_or("?"),
                num(t.get("p_torque_better").unwrap_or(&Value::Null)),
            )),
            None => md.push_str(
                "Indistinguishable on these data (the cause is the one with fewer parameters):\n\n",
            ),
        }
        for x in a {
            md.push_str(&format!(
                "- `{}` (CV RMSE {}, p that the cause is better {}). To tell them apart: {}.\n",
                x["effect"].as_str().unwrap_or("?"),
                num(&x["cv_rmse"]),
                num(&x["p_cause_better"]),
                x["measurement"]
                    .as_str()
                    .unwrap_or("no separating condition found")
            ));
        }
        md.push('\n');
    }
    // what is wrong
    md.push_str("## What is wrong: the baseline\n\n");
    md.push_str(&format!(
        "RMSE of d = eta_v,meas - eta_v,sim: {}; Delta_nu max {}.\n\n",
        num(&v["baseline"]["rmse"]),
        num(&v["baseline"]["delta_nu_max"])
    ));
    conditions_table(&mut md, &v["baseline"]["conditions"], None);
    md.push_str("\nResidual structure (pumps are the independent units; Holm-adjusted over the features):\n\n| feature | kind | effect | t | p | p (Holm) | significant |\n|---|---|---|---|---|---|---|\n");
    for f in v["findings"].as_array().into_iter().flatten() {
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} |\n",
            f["feature"].as_str().unwrap_or("?"),
            f["kind"].as_str().unwrap_or("?"),
            num(&f["effect"]),
            num(&f["statistic"]),
            num(&f["p_value"]),
            num(&f["p_adjusted"]),
            if f["significant"].as_bool() == Some(true) {
                "yes"
            } else {
                ""
            }
        ));
    }
    // why
    md.push_str("\n## Why: the candidates\n\nEach extension of docs/model.md section 8, fitted to all tests (Gauss-Newton on the model with Broyden updates), scored by leave-one-pump-out cross-validation; p: one-sided paired t over pumps that the held-out error is below the base model's, Holm-adjusted over the candidates. `~`: a candidate that could not compete was not refined; its parameters are the optimum its sensitivities predict.\n\n| effect | parameters (jackknife s.e.) | fit RMSE | CV RMSE | t | p | p (Holm) | runs |\n|---|---|---|---|---|---|---|---|\n");
    for c in v["candidates"].as_array().into_iter().flatten() {
        let params: Vec<String> = c["params"]
            .as_object()
            .map(|m| {
                m.iter()
                    .map(|(k, x)| format!("{k} = {} ({})", num(x), num(&c["params_se"][k])))
                    .collect()
            })
            .unwrap_or_default();
        let approx = if c["params_predicted"].as_bool() == Some(true) {
            "~ "
        } else {
            ""
        };
        md.push_str(&format!(
            "| {} | {approx}{} | {} | {} | {} | {} | {} | {} |\n",
            c["effect"].as_str().unwrap_or("?"),
            params.join(", "),
            num(&c["fit_rmse"]),
            num(&c["cv_rmse"]),
            num(&c["statistic"]),
            num(&c["p_value"]),
            num(&c["p_adjusted"]),
            c["runs"]
        ));
    }
    md.push_str(&format!(
        "\nBase model RMSE {}. {} model runs in the candidate stage ({:.1} s); whole diagnosis {:.1} s.\n",
        num(&v["baseline"]["rmse"]),
        v["runs"],
        v["candidate_stage_s"].as_f64().unwrap_or(f64::NAN),
        v["wall_s"].as_f64().unwrap_or(f64::NAN)
    ));
    // extension
    let ext = if v["extended"].is_null() {
        &v["partial"]["extended"]
    } else {
        &v["extended"]
    };
    if !ext.is_null() {
        md.push_str(&format!(
            "\n## Extension `{}` and its gain\n\nPer condition, before and after (Eqs. 17-20 of the seed); files in `{EXTENDED_DIR}/`.\n\n",
            ext["effect"].as_str().unwrap_or("?")
        ));
        conditions_table(
            &mut md,
            &v["baseline"]["conditions"],
            Some(&ext["conditions"]),
        );
    }
    if !figures.is_empty() {
        md.push_str("\n## Figures\n\n");
        for (file, caption) in figures {
            md.push_str(&format!("- [{file}]({file}): {caption}\n"));
        }
    }
    md
}

type Drawn = Result<String, Box<dyn std::error::Error>>;

fn diagnosis_svg(v: &Value) -> Drawn {
    let empty = Vec::new();
    let before = v["baseline"]["conditions"].as_array().unwrap_or(&empty);
    let ext = if v["extended"].is_null() {
        &v["partial"]["extended"]
    } else {
        &v["extended"]
    };
    let after = ext["conditions"].as_array();
    let cands = v["candidates"].as_array().unwrap_or(&empty);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1100, 420)).into_drawing_area();
        root.fill(&WHITE)?;
        let (left, right) = root.split_horizontally(650);
        // per-condition d_mean and CI
        let ci = |c: &Value| {
            (
                c["d_mean"].as_f64(),
                c["ci_low"].as_f64(),
                c["ci_high"].as_f64(),
            )
        };
        let mut ymax: f64 = 1e-3;
        for c in before.iter().chain(after.into_iter().flatten()) {
            if let (Some(_), Some(l), Some(h)) = ci(c) {
                ymax = ymax.max(l.abs()).max(h.abs());
            }
        }
        let n = before.len().max(1) as f64;
        let mut chart = ChartBuilder::on(&left)
            .caption(
                "Mean residual d per condition, 95 % CI: base (grey), extended (blue)",
                (FONT, 14),
            )
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(55)
            .build_cartesian_2d(-0.5..n - 0.5, -1.1 * ymax..1.1 * ymax)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("condition (p bar / n rpm / T degC, in conditions.csv order)")
            .y_desc("d")
            .x_labels(before.len().max(2))
            .x_label_formatter(&|x| format!("{}", x.round() as i64 + 1))
            .y_label_formatter(&|y| format!("{y:.3}"))
            .label_style((FONT, 10))
            .draw()?;
        chart.draw_series(LineSeries::new(
            vec![(-0.5, 0.0), (n - 0.5, 0.0)],
            RGBColor(150, 150, 150),
        ))?;
        for (set, dx, colour) in [
            (Some(before), -0.12, RGBColor(120, 120, 120)),
            (after, 0.12, RGBColor(30, 90, 200)),
        ] {
            for (k, c) in set.into_iter().flatten().enumerate() {
                if let (Some(m), Some(l), Some(h)) = ci(c) {
                    let x = k as f64 + dx;
                    chart.draw_series(LineSeries::new(
                        vec![(x, l), (x, h)],
                        colour.stroke_width(2),
                    ))?;
                    chart.draw_series(std::iter::once(Circle::new((x, m), 3, colour.filled())))?;
                }
            }
        }
        // candidates
        let base = v["baseline"]["rmse"].as_f64().unwrap_or(0.0);
        let xmax = cands
            .iter()
            .filter_map(|c| c["cv_rmse"].as_f64())
            .fold(base, f64::max)
            * 1.15;
        let m = cands.len().max(1) as f64;
        let mut chart = ChartBuilder::on(&right)
            .caption("CV RMSE per candidate (line: base model)", (FONT, 14))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(130)
            .build_cartesian_2d(0.0..xmax.max(1e-6), -0.5..m - 0.5)?;
        let names: Vec<String> = cands
            .iter()
            .map(|c| c["effect"].as_str().unwrap_or("?").to_string())
            .collect();
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("held-out RMSE of d")
            .y_labels(cands.len().max(2))
            .y_label_formatter(&|y| {
                let k = y.round();
                if (y - k).abs() < 0.01 && k >= 0.0 {
                    names.get(k as usize).cloned().unwrap_or_default()
                } else {
                    String::new()
                }
            })
            .x_label_formatter(&|x| format!("{x:.4}"))
            .label_style((FONT, 10))
            .draw()?;
        for (k, c) in cands.iter().enumerate() {
            let r = c["cv_rmse"].as_f64().unwrap_or(0.0);
            let sig = c["p_adjusted"].as_f64().unwrap_or(1.0) < v["alpha"].as_f64().unwrap_or(0.05);
            let colour = if sig {
                RGBColor(30, 90, 200)
            } else {
                RGBColor(170, 170, 170)
            };
            let y = k as f64;
            chart.draw_series(std::iter::once(Rectangle::new(
                [(0.0, y - 0.35), (r, y + 0.35)],
                colour.filled(),
            )))?;
        }
        chart.draw_series(LineSeries::new(
            vec![(base, -0.5), (base, m - 0.5)],
            BLACK.stroke_width(2),
        ))?;
        root.present()?;
    }
    Ok(svg)
}

type RowFeature = (&'static str, fn(&ResidualRow) -> Option<f64>);

/// d against every feature of the findings: base model grey, extended blue.
fn features_svg(base: &[ResidualRow], ext: Option<&[ResidualRow]>) -> Drawn {
    let features: [RowFeature; 10] = [
        ("delivery pressure (bar)", |r| Some(pa_to_bar(r.pressure))),
        ("speed (rpm)", |r| Some(rad_s_to_rpm(r.speed))),
        ("oil temperature (degC)", |r| {
            Some(kelvin_to_celsius(r.temp))
        }),
        ("viscosity (mPa s)", |r| Some(pa_s_to_mpa_s(r.viscosity))),
        ("slip group dp/(mu n) (1e9)", |r| {
            Some(r.pressure / (r.viscosity * r.speed) * 1e-9)
        }),
        ("torque residual (N m)", |r| r.torque_residual),
        ("tip clearance, driving (um)", |r| Some(m_to_um(r.tip[0]))),
        ("tip clearance, driven (um)", |r| Some(m_to_um(r.tip[1]))),
        ("bearing clearance, driving (um)", |r| {
            Some(m_to_um(r.bearing[0]))
        }),
        ("bearing clearance, driven (um)", |r| {
            Some(m_to_um(r.bearing[1]))
        }),
    ];
    let all = base.iter().chain(ext.into_iter().flatten());
    let dmax = all
        .map(|r| r.d.abs())
        .filter(|x| x.is_finite())
        .fold(1e-3, f64::max)
        * 1.1;
    let (nr, nc) = (2usize, 5usize);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (260 * nc as u32, 230 * nr as u32 + 40))
            .into_drawing_area();
        root.fill(&WHITE)?;
        let (top, body) = root.split_vertically(40);
        top.draw(&Text::new(
            "Residual d = eta_v,meas - eta_v,sim against each feature: base model (grey), extended (blue)",
            (10, 10),
            (FONT, 15).into_font(),
        ))?;
        for (panel, (name, f)) in body.split_evenly((nr, nc)).iter().zip(features.iter()) {
            let xs: Vec<f64> = base
                .iter()
                .filter_map(f)
                .filter(|x| x.is_finite())
                .collect();
            if xs.is_empty() {
                continue;
            }
            let lo = xs.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let pad = ((hi - lo) * 0.05).max(1e-9 * hi.abs().max(1.0));
            let (lo, hi) = (lo - pad, hi + pad);
            let mut chart = ChartBuilder::on(panel)
                .margin(6)
                .x_label_area_size(32)
                .y_label_area_size(46)
                .build_cartesian_2d(lo..hi, -dmax..dmax)?;
            chart
                .configure_mesh()
                .disable_mesh()
                .x_labels(4)
                .y_labels(5)
                .x_desc(*name)
                .y_desc("d")
                .x_label_formatter(&|v| format!("{v:.3}"))
                .y_label_formatter(&|v| format!("{v:.3}"))
                .label_style((FONT, 10))
                .draw()?;
            chart.draw_series(LineSeries::new(
                vec![(lo, 0.0), (hi, 0.0)],
                RGBColor(150, 150, 150),
            ))?;
            for (rows, colour) in [
                (Some(base), RGBColor(150, 150, 150)),
                (ext, RGBColor(30, 90, 200)),
            ] {
                chart.draw_series(rows.into_iter().flatten().filter_map(|r| {
                    let x = f(r)?;
                    (x.is_finite() && r.d.is_finite())
                        .then(|| Circle::new((x, r.d), 2, colour.filled()))
                }))?;
            }
        }
        root.present()?;
    }
    Ok(svg)
}

/// Writes `report.md`, `diagnosis.svg` and the extended model's campaign
/// figures; returns the files written.
pub fn write_report(
    out: &Path,
    baseline: &CampaignResult,
    diagnosis: &Diagnosis,
    extended: Option<&[TestOutcome]>,
    base_rows: &[ResidualRow],
    ext_rows: Option<&[ResidualRow]>,
) -> Result<Vec<PathBuf>, RunError> {
    let v = &diagnosis.json;
    let mut files = Vec::new();
    let mut figures: Vec<(String, String)> = Vec::new();
    let svg = diagnosis_svg(v).map_err(|e| RunError::Plot {
        file: DIAGNOSIS_SVG.into(),
        message: e.to_string(),
    })?;
    atomic_write_text(&out.join(DIAGNOSIS_SVG), &svg)?;
    files.push(out.join(DIAGNOSIS_SVG));
    figures.push((
        DIAGNOSIS_SVG.into(),
        "mean residual per condition before/after the extension; candidates' cross-validated RMSE"
            .into(),
    ));
    let svg = features_svg(base_rows, ext_rows).map_err(|e| RunError::Plot {
        file: FEATURES_SVG.into(),
        message: e.to_string(),
    })?;
    atomic_write_text(&out.join(FEATURES_SVG), &svg)?;
    files.push(out.join(FEATURES_SVG));
    figures.push((
        FEATURES_SVG.into(),
        "residual d against every feature tested (grey: base model, blue: extended)".into(),
    ));
    for f in gearpump_campaign::plots::FIGURE_FILES {
        if out.join(f).exists() {
            figures.push((f.to_string(), "the base model (campaign figure)".into()));
        }
    }
    if let Some(outcomes) = extended {
        let dir = out.join(EXTENDED_DIR);
        for f in write_plots(&dir, &baseline.campaign.rows, outcomes)? {
            files.push(dir.join(&f.file));
            figures.push((
                format!("{EXTENDED_DIR}/{}", f.file),
                format!("extended model: {}", f.caption),
            ));
        }
    }
    let path = out.join(REPORT_MD);
    atomic_write_text(&path, &report_text(v, &figures))?;
    files.push(path);
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// The report says when the torque chose the site, with the figures of
    /// `site_by_torque`, and says nothing of it otherwise.
    #[test]
    fn the_report_says_when_the_torque_chose_the_site() {
        let mut v = json!({
            "cause": "pressure_clearance@tips",
            "site_by_torque": {
                "flow_pick": "pressure_clearance@all",
                "flow_excess": 0.0025,
                "flow_noise_floor": 0.0048,
                "torque_structure_nm": {"flow_pick": 0.0294, "chosen": 0.0035},
                "material_nm": 0.0135,
            },
        });
        let md = report_text(&v, &[]);
        let line = md
            .lines()
            .find(|l| l.starts_with("**The torque chose the site**"))
            .expect("the paragraph");
        for x in [
            "`pressure_clearance@all` was preferred",
            "`pressure_clearance@tips` leaves",
            "0.0294",
            "0.0035",
            "0.0048",
        ] {
            assert!(line.contains(x), "{x} not in {line}");
        }
        v["site_by_torque"] = Value::Null;
        assert!(!report_text(&v, &[]).contains("The torque chose the site"));
    }

    /// The report says when the torque reconsidered the flow's causes and
    /// which alternative it took, or that none was taken.
    #[test]
    fn the_report_says_when_the_torque_reconsidered_the_causes() {
        let mut v = json!({
            "reconsidered_by_torque": {
                "flow_causes": ["lateral_clearance", "viscosity_shift"],
                "rmse": 0.00473,
                "tried": [
                    {"excluded": "lateral_clearance", "causes": ["thermal_clearance@lateral", "viscosity_shift"], "rmse": 0.00486, "flow_excess": 0.0011, "flow_noise_floor": 0.0050, "adopted": false},
                    {"excluded": "viscosity_shift", "causes": ["thermal_clearance@tips", "lateral_clearance"], "rmse": 0.00492, "flow_excess": 0.0014, "flow_noise_floor": 0.0048, "adopted": true},
                ],
            },
        });
        let para = |md: &str| {
            md.lines()
                .find(|l| l.starts_with("**The torque reconsidered the flow's causes**"))
                .map(String::from)
        };
        let line = para(&report_text(&v, &[])).expect("the paragraph");
        for x in [
            "lateral_clearance + viscosity_shift",
            "Without `viscosity_shift`",
            "thermal_clearance@tips + lateral_clearance",
            "0.0014",
            "0.0048",
        ] {
            assert!(line.contains(x), "{x} not in {line}");
        }
        v["reconsidered_by_torque"]["tried"][1]["adopted"] = json!(false);
        let line = para(&report_text(&v, &[])).expect("the paragraph");
        assert!(line.contains("the causes stay, contradicted"), "{line}");
        v["reconsidered_by_torque"] = Value::Null;
        assert!(para(&report_text(&v, &[])).is_none());
    }

    /// The report says why the causes do not explain the discrepancy: by
    /// the size of what they leave, or by its share (smaller than one
    /// test's scatter, but a quarter or more of what was there).
    #[test]
    fn the_report_says_when_what_is_left_is_material_by_its_share() {
        let mut v = json!({
            "causes": [{"effect": "lateral_clearance", "params": {"h_lat_um": 16.65}}],
            "unexplained": true,
            "unexplained_features": ["pressure_bar"],
            "noise_floor": 0.0044,
            "structure": {
                "baseline": {"structure": 0.0089},
                "final": {"structure": 0.0032, "p": 7.8e-16},
                "threshold": 0.0044,
                "share_left": 0.364,
            },
        });
        let line = |v: &Value| {
            report_text(v, &[])
                .lines()
                .find(|l| l.starts_with("**Not explained**"))
                .map(String::from)
        };
        let by_share = line(&v).expect("the sentence");
        assert!(by_share.contains("pressure_bar"), "{by_share}");
        assert!(by_share.contains("a quarter or more"), "{by_share}");
        let md = report_text(&v, &[]);
        assert!(
            md.contains("(0.3640 of it left; F test of what is left p = 7.800e-16)"),
            "{md}"
        );
        // left by its size: no word of shares
        v["structure"]["final"]["structure"] = json!(0.006);
        let by_size = line(&v).expect("the sentence");
        assert!(!by_size.contains("a quarter"), "{by_size}");
        // contradicted by the torque, with no alternative adopted
        v["unexplained_by_torque"] = json!(true);
        let by_torque = line(&v).expect("the sentence");
        assert!(
            by_torque.contains("torque contradicts the causes"),
            "{by_torque}"
        );
        v["unexplained_by_torque"] = json!(false);
        v["unexplained"] = json!(false);
        assert!(line(&v).is_none());
    }
}
