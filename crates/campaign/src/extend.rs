//! The extended model as a design file: a base design (its text and `--set`
//! overrides) with effects written as the design keys that carry them, so
//! `simulate`, `campaign`, `synth` and `diagnose` run it as it is
//! (`--design extended_design.toml`).
//!
//! | effect | keys written |
//! |---|---|
//! | thermal_clearance[@site] | `clearance.thermal_growth_um_per_k`, `clearance.thermal_growth_on` |
//! | pressure_clearance[@site] | `clearance.pressure_growth_um_per_bar`, `clearance.pressure_growth_on` |
//! | lateral_clearance | `clearance.lateral_um` |
//! | viscosity_shift | `oil.viscosity_factor_60c`, `oil.viscosity_factor_120c` |
//! | entrained_air | `oil.air_fraction` |
//! | displacement_error | `gears.face_width_mm` (the real face width: eta_v of runs of this design is relative to its real displacement, while a diagnosis keeps the drawing's) |
//! | pressure_viscosity | `oil.pressure_viscosity_per_pa` |
//!
//! A diagnosis's torque causes with a design key (the loss model's
//! coefficients: `losses.mesh_friction_coefficient`,
//! `losses.thrust_plate_friction`, `losses.churning_coefficient`) are
//! written beside them ([`design_toml_with_losses`]).

use gearpump_core::design::{self, apply_set, Site};
use gearpump_core::units::{m_to_um, pa_to_bar};

use super::effects::Effect;
use super::run::{DesignSource, RunError, Setting};

fn setting(message: String) -> RunError {
    RunError::Setting {
        setting: Setting::Effects,
        message,
    }
}

/// Sets `section.key` (creating the key when the base file lacks it).
fn put(
    root: &mut toml::Value,
    section: &str,
    key: &str,
    value: toml::Value,
) -> Result<(), RunError> {
    let table = root
        .get_mut(section)
        .and_then(toml::Value::as_table_mut)
        .ok_or_else(|| setting(format!("the design has no [{section}] section")))?;
    table.insert(key.to_string(), value);
    Ok(())
}

/// The design file of `source` with `effects` written as its keys (module
/// doc); checked by reading it back.
pub fn design_toml_with(source: &DesignSource, effects: &[Effect]) -> Result<String, RunError> {
    design_toml_with_losses(source, effects, &[])
}

/// [`design_toml_with`], and the loss-model keys `losses` (`(key in the
/// [losses] section, value)`) written too.
pub fn design_toml_with_losses(
    source: &DesignSource,
    effects: &[Effect],
    losses: &[(&str, f64)],
) -> Result<String, RunError> {
    let mut root: toml::Value =
        toml::from_str(&source.text).map_err(|e| setting(format!("{}: {e}", source.label)))?;
    for s in &source.sets {
        apply_set(&mut root, s)?;
    }
    let f = toml::Value::Float;
    let s = |site: Site| toml::Value::String(site.name().to_string());
    for e in effects {
        match *e {
            Effect::ThermalClearance { k_t, site } => {
                put(
                    &mut root,
                    "clearance",
                    "thermal_growth_um_per_k",
                    f(round(m_to_um(k_t))),
                )?;
                put(&mut root, "clearance", "thermal_growth_on", s(site))?;
            }
            Effect::PressureClearance { k_p, site } => {
                let v = round(m_to_um(k_p) / pa_to_bar(1.0));
                put(&mut root, "clearance", "pressure_growth_um_per_bar", f(v))?;
                put(&mut root, "clearance", "pressure_growth_on", s(site))?;
            }
            Effect::LateralClearance { lateral } => put(
                &mut root,
                "clearance",
                "lateral_um",
                f(round(m_to_um(lateral))),
            )?,
            Effect::ViscosityShift { factors } => {
                put(
                    &mut root,
                    "oil",
                    "viscosity_factor_60c",
                    f(round(factors.0)),
                )?;
                put(
                    &mut root,
                    "oil",
                    "viscosity_factor_120c",
                    f(round(factors.1)),
                )?;
            }
            Effect::EntrainedAir { fraction } => {
                put(&mut root, "oil", "air_fraction", f(round(fraction)))?
            }
            Effect::DisplacementError { relative } => {
                let b = round(m_to_um(source.design.face_width) * 1e-3 * (1.0 + relative));
                put(&mut root, "gears", "face_width_mm", f(b))?
            }
            Effect::PressureViscosity { alpha } => put(
                &mut root,
                "oil",
                "pressure_viscosity_per_pa",
                f(round(alpha)),
            )?,
        }
    }
    for (key, value) in losses {
        put(&mut root, "losses", key, f(round(*value)))?;
    }
    let body = toml::to_string(&root).map_err(|e| setting(format!("design: {e}")))?;
    let mut with: Vec<String> = effects.iter().map(|e| e.to_string()).collect();
    with.extend(
        losses
            .iter()
            .map(|(k, v)| format!("losses.{k} = {}", round(*v))),
    );
    let text = format!(
        "# The extended model: {} with {} (written by gearpump diagnose; keys in\n# docs/interfaces.md section 6 and docs/model.md section 8).\n{body}",
        source.label,
        if with.is_empty() {
            "no effect".to_string()
        } else {
            with.join(", ")
        }
    );
    design::from_toml_str(&text, &[])?;
    Ok(text)
}

/// Twelve significant digits (the effects' edge precision).
fn round(v: f64) -> f64 {
    format!("{v:.11e}").parse().unwrap_or(v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::EffectModel;
    use crate::run::simulate_test;
    use gearpump_core::model::Pump;
    use std::sync::Arc;

    /// Every effect (and a clearance effect at every site) written as keys
    /// and read back runs the same model as the effect itself: same flow
    /// and torque of a test at 120 degC and 40 bar, micromotion on (within
    /// the 12 digits the keys are written with).
    #[test]
    fn an_extended_design_runs_the_effects_it_was_written_with() {
        let source = DesignSource::load(None, &["clearance.tip_um=32".into()]).unwrap();
        let pump = Arc::new(Pump::new(source.design.clone()));
        let csv = "sample,tip_clearance_drive_um,tip_clearance_driven_um,bearing_clearance_drive_um,bearing_clearance_driven_um,pressure_bar,speed_rpm,temp_c,flow_lpm,torque_nm\nA,31,33,13,14,40,1000,120,10,\n";
        let row = &crate::data::parse_campaign_str("t", csv).unwrap().rows[0];
        let cases = [
            "thermal_clearance=0.05",
            "thermal_clearance@tips=0.05",
            "thermal_clearance@bearings=0.4",
            "thermal_clearance@lateral=0.05",
            "pressure_clearance@all=0.2",
            "lateral_clearance=21",
            "viscosity_shift=0.8,0.7",
            "entrained_air=0.03",
            "displacement_error=-0.02",
            "pressure_viscosity=5e-8",
        ];
        for case in cases {
            let e = Effect::parse(case).unwrap();
            let direct =
                simulate_test(&EffectModel::on(&pump, &[e]).unwrap(), row, None, true).unwrap();
            let text = design_toml_with(&source, &[e]).unwrap();
            let back = Arc::new(Pump::new(design::from_toml_str(&text, &[]).unwrap()));
            let keyed =
                simulate_test(&EffectModel::on(&back, &[]).unwrap(), row, None, true).unwrap();
            let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
            assert!(
                rel(keyed.flow, direct.flow) < 1e-9,
                "{case}: {} vs {}",
                keyed.flow,
                direct.flow
            );
            assert!(rel(keyed.torque, direct.torque) < 1e-9, "{case}");
            // and the effect did something
            let base =
                simulate_test(&EffectModel::on(&pump, &[]).unwrap(), row, None, true).unwrap();
            assert!(rel(direct.flow, base.flow) > 1e-4, "{case} changes nothing");
        }
    }

    /// The located thermal law against a hand calculation: `@tips` at k_T
    /// is a plain run whose tip clearances were opened by k_T (T - 20) by
    /// hand, bearings untouched; `@bearings` opens the bearings by
    /// k_T (T - 20) R_journal / R_tip.
    #[test]
    fn a_located_thermal_law_is_the_hand_opened_clearance() {
        let source = DesignSource::load(None, &[]).unwrap();
        let pump = Arc::new(Pump::new(source.design.clone()));
        let line = |tip: [f64; 2], brg: [f64; 2]| {
            format!("sample,tip_clearance_drive_um,tip_clearance_driven_um,bearing_clearance_drive_um,bearing_clearance_driven_um,pressure_bar,speed_rpm,temp_c,flow_lpm,torque_nm\nA,{},{},{},{},30,1000,120,10,\n", tip[0], tip[1], brg[0], brg[1])
        };
        let row = |tip, brg| {
            crate::data::parse_campaign_str("t", &line(tip, brg))
                .unwrap()
                .rows[0]
                .clone()
        };
        let base = EffectModel::on(&pump, &[]).unwrap();
        let k = 0.05; // um/K, 100 K above the lab: +5 um
        let tips = EffectModel::on(
            &pump,
            &[Effect::parse(&format!("thermal_clearance@tips={k}")).unwrap()],
        )
        .unwrap();
        let a = simulate_test(&tips, &row([30.0, 31.0], [12.0, 13.0]), None, false).unwrap();
        let b = simulate_test(&base, &row([35.0, 36.0], [12.0, 13.0]), None, false).unwrap();
        assert!(
            (a.flow - b.flow).abs() <= 1e-12 * b.flow.abs(),
            "{} {}",
            a.flow,
            b.flow
        );
        let g = &pump.geo;
        let scale = [0, 1].map(|i| 0.5 * g.bearing_diameter[i] / g.tip_radius[i]);
        let brg = EffectModel::on(
            &pump,
            &[Effect::parse(&format!("thermal_clearance@bearings={k}")).unwrap()],
        )
        .unwrap();
        let a = simulate_test(&brg, &row([30.0, 31.0], [12.0, 13.0]), None, false).unwrap();
        let b = simulate_test(
            &base,
            &row([30.0, 31.0], [12.0 + 5.0 * scale[0], 13.0 + 5.0 * scale[1]]),
            None,
            false,
        )
        .unwrap();
        assert!(
            (a.flow - b.flow).abs() <= 1e-9 * b.flow.abs(),
            "{} {}",
            a.flow,
            b.flow
        );
    }
}
