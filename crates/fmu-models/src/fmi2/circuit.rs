//! The automatic-transmission hydraulic circuit ([`crate::circuit`]) as an
//! FMI 2.0 co-simulation model, [`TransmissionCircuitFmu`]: the second model
//! of the same glue, exported as `TransmissionCircuit.fmu`.
//!
//! # Co-simulation semantics
//! * **Causality: flow in, pressure out.** The input `Q_pump` (m3/s) is the
//!   pump's delivered flow, held over the step; the circuit integrates it
//!   into its line volume and returns the line pressure `p_line` (Pa
//!   absolute) for the pump's `p_out`. This is the stable way round: the
//!   circuit is the stiff side (a small, nearly incompressible volume whose
//!   pressure follows the volume balance), and it integrates the received
//!   flow implicitly; the pump is a flow source that depends only weakly on
//!   its delivery pressure.
//! * **Exact volume bookkeeping.** `V_in` is the sum of `Q_pump h` over the
//!   steps: coupled to GearPump.fmu's `Q_out` (volume over the step / h) it
//!   equals the pump's `V_delivered` to round-off. `V_in - V_sump -
//!   V_stored` is zero to the Newton tolerance.
//! * **Step.** `fmi2DoStep(t, h)` runs `ceil(h / dt_max)` equal
//!   backward-Euler substeps; a step needing more than
//!   [`crate::circuit::MAX_SUBSTEPS`] (10 s at the default `dt_max`) is
//!   refused with `fmi2Error` before it starts, and `dt_max` lies within
//!   [1e-7, 1e-2] s (checked by `fmi2SetReal`, at initialisation and in a
//!   restored state), so no call can run unbounded.
//!   The flows `Q_reg`, `Q_lube`, `Q_clutch` are means over the last step.
//! * **Parameters** are fixed (set before `fmi2ExitInitializationMode`,
//!   checked together there). The oil is the bundled ATF of the pump design
//!   (density at `T_oil`, gas-release law), with its bulk modulus given by
//!   the parameter `bulk_modulus`.
//! * **Errors.** `Q_pump < 0`, `clutch_cmd` outside [0, 1], a parameter out
//!   of range, or a substep whose Newton iteration fails gives `fmi2Error`
//!   with the reason; a failed step leaves the state as before the step.
//!
//! # State
//! Parameters, inputs, the circuit state at the start and now (pressures,
//! positions, velocities, volume accounts) and the last step's mean flows:
//! plain numbers, so serialized states restore in a fresh process.

use std::path::Path;

use crate::circuit::{Circuit, CircuitInputs, CircuitParams, CircuitState, Flows};
use gearpump_core::design::Design;
use gearpump_core::oil::Oil;

use super::model::{
    BaseUnit, Causality, CoSimModel, DefaultExperiment, DisplayUnit, ModelError, StateReader,
    StateWriter, UnitDefinition, Variability, Variable, STANDARD_UNITS,
};

/// Value references of [`TransmissionCircuitFmu`].
pub mod vr {
    pub const Q_PUMP: u32 = 1;
    pub const CLUTCH_CMD: u32 = 2;
    pub const Q_PUMP_SLOPE: u32 = 3;
    pub const G_PUMP: u32 = 4;
    pub const V_LIN: u32 = 21;

    pub const P_LINE: u32 = 10;
    pub const P_CLUTCH: u32 = 11;
    pub const X_CLUTCH: u32 = 12;
    pub const X_REG: u32 = 13;
    pub const Q_REG: u32 = 14;
    pub const Q_LUBE: u32 = 15;
    pub const Q_CLUTCH: u32 = 16;
    pub const V_IN: u32 = 17;
    pub const V_SUMP: u32 = 18;
    pub const V_STORED: u32 = 19;
    pub const RHO_OIL: u32 = 20;

    pub const P_LINE_START: u32 = 100;
    pub const P_SUMP: u32 = 101;
    pub const T_OIL: u32 = 102;
    pub const BULK_MODULUS: u32 = 103;
    pub const CD: u32 = 104;
    pub const LINE_VOLUME: u32 = 105;
    pub const REG_DP_SET: u32 = 106;
    pub const REG_DIAMETER: u32 = 107;
    pub const REG_MASS: u32 = 108;
    pub const REG_SPRING_RATE: u32 = 109;
    pub const REG_DAMPING: u32 = 110;
    pub const REG_OVERLAP: u32 = 111;
    pub const REG_STROKE: u32 = 112;
    pub const REG_PORT_WIDTH: u32 = 113;
    pub const LUBE_DIAMETER: u32 = 114;
    pub const CLUTCH_AREA: u32 = 115;
    pub const CLUTCH_STROKE: u32 = 116;
    pub const CLUTCH_DEAD_VOLUME: u32 = 117;
    pub const CLUTCH_MASS: u32 = 118;
    pub const CLUTCH_SPRING_PRELOAD: u32 = 119;
    pub const CLUTCH_SPRING_RATE: u32 = 120;
    pub const CLUTCH_DAMPING: u32 = 121;
    pub const CLUTCH_PACK_STIFFNESS: u32 = 122;
    pub const FEED_DIAMETER: u32 = 123;
    pub const EXHAUST_DIAMETER: u32 = 124;
    pub const DT_MAX: u32 = 125;
}

use Causality::{Input, Output, Parameter};
use Variability::{Continuous, Fixed};

const fn param(name: &'static str, r: u32, unit: &'static str, start: f64) -> Variable {
    Variable::real(name, r, Parameter, Fixed, unit).start(start)
}

const fn out(name: &'static str, r: u32, unit: &'static str) -> Variable {
    Variable::real(name, r, Output, Continuous, unit)
}

/// Start of the line pressure: sump plus the set point (the regulator just
/// cracking), Pa absolute.
pub const P_LINE_START: f64 = 101_325.0 + 12.0e5;

const VARIABLES: &[Variable] = &[
    Variable::real("Q_pump", vr::Q_PUMP, Input, Continuous, "m3/s")
        .describe("Pump flow into the line, held over the step (couple to GearPump.Q_out)")
        .display("l/min")
        .start(1.8e-4),
    Variable::real("clutch_cmd", vr::CLUTCH_CMD, Input, Continuous, "1")
        .describe("Clutch apply valve command: 0 released (exhausted) .. 1 applied (fed)")
        .start(0.0),
    out("p_line", vr::P_LINE, "Pa")
        .describe("Line pressure, absolute (couple to GearPump.p_out)")
        .display("bar"),
    out("p_clutch", vr::P_CLUTCH, "Pa")
        .describe("Clutch chamber pressure, absolute")
        .display("bar"),
    out("x_clutch", vr::X_CLUTCH, "m")
        .describe("Clutch piston stroke (pack contact at clutch_stroke)")
        .display("mm"),
    out("x_reg", vr::X_REG, "m")
        .describe("Regulator spool position (metering edge open beyond reg_overlap)")
        .display("mm"),
    out("Q_reg", vr::Q_REG, "m3/s")
        .describe("Regulator flow to the sump, mean over the last step")
        .display("l/min"),
    out("Q_lube", vr::Q_LUBE, "m3/s")
        .describe("Lubrication flow, mean over the last step")
        .display("l/min"),
    out("Q_clutch", vr::Q_CLUTCH, "m3/s")
        .describe("Net flow into the clutch (feed - exhaust), mean over the last step")
        .display("l/min"),
    out("V_in", vr::V_IN, "m3")
        .describe("Volume received from the pump since the start: sum of Q_pump*h")
        .display("l"),
    out("V_sump", vr::V_SUMP, "m3")
        .describe("Volume returned to the sump since the start (regulator, lube, clutch exhaust)")
        .display("l"),
    out("V_stored", vr::V_STORED, "m3")
        .describe("Volume stored since the start (compression, spool and piston displacement): V_in - V_sump")
        .display("l"),
    out("rho_oil", vr::RHO_OIL, "kg/m3")
        .describe("Oil density at T_oil used by the orifice laws (bundled ATF)"),
    param("p_line_start", vr::P_LINE_START, "Pa", P_LINE_START)
        .describe("Initial line pressure, absolute")
        .display("bar"),
    param("p_sump", vr::P_SUMP, "Pa", 101_325.0)
        .describe("Sump pressure, absolute")
        .display("bar"),
    param("T_oil", vr::T_OIL, "K", 353.15)
        .describe("Oil temperature (density of the bundled ATF)")
        .display("degC"),
    param("bulk_modulus", vr::BULK_MODULUS, "Pa", 1.4e9)
        .describe("Effective bulk modulus of the oil (bundled ATF: 1.4 GPa)")
        .display("bar"),
    param("cd", vr::CD, "1", 0.7).describe("Discharge coefficient of every orifice and metering edge"),
    param("line_volume", vr::LINE_VOLUME, "m3", 0.4e-3)
        .describe("Line volume: pump outlet, passages, valve body (0.2-1 l)")
        .display("l"),
    param("reg_dp_set", vr::REG_DP_SET, "Pa", 12.0e5)
        .describe("Regulator set point: line minus sump pressure at which the metering edge cracks (5-20 bar)")
        .display("bar"),
    param("reg_diameter", vr::REG_DIAMETER, "m", 0.012)
        .describe("Regulator spool diameter (feedback area pi d^2/4)")
        .display("mm"),
    param("reg_mass", vr::REG_MASS, "kg", 0.045).describe("Regulator spool mass"),
    param("reg_spring_rate", vr::REG_SPRING_RATE, "N/m", 1.0e4)
        .describe("Regulator spring rate (the preload follows from reg_dp_set)"),
    param("reg_damping", vr::REG_DAMPING, "N.s/m", 800.0)
        .describe("Regulator viscous damping (feedback damping orifice A^2/G)"),
    param("reg_overlap", vr::REG_OVERLAP, "m", 0.5e-3)
        .describe("Metering edge overlap: open for x_reg > reg_overlap")
        .display("mm"),
    param("reg_stroke", vr::REG_STROKE, "m", 3.0e-3)
        .describe("Regulator spool stroke")
        .display("mm"),
    param("reg_port_width", vr::REG_PORT_WIDTH, "m", 0.01)
        .describe("Width of the regulator's metering port")
        .display("mm"),
    param("lube_diameter", vr::LUBE_DIAMETER, "m", 1.5e-3)
        .describe("Lubrication orifice diameter (about 4 l/min at 12 bar)")
        .display("mm"),
    param("clutch_area", vr::CLUTCH_AREA, "m2", 9.8e-3)
        .describe("Clutch piston area (annulus 150/100 mm)"),
    param("clutch_stroke", vr::CLUTCH_STROKE, "m", 1.5e-3)
        .describe("Clutch piston stroke to the pack (1-2 mm)")
        .display("mm"),
    param("clutch_dead_volume", vr::CLUTCH_DEAD_VOLUME, "m3", 2.0e-5)
        .describe("Clutch chamber volume at zero stroke")
        .display("l"),
    param("clutch_mass", vr::CLUTCH_MASS, "kg", 0.6).describe("Clutch piston mass"),
    param("clutch_spring_preload", vr::CLUTCH_SPRING_PRELOAD, "N", 1500.0)
        .describe("Return spring force at zero stroke (about 1.5 bar on the piston)"),
    param("clutch_spring_rate", vr::CLUTCH_SPRING_RATE, "N/m", 2.0e5)
        .describe("Return spring rate"),
    param("clutch_damping", vr::CLUTCH_DAMPING, "N.s/m", 300.0)
        .describe("Piston seal viscous friction"),
    param("clutch_pack_stiffness", vr::CLUTCH_PACK_STIFFNESS, "N/m", 2.0e8)
        .describe("Clutch pack stiffness beyond the stroke"),
    param("feed_diameter", vr::FEED_DIAMETER, "m", 1.5e-3)
        .describe("Clutch feed orifice diameter (fill time about 0.2 s)")
        .display("mm"),
    param("exhaust_diameter", vr::EXHAUST_DIAMETER, "m", 2.0e-3)
        .describe("Clutch exhaust orifice diameter")
        .display("mm"),
    param("dt_max", vr::DT_MAX, "s", 1.0e-5)
        .describe("Longest internal backward-Euler substep"),
    Variable::real("Q_pump_slope", vr::Q_PUMP_SLOPE, Input, Continuous, "m3/s2")
        .describe("Slope of the pump flow over the step: the inflow is Q_pump + Q_pump_slope (s - h/2), s from the step's start (couple to GearPump.Q_out_slope; 0: held)")
        .start(0.0),
    Variable::real("G_pump", vr::G_PUMP, Input, Continuous, "m3/(s.Pa)")
        .describe("Pump pressure sensitivity dQ_pump/dp_line (<= 0): the line pressure is solved with the inflow Q_pump + G_pump (p_line - p_line(t)) over the step (couple to GearPump.dQ_out_dp_out; 0: none)")
        .start(0.0),
    out("V_lin", vr::V_LIN, "m3")
        .describe("Volume the pump's linearisation (G_pump) added to V_in since the start")
        .display("l"),
];

/// The parameters that may be 0 (the others must be > 0).
const MAY_BE_ZERO: &[u32] = &[
    vr::REG_DAMPING,
    vr::REG_OVERLAP,
    vr::CLUTCH_SPRING_PRELOAD,
    vr::CLUTCH_SPRING_RATE,
    vr::CLUTCH_DAMPING,
];

const fn same(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

const fn standard(name: &str) -> UnitDefinition {
    let mut i = 0;
    while i < STANDARD_UNITS.len() {
        if same(STANDARD_UNITS[i].name, name) {
            return STANDARD_UNITS[i];
        }
        i += 1;
    }
    panic!("not a standard unit")
}

const fn base(kg: i32, m: i32, s: i32) -> BaseUnit {
    BaseUnit {
        kg,
        m,
        s,
        a: 0,
        k: 0,
        mol: 0,
        cd: 0,
        rad: 0,
    }
}

/// The standard units plus the mechanical ones of the valve and piston.
const UNITS: &[UnitDefinition] = &[
    standard("Pa"),
    standard("K"),
    standard("m3/s"),
    standard("m3"),
    standard("m"),
    standard("m2"),
    standard("N"),
    standard("s"),
    standard("1"),
    standard("kg/m3"),
    standard("m3/s2"),
    standard("m3/(s.Pa)"),
    UnitDefinition {
        name: "kg",
        base: base(1, 0, 0),
        display: &[DisplayUnit {
            name: "g",
            factor: 1.0e3,
            offset: 0.0,
        }],
    },
    UnitDefinition {
        name: "N/m",
        base: base(1, 0, -2),
        display: &[DisplayUnit {
            name: "N/mm",
            factor: 1.0e-3,
            offset: 0.0,
        }],
    },
    UnitDefinition {
        name: "N.s/m",
        base: base(1, 0, -1),
        display: &[],
    },
];

const STATE_TAG: &[u8; 8] = b"TCIRC002";

/// HTML fragment of `documentation/index.html`.
pub const DOCUMENTATION: &str = "<h2>Transmission circuit</h2>
<p>Line volume with the oil's bulk modulus, a spring-loaded line-pressure
regulator valve (spool mass, spring, damping, stroke limits, metering edge to
the sump), a lubrication orifice, and a clutch (3-way apply valve driven by
<code>clutch_cmd</code>, feed and exhaust orifices, chamber growing with the
piston stroke, return spring, pack contact). Equations: the doc comment of
<code>crates/fmu-models/src/circuit/mod.rs</code>.</p>
<h2>Co-simulation</h2>
<p>Causality: flow in (<code>Q_pump</code>, m3/s), pressure out
(<code>p_line</code>, Pa absolute). Couple <code>GearPump.Q_out</code> to
<code>Q_pump</code> and <code>p_line</code> to <code>GearPump.p_out</code>.
Each step runs backward-Euler substeps of at most <code>dt_max</code>
(implicit: the circuit is stiff). <code>V_in</code> sums
<code>Q_pump*h</code>: it equals the pump's <code>V_delivered</code> to
round-off. Variable step sizes, FMU state get/set/serialize and reset are
supported.</p>";

/// The circuit as a co-simulation model (see the module docs).
#[derive(Debug, Clone)]
pub struct TransmissionCircuitFmu {
    oil: Oil,
    params: CircuitParams,
    p_line_start: f64,
    inputs: CircuitInputs,
    /// Built at `fmi2ExitInitializationMode`.
    circuit: Option<Circuit>,
    /// Mean flows over the last step.
    mean: Flows,
}

impl TransmissionCircuitFmu {
    /// A model at the start values with the given oil.
    pub fn new(oil: Oil) -> Self {
        TransmissionCircuitFmu {
            oil,
            params: CircuitParams::default(),
            p_line_start: P_LINE_START,
            inputs: CircuitInputs {
                q_pump: 1.8e-4,
                ..CircuitInputs::default()
            },
            circuit: None,
            mean: Flows::default(),
        }
    }

    /// The circuit (after initialisation).
    pub fn circuit(&self) -> Option<&Circuit> {
        self.circuit.as_ref()
    }

    fn param_mut(&mut self, r: u32) -> Option<&mut f64> {
        let p = &mut self.params;
        Some(match r {
            vr::P_LINE_START => &mut self.p_line_start,
            vr::P_SUMP => &mut p.p_sump,
            vr::T_OIL => &mut p.t_oil,
            vr::BULK_MODULUS => &mut p.bulk_modulus,
            vr::CD => &mut p.cd,
            vr::LINE_VOLUME => &mut p.line_volume,
            vr::REG_DP_SET => &mut p.reg_dp_set,
            vr::REG_DIAMETER => &mut p.reg_diameter,
            vr::REG_MASS => &mut p.reg_mass,
            vr::REG_SPRING_RATE => &mut p.reg_spring_rate,
            vr::REG_DAMPING => &mut p.reg_damping,
            vr::REG_OVERLAP => &mut p.reg_overlap,
            vr::REG_STROKE => &mut p.reg_stroke,
            vr::REG_PORT_WIDTH => &mut p.reg_port_width,
            vr::LUBE_DIAMETER => &mut p.lube_diameter,
            vr::CLUTCH_AREA => &mut p.clutch_area,
            vr::CLUTCH_STROKE => &mut p.clutch_stroke,
            vr::CLUTCH_DEAD_VOLUME => &mut p.clutch_dead_volume,
            vr::CLUTCH_MASS => &mut p.clutch_mass,
            vr::CLUTCH_SPRING_PRELOAD => &mut p.clutch_spring_preload,
            vr::CLUTCH_SPRING_RATE => &mut p.clutch_spring_rate,
            vr::CLUTCH_DAMPING => &mut p.clutch_damping,
            vr::CLUTCH_PACK_STIFFNESS => &mut p.clutch_pack_stiffness,
            vr::FEED_DIAMETER => &mut p.feed_diameter,
            vr::EXHAUST_DIAMETER => &mut p.exhaust_diameter,
            vr::DT_MAX => &mut p.dt_max,
            _ => return None,
        })
    }

    fn name(r: u32) -> &'static str {
        VARIABLES
            .iter()
            .find(|v| v.value_reference == r)
            .map_or("?", |v| v.name)
    }

    /// The state reported before initialisation: the start state.
    fn state(&self) -> CircuitState {
        match &self.circuit {
            Some(c) => c.state,
            None => Circuit::new(self.params.clone(), &self.oil, self.p_line_start)
                .map(|c| c.state)
                .unwrap_or(CircuitState::at_rest(self.p_line_start, self.params.p_sump)),
        }
    }

    fn params_array(&self) -> Vec<f64> {
        let mut copy = self.clone();
        PARAM_VRS
            .iter()
            .map(|&r| copy.param_mut(r).map_or(f64::NAN, |v| *v))
            .collect()
    }
}

/// Every parameter's value reference, in table order (state layout).
const PARAM_VRS: [u32; 26] = [
    vr::P_LINE_START,
    vr::P_SUMP,
    vr::T_OIL,
    vr::BULK_MODULUS,
    vr::CD,
    vr::LINE_VOLUME,
    vr::REG_DP_SET,
    vr::REG_DIAMETER,
    vr::REG_MASS,
    vr::REG_SPRING_RATE,
    vr::REG_DAMPING,
    vr::REG_OVERLAP,
    vr::REG_STROKE,
    vr::REG_PORT_WIDTH,
    vr::LUBE_DIAMETER,
    vr::CLUTCH_AREA,
    vr::CLUTCH_STROKE,
    vr::CLUTCH_DEAD_VOLUME,
    vr::CLUTCH_MASS,
    vr::CLUTCH_SPRING_PRELOAD,
    vr::CLUTCH_SPRING_RATE,
    vr::CLUTCH_DAMPING,
    vr::CLUTCH_PACK_STIFFNESS,
    vr::FEED_DIAMETER,
    vr::EXHAUST_DIAMETER,
    vr::DT_MAX,
];

fn model_error(e: crate::circuit::CircuitError) -> ModelError {
    use crate::circuit::CircuitError as E;
    match e {
        E::InvalidParameter { name, value, rule } | E::InvalidInput { name, value, rule } => {
            ModelError::invalid(name, value, rule)
        }
        E::Solver { t, dt, source } => ModelError::StepFailed {
            t,
            h: dt,
            reason: source.to_string(),
        },
    }
}

impl CoSimModel for TransmissionCircuitFmu {
    const MODEL_IDENTIFIER: &'static str = "TransmissionCircuit";
    const GUID: &'static str = "{7c2f4d90-3e1a-4b6b-a8d5-0f9c61e2b374}";
    const MODEL_NAME: &'static str = "gearpump.TransmissionCircuit";
    const DESCRIPTION: &'static str =
        "Automatic-transmission hydraulic circuit fed by a pump: line volume, line-pressure \
         regulator valve with spool dynamics, lubrication orifice, clutch fill (implicit, stiff)";
    const AUTHOR: &'static str = "gearpump contributors";
    const DEFAULT_EXPERIMENT: Option<DefaultExperiment> = Some(DefaultExperiment {
        start_time: 0.0,
        stop_time: 0.5,
        tolerance: None,
        step_size: 1.0e-3,
    });

    fn variables() -> &'static [Variable] {
        VARIABLES
    }

    fn units() -> &'static [UnitDefinition] {
        UNITS
    }

    fn documentation() -> &'static str {
        DOCUMENTATION
    }

    fn resource_files() -> Vec<(String, Vec<u8>)> {
        vec![(
            "README.txt".into(),
            b"TransmissionCircuit needs no resources: its oil is the bundled ATF of the gearpump design.\n"
                .to_vec(),
        )]
    }

    fn instantiate(_resources: &Path, logger: &dyn Fn(&str)) -> Result<Self, ModelError> {
        let oil = Design::seed().oil;
        logger("transmission circuit ready (oil: the bundled ATF)");
        Ok(TransmissionCircuitFmu::new(oil))
    }

    fn set_real(&mut self, r: u32, value: f64) -> Result<(), ModelError> {
        match r {
            vr::Q_PUMP => {
                if !(value.is_finite() && value >= 0.0) {
                    return Err(ModelError::invalid(
                        "Q_pump",
                        value,
                        "must be a finite flow >= 0 m3/s (the circuit takes the pump's delivery)",
                    ));
                }
                self.inputs.q_pump = value;
            }
            vr::CLUTCH_CMD => {
                if !(value.is_finite() && (0.0..=1.0).contains(&value)) {
                    return Err(ModelError::invalid(
                        "clutch_cmd",
                        value,
                        "must be in [0, 1]",
                    ));
                }
                self.inputs.clutch_cmd = value;
            }
            vr::Q_PUMP_SLOPE => {
                if !value.is_finite() {
                    return Err(ModelError::invalid("Q_pump_slope", value, "must be finite"));
                }
                self.inputs.q_pump_slope = value;
            }
            vr::G_PUMP => {
                if !(value.is_finite() && (-crate::circuit::MAX_G_PUMP..=0.0).contains(&value)) {
                    return Err(ModelError::invalid(
                        "G_pump",
                        value,
                        "must be finite, <= 0 and >= -1e-7 m3/s/Pa (a pump's flow falls as its delivery pressure rises)",
                    ));
                }
                self.inputs.g_pump = value;
            }
            _ => {
                let zero_ok = MAY_BE_ZERO.contains(&r);
                let name = Self::name(r);
                let target = self
                    .param_mut(r)
                    .ok_or(ModelError::UnknownValueReference(r))?;
                if r == vr::DT_MAX
                    && !(crate::circuit::MIN_DT_MAX..=crate::circuit::MAX_DT_MAX).contains(&value)
                {
                    return Err(ModelError::invalid(
                        name,
                        value,
                        "must lie within [1e-7, 1e-2] s (the substep count of a step is bounded)",
                    ));
                }
                let ok = value.is_finite() && (value > 0.0 || (zero_ok && value == 0.0));
                if !ok {
                    let rule = if zero_ok {
                        "must be finite and >= 0"
                    } else {
                        "must be finite and > 0"
                    };
                    return Err(ModelError::invalid(name, value, rule));
                }
                *target = value;
            }
        }
        Ok(())
    }

    fn get_real(&self, r: u32) -> Result<f64, ModelError> {
        let s = self.state();
        let stored = |c: &Circuit| c.volume_stored();
        Ok(match r {
            vr::Q_PUMP => self.inputs.q_pump,
            vr::CLUTCH_CMD => self.inputs.clutch_cmd,
            vr::Q_PUMP_SLOPE => self.inputs.q_pump_slope,
            vr::G_PUMP => self.inputs.g_pump,
            vr::V_LIN => s.v_lin,
            vr::P_LINE => s.p_line,
            vr::P_CLUTCH => s.p_clutch,
            vr::X_CLUTCH => s.x_clutch,
            vr::X_REG => s.x_reg,
            vr::Q_REG => self.mean.reg,
            vr::Q_LUBE => self.mean.lube,
            vr::Q_CLUTCH => self.mean.feed - self.mean.exhaust,
            vr::V_IN => s.v_in,
            vr::V_SUMP => s.v_reg_out + s.v_lube_out + s.v_exhaust,
            vr::V_STORED => self.circuit.as_ref().map_or(0.0, stored),
            vr::RHO_OIL => self.oil.density(self.params.t_oil),
            _ => {
                let mut copy = self.clone();
                return copy
                    .param_mut(r)
                    .map(|v| *v)
                    .ok_or(ModelError::UnknownValueReference(r));
            }
        })
    }

    fn exit_initialization(&mut self) -> Result<(), ModelError> {
        let c =
            Circuit::new(self.params.clone(), &self.oil, self.p_line_start).map_err(model_error)?;
        self.mean = c.flows_now(self.inputs.clutch_cmd);
        self.circuit = Some(c);
        Ok(())
    }

    fn do_step(&mut self, t: f64, h: f64) -> Result<(), ModelError> {
        let c = self
            .circuit
            .as_mut()
            .ok_or_else(|| ModelError::Other("not initialised".into()))?;
        let report = c.step(t, h, self.inputs).map_err(model_error)?;
        self.mean = report.mean;
        Ok(())
    }

    fn reset(&mut self) -> Result<(), ModelError> {
        *self = TransmissionCircuitFmu::new(self.oil.clone());
        Ok(())
    }

    fn save_state(&self) -> Vec<u8> {
        let mut w = StateWriter::new(STATE_TAG);
        w.f64s(&self.params_array())
            .f64(self.inputs.q_pump)
            .f64(self.inputs.clutch_cmd)
            .f64(self.inputs.q_pump_slope)
            .f64(self.inputs.g_pump)
            .f64(self.mean.reg)
            .f64(self.mean.lube)
            .f64(self.mean.feed)
            .f64(self.mean.exhaust)
            .bool(self.circuit.is_some());
        if let Some(c) = &self.circuit {
            w.f64s(&c.start_state().to_array())
                .f64s(&c.state.to_array());
        }
        w.finish()
    }

    fn restore_state(&mut self, bytes: &[u8]) -> Result<(), ModelError> {
        let mut r = StateReader::new(bytes, STATE_TAG)?;
        let params = r.f64s()?;
        if params.len() != PARAM_VRS.len() {
            return Err(ModelError::InvalidState(format!(
                "{} parameters, expected {}",
                params.len(),
                PARAM_VRS.len()
            )));
        }
        let mut m = TransmissionCircuitFmu::new(self.oil.clone());
        for (&vr, &v) in PARAM_VRS.iter().zip(&params) {
            if let Some(p) = m.param_mut(vr) {
                *p = v;
            }
        }
        m.inputs = CircuitInputs {
            q_pump: r.f64()?,
            clutch_cmd: r.f64()?,
            q_pump_slope: r.f64()?,
            g_pump: r.f64()?,
        };
        m.inputs
            .validate()
            .map_err(|e| ModelError::InvalidState(e.to_string()))?;
        m.mean = Flows {
            reg: r.f64()?,
            lube: r.f64()?,
            feed: r.f64()?,
            exhaust: r.f64()?,
        };
        if r.bool()? {
            let array = |v: Vec<f64>| -> Result<[f64; 13], ModelError> {
                v.try_into()
                    .map_err(|_| ModelError::InvalidState("circuit state length".into()))
            };
            let start = CircuitState::from_array(array(r.f64s()?)?);
            let now = CircuitState::from_array(array(r.f64s()?)?);
            let mut c = Circuit::new(m.params.clone(), &m.oil, m.p_line_start)
                .map_err(|e| ModelError::InvalidState(e.to_string()))?;
            c.restore(start, now);
            m.circuit = Some(c);
        }
        r.finish()?;
        *self = m;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fmi2::model::check_model;

    #[test]
    fn table_is_valid_and_the_start_values_are_the_physics_defaults() {
        check_model::<TransmissionCircuitFmu>().unwrap();
        let m = TransmissionCircuitFmu::new(Design::seed().oil);
        let d = CircuitParams::default();
        let mut fresh = TransmissionCircuitFmu::new(Design::seed().oil);
        for v in VARIABLES
            .iter()
            .filter(|v| v.causality == Causality::Parameter)
        {
            let crate::fmi2::VariableKind::Real {
                start: Some(start), ..
            } = v.kind
            else {
                panic!("{} has no start", v.name)
            };
            assert_eq!(m.get_real(v.value_reference).unwrap(), start, "{}", v.name);
            // and the setter reaches the same field
            fresh.set_real(v.value_reference, start * 2.0).unwrap();
            assert_eq!(fresh.get_real(v.value_reference).unwrap(), start * 2.0);
        }
        assert_eq!(m.params, d);
        assert_eq!(
            PARAM_VRS.len(),
            VARIABLES
                .iter()
                .filter(|v| v.causality == Causality::Parameter)
                .count()
        );
    }

    #[test]
    fn state_round_trip_and_refusals() {
        let mut m = TransmissionCircuitFmu::new(Design::seed().oil);
        m.set_real(vr::CLUTCH_CMD, 1.0).unwrap();
        m.exit_initialization().unwrap();
        m.do_step(0.0, 1e-3).unwrap();
        let bytes = m.save_state();
        m.do_step(1e-3, 1e-3).unwrap();
        let after = m.get_real(vr::P_CLUTCH).unwrap();
        let mut n = TransmissionCircuitFmu::new(Design::seed().oil);
        n.restore_state(&bytes).unwrap();
        n.do_step(1e-3, 1e-3).unwrap();
        assert_eq!(n.get_real(vr::P_CLUTCH).unwrap(), after);
        assert!(n.restore_state(&bytes[..bytes.len() - 3]).is_err());
        assert!(n.set_real(vr::Q_PUMP, -1.0).is_err());
        assert!(n.set_real(vr::CLUTCH_CMD, 2.0).is_err());
        assert!(n.set_real(vr::LINE_VOLUME, 0.0).is_err());
        assert!(n.set_real(vr::REG_DAMPING, 0.0).is_ok());
    }

    #[test]
    fn no_call_runs_unbounded() {
        let oil = || Design::seed().oil;
        // fmi2SetReal refuses a dt_max outside [1e-7, 1e-2] s
        let mut m = TransmissionCircuitFmu::new(oil());
        for v in [1e-12, 1.0, 0.0] {
            assert!(m.set_real(vr::DT_MAX, v).is_err(), "{v}");
        }
        // one that got in another way (a state saved before initialisation)
        // is refused when the circuit is built
        *m.param_mut(vr::DT_MAX).unwrap() = 1e-12;
        let bytes = m.save_state();
        let mut n = TransmissionCircuitFmu::new(oil());
        n.restore_state(&bytes).unwrap();
        assert!(n.exit_initialization().is_err());
        assert!(m.exit_initialization().is_err());
        // a huge communication step is refused at once, the state kept
        let mut m = TransmissionCircuitFmu::new(oil());
        m.exit_initialization().unwrap();
        let before = m.get_real(vr::P_LINE).unwrap();
        for h in [1e3, 1e6, 1e30, f64::MAX] {
            assert!(m.do_step(0.0, h).is_err(), "{h}");
        }
        assert_eq!(m.get_real(vr::P_LINE).unwrap(), before);
        assert!(m.do_step(0.0, 1e-3).is_ok());
    }
}
