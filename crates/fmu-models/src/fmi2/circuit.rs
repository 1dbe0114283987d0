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
//! * **Errors.** Every input and parameter has a physical range
//!   ([`crate::circuit::range`], the XML's min/max, docs/fmu.md); a value
//!   outside it (or NaN, infinite) is refused by `fmi2SetReal` naming the
//!   variable, the range and the reason. The combinations (`p_line_start >=
//!   p_sump`, `reg_overlap < reg_stroke`, a positive regulator spring
//!   preload) are checked at `fmi2ExitInitializationMode`. A step whose
//!   line or clutch pressure would pass [`crate::circuit::MAX_PRESSURE`]
//!   (1000 bar: the inflow is more than the circuit passes) or whose Newton
//!   iteration fails gives `fmi2Error` with the reason; a failed step
//!   leaves the state as before the step.
//!
//! # State
//! Parameters, inputs, the circuit state at the start and now (pressures,
//! positions, velocities, volume accounts) and the last step's mean flows:
//! plain numbers, so serialized states restore in a fresh process.

use std::path::Path;

use crate::circuit::range as R;
use crate::circuit::{Circuit, CircuitInputs, CircuitParams, CircuitState, Flows, Range};
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

/// A parameter with its start value and its range ([`crate::circuit::range`]).
const fn param(name: &'static str, r: u32, start: f64, range: Range) -> Variable {
    Variable::real(name, r, Parameter, Fixed, range.unit)
        .start(start)
        .range(range.min, range.max)
}

/// An input with its start value and its range.
const fn input(name: &'static str, r: u32, start: f64, range: Range) -> Variable {
    Variable::real(name, r, Input, Continuous, range.unit)
        .start(start)
        .range(range.min, range.max)
}

const fn out(name: &'static str, r: u32, unit: &'static str) -> Variable {
    Variable::real(name, r, Output, Continuous, unit)
}

/// Start of the line pressure: sump plus the set point (the regulator just
/// cracking), Pa absolute.
pub const P_LINE_START: f64 = 101_325.0 + 12.0e5;

const VARIABLES: &[Variable] = &[
    input("Q_pump", vr::Q_PUMP, 1.8e-4, R::Q_PUMP)
        .describe("Pump flow into the line, held over the step (couple to GearPump.Q_out)")
        .display("l/min"),
    input("clutch_cmd", vr::CLUTCH_CMD, 0.0, R::CLUTCH_CMD)
        .describe("Clutch apply valve command: 0 released (exhausted) .. 1 applied (fed)"),
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
    param("p_line_start", vr::P_LINE_START, P_LINE_START, R::P_LINE_START)
        .describe("Initial line pressure, absolute")
        .display("bar"),
    param("p_sump", vr::P_SUMP, 101_325.0, R::P_SUMP)
        .describe("Sump pressure, absolute")
        .display("bar"),
    param("T_oil", vr::T_OIL, 353.15, R::T_OIL)
        .describe("Oil temperature (density of the bundled ATF)")
        .display("degC"),
    param("bulk_modulus", vr::BULK_MODULUS, 1.4e9, R::BULK_MODULUS)
        .describe("Effective bulk modulus of the oil (bundled ATF: 1.4 GPa)")
        .display("bar"),
    param("cd", vr::CD, 0.7, R::CD).describe("Discharge coefficient of every orifice and metering edge"),
    param("line_volume", vr::LINE_VOLUME, 0.4e-3, R::LINE_VOLUME)
        .describe("Line volume: pump outlet, passages, valve body (0.2-1 l)")
        .display("l"),
    param("reg_dp_set", vr::REG_DP_SET, 12.0e5, R::REG_DP_SET)
        .describe("Regulator set point: line minus sump pressure at which the metering edge cracks (5-20 bar)")
        .display("bar"),
    param("reg_diameter", vr::REG_DIAMETER, 0.012, R::REG_DIAMETER)
        .describe("Regulator spool diameter (feedback area pi d^2/4)")
        .display("mm"),
    param("reg_mass", vr::REG_MASS, 0.045, R::REG_MASS).describe("Regulator spool mass"),
    param("reg_spring_rate", vr::REG_SPRING_RATE, 1.0e4, R::REG_SPRING_RATE)
        .describe("Regulator spring rate (the preload follows from reg_dp_set)"),
    param("reg_damping", vr::REG_DAMPING, 800.0, R::REG_DAMPING)
        .describe("Regulator viscous damping (feedback damping orifice A^2/G)"),
    param("reg_overlap", vr::REG_OVERLAP, 0.5e-3, R::REG_OVERLAP)
        .describe("Metering edge overlap: open for x_reg > reg_overlap")
        .display("mm"),
    param("reg_stroke", vr::REG_STROKE, 3.0e-3, R::REG_STROKE)
        .describe("Regulator spool stroke")
        .display("mm"),
    param("reg_port_width", vr::REG_PORT_WIDTH, 0.01, R::REG_PORT_WIDTH)
        .describe("Width of the regulator's metering port")
        .display("mm"),
    param("lube_diameter", vr::LUBE_DIAMETER, 1.5e-3, R::ORIFICE_DIAMETER)
        .describe("Lubrication orifice diameter (about 4 l/min at 12 bar)")
        .display("mm"),
    param("clutch_area", vr::CLUTCH_AREA, 9.8e-3, R::CLUTCH_AREA)
        .describe("Clutch piston area (annulus 150/100 mm)"),
    param("clutch_stroke", vr::CLUTCH_STROKE, 1.5e-3, R::CLUTCH_STROKE)
        .describe("Clutch piston stroke to the pack (1-2 mm)")
        .display("mm"),
    param("clutch_dead_volume", vr::CLUTCH_DEAD_VOLUME, 2.0e-5, R::CLUTCH_DEAD_VOLUME)
        .describe("Clutch chamber volume at zero stroke")
        .display("l"),
    param("clutch_mass", vr::CLUTCH_MASS, 0.6, R::CLUTCH_MASS).describe("Clutch piston mass"),
    param("clutch_spring_preload", vr::CLUTCH_SPRING_PRELOAD, 1500.0, R::CLUTCH_SPRING_PRELOAD)
        .describe("Return spring force at zero stroke (about 1.5 bar on the piston)"),
    param("clutch_spring_rate", vr::CLUTCH_SPRING_RATE, 2.0e5, R::CLUTCH_SPRING_RATE)
        .describe("Return spring rate"),
    param("clutch_damping", vr::CLUTCH_DAMPING, 300.0, R::CLUTCH_DAMPING)
        .describe("Piston seal viscous friction"),
    param("clutch_pack_stiffness", vr::CLUTCH_PACK_STIFFNESS, 2.0e8, R::CLUTCH_PACK_STIFFNESS)
        .describe("Clutch pack stiffness beyond the stroke"),
    param("feed_diameter", vr::FEED_DIAMETER, 1.5e-3, R::ORIFICE_DIAMETER)
        .describe("Clutch feed orifice diameter (fill time about 0.2 s)")
        .display("mm"),
    param("exhaust_diameter", vr::EXHAUST_DIAMETER, 2.0e-3, R::ORIFICE_DIAMETER)
        .describe("Clutch exhaust orifice diameter")
        .display("mm"),
    param("dt_max", vr::DT_MAX, 1.0e-5, R::DT_MAX)
        .describe("Longest internal backward-Euler substep"),
    input("Q_pump_slope", vr::Q_PUMP_SLOPE, 0.0, R::Q_PUMP_SLOPE)
        .describe("Slope of the pump flow over the step: the inflow is Q_pump + Q_pump_slope (s - h/2), s from the step's start (couple to GearPump.Q_out_slope; 0: held)"),
    input("G_pump", vr::G_PUMP, 0.0, R::G_PUMP)
        .describe("Pump pressure sensitivity dQ_pump/dp_line (<= 0): the line pressure is solved with the inflow Q_pump + G_pump (p_line - p_line(t)) over the step (couple to GearPump.dQ_out_dp_out; 0: none)"),
    out("V_lin", vr::V_LIN, "m3")
        .describe("Volume the pump's linearisation (G_pump) added to V_in since the start")
        .display("l"),
];

/// The range of the settable (input or parameter) variable `r` (the
/// table's min/max are the same: a unit test holds them together).
fn variable_range(r: u32) -> Option<Range> {
    Some(match r {
        vr::Q_PUMP => R::Q_PUMP,
        vr::CLUTCH_CMD => R::CLUTCH_CMD,
        vr::Q_PUMP_SLOPE => R::Q_PUMP_SLOPE,
        vr::G_PUMP => R::G_PUMP,
        vr::P_LINE_START => R::P_LINE_START,
        vr::P_SUMP => R::P_SUMP,
        vr::T_OIL => R::T_OIL,
        vr::BULK_MODULUS => R::BULK_MODULUS,
        vr::CD => R::CD,
        vr::LINE_VOLUME => R::LINE_VOLUME,
        vr::REG_DP_SET => R::REG_DP_SET,
        vr::REG_DIAMETER => R::REG_DIAMETER,
        vr::REG_MASS => R::REG_MASS,
        vr::REG_SPRING_RATE => R::REG_SPRING_RATE,
        vr::REG_DAMPING => R::REG_DAMPING,
        vr::REG_OVERLAP => R::REG_OVERLAP,
        vr::REG_STROKE => R::REG_STROKE,
        vr::REG_PORT_WIDTH => R::REG_PORT_WIDTH,
        vr::LUBE_DIAMETER | vr::FEED_DIAMETER | vr::EXHAUST_DIAMETER => R::ORIFICE_DIAMETER,
        vr::CLUTCH_AREA => R::CLUTCH_AREA,
        vr::CLUTCH_STROKE => R::CLUTCH_STROKE,
        vr::CLUTCH_DEAD_VOLUME => R::CLUTCH_DEAD_VOLUME,
        vr::CLUTCH_MASS => R::CLUTCH_MASS,
        vr::CLUTCH_SPRING_PRELOAD => R::CLUTCH_SPRING_PRELOAD,
        vr::CLUTCH_SPRING_RATE => R::CLUTCH_SPRING_RATE,
        vr::CLUTCH_DAMPING => R::CLUTCH_DAMPING,
        vr::CLUTCH_PACK_STIFFNESS => R::CLUTCH_PACK_STIFFNESS,
        vr::DT_MAX => R::DT_MAX,
        _ => return None,
    })
}

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

    /// The flows the outputs report: the last step's means, or in
    /// Initialization mode the flows of the starting state at the inputs
    /// set so far, which `fmi2ExitInitializationMode` then reports (0 when
    /// the parameters do not yet make a circuit, as the state falls back
    /// to rest).
    fn mean_flows(&self) -> Flows {
        match &self.circuit {
            Some(_) => self.mean,
            None => Circuit::new(self.params.clone(), &self.oil, self.p_line_start)
                .map(|c| c.flows_now(self.inputs.clutch_cmd))
                .unwrap_or_default(),
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
    const GUID: &'static str = "{7c2f4d90-3e1a-4b6b-a8d5-0f9c61e2b375}";
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

    /// Every input and parameter within its range ([`crate::circuit::range`],
    /// the XML's min/max), refused naming the variable, the range and the
    /// reason; the combinations (`p_line_start >= p_sump`, `reg_overlap <
    /// reg_stroke`, a positive regulator preload, `T_oil` within the oil
    /// model's range) at `fmi2ExitInitializationMode`.
    fn set_real(&mut self, r: u32, value: f64) -> Result<(), ModelError> {
        let range = variable_range(r).ok_or(ModelError::UnknownValueReference(r))?;
        let name = Self::name(r);
        if !(value.is_finite() && value >= range.min && value <= range.max) {
            return Err(ModelError::invalid(name, value, range.rule()));
        }
        match r {
            vr::Q_PUMP => self.inputs.q_pump = value,
            vr::CLUTCH_CMD => self.inputs.clutch_cmd = value,
            vr::Q_PUMP_SLOPE => self.inputs.q_pump_slope = value,
            vr::G_PUMP => self.inputs.g_pump = value,
            _ => {
                *self
                    .param_mut(r)
                    .ok_or(ModelError::UnknownValueReference(r))? = value;
            }
        }
        Ok(())
    }

    fn get_real(&self, r: u32) -> Result<f64, ModelError> {
        let s = self.state();
        let stored = |c: &Circuit| c.volume_stored();
        let mean = match r {
            vr::Q_REG | vr::Q_LUBE | vr::Q_CLUTCH => self.mean_flows(),
            _ => Flows::default(),
        };
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
            vr::Q_REG => mean.reg,
            vr::Q_LUBE => mean.lube,
            vr::Q_CLUTCH => mean.feed - mean.exhaust,
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
            // and the setter reaches the same field (a value between the
            // start and the maximum)
            let (lo, hi) = v.real_range().unwrap();
            assert!(
                lo <= start && start < hi,
                "{}: {start} in [{lo}, {hi}]",
                v.name
            );
            let other = 0.5 * (start + hi);
            fresh.set_real(v.value_reference, other).unwrap();
            assert_eq!(fresh.get_real(v.value_reference).unwrap(), other);
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

    /// In Initialization mode every output reads what it reads right
    /// after `fmi2ExitInitializationMode` (an importer solving the initial
    /// coupling reads them there): the line pressure and the regulator's,
    /// lubrication's and clutch's flows of the starting state, with the
    /// clutch commanded and not.
    #[test]
    fn outputs_in_initialization_mode_are_those_of_the_exit() {
        let outputs = [
            vr::P_LINE,
            vr::P_CLUTCH,
            vr::X_CLUTCH,
            vr::X_REG,
            vr::Q_REG,
            vr::Q_LUBE,
            vr::Q_CLUTCH,
            vr::V_IN,
            vr::V_SUMP,
            vr::V_STORED,
            vr::RHO_OIL,
        ];
        for cmd in [0.0, 1.0] {
            let mut m = TransmissionCircuitFmu::new(Design::seed().oil);
            m.set_real(vr::CLUTCH_CMD, cmd).unwrap();
            m.set_real(vr::P_LINE_START, 12.0e5).unwrap();
            let before: Vec<f64> = outputs.iter().map(|&r| m.get_real(r).unwrap()).collect();
            m.exit_initialization().unwrap();
            let after: Vec<f64> = outputs.iter().map(|&r| m.get_real(r).unwrap()).collect();
            assert_eq!(before, after, "clutch command {cmd}");
            // the regulator and lubrication pass oil from a line at 12 bar
            assert!(after[5] > 0.0, "clutch command {cmd}: {after:?}");
        }
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
        assert!(n.set_real(vr::REG_DAMPING, 0.0).is_err());
        assert!(n.set_real(vr::CLUTCH_DAMPING, 0.0).is_ok());
        assert!(n.set_real(vr::REG_OVERLAP, 0.0).is_ok());
    }

    /// Every input and parameter has a range, the table's min/max are the
    /// setter's, and each is refused just outside it (and at 0, 1e30, NaN,
    /// infinity when outside), naming the variable and the range; a value
    /// at either end is accepted.
    #[test]
    fn every_input_and_parameter_has_its_range_and_it_is_refused_outside() {
        let oil = || Design::seed().oil;
        for v in VARIABLES
            .iter()
            .filter(|v| v.causality != Causality::Output)
        {
            let r = v.value_reference;
            let range = variable_range(r).unwrap_or_else(|| panic!("{} has no range", v.name));
            assert_eq!(v.real_range(), Some((range.min, range.max)), "{}", v.name);
            let crate::fmi2::VariableKind::Real { unit, .. } = v.kind else {
                panic!("{}", v.name)
            };
            assert_eq!(unit, Some(range.unit), "{}", v.name);
            let mut m = TransmissionCircuitFmu::new(oil());
            for ok in [range.min, range.max] {
                m.set_real(r, ok)
                    .unwrap_or_else(|e| panic!("{} = {ok}: {e}", v.name));
            }
            let below = if range.min == 0.0 {
                -1e-300
            } else {
                range.min - range.min.abs() * 1e-9
            };
            let above = range.max + range.max.abs().max(1e-300) * 1e-9;
            for bad in [below, above, 1e30, -1e30, f64::NAN, f64::INFINITY] {
                if (range.min..=range.max).contains(&bad) {
                    continue;
                }
                let e = m.set_real(r, bad).unwrap_err().to_string();
                assert!(
                    e.contains(v.name) && e.contains("outside its range"),
                    "{} = {bad}: {e}",
                    v.name
                );
            }
        }
    }

    /// The tester's cases: 1e30 for the size and stiffness parameters,
    /// 0 for the regulator damping and the clutch spring, Q_pump = 2 m3/s,
    /// p_line_start and reg_dp_set 1e30: refused at set time naming the
    /// variable; the combinations at initialisation; a too large inflow for
    /// the circuit at the step, naming Q_pump, the state kept.
    #[test]
    fn absurd_values_are_refused_naming_the_variable() {
        let oil = || Design::seed().oil;
        let mut m = TransmissionCircuitFmu::new(oil());
        let huge = [
            vr::FEED_DIAMETER,
            vr::EXHAUST_DIAMETER,
            vr::REG_DIAMETER,
            vr::LINE_VOLUME,
            vr::BULK_MODULUS,
            vr::REG_MASS,
            vr::REG_SPRING_RATE,
            vr::REG_DAMPING,
            vr::CLUTCH_AREA,
            vr::CLUTCH_STROKE,
            vr::CLUTCH_DEAD_VOLUME,
            vr::CLUTCH_MASS,
            vr::CLUTCH_SPRING_PRELOAD,
            vr::CLUTCH_SPRING_RATE,
            vr::CLUTCH_DAMPING,
            vr::CLUTCH_PACK_STIFFNESS,
            vr::P_LINE_START,
            vr::REG_DP_SET,
        ];
        for r in huge {
            let e = m.set_real(r, 1e30).unwrap_err().to_string();
            assert!(e.contains(TransmissionCircuitFmu::name(r)), "{e}");
        }
        for r in [
            vr::REG_DAMPING,
            vr::CLUTCH_SPRING_RATE,
            vr::CLUTCH_SPRING_PRELOAD,
        ] {
            let e = m.set_real(r, 0.0).unwrap_err().to_string();
            assert!(e.contains(TransmissionCircuitFmu::name(r)), "{e}");
        }
        let e = m.set_real(vr::Q_PUMP, 2.0).unwrap_err().to_string();
        assert!(
            e.contains("Q_pump") && e.contains("outside its range"),
            "{e}"
        );
        // combinations, at initialisation
        let mut m = TransmissionCircuitFmu::new(oil());
        m.set_real(vr::P_SUMP, 3e5).unwrap();
        m.set_real(vr::P_LINE_START, 2e5).unwrap();
        let e = m.exit_initialization().unwrap_err().to_string();
        assert!(e.contains("p_line_start") && e.contains("p_sump"), "{e}");
        let mut m = TransmissionCircuitFmu::new(oil());
        m.set_real(vr::REG_OVERLAP, 5e-3).unwrap();
        let e = m.exit_initialization().unwrap_err().to_string();
        assert!(e.contains("reg_overlap") && e.contains("reg_stroke"), "{e}");
        let mut m = TransmissionCircuitFmu::new(oil());
        m.set_real(vr::REG_DP_SET, 1e5).unwrap();
        m.set_real(vr::REG_DIAMETER, 2e-3).unwrap();
        let e = m.exit_initialization().unwrap_err().to_string();
        assert!(e.contains("reg_dp_set") && e.contains("preload"), "{e}");
        // the largest inflow into a circuit that cannot pass it: the step
        // is refused naming Q_pump before the line reaches 1000 bar
        let mut m = TransmissionCircuitFmu::new(oil());
        m.exit_initialization().unwrap();
        m.set_real(vr::Q_PUMP, R::Q_PUMP.max).unwrap();
        let before = m.get_real(vr::P_LINE).unwrap();
        let mut t = 0.0;
        let e = loop {
            match m.do_step(t, 1e-3) {
                Ok(()) => {
                    let p = m.get_real(vr::P_LINE).unwrap();
                    assert!(p <= crate::circuit::MAX_PRESSURE, "{p}");
                    t += 1e-3;
                    assert!(t < 1.0, "never refused, p_line {p}");
                }
                Err(e) => break e.to_string(),
            }
        };
        assert!(e.contains("Q_pump") && e.contains("relief"), "{e}");
        assert!(m.get_real(vr::P_LINE).unwrap() >= before);
        // and a correct call still works
        let mut m = TransmissionCircuitFmu::new(oil());
        m.set_real(vr::Q_PUMP, 3e-4).unwrap();
        m.set_real(vr::REG_DAMPING, 1.0).unwrap();
        m.exit_initialization().unwrap();
        m.do_step(0.0, 1e-3).unwrap();
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
