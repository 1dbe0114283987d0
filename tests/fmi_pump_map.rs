//! GearPump.fmu's `map` fidelity (issue 16 point 3) through the model's
//! safe API: the map shipped in resources/ is read at instantiation; its
//! mean flow and torque against LP runs off the grid's nodes (target 0.3
//! %), in the map itself and stepped through the FMU against the LP
//! fidelity; the outlet volume's compressibility against a hand
//! calculation; the ripple's phase against the LP fidelity's step flows;
//! the fidelity parameter's range; state save/restore; a map computed at
//! initialisation when the clearances differ.

mod fmu_outputs;
use fmu_outputs::outputs;
use std::path::PathBuf;
use std::sync::Arc;

use gearpump::fmi2::pump::{vr, GearPumpFmu, FIDELITY_MAP, MAP_FILE};
use gearpump::fmi2::{CoSimModel, ModelError};
use gearpump::model::map::{MapGrid, PumpMap};
use gearpump::model::{Options, Pump};
use gearpump::units::*;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("gearpump-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The bundled FMU's resources/ (with its map), instantiated; the log.
fn instance(name: &str) -> (GearPumpFmu, String, PathBuf) {
    let res = temp_dir(name).join("resources");
    std::fs::create_dir_all(&res).unwrap();
    // packaged once (the map takes seconds to build), written per test
    static FILES: std::sync::OnceLock<Vec<(String, Vec<u8>)>> = std::sync::OnceLock::new();
    for (file, bytes) in FILES.get_or_init(GearPumpFmu::resource_files) {
        std::fs::write(res.join(file), bytes).unwrap();
    }
    let log = std::cell::RefCell::new(String::new());
    let m = GearPumpFmu::instantiate(&res, &|s: &str| log.borrow_mut().push_str(s)).unwrap();
    (m, log.into_inner(), res)
}

fn set_point(m: &mut GearPumpFmu, rpm: f64, bar: f64, degc: f64) {
    m.set_real(vr::SPEED, rpm_to_rad_s(rpm)).unwrap();
    m.set_real(vr::P_IN, ATMOSPHERE_PA).unwrap();
    m.set_real(vr::P_OUT, ATMOSPHERE_PA + bar_to_pa(bar))
        .unwrap();
    m.set_real(vr::T_OIL, celsius_to_kelvin(degc)).unwrap();
}

fn get(m: &GearPumpFmu, r: u32) -> f64 {
    m.get_real(r).unwrap()
}

/// The shipped map against LP periodic solutions at 40 points spread over
/// the grid's range and off its nodes: mean delivered flow and torque
/// within 0.3 % (the target); and the map FMU stepped at 1 ms at
/// points off the nodes gives the LP fidelity's mean flow and torque over
/// whole mesh periods within 0.3 %.
#[test]
fn the_map_is_within_0_3_percent_of_the_lp_model_off_its_nodes() {
    let (m, log, res) = instance("map-error");
    assert!(log.contains("pump map read from"), "{log}");
    let pump = Arc::new(Pump::new(gearpump::design::load(None, &[]).unwrap()));
    let sample = gearpump::fmi2::pump::start_clearances(&pump.design);
    let options = Options { micromotion: true };
    let grid = MapGrid::standard();
    let bytes = std::fs::read(res.join(MAP_FILE)).unwrap();
    let map = PumpMap::from_bytes(&bytes, PumpMap::key_for(&pump, &sample, options, &grid))
        .expect("the shipped map is the nominal sample's");
    drop(m);
    let (mut worst_q, mut worst_t) = (0.0f64, 0.0f64);
    for (w, dp, t) in grid.check_points(40) {
        // off every node on every axis
        for (axis, x) in [(&grid.speed, w), (&grid.dp, dp), (&grid.temp, t)] {
            assert!(axis
                .iter()
                .all(|&a| (a - x).abs() > 1e-6 * a.abs().max(1.0)));
        }
        let lp = PumpMap::lp_point(&pump, sample, options, w, dp, t, grid.p_in).unwrap();
        let v = map.eval(w, dp, t);
        assert!(!v.outside && !v.flagged);
        worst_q = worst_q.max(((v.q_out - lp.q_out) / lp.q_out).abs());
        worst_t = worst_t.max(((v.torque - lp.torque) / lp.torque).abs());
    }
    // a map of another sample, or bytes that are not a map, are refused
    let mut other = sample;
    other.lateral *= 1.5;
    let e = PumpMap::from_bytes(&bytes, PumpMap::key_for(&pump, &other, options, &grid))
        .unwrap_err()
        .to_string();
    assert!(e.contains("another pump, sample or grid"), "{e}");
    std::fs::write(res.join(MAP_FILE), b"not a map").unwrap();
    let log = std::cell::RefCell::new(String::new());
    GearPumpFmu::instantiate(&res, &|s: &str| log.borrow_mut().push_str(s)).unwrap();
    let log = log.into_inner();
    assert!(
        log.contains("refused") && log.contains("computes it at initialisation"),
        "{log}"
    );
    assert!(worst_q < 3e-3, "mean flow off by {:.3} %", 100.0 * worst_q);
    assert!(worst_t < 3e-3, "torque off by {:.3} %", 100.0 * worst_t);

    // through the FMU: map fidelity against the LP fidelity
    for (rpm, bar, degc) in [(1350.0, 47.0, 43.0), (2900.0, 130.0, 67.0)] {
        let mut results = Vec::new();
        for fidelity in [1, FIDELITY_MAP] {
            let (mut f, _, _) = instance(&format!("map-fmu-{fidelity}"));
            f.set_integer(vr::FIDELITY, fidelity).unwrap();
            set_point(&mut f, rpm, bar, degc);
            f.exit_initialization().unwrap();
            // whole mesh periods of ~1 ms steps
            let omega = rpm_to_rad_s(rpm);
            let period = 2.0 * std::f64::consts::PI / pump.tables.z[0] as f64 / omega;
            let n = (10.0 * period / 1e-3).round();
            let h = 10.0 * period / n;
            let (mut t, mut torque_time) = (0.0, 0.0);
            for _ in 0..n as usize {
                f.do_step(t, h).unwrap();
                torque_time += get(&f, vr::TORQUE) * h;
                t += h;
            }
            results.push((get(&f, vr::V_DELIVERED) / t, torque_time / t));
        }
        let (lp, mp) = (results[0], results[1]);
        assert!(
            ((mp.0 - lp.0) / lp.0).abs() < 3e-3,
            "{rpm} rpm: Q {mp:?} LP {lp:?}"
        );
        assert!(
            ((mp.1 - lp.1) / lp.1).abs() < 3e-3,
            "{rpm} rpm: T {mp:?} LP {lp:?}"
        );
    }
}

/// A pressure ramp on the outlet: the delivered flow is the map's less the
/// oil stored in the outlet volume by compression, V (1 - exp(-dp/B)) / h
/// for the liquid oil (no air), computed here from the design's outlet
/// volume and bulk modulus by the library's `exp_m1`; the inlet likewise
/// with the opposite sign. The delivered volume stays the sum of Q_out h.
/// A rise of 20 bar over a step and one of 0.2 bar (the model's series for
/// small steps).
#[test]
fn the_outlet_volume_stores_oil_as_its_pressure_rises() {
    for (n, rise) in [20.0, 0.2].into_iter().enumerate() {
        let (mut m, _, _) = instance(&format!("map-compress-{n}"));
        let d = m.pump().design.clone();
        assert_eq!(d.oil.air_fraction, 0.0);
        m.set_integer(vr::FIDELITY, FIDELITY_MAP).unwrap();
        set_point(&mut m, 2000.0, 50.0, 60.0);
        m.exit_initialization().unwrap();
        let q0 = get(&m, vr::Q_OUT);
        let h = 1e-3;
        m.do_step(0.0, h).unwrap();
        assert_eq!(get(&m, vr::Q_OUT), q0);
        let (mut volume, mut t) = (get(&m, vr::V_DELIVERED), h);
        // the rise over one step, then held
        set_point(&mut m, 2000.0, 50.0 + rise, 60.0);
        let (mut steady, _, _) = instance(&format!("map-compress-steady-{n}"));
        steady.restore_state(&m.save_state()).unwrap();
        m.do_step(t, h).unwrap();
        volume += get(&m, vr::Q_OUT) * h;
        t += h;
        // the map's flow at the new pressure: the same step with the
        // pressure already there
        steady.do_step(t - h, h).unwrap();
        steady.do_step(t, h).unwrap();
        let q1 = get(&steady, vr::Q_OUT);
        let stored = -d.casing.outlet_volume * (-bar_to_pa(rise) / d.oil.bulk_modulus).exp_m1();
        let expected = q1 - stored / h;
        assert!(
            (get(&m, vr::Q_OUT) - expected).abs() < 1e-12 * q1,
            "+{rise} bar: {} against {expected}",
            get(&m, vr::Q_OUT)
        );
        assert!(
            stored / h > 1e-4 * rise * q1,
            "+{rise} bar: the stored oil counts"
        );
        m.do_step(t, h).unwrap();
        volume += get(&m, vr::Q_OUT) * h;
        assert_eq!(get(&m, vr::Q_OUT), q1);
        assert!((get(&m, vr::V_DELIVERED) - volume).abs() < 1e-12 * volume);
    }
}

/// With `map_ripple` the delivered flow ripples with the mesh harmonics
/// taken from the LP solution: stepped one angular step at a time over a
/// mesh period it follows the LP fidelity's step flows (the residual is
/// less than half the LP ripple: a wrong phase would double it), and its
/// mean over a whole period is the map's mean.
#[test]
fn the_ripple_follows_the_lp_step_flows() {
    let (rpm, bar, degc) = (1500.0, 40.0, 50.0);
    let mut series = Vec::new();
    let mut steps = 0;
    for (fidelity, ripple) in [(1, false), (FIDELITY_MAP, true)] {
        let (mut m, _, _) = instance(&format!("map-ripple-{fidelity}"));
        m.set_integer(vr::FIDELITY, fidelity).unwrap();
        m.set_boolean(vr::MAP_RIPPLE, ripple).unwrap();
        set_point(&mut m, rpm, bar, degc);
        m.exit_initialization().unwrap();
        steps = m.pump().steps_per_period();
        let h = m.pump().tables.dtheta / rpm_to_rad_s(rpm);
        let mut q = Vec::new();
        let mut t = 0.0;
        for _ in 0..steps {
            m.do_step(t, h).unwrap();
            t += h;
            q.push(get(&m, vr::Q_OUT));
        }
        series.push(q);
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (lp, mp) = (&series[0], &series[1]);
    let (ml, mm) = (mean(lp), mean(mp));
    let rms = |f: &dyn Fn(usize) -> f64| {
        ((0..steps).map(|i| f(i).powi(2)).sum::<f64>() / steps as f64).sqrt()
    };
    let ripple_lp = rms(&|i| lp[i] - ml);
    let residual = rms(&|i| (lp[i] - ml) - (mp[i] - mm));
    assert!(ripple_lp > 0.01 * ml, "LP ripple {ripple_lp}");
    assert!(residual < 0.5 * ripple_lp, "{residual} against {ripple_lp}");
    assert!(((mm - ml) / ml).abs() < 3e-3, "{mm} {ml}");
}

/// The ripple's mesh angle is carried from step to step by rotation (and
/// taken afresh every `MESH_EXACT_EVERY` steps): after 50,001 steps of
/// 1 ms at held inputs, the instantaneous flow is the one an instance that
/// covered the same angle in one step (its mesh angle taken from the angle
/// itself; 50 s at 1537 rpm is 0.92e6 angular steps, within the step
/// limit both fidelities have) gives, within 1e-6 of the ripple's amplitude (the rotation
/// taken the wrong way is off by 1.7 times it).
#[test]
fn the_carried_mesh_angle_is_the_angles_own() {
    // a speed whose mesh angle per step is no simple fraction of a turn
    let (rpm, bar, degc) = (1537.0, 40.0, 50.0);
    let start = |name: &str| {
        let (mut m, _, _) = instance(name);
        m.set_integer(vr::FIDELITY, FIDELITY_MAP).unwrap();
        m.set_boolean(vr::MAP_RIPPLE, true).unwrap();
        set_point(&mut m, rpm, bar, degc);
        m.exit_initialization().unwrap();
        m
    };
    let (mut stepped, mut once) = (start("map-carried"), start("map-once"));
    let (n, h) = (50_001, 1e-3);
    let (mut t, mut lo, mut hi) = (0.0, f64::INFINITY, f64::NEG_INFINITY);
    for _ in 0..n {
        stepped.do_step(t, h).unwrap();
        t += h;
        let q = get(&stepped, vr::Q_OUT_INST);
        (lo, hi) = (lo.min(q), hi.max(q));
    }
    // the one step ends at the stepped instance's angle (the sum of the
    // steps' angles has its own rounding)
    let theta = get(&stepped, vr::THETA);
    once.do_step(0.0, theta / rpm_to_rad_s(rpm)).unwrap();
    assert!(((get(&once, vr::THETA) - theta) / theta).abs() < 1e-15);
    let amplitude = 0.5 * (hi - lo);
    assert!(
        amplitude > 1e-3 * get(&stepped, vr::Q_OUT),
        "ripple {amplitude}"
    );
    let (a, b) = (get(&stepped, vr::Q_OUT_INST), get(&once, vr::Q_OUT_INST));
    assert!(
        (a - b).abs() < 1e-6 * amplitude,
        "{a} against {b} (ripple {amplitude})"
    );
}

/// `Q_out_slope` with the map's ripple, against the flow it describes:
/// at steps of a fiftieth of the mesh period, the slope each step reports
/// is the derivative of the rippling flow there, which the step means
/// `Q_out` also give by their central differences (the two readings come
/// from different outputs: the slope from the step's mean and its end
/// value, the differences from consecutive means). They agree within 2 %
/// of the ripple's largest slope over a mesh period, the line through the
/// step's mean ending at the instantaneous flow gives back `Q_out_inst`,
/// and without the ripple the slope is 0 (the mean is held).
#[test]
fn the_flow_slope_with_the_ripple_is_the_ripples_derivative() {
    let (rpm, bar, degc) = (1500.0, 40.0, 50.0);
    let (mut m, _, _) = instance("map-slope");
    m.set_integer(vr::FIDELITY, FIDELITY_MAP).unwrap();
    m.set_boolean(vr::MAP_RIPPLE, true).unwrap();
    set_point(&mut m, rpm, bar, degc);
    m.exit_initialization().unwrap();
    let period = 2.0 * std::f64::consts::PI / m.pump().tables.z[0] as f64 / rpm_to_rad_s(rpm);
    let n = 50;
    let h = period / n as f64;
    let (mut q, mut slope) = (Vec::new(), Vec::new());
    let mut t = 0.0;
    for _ in 0..(n + 3) {
        m.do_step(t, h).unwrap();
        t += h;
        let (qm, s, qi) = (
            get(&m, vr::Q_OUT),
            get(&m, vr::Q_OUT_SLOPE),
            get(&m, vr::Q_OUT_INST),
        );
        assert!(
            ((qm + s * h / 2.0) - qi).abs() <= 1e-9 * qi.abs(),
            "{qm} {s} {qi}"
        );
        q.push(qm);
        slope.push(s);
    }
    // the central difference of the means at step k is the derivative at
    // the step's middle (to h^2); the line through a step's mean ending at
    // its end value has the derivative a third of a step before the end
    // (`q1 - q2 h / 3` for q = q0 + q1 s + q2 s^2 / 2, s from the end),
    // a sixth of a step after the middle: interpolated there
    let d = |k: usize| (q[k + 1] - q[k - 1]) / (2.0 * h);
    let largest = slope.iter().fold(0.0f64, |a, &s| a.max(s.abs()));
    let worst = (1..n)
        .map(|k| (d(k) + (d(k + 1) - d(k)) / 6.0 - slope[k]).abs())
        .fold(0.0f64, f64::max);
    println!("largest slope {largest:.4e} m3/s2, worst difference {worst:.3e}");
    assert!(largest > 0.0);
    assert!(worst < 0.02 * largest, "{worst} against {largest}");
    // without the ripple the mean is held
    let (mut plain, _, _) = instance("map-slope-plain");
    plain.set_integer(vr::FIDELITY, FIDELITY_MAP).unwrap();
    plain.set_boolean(vr::MAP_RIPPLE, false).unwrap();
    set_point(&mut plain, rpm, bar, degc);
    plain.exit_initialization().unwrap();
    plain.do_step(0.0, h).unwrap();
    assert_eq!(get(&plain, vr::Q_OUT_SLOPE), 0.0);
}

/// `fidelity` takes 1 and 2 only, refused otherwise naming the variable
/// and its range; the state (with the map fidelity's angle, volume and
/// pressures) saves and restores to the same bits, also in another
/// instance; a state whose map stepping was changed (a mesh angle's
/// (sin, cos) off the unit circle, a count of rotations out of range) is
/// refused with fmi2Error's reason naming it.
#[test]
fn fidelity_is_checked_and_the_map_state_restores() {
    let (mut m, _, _) = instance("map-state");
    for bad in [0, 3, -1, i32::MAX] {
        match m.set_integer(vr::FIDELITY, bad) {
            Err(ModelError::InvalidValue { name, reason, .. }) => {
                assert_eq!(name, "fidelity");
                assert!(reason.contains("[1, 2]"), "{reason}");
            }
            other => panic!("fidelity = {bad} accepted: {other:?}"),
        }
    }
    assert_eq!(m.get_integer(vr::FIDELITY).unwrap(), 1);
    m.set_integer(vr::FIDELITY, FIDELITY_MAP).unwrap();
    m.set_boolean(vr::MAP_RIPPLE, true).unwrap();
    set_point(&mut m, 2500.0, 80.0, 55.0);
    m.exit_initialization().unwrap();
    let mut t = 0.0;
    for k in 0..7 {
        set_point(&mut m, 2500.0 + 10.0 * k as f64, 80.0 + k as f64, 55.0);
        m.do_step(t, 1e-3).unwrap();
        t += 1e-3;
    }
    let saved = m.save_state();
    let run = |m: &mut GearPumpFmu| {
        let mut out = Vec::new();
        let mut t = t;
        for k in 0..5 {
            set_point(m, 2600.0, 90.0 - k as f64, 56.0);
            m.do_step(t, 7e-4).unwrap();
            t += 7e-4;
            out.extend([vr::Q_OUT, vr::TORQUE, vr::V_DELIVERED, vr::THETA].map(|r| get(m, r)));
        }
        out
    };
    let first = run(&mut m);
    m.restore_state(&saved).unwrap();
    assert_eq!(run(&mut m), first);
    // a state whose map stepping was changed (checksum made good again)
    // is refused, naming what is wrong: the last eight numbers before the
    // checksum are the angle, volume, two pressures, whether the mesh
    // angle is known, its sin and cos, and the rotations since it was
    // taken afresh
    m.restore_state(&saved).unwrap();
    let body = &saved[..saved.len() - 8];
    let at = |k: usize| body.len() - 8 * (8 - k);
    assert_eq!(
        f64::from_le_bytes(body[at(0)..at(0) + 8].try_into().unwrap()),
        get(&m, vr::THETA),
        "the layout this test assumes"
    );
    for (k, value, says) in [
        (4, 0.5, "0 or 1"),
        (5, 2.0, "unit vector"),
        (7, 1000.0, "rotations"),
        (7, 2.5, "rotations"),
    ] {
        let mut b = body.to_vec();
        b[at(k)..at(k) + 8].copy_from_slice(&f64::to_le_bytes(value));
        let sum = gearpump::fmi2::model::state_checksum(&b);
        b.extend_from_slice(&sum.to_le_bytes());
        match m.restore_state(&b) {
            Err(ModelError::InvalidState(why)) => assert!(why.contains(says), "{why}"),
            other => panic!("value {value} at {k} accepted: {other:?}"),
        }
    }
    let (mut other, _, _) = instance("map-state-2");
    other.restore_state(&saved).unwrap();
    assert_eq!(other.get_integer(vr::FIDELITY).unwrap(), FIDELITY_MAP);
    assert_eq!(run(&mut other), first);
}

/// Clearances other than the shipped map's: the map is computed at
/// initialisation (a warning says so and how long it took) and its flow
/// is the LP model's for that sample.
#[test]
fn other_clearances_compute_their_map_at_initialisation() {
    let (mut m, _, _) = instance("map-built");
    m.set_integer(vr::FIDELITY, FIDELITY_MAP).unwrap();
    m.set_real(vr::LATERAL, 20e-6).unwrap();
    set_point(&mut m, 1800.0, 60.0, 45.0);
    m.exit_initialization().unwrap();
    let warnings = m.take_warnings().join("\n");
    assert!(warnings.contains("computed now"), "{warnings}");
    let pump = Arc::new(Pump::new(gearpump::design::load(None, &[]).unwrap()));
    let mut sample = gearpump::fmi2::pump::start_clearances(&pump.design);
    sample.lateral = 20e-6;
    let lp = PumpMap::lp_point(
        &pump,
        sample,
        Options { micromotion: true },
        rpm_to_rad_s(1800.0),
        bar_to_pa(60.0),
        celsius_to_kelvin(45.0),
        ATMOSPHERE_PA,
    )
    .unwrap();
    let q = get(&m, vr::Q_OUT);
    assert!(
        ((q - lp.q_out) / lp.q_out).abs() < 3e-3,
        "{q} against {}",
        lp.q_out
    );
}

/// The map fidelity's `dQ_out_dp_out`: the slope of the flow the map FMU
/// itself delivers once the pressure is held at p_out -+ 0.5 bar (stepped,
/// the outlet volume's transient over), and within 5 % of the LP
/// fidelity's, which differences two periodic LP runs (another mechanism:
/// the map only interpolates such runs at its nodes). Negative: the
/// leakage grows with the pressure rise.
#[test]
fn the_map_fidelity_gives_its_own_pressure_sensitivity() {
    let (rpm, bar, degc) = (2000.0, 50.0, 60.0);
    let held = |b: f64| {
        let (mut m, _, _) = instance("map-dqdp");
        m.set_integer(vr::FIDELITY, FIDELITY_MAP).unwrap();
        set_point(&mut m, rpm, bar, degc);
        m.exit_initialization().unwrap();
        set_point(&mut m, rpm, b, degc);
        m.do_step(0.0, 1e-3).unwrap();
        m.do_step(1e-3, 1e-3).unwrap();
        get(&m, vr::Q_OUT)
    };
    let stepped = (held(bar + 0.5) - held(bar - 0.5)) / bar_to_pa(1.0);
    let (mut m, _, _) = instance("map-dqdp-map");
    m.set_integer(vr::FIDELITY, FIDELITY_MAP).unwrap();
    set_point(&mut m, rpm, bar, degc);
    m.exit_initialization().unwrap();
    let map = get(&m, vr::DQ_OUT_DP_OUT);
    let (mut lp, _, _) = instance("map-dqdp-lp");
    set_point(&mut lp, rpm, bar, degc);
    lp.exit_initialization().unwrap();
    let lp = get(&lp, vr::DQ_OUT_DP_OUT);
    println!("dQ/dp map {map:e}, stepped map {stepped:e}, LP {lp:e} m3/(s Pa)");
    assert!(map < 0.0 && lp < 0.0);
    assert!((map / stepped - 1.0).abs() < 1e-6, "{map} {stepped}");
    assert!((map / lp - 1.0).abs() < 0.05, "{map} {lp}");
}

/// The map fidelity has the LP fidelity's communication-step limit (a step
/// covering more than 1e6 angular steps is refused, the state kept; the
/// tester's `doStep(0, 1e15)` gave V_delivered 2.3e11 m3 at fmi2OK), and
/// its directional derivative is refused until the model has run.
#[test]
fn the_map_fidelity_refuses_huge_steps_as_the_lp_fidelity_does() {
    use gearpump::fmi2::pump::FIDELITY_LP;
    for fidelity in [FIDELITY_MAP, FIDELITY_LP] {
        let (mut m, _, _) = instance(&format!("map-huge-step-{fidelity}"));
        m.set_integer(vr::FIDELITY, fidelity).unwrap();
        let e = m.partial_derivative(vr::Q_OUT, vr::P_OUT).unwrap_err();
        assert!(
            e.to_string().contains("before fmi2ExitInitializationMode")
                && e.to_string().contains("p_out"),
            "{e}"
        );
        m.exit_initialization().unwrap();
        let (v, th) = (get(&m, vr::V_DELIVERED), get(&m, vr::THETA));
        for h in [1e15, 1e4] {
            let e = m.do_step(0.0, h).unwrap_err().to_string();
            assert!(
                e.contains("angular steps") && e.contains("limit 1e6"),
                "fidelity {fidelity}, h {h}: {e}"
            );
            assert_eq!((get(&m, vr::V_DELIVERED), get(&m, vr::THETA)), (v, th));
        }
        // a correct step still works, and so does the derivative
        m.do_step(0.0, 1e-3).unwrap();
        assert!(get(&m, vr::V_DELIVERED) > v);
        assert!(m.partial_derivative(vr::Q_OUT, vr::P_OUT).unwrap() < 0.0);
        // at standstill no angle is covered: a long step is fine
        m.set_real(vr::SPEED, 0.0).unwrap();
        m.do_step(1e-3, 1e4).unwrap();
    }
}

/// The map fidelity's outputs in Initialization mode
/// (`CoSimModel::initial_outputs`, which the glue calls before an output
/// read there; they read 0 before it): the map at the inputs set so far,
/// the same to the bit as after `exit_initialization`, which keeps them
/// (the same saved state as a plain exit); a higher delivery pressure set
/// after a read gives less flow and more torque at the next read; the
/// fidelity set to map after a read of the LP fidelity's outputs gives
/// the map's.
#[test]
fn the_map_fidelitys_outputs_in_initialization_mode_are_its_start() {
    let (rpm, bar, degc) = (1700.0, 70.0, 50.0);
    for ripple in [false, true] {
        let (mut fresh, _, _) = instance("map-init-fresh");
        fresh.set_integer(vr::FIDELITY, FIDELITY_MAP).unwrap();
        fresh.set_boolean(vr::MAP_RIPPLE, ripple).unwrap();
        set_point(&mut fresh, rpm, bar, degc);
        fresh.exit_initialization().unwrap();

        let (mut m, _, _) = instance("map-init");
        m.set_integer(vr::FIDELITY, FIDELITY_MAP).unwrap();
        m.set_boolean(vr::MAP_RIPPLE, ripple).unwrap();
        set_point(&mut m, rpm, bar, degc);
        assert_eq!(get(&m, vr::Q_OUT), 0.0, "nothing computed yet");
        m.initial_outputs().unwrap();
        let (q, torque) = (get(&m, vr::Q_OUT), get(&m, vr::TORQUE));
        assert!(q > 0.0 && torque > 0.0, "{q} {torque}");
        assert_eq!(outputs(&m), outputs(&fresh), "ripple {ripple}");

        // a higher delivery pressure: less flow, more torque
        m.set_real(vr::P_OUT, ATMOSPHERE_PA + bar_to_pa(bar + 20.0))
            .unwrap();
        m.initial_outputs().unwrap();
        let (q_hi, torque_hi) = (get(&m, vr::Q_OUT), get(&m, vr::TORQUE));
        assert!(
            q_hi < q && torque_hi > torque,
            "{q_hi} {q} / {torque_hi} {torque}"
        );
        // back: the first values, kept by the exit
        m.set_real(vr::P_OUT, ATMOSPHERE_PA + bar_to_pa(bar))
            .unwrap();
        m.initial_outputs().unwrap();
        assert_eq!(outputs(&m), outputs(&fresh), "ripple {ripple}");
        m.exit_initialization().unwrap();
        assert_eq!(m.save_state(), fresh.save_state(), "ripple {ripple}");
        m.do_step(0.0, 1e-3).unwrap();
        fresh.do_step(0.0, 1e-3).unwrap();
        assert_eq!(outputs(&m), outputs(&fresh), "ripple {ripple}");

        // the LP fidelity's outputs read, then the fidelity set to map
        let (mut m, _, _) = instance("map-init-switch");
        m.set_boolean(vr::MAP_RIPPLE, ripple).unwrap();
        set_point(&mut m, rpm, bar, degc);
        m.initial_outputs().unwrap();
        let lp = get(&m, vr::Q_OUT);
        m.set_integer(vr::FIDELITY, FIDELITY_MAP).unwrap();
        m.initial_outputs().unwrap();
        assert_eq!(get(&m, vr::Q_OUT).to_bits(), q.to_bits());
        assert_ne!(lp.to_bits(), q.to_bits());
        m.exit_initialization().unwrap();
        // (`fresh` has stepped: against a plain exit again)
        let (mut plain, _, _) = instance("map-init-plain");
        plain.set_integer(vr::FIDELITY, FIDELITY_MAP).unwrap();
        plain.set_boolean(vr::MAP_RIPPLE, ripple).unwrap();
        set_point(&mut plain, rpm, bar, degc);
        plain.exit_initialization().unwrap();
        assert_eq!(outputs(&m), outputs(&plain), "ripple {ripple}");
        assert_eq!(m.save_state(), plain.save_state(), "ripple {ripple}");
    }
}
