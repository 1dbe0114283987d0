//! The system of examples/transmission_cosim.py coupled from Rust with a
//! third-party importer, the `fmi` crate: GearPump.fmu feeds
//! TransmissionCircuit.fmu (pump first over each step with the line pressure
//! and the step's mean speed held, then the circuit with the pump's mean
//! flow of the same interval, its slope `Q_out_slope` and its pressure
//! sensitivity `dQ_out_dp_out`: the "shaped" coupling of the example).
//! Checks: the volume the circuit receives is the pump's delivered volume
//! plus the linearisation's (`V_lin`) to round-off at every step; the line pressure settles at the regulator's
//! balance for the pump's flow; the clutch fills in the time its feed
//! orifice allows; both FMUs' states saved in the middle of the run and
//! restored replay the rest bit for bit (what a master with step rejection
//! does). Expected values come from the circuit's parameters read from the
//! FMU and the formulas of `gearpump::circuit`.
//!
//! The FMUs are `$GEARPUMP_FMU` and `$TRANSMISSION_FMU` when set
//! (scripts/test-fmu.sh sets them to the ones `fmu-build` wrote), otherwise
//! they are packaged here from the `fmus/*` cdylibs built for this run.

mod fmi_common;

use std::path::PathBuf;

use fmi::fmi2::import::Fmi2Import;
use fmi::fmi2::instance::{CoSimulation, Common, Instance};
use fmi::traits::FmiStatus;
use fmi::CS;
use gearpump::circuit::CircuitParams;
use gearpump::fmi2::circuit::vr as cvr;
use gearpump::fmi2::pump::vr as pvr;
use gearpump::fmi2::FmuModel;
use gearpump::units::*;

use fmi_common::TempDir;

fn fmu(model: FmuModel, var: &str, dir: &TempDir) -> PathBuf {
    if let Some(p) = std::env::var_os(var) {
        return PathBuf::from(p);
    }
    let so = fmi_common::cdylib(model);
    let out = dir.path().join(format!("{}.fmu", model.model_identifier()));
    model.package(&out, &so).unwrap();
    out
}

fn ok<T, E: std::fmt::Debug>(r: Result<T, E>, what: &str) -> T {
    r.unwrap_or_else(|e| panic!("{what}: {e:?}"))
}

fn real(inst: &mut Instance<CS>, r: u32) -> f64 {
    let mut v = [f64::NAN];
    ok(Common::get_real(inst, &[r], &mut v), "get_real");
    v[0]
}

fn set(inst: &mut Instance<CS>, vrs: &[u32], values: &[f64]) {
    ok(Common::set_real(inst, vrs, values), "set_real");
}

const IDLE_RPM: f64 = 800.0;
const RUN_RPM: f64 = 2500.0;
const CLUTCH_ON: f64 = 0.02;

fn speed_rpm(t: f64) -> f64 {
    IDLE_RPM + (RUN_RPM - IDLE_RPM) * ((t - 0.2) / 0.1).clamp(0.0, 1.0)
}

/// The mean of [`speed_rpm`] over `[t, t + h]` (exact: the integral of the
/// clamped ramp), the speed held over a step.
fn speed_mean_rpm(t: f64, h: f64) -> f64 {
    let shape = |x: f64| {
        let (a, b) = (0.2, 0.3);
        if x <= a {
            0.0
        } else if x <= b {
            (x - a) * (x - a) / (2.0 * (b - a))
        } else {
            (b - a) / 2.0 + (x - b)
        }
    };
    IDLE_RPM + (RUN_RPM - IDLE_RPM) * (shape(t + h) - shape(t)) / h
}

/// One communication point of the coupled run.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Point {
    t: f64,
    p_line: f64,
    p_clutch: f64,
    x_clutch: f64,
    q_pump: f64,
    v_delivered: f64,
    v_in: f64,
    v_lin: f64,
    g_pump: f64,
}

/// The two instances and the coupling signal between steps.
struct System {
    pump: Instance<CS>,
    circuit: Instance<CS>,
    p_line: f64,
    t: f64,
}

impl System {
    fn new(pump: &Fmi2Import, circuit: &Fmi2Import) -> System {
        let mut c = ok(
            circuit.instantiate_cs("circuit", false, true),
            "instantiate circuit",
        );
        ok(Common::setup_experiment(&mut c, None, 0.0, None), "setup");
        ok(Common::enter_initialization_mode(&mut c), "enter");
        ok(Common::exit_initialization_mode(&mut c), "exit");
        let p_line = real(&mut c, cvr::P_LINE);
        let mut p = ok(pump.instantiate_cs("pump", false, true), "instantiate pump");
        ok(Common::setup_experiment(&mut p, None, 0.0, None), "setup");
        ok(Common::enter_initialization_mode(&mut p), "enter");
        // micromotion off: this test is about the coupling, and it keeps the run short
        ok(
            Common::set_boolean(&mut p, &[pvr::MICROMOTION], &[0]),
            "micromotion",
        );
        set(
            &mut p,
            &[pvr::SPEED, pvr::P_OUT, pvr::T_OIL],
            &[
                rpm_to_rad_s(speed_rpm(0.0)),
                p_line,
                celsius_to_kelvin(80.0),
            ],
        );
        ok(Common::exit_initialization_mode(&mut p), "exit");
        System {
            pump: p,
            circuit: c,
            p_line,
            t: 0.0,
        }
    }

    fn step(&mut self, h: f64) -> Point {
        let t = self.t;
        set(
            &mut self.pump,
            &[pvr::SPEED, pvr::P_OUT],
            &[rpm_to_rad_s(speed_mean_rpm(t, h)), self.p_line],
        );
        ok(
            CoSimulation::do_step(&self.pump, t, h, true),
            "pump do_step",
        );
        let q = real(&mut self.pump, pvr::Q_OUT);
        let slope = real(&mut self.pump, pvr::Q_OUT_SLOPE);
        let g = real(&mut self.pump, pvr::DQ_OUT_DP_OUT);
        let cmd = if t >= CLUTCH_ON { 1.0 } else { 0.0 };
        set(
            &mut self.circuit,
            &[cvr::Q_PUMP, cvr::CLUTCH_CMD, cvr::Q_PUMP_SLOPE, cvr::G_PUMP],
            &[q, cmd, slope, g],
        );
        ok(
            CoSimulation::do_step(&self.circuit, t, h, true),
            "circuit do_step",
        );
        self.t = t + h;
        self.p_line = real(&mut self.circuit, cvr::P_LINE);
        Point {
            t: self.t,
            p_line: self.p_line,
            p_clutch: real(&mut self.circuit, cvr::P_CLUTCH),
            x_clutch: real(&mut self.circuit, cvr::X_CLUTCH),
            q_pump: q,
            v_delivered: real(&mut self.pump, pvr::V_DELIVERED),
            v_in: real(&mut self.circuit, cvr::V_IN),
            v_lin: real(&mut self.circuit, cvr::V_LIN),
            g_pump: g,
        }
    }

    /// The circuit's parameters, read from the FMU.
    fn circuit_params(&mut self) -> CircuitParams {
        let c = &mut self.circuit;
        CircuitParams {
            p_sump: real(c, cvr::P_SUMP),
            t_oil: real(c, cvr::T_OIL),
            bulk_modulus: real(c, cvr::BULK_MODULUS),
            cd: real(c, cvr::CD),
            line_volume: real(c, cvr::LINE_VOLUME),
            reg_dp_set: real(c, cvr::REG_DP_SET),
            reg_diameter: real(c, cvr::REG_DIAMETER),
            reg_mass: real(c, cvr::REG_MASS),
            reg_spring_rate: real(c, cvr::REG_SPRING_RATE),
            reg_damping: real(c, cvr::REG_DAMPING),
            reg_overlap: real(c, cvr::REG_OVERLAP),
            reg_stroke: real(c, cvr::REG_STROKE),
            reg_port_width: real(c, cvr::REG_PORT_WIDTH),
            lube_diameter: real(c, cvr::LUBE_DIAMETER),
            clutch_area: real(c, cvr::CLUTCH_AREA),
            clutch_stroke: real(c, cvr::CLUTCH_STROKE),
            clutch_dead_volume: real(c, cvr::CLUTCH_DEAD_VOLUME),
            clutch_mass: real(c, cvr::CLUTCH_MASS),
            clutch_spring_preload: real(c, cvr::CLUTCH_SPRING_PRELOAD),
            clutch_spring_rate: real(c, cvr::CLUTCH_SPRING_RATE),
            clutch_damping: real(c, cvr::CLUTCH_DAMPING),
            clutch_pack_stiffness: real(c, cvr::CLUTCH_PACK_STIFFNESS),
            feed_diameter: real(c, cvr::FEED_DIAMETER),
            exhaust_diameter: real(c, cvr::EXHAUST_DIAMETER),
            dt_max: real(c, cvr::DT_MAX),
        }
    }
}

fn mean(xs: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = xs.fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    s / n as f64
}

#[test]
fn pump_and_circuit_coupled_through_the_fmi_crate() {
    let dir = TempDir::new("transmission");
    let pump: Fmi2Import = ok(
        fmi::import::from_path(fmu(FmuModel::GearPump, "GEARPUMP_FMU", &dir)),
        "import pump",
    );
    let circuit: Fmi2Import = ok(
        fmi::import::from_path(fmu(FmuModel::TransmissionCircuit, "TRANSMISSION_FMU", &dir)),
        "import circuit",
    );
    let mut sys = System::new(&pump, &circuit);
    let p = sys.circuit_params();
    let rho = real(&mut sys.circuit, cvr::RHO_OIL);
    let h = 1e-3;
    let n = 500;
    let mut run = Vec::with_capacity(n);
    let mut saved = None;
    for k in 0..n {
        if k == 150 {
            // mid-fill: save both units, as a master that may reject a step does
            let s = (
                ok(sys.pump.get_fmu_state(), "pump state"),
                ok(sys.circuit.get_fmu_state(), "circuit state"),
                sys.p_line,
                sys.t,
            );
            saved = Some(s);
        }
        run.push(sys.step(h));
    }

    // volume: what the circuit received is what the pump delivered plus
    // what the pump's linearisation added (small: the sensitivity times the
    // pressure's excursion within a step)
    let eps_bound = n as f64 * f64::EPSILON * run[n - 1].v_delivered;
    for pt in &run {
        assert!(
            pt.g_pump < 0.0 && pt.v_lin.abs() < 1e-3 * run[n - 1].v_in,
            "{pt:?}"
        );
        assert!(
            (pt.v_in - pt.v_lin - pt.v_delivered).abs() <= eps_bound,
            "t = {}: V_in {} vs V_delivered {}",
            pt.t,
            pt.v_in,
            pt.v_delivered
        );
    }
    let v_sump = real(&mut sys.circuit, cvr::V_SUMP);
    let v_stored = real(&mut sys.circuit, cvr::V_STORED);
    let v_in = run[n - 1].v_in;
    assert!((v_in - v_sump - v_stored).abs() < 1e-9 * v_in);

    // set point: the last 100 ms at 2500 rpm with the clutch full
    let late: Vec<&Point> = run.iter().filter(|pt| pt.t > 0.4).collect();
    assert!(late.iter().all(|pt| pt.x_clutch >= p.clutch_stroke));
    let q = mean(late.iter().map(|pt| pt.q_pump));
    let dp = mean(late.iter().map(|pt| pt.p_line)) - p.p_sump;
    let expect = p
        .steady_line_dp(rho, q)
        .expect("pump flow within the regulating range");
    let tol = 0.01 * (expect - p.reg_dp_set);
    println!(
        "line {:.4} bar vs balance {:.4} bar at {:.2} l/min (tolerance {tol:.0} Pa)",
        pa_to_bar(dp),
        pa_to_bar(expect),
        m3_s_to_lpm(q)
    );
    assert!(dp > p.reg_dp_set && dp < p.reg_dp_set + p.reg_droop_full_open());
    assert!((dp - expect).abs() < tol, "{dp} vs {expect}");

    // clutch fill against the feed orifice's estimate
    let fill = run
        .iter()
        .find(|pt| pt.x_clutch >= p.clutch_stroke)
        .map(|pt| pt.t - CLUTCH_ON)
        .expect("the clutch fills");
    let during = run
        .iter()
        .filter(|pt| pt.t > CLUTCH_ON + 0.01 && pt.t < CLUTCH_ON + 0.8 * fill);
    let dp_line = mean(during.map(|pt| pt.p_line)) - p.p_sump;
    let dp_feed = dp_line - p.clutch_spring_dp(0.5 * p.clutch_stroke);
    let area = std::f64::consts::PI * p.feed_diameter * p.feed_diameter / 4.0;
    let estimate = p.clutch_fill_volume() / (p.cd * area * (2.0 * dp_feed / rho).sqrt());
    println!(
        "fill {:.1} ms vs orifice estimate {:.1} ms",
        fill * 1e3,
        estimate * 1e3
    );
    assert!((fill / estimate - 1.0).abs() < 0.1);
    assert!((0.1..0.5).contains(&fill));

    // replay from the saved states: bit for bit the same
    let (ps, cs, p_line, t) = saved.unwrap();
    ok(sys.pump.set_fmu_state(&ps).ok(), "restore pump");
    ok(sys.circuit.set_fmu_state(&cs).ok(), "restore circuit");
    (sys.p_line, sys.t) = (p_line, t);
    for (k, expected) in run.iter().enumerate().skip(150).take(100) {
        assert_eq!(&sys.step(h), expected, "replayed step {k}");
    }
    ok(Common::terminate(&mut sys.pump), "terminate");
    ok(Common::terminate(&mut sys.circuit), "terminate");
}
