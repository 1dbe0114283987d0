//! Effects that a measured campaign may show and the base model lacks
//! (docs/model.md section 8), each a switchable *physical* extension of the model.
//!
//! An effect never corrects the model's output: it changes what the model is
//! given (the design, a sample's clearances at the operating point, the gap
//! viscosity) before the run, and the pocket network then does the rest. The
//! same [`EffectModel`] with no effect is the project's base model, so
//! `synth` (the truth of a synthetic campaign) and `campaign` (trace-driven
//! simulation) share one code path.
//!
//! # The effects, their parameters and plausible ranges
//! Values at the edge (`--effect NAME=VALUE`) are in the units below; inside
//! they are SI.
//!
//! | name | edge value | mechanism | plausible range |
//! |---|---|---|---|
//! | `thermal_clearance` | `k_T`, um/K | radial clearances follow the oil temperature | 0.02-0.3 um/K |
//! | `pressure_clearance` | `k_p`, um/bar | casing and bearing bores open with delivery pressure | 0.1-0.5 um/bar |
//! | `lateral_clearance` | `h_lat`, um | the real axial gap differs from the nominal one | 10-40 um |
//! | `viscosity_shift` | `f1[,f2]` | factors on the datasheet viscosity at the design's two reference temperatures (60 / 120 degC) | 0.7-1.4 |
//! | `entrained_air` | `x0`, volume fraction at 1 atm | free air softens the oil and is compressed at delivery | 0.005-0.05 |
//! | `displacement_error` | `delta`, relative | the real gears are wider/narrower than drawn | +-0.01-0.03 |
//! | `pressure_viscosity` | `alpha`, 1/Pa | Barus law in the gaps | 1e-8-3e-8 1/Pa |
//!
//! ## thermal_clearance
//! Clearances are measured at `T_meas = 20 degC` in the metrology lab; in
//! service the casing (cast iron) and the steel gears expand differently,
//! `h(T) = h_meas + k_T (T - T_meas)` on the tooth-tip clearance of both gears
//! (`k_T = (alpha_casing - alpha_gear) R_tip`: about 0.02 um/K in magnitude
//! for a cast-iron casing on steel gears, 0.2 um/K for an aluminium casing;
//! leakage grows with the cube of the clearance, so 0.03 um/K already moves
//! `eta_v` by several points at 120 degC). The same differential strain
//! `k_T / R_tip` acts on the journal-bearing bores, so the bearing radial
//! clearance changes by `k_T (T - T_meas) R_journal / R_tip` (about 0.4 of the
//! tip change for this pump). The lateral (axial) gap is **not** changed: it is
//! set by the thrust plate that rests on the gear faces, not by the casing
//! length.
//!
//! ## pressure_clearance
//! The delivery pressure dilates the casing bore and the bearing housings
//! (elastic ring: radial growth proportional to radius):
//! `h = h_meas + k_p p` on the tip clearances with `p` the delivery gauge
//! pressure (above suction), and `k_p p R_journal / R_tip` on the bearing
//! clearances. The lateral gap is not changed: the thrust plate is pressure
//! balanced (its relief grooves and back face) and the cover plate is clamped.
//!
//! Both clearance laws keep every clearance at least [`MIN_CLEARANCE`] (the
//! gap cannot close below the surface roughness; a closed gap is metal contact,
//! outside the model).
//!
//! ## lateral_clearance
//! The seed assumes the nominal axial clearance (docs/model.md section 1); this
//! effect sets the real one, `h_lat`, on every sample (it replaces the design's
//! `clearance.lateral_um` for the run).
//!
//! ## viscosity_shift
//! An aged or different oil: the kinematic viscosity is the datasheet Walther
//! value times a factor that is log-linear in temperature between the two
//! reference temperatures of the design's oil (`Oil::nu_factor_t_k`, 60 and
//! 120 degC for the bundled design): `f1` at the first, `f2` at the second
//! (one value = the same factor at both). Changes `design.oil.nu_factor`.
//!
//! ## entrained_air
//! Free air, volume fraction `x0` at atmospheric pressure, isothermal ideal
//! gas (`Compressibility::density_ratio`): it lowers the effective bulk
//! modulus (strongly at low pressure) and the delivered flow measured at
//! delivery pressure (the air drawn in at suction is compressed).
//! Changes `design.oil.air_fraction`.
//!
//! ## displacement_error
//! A real geometry change: the face width is scaled by `1 + delta`, so pocket
//! volumes, the displacement and the gap lengths along the face all scale;
//! the pump's look-up tables are rebuilt for it. A campaign keeps computing
//! `eta_v` with the nominal displacement, as a test rig does (the rig knows
//! only the drawing).
//!
//! ## pressure_viscosity
//! Barus law `mu(p) = mu_0 exp(alpha p)`, applied to every gap
//! (`GapState::gap_viscosity_factor`) at a documented mean gap pressure: half
//! the delivery gauge pressure, `p_gap = (p_delivery - p_suction) / 2` (the
//! gaps drop the pressure from delivery to suction, linearly to first
//! order). The same viscosity shears the tip and lateral films, so their
//! viscous torque takes the factor too (`LossModel::losses`, `gap_factor`);
//! the journal bearings' friction keeps the bulk viscosity (their film
//! pressure is hydrodynamic, not the ports').
//!
//! # Reference
//! docs/model.md section 8; Barus (1893); Ivantysyn & Ivantysynova, *Hydrostatic
//! pumps and motors* (2001), ch. 3 for the clearance and air mechanisms.

use std::fmt;
use std::sync::Arc;

use thiserror::Error;

use gearpump_core::design::{Design, Site};
use gearpump_core::model::{Inputs, ModelError, Options, Pump, SampleClearances, Simulation};
use gearpump_core::units::{bar_to_pa, celsius_to_kelvin, m_to_um, pa_to_bar, um_to_m};

/// Names of the effects, as written on the command line.
pub const EFFECT_NAMES: [&str; 7] = [
    "thermal_clearance",
    "pressure_clearance",
    "lateral_clearance",
    "viscosity_shift",
    "entrained_air",
    "displacement_error",
    "pressure_viscosity",
];

/// The clearance effects at every site but the default (radial), as
/// `NAME@SITE`: the diagnosis lets the data choose among them.
pub const LOCATED: [&str; 8] = [
    "thermal_clearance@tips",
    "thermal_clearance@bearings",
    "thermal_clearance@lateral",
    "thermal_clearance@all",
    "pressure_clearance@tips",
    "pressure_clearance@bearings",
    "pressure_clearance@lateral",
    "pressure_clearance@all",
];

/// The name of a clearance effect at `site` (the base name when radial).
fn located(base: usize, site: Site) -> &'static str {
    match site {
        Site::Radial => EFFECT_NAMES[base],
        Site::Tips => LOCATED[4 * base],
        Site::Bearings => LOCATED[4 * base + 1],
        Site::Lateral => LOCATED[4 * base + 2],
        Site::All => LOCATED[4 * base + 3],
    }
}

/// The base name and site of `NAME[@SITE]` (radial when no site is given).
pub fn split_site(name: &str) -> (&str, Option<Site>) {
    match name.split_once('@') {
        Some((b, s)) => (b, Site::parse(s)),
        None => (name, Some(Site::Radial)),
    }
}

/// Temperature of the metrology lab where clearances are measured, degC
/// (the core's, shared with the design's own service laws).
pub const T_MEASURE_C: f64 = gearpump_core::model::service::T_MEASURE_C;

/// Smallest clearance an effect may leave, m (surface roughness scale; the
/// core's, shared with the design's own service laws).
pub const MIN_CLEARANCE: f64 = gearpump_core::model::service::MIN_SERVICE_CLEARANCE;

/// One effect with its parameter(s), SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Effect {
    /// `k_T`, m/K: clearance change per kelvin above [`T_MEASURE_C`] on
    /// `site` (radial: tips and bearings).
    ThermalClearance { k_t: f64, site: Site },
    /// `k_p`, m/Pa: clearance change per pascal of delivery gauge pressure
    /// on `site`.
    PressureClearance { k_p: f64, site: Site },
    /// The real lateral clearance on each face, m.
    LateralClearance { lateral: f64 },
    /// Viscosity factors at the oil's two reference temperatures.
    ViscosityShift { factors: (f64, f64) },
    /// Free air volume fraction at atmospheric pressure.
    EntrainedAir { fraction: f64 },
    /// Relative error of the real displacement (face width scale - 1).
    DisplacementError { relative: f64 },
    /// Barus coefficient, 1/Pa.
    PressureViscosity { alpha: f64 },
}

/// A refused `--effect` argument.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum EffectError {
    #[error("effect {arg}: expected NAME=VALUE (effects: {})", EFFECT_NAMES.join(", "))]
    Syntax { arg: String },
    #[error("effect {arg}: unknown effect `{name}` (effects: {})", EFFECT_NAMES.join(", "))]
    Unknown { arg: String, name: String },
    #[error("effect {arg}: {message}")]
    Value { arg: String, message: String },
    #[error("effect {name}: given more than once")]
    Duplicate { name: &'static str },
}

fn finite_number(arg: &str, text: &str) -> Result<f64, EffectError> {
    let t = text.trim();
    match t.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(EffectError::Value {
            arg: arg.to_string(),
            message: format!("`{t}` is not a finite number"),
        }),
    }
}

impl Effect {
    /// Parses `NAME=VALUE` in edge units (see the module doc).
    pub fn parse(arg: &str) -> Result<Effect, EffectError> {
        let (name, value) = arg.split_once('=').ok_or_else(|| EffectError::Syntax {
            arg: arg.to_string(),
        })?;
        let name = name.trim();
        let (base, site) = split_site(name);
        let parts: Vec<&str> = value.split(',').collect();
        let want = if name == "viscosity_shift" {
            1..=2
        } else {
            1..=1
        };
        let clearance = base == EFFECT_NAMES[0] || base == EFFECT_NAMES[1];
        if !EFFECT_NAMES.contains(&base) || site.is_none() || (!clearance && base != name) {
            return Err(EffectError::Unknown {
                arg: arg.to_string(),
                name: name.to_string(),
            });
        }
        if !want.contains(&parts.len()) {
            return Err(EffectError::Value {
                arg: arg.to_string(),
                message: format!(
                    "expected {} value(s), got {}",
                    if name == "viscosity_shift" {
                        "one or two comma-separated"
                    } else {
                        "one"
                    },
                    parts.len()
                ),
            });
        }
        let values = parts
            .iter()
            .map(|p| finite_number(arg, p))
            .collect::<Result<Vec<f64>, _>>()?;
        Effect::from_edge(name, &values).map_err(|message| EffectError::Value {
            arg: arg.to_string(),
            message,
        })
    }

    /// Builds an effect from its name and edge-unit values (the diagnosis
    /// fits these); the message says what is out of range.
    pub fn from_edge(name: &str, values: &[f64]) -> Result<Effect, String> {
        let (base, site) = split_site(name);
        let site = site.ok_or_else(|| {
            format!("{name}: a site is one of tips, bearings, lateral, radial, all")
        })?;
        if site != Site::Radial && base != EFFECT_NAMES[0] && base != EFFECT_NAMES[1] {
            return Err(format!("{name}: only clearance effects take a site"));
        }
        let one = || -> Result<f64, String> {
            match values {
                [v] if v.is_finite() => Ok(*v),
                _ => Err(format!("{name} takes one finite value")),
            }
        };
        let effect = match base {
            "thermal_clearance" => {
                let v = one()?;
                if v.abs() > 10.0 {
                    return Err(format!("k_T = {v} um/K is not physical (|k_T| <= 10)"));
                }
                Effect::ThermalClearance {
                    k_t: um_to_m(v),
                    site,
                }
            }
            "pressure_clearance" => {
                let v = one()?;
                if v.abs() > 10.0 {
                    return Err(format!("k_p = {v} um/bar is not physical (|k_p| <= 10)"));
                }
                Effect::PressureClearance {
                    k_p: um_to_m(v) / bar_to_pa(1.0),
                    site,
                }
            }
            "lateral_clearance" => {
                let v = one()?;
                if !(v > 0.0 && v <= 1000.0) {
                    return Err(format!("h_lat must be in (0, 1000] um, got {v}"));
                }
                Effect::LateralClearance {
                    lateral: um_to_m(v),
                }
            }
            "viscosity_shift" => {
                let (f1, f2) = match values {
                    [f] => (*f, *f),
                    [f1, f2] => (*f1, *f2),
                    _ => return Err("viscosity_shift takes one or two factors".into()),
                };
                for f in [f1, f2] {
                    if !(f.is_finite() && f > 0.0 && f <= 100.0) {
                        return Err(format!("viscosity factors must be in (0, 100], got {f}"));
                    }
                }
                Effect::ViscosityShift { factors: (f1, f2) }
            }
            "entrained_air" => {
                let v = one()?;
                if !(0.0..0.5).contains(&v) {
                    return Err(format!(
                        "air volume fraction must be in [0, 0.5) (e.g. 0.02 for 2 %), got {v}"
                    ));
                }
                Effect::EntrainedAir { fraction: v }
            }
            "displacement_error" => {
                let v = one()?;
                if !(v > -0.5 && v < 0.5) {
                    return Err(format!(
                        "relative displacement error must be in (-0.5, 0.5) (e.g. 0.02), got {v}"
                    ));
                }
                Effect::DisplacementError { relative: v }
            }
            "pressure_viscosity" => {
                let v = one()?;
                if !(0.0..=1.0e-6).contains(&v) {
                    return Err(format!(
                        "Barus alpha must be in [0, 1e-6] 1/Pa (oils: 1e-8 to 3e-8), got {v}"
                    ));
                }
                Effect::PressureViscosity { alpha: v }
            }
            other => return Err(format!("unknown effect `{other}`")),
        };
        Ok(effect)
    }

    /// The effect's name.
    pub fn name(&self) -> &'static str {
        match self {
            Effect::ThermalClearance { site, .. } => located(0, *site),
            Effect::PressureClearance { site, .. } => located(1, *site),
            Effect::LateralClearance { .. } => EFFECT_NAMES[2],
            Effect::ViscosityShift { .. } => EFFECT_NAMES[3],
            Effect::EntrainedAir { .. } => EFFECT_NAMES[4],
            Effect::DisplacementError { .. } => EFFECT_NAMES[5],
            Effect::PressureViscosity { .. } => EFFECT_NAMES[6],
        }
    }

    /// The parameters in edge units, named with their unit, rounded to 12
    /// significant digits (so `0.3` um/bar reads back as `0.3`, not as the
    /// last-bit noise of the unit conversion).
    pub fn params_edge(&self) -> Vec<(&'static str, f64)> {
        let mut p = self.params_edge_exact();
        for (_, v) in p.iter_mut() {
            *v = format!("{:.11e}", *v).parse().unwrap_or(*v);
        }
        p
    }

    fn params_edge_exact(&self) -> Vec<(&'static str, f64)> {
        match *self {
            Effect::ThermalClearance { k_t, .. } => vec![("k_t_um_per_k", m_to_um(k_t))],
            Effect::PressureClearance { k_p, .. } => {
                vec![("k_p_um_per_bar", m_to_um(k_p) / pa_to_bar(1.0))]
            }
            Effect::LateralClearance { lateral } => vec![("h_lat_um", m_to_um(lateral))],
            Effect::ViscosityShift { factors } => {
                vec![("factor_t1", factors.0), ("factor_t2", factors.1)]
            }
            Effect::EntrainedAir { fraction } => vec![("air_fraction", fraction)],
            Effect::DisplacementError { relative } => vec![("relative", relative)],
            Effect::PressureViscosity { alpha } => vec![("alpha_per_pa", alpha)],
        }
    }

    /// The mechanism, whatever the site (two effects of one kind do not
    /// stack).
    pub fn kind(&self) -> &'static str {
        split_site(self.name()).0
    }

    /// True when the effect changes the gear geometry (the pump's look-up
    /// tables must be rebuilt).
    pub fn changes_geometry(&self) -> bool {
        matches!(self, Effect::DisplacementError { .. })
    }

    /// True when the effect changes the design (oil or geometry), i.e. a
    /// different [`Pump`] is needed; the others act per test.
    pub fn changes_design(&self) -> bool {
        matches!(
            self,
            Effect::ViscosityShift { .. }
                | Effect::EntrainedAir { .. }
                | Effect::DisplacementError { .. }
        )
    }

    /// Applies a design-level effect to `design` (no-op for per-test effects).
    pub fn apply_design(&self, design: &mut Design) {
        match *self {
            Effect::ViscosityShift { factors } => design.oil.nu_factor = factors,
            Effect::EntrainedAir { fraction } => design.oil.air_fraction = fraction,
            Effect::DisplacementError { relative } => design.face_width *= 1.0 + relative,
            _ => {}
        }
    }
}

impl fmt::Display for Effect {
    /// `NAME=VALUE` in edge units; [`Effect::parse`] reads it back.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let values: Vec<String> = self
            .params_edge()
            .iter()
            .map(|(_, v)| format!("{v}"))
            .collect();
        write!(f, "{}={}", self.name(), values.join(","))
    }
}

/// Parses every `--effect` argument; an effect given twice is refused.
pub fn parse_effects(args: &[String]) -> Result<Vec<Effect>, EffectError> {
    let mut out: Vec<Effect> = Vec::with_capacity(args.len());
    for a in args {
        let e = Effect::parse(a)?;
        if out.iter().any(|x| x.name() == e.name()) {
            return Err(EffectError::Duplicate { name: e.name() });
        }
        out.push(e);
    }
    Ok(out)
}

/// The project's model with zero or more effects switched on.
///
/// Design-level effects (oil, geometry) are applied once, at construction,
/// to a copy of the pump (oil only) or a rebuilt one (geometry); per-test
/// effects (clearances, gap viscosity) are applied to each run by
/// [`EffectModel::simulation`]. With no design-level effect the base pump is
/// shared, not copied.
#[derive(Debug)]
pub struct EffectModel {
    pump: Arc<Pump>,
    effects: Vec<Effect>,
}

impl EffectModel {
    /// The model on top of an already built `base` pump (shared when no
    /// design-level effect is on). A geometry effect rebuilds the tables
    /// (about half a second).
    pub fn on(base: &Arc<Pump>, effects: &[Effect]) -> Result<Self, EffectError> {
        check_unique(effects)?;
        let pump = if effects.iter().any(Effect::changes_geometry) {
            Arc::new(Pump::new(modified_design(&base.design, effects)))
        } else if effects.iter().any(Effect::changes_design) {
            let mut p = Pump::clone(base);
            p.design = modified_design(&base.design, effects);
            Arc::new(p)
        } else {
            Arc::clone(base)
        };
        // the design's own per-test keys (clearance growth, Barus), unless
        // an effect of the same kind is given
        let mut all = design_effects(&base.design);
        all.retain(|d| !effects.iter().any(|e| e.kind() == d.kind()));
        all.extend_from_slice(effects);
        Ok(EffectModel { pump, effects: all })
    }

    /// The effects switched on.
    pub fn effects(&self) -> &[Effect] {
        &self.effects
    }

    /// The pump the runs use (with the design-level effects).
    pub fn pump(&self) -> &Pump {
        &self.pump
    }

    /// The clearances in service at `inputs` of a sample whose measured
    /// clearances are `measured` (per-test effects applied).
    pub fn clearances(&self, measured: SampleClearances, inputs: &Inputs) -> SampleClearances {
        let geo = &self.pump.geo;
        let mut s = measured;
        let open = |s: &mut SampleClearances, dh: f64, site: Site| {
            gearpump_core::model::service::open_clearances(geo, s, dh, site)
        };
        for e in &self.effects {
            match *e {
                Effect::ThermalClearance { k_t, site } => open(
                    &mut s,
                    k_t * (inputs.temp_k - celsius_to_kelvin(T_MEASURE_C)),
                    site,
                ),
                Effect::PressureClearance { k_p, site } => {
                    open(&mut s, k_p * (inputs.p_delivery - inputs.p_suction), site)
                }
                Effect::LateralClearance { lateral } => s.lateral = lateral,
                _ => {}
            }
        }
        s
    }

    /// A simulation of one test: `measured` are the sample's measured
    /// clearances, the effects are applied to them and to the gaps.
    pub fn simulation(
        &self,
        inputs: Inputs,
        measured: SampleClearances,
        options: Options,
    ) -> Result<Simulation, ModelError> {
        let sample = self.clearances(measured, &inputs);
        let mut sim = Simulation::new(Arc::clone(&self.pump), inputs, sample, options)?;
        for e in &self.effects {
            if let Effect::PressureViscosity { alpha } = *e {
                let p_gap = 0.5 * (inputs.p_delivery - inputs.p_suction).max(0.0);
                sim.scale_gap_viscosity(gearpump_core::oil::barus_factor(alpha, p_gap));
            }
        }
        Ok(sim)
    }
}

/// The per-test effects a design's keys switch on: the clearance growth
/// laws of `[clearance]` and the Barus coefficient of `[oil]` (the
/// design-level keys act through the design itself).
pub fn design_effects(design: &Design) -> Vec<Effect> {
    let g = design.clearance.growth;
    let mut out = Vec::new();
    if g.thermal != 0.0 {
        out.push(Effect::ThermalClearance {
            k_t: g.thermal,
            site: g.thermal_on,
        });
    }
    if g.pressure != 0.0 {
        out.push(Effect::PressureClearance {
            k_p: g.pressure,
            site: g.pressure_on,
        });
    }
    if design.oil.pressure_viscosity != 0.0 {
        out.push(Effect::PressureViscosity {
            alpha: design.oil.pressure_viscosity,
        });
    }
    out
}

/// The design with every design-level effect applied.
pub fn modified_design(base: &Design, effects: &[Effect]) -> Design {
    let mut d = base.clone();
    for e in effects {
        e.apply_design(&mut d);
    }
    d
}

fn check_unique(effects: &[Effect]) -> Result<(), EffectError> {
    for (i, e) in effects.iter().enumerate() {
        if effects[..i].iter().any(|x| x.kind() == e.kind()) {
            return Err(EffectError::Duplicate { name: e.name() });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn campaign_effects_parse_and_display_round_trip() {
        for arg in [
            "thermal_clearance=0.15",
            "pressure_clearance=0.3",
            "lateral_clearance=25",
            "viscosity_shift=0.8,1.1",
            "entrained_air=0.02",
            "displacement_error=-0.02",
            "pressure_viscosity=2e-8",
        ] {
            let e = Effect::parse(arg).unwrap();
            if !arg.contains("e-") {
                assert_eq!(e.to_string(), arg);
            }
            let back = Effect::parse(&e.to_string()).unwrap();
            let (a, b) = (e.params_edge_exact(), back.params_edge_exact());
            for (x, y) in a.iter().zip(&b) {
                assert!((x.1 - y.1).abs() <= 1e-12 * x.1.abs(), "{arg} -> {e}");
            }
        }
        let e = Effect::parse("thermal_clearance=0.15").unwrap();
        match e {
            Effect::ThermalClearance { k_t, .. } => assert!((k_t - 0.15e-6).abs() < 1e-18),
            _ => panic!(),
        }
        let e = Effect::parse("pressure_clearance=0.3").unwrap();
        match e {
            Effect::PressureClearance { k_p, .. } => assert!((k_p * 30e5 - 9e-6).abs() < 1e-15),
            _ => panic!(),
        }
        assert_eq!(
            Effect::parse("viscosity_shift=0.9").unwrap(),
            Effect::ViscosityShift {
                factors: (0.9, 0.9)
            }
        );
    }

    #[test]
    fn campaign_effects_refuse_bad_arguments() {
        assert!(matches!(
            Effect::parse("thermal_clearance"),
            Err(EffectError::Syntax { .. })
        ));
        assert!(matches!(
            Effect::parse("warp_drive=1"),
            Err(EffectError::Unknown { .. })
        ));
        for bad in [
            "thermal_clearance=abc",
            "thermal_clearance=NaN",
            "thermal_clearance=1,2",
            "lateral_clearance=0",
            "viscosity_shift=0,1",
            "viscosity_shift=1,1,1",
            "entrained_air=0.7",
            "displacement_error=0.9",
            "pressure_viscosity=-1e-8",
        ] {
            let e = Effect::parse(bad).unwrap_err();
            assert!(matches!(e, EffectError::Value { .. }), "{bad}: {e}");
            assert!(e.to_string().starts_with(&format!("effect {bad}:")), "{e}");
        }
        let e =
            parse_effects(&["entrained_air=0.01".into(), "entrained_air=0.02".into()]).unwrap_err();
        assert_eq!(
            e,
            EffectError::Duplicate {
                name: "entrained_air"
            }
        );
    }

    #[test]
    fn campaign_effects_design_level_changes() {
        let base = Design::seed();
        let d = modified_design(
            &base,
            &[
                Effect::ViscosityShift {
                    factors: (0.8, 1.2),
                },
                Effect::EntrainedAir { fraction: 0.03 },
                Effect::DisplacementError { relative: 0.02 },
                Effect::ThermalClearance {
                    k_t: 1e-7,
                    site: Site::Radial,
                },
            ],
        );
        assert_eq!(d.oil.nu_factor, (0.8, 1.2));
        assert_eq!(d.oil.air_fraction, 0.03);
        assert!((d.face_width / base.face_width - 1.02).abs() < 1e-12);
        assert_eq!(d.clearance, base.clearance);
    }
}
