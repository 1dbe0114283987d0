//! GearPump.fmu imported by a third-party Rust importer, the `fmi` crate
//! (loads the zipped FMU, resolves the FMI 2.0 functions, drives the
//! co-simulation interface): the mean `Q_out` over whole mesh periods at
//! 1000 rpm / 30 bar / 60 degC matches `gearpump simulate` within 0.5 %;
//! two instances side by side; FMU state serialized and restored into a
//! fresh instance; reset; `gearpump fmu` writes an FMU that imports, and
//! leaves nothing but its output (no scratch file, no folder after a
//! failure).
//!
//! The FMU is `$GEARPUMP_FMU` when set (scripts/test-fmu.sh sets it to the
//! one `fmu-build` wrote), otherwise it is packaged here from the
//! `fmus/gear-pump` cdylib built for this test run's profile.

mod campaign_common;
mod fmi_common;

use std::path::PathBuf;
use std::process::Command;

use fmi::fmi2::import::Fmi2Import;
use fmi::fmi2::instance::{CoSimulation, Common, Instance};
use fmi::traits::FmiStatus;
use fmi::CS;
use gearpump::fmi2::pump::vr;
use gearpump::units::*;

use campaign_common::{tree, FileSizeLimit};
use fmi_common::TempDir;

fn fmu(dir: &TempDir) -> PathBuf {
    if let Some(p) = std::env::var_os("GEARPUMP_FMU") {
        return PathBuf::from(p);
    }
    let so = fmi_common::cdylib(gearpump::fmi2::FmuModel::GearPump);
    let out = dir.path().join("GearPump.fmu");
    gearpump::fmi2::build_exported_fmu(&out, &so).unwrap();
    out
}

fn ok<T, E: std::fmt::Debug>(r: Result<T, E>, what: &str) -> T {
    r.unwrap_or_else(|e| panic!("{what}: {e:?}"))
}

fn start(import: &Fmi2Import, name: &str, inputs: &[(u32, f64)]) -> Instance<CS> {
    let mut inst = ok(import.instantiate_cs(name, false, true), "instantiate");
    ok(
        Common::setup_experiment(&mut inst, None, 0.0, None),
        "setup",
    );
    ok(Common::enter_initialization_mode(&mut inst), "enter");
    let (vrs, vals): (Vec<u32>, Vec<f64>) = inputs.iter().copied().unzip();
    ok(Common::set_real(&mut inst, &vrs, &vals), "set_real");
    ok(Common::exit_initialization_mode(&mut inst), "exit");
    inst
}

fn real(inst: &mut Instance<CS>, r: u32) -> f64 {
    let mut v = [f64::NAN];
    ok(Common::get_real(inst, &[r], &mut v), "get_real");
    v[0]
}

fn steps(inst: &mut Instance<CS>, t: &mut f64, h: f64, n: usize) {
    for _ in 0..n {
        ok(CoSimulation::do_step(inst, *t, h, true), "do_step");
        *t += h;
    }
}

fn rated() -> [(u32, f64); 4] {
    [
        (vr::SPEED, rpm_to_rad_s(1000.0)),
        (vr::P_IN, ATMOSPHERE_PA),
        (vr::P_OUT, ATMOSPHERE_PA + bar_to_pa(30.0)),
        (vr::T_OIL, celsius_to_kelvin(60.0)),
    ]
}

#[test]
fn mean_flow_over_mesh_periods_matches_gearpump_simulate() {
    let dir = TempDir::new("import");
    let import: Fmi2Import = ok(fmi::import::from_path(fmu(&dir)), "import");
    let mut inst = start(&import, "rated", &rated());

    // whole mesh periods (14 per revolution), 8 communication steps each
    let period = 60.0 / 1000.0 / 14.0;
    let (mut t, n_periods) = (0.0, 4);
    let v0 = real(&mut inst, vr::V_DELIVERED);
    steps(&mut inst, &mut t, period / 8.0, 8 * n_periods);
    let mean = (real(&mut inst, vr::V_DELIVERED) - v0) / t;

    let out = Command::new(env!("CARGO_BIN_EXE_gearpump"))
        .args([
            "simulate",
            "--speed",
            "1000",
            "--pressure",
            "30",
            "--temp",
            "60",
            "--json",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let cli = json["flow_lpm"].as_f64().unwrap();
    let fmu = m3_s_to_lpm(mean);
    let rel = (fmu - cli) / cli;
    println!(
        "mean Q_out {fmu:.4} l/min (FMU) vs {cli:.4} l/min (gearpump simulate): {:+.4} %",
        rel * 100.0
    );
    assert!(rel.abs() < 5e-3, "FMU {fmu} l/min vs simulate {cli} l/min");
    let eta_v = real(&mut inst, vr::ETA_V);
    let cli_eta = json["eta_v"].as_f64().unwrap();
    assert!((eta_v - cli_eta).abs() < 5e-3, "eta_v {eta_v} vs {cli_eta}");
    ok(Common::terminate(&mut inst), "terminate");
}

#[test]
fn instances_side_by_side_state_serialization_and_reset() {
    let dir = TempDir::new("import-state");
    let import: Fmi2Import = ok(fmi::import::from_path(fmu(&dir)), "import");
    let h = 1e-3;
    let mut a = start(&import, "a", &rated());
    let mut b = start(&import, "b", &[(vr::SPEED, rpm_to_rad_s(2000.0))]);
    let (mut ta, mut tb) = (0.0, 0.0);
    steps(&mut a, &mut ta, h, 5);
    steps(&mut b, &mut tb, h, 5);
    // b turns twice as fast: about twice the angle and the volume
    let (tha, thb) = (real(&mut a, vr::THETA), real(&mut b, vr::THETA));
    assert!((thb / tha - 2.0).abs() < 1e-9, "{tha} {thb}");

    let s = ok(a.get_fmu_state(), "get_fmu_state");
    let bytes = ok(a.serialize_fmu_state(&s), "serialize");
    let t_saved = ta;
    steps(&mut a, &mut ta, h, 5);
    let reference = [vr::Q_OUT, vr::TORQUE, vr::V_DELIVERED, vr::THETA].map(|r| real(&mut a, r));

    // roll back in place
    ok(a.set_fmu_state(&s).ok(), "set_fmu_state");
    ta = t_saved;
    steps(&mut a, &mut ta, h, 5);
    assert_eq!(
        [vr::Q_OUT, vr::TORQUE, vr::V_DELIVERED, vr::THETA].map(|r| real(&mut a, r)),
        reference
    );

    // restore the bytes into a fresh instance
    let mut c = ok(import.instantiate_cs("c", false, true), "instantiate c");
    let sc = ok(c.deserialize_fmu_state(&bytes), "deserialize");
    ok(c.set_fmu_state(&sc).ok(), "set_fmu_state c");
    let mut tc = t_saved;
    steps(&mut c, &mut tc, h, 5);
    assert_eq!(
        [vr::Q_OUT, vr::TORQUE, vr::V_DELIVERED, vr::THETA].map(|r| real(&mut c, r)),
        reference
    );

    // reset: start values again, a new run from t = 0
    ok(Common::reset(&mut b), "reset");
    ok(Common::setup_experiment(&mut b, None, 0.0, None), "setup");
    ok(Common::enter_initialization_mode(&mut b), "enter");
    ok(Common::exit_initialization_mode(&mut b), "exit");
    assert_eq!(real(&mut b, vr::SPEED), rpm_to_rad_s(1000.0));
    assert_eq!(real(&mut b, vr::V_DELIVERED), 0.0);
    let mut tb = 0.0;
    steps(&mut b, &mut tb, h, 5);
    assert!(real(&mut b, vr::V_DELIVERED) > 0.0);
}

#[test]
fn gearpump_fmu_subcommand_writes_an_importable_fmu() {
    let dir = TempDir::new("import-cli");
    let out = dir.path().join("sub").join("GearPump.fmu");
    let r = Command::new(env!("CARGO_BIN_EXE_gearpump"))
        .args(["fmu", "--json", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let json: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(json["fmu"].as_str().map(PathBuf::from), Some(out.clone()));
    assert_eq!(json["model_identifier"], "GearPump");
    let import: Fmi2Import = ok(fmi::import::from_path(&out), "import");
    let mut inst = start(&import, "cli", &rated());
    let mut t = 0.0;
    steps(&mut inst, &mut t, 1e-3, 3);
    assert!(real(&mut inst, vr::Q_OUT) > 0.0);

    // --model transmission-circuit: the second FMU
    let out = dir.path().join("sub").join("TransmissionCircuit.fmu");
    fmi_common::cdylib(gearpump::fmi2::FmuModel::TransmissionCircuit);
    let r = Command::new(env!("CARGO_BIN_EXE_gearpump"))
        .args(["fmu", "--json", "--model", "transmission-circuit", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let json: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(json["model_identifier"], "TransmissionCircuit");
    let import: Fmi2Import = ok(fmi::import::from_path(&out), "import circuit");
    let mut inst = start(&import, "cli-circuit", &[]);
    let mut t = 0.0;
    steps(&mut inst, &mut t, 1e-3, 3);
    use gearpump::fmi2::circuit::vr as cvr;
    assert!(real(&mut inst, cvr::P_LINE) > ATMOSPHERE_PA);
    assert!(real(&mut inst, cvr::V_IN) > 0.0);

    // an unknown model is bad input (exit 2)
    let r = Command::new(env!("CARGO_BIN_EXE_gearpump"))
        .args(["fmu", "--model", "pump"])
        .output()
        .unwrap();
    assert_eq!(r.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&r.stderr).contains("--model"));
}

/// `gearpump fmu` into folders that do not exist yet makes them and
/// leaves only its output there (the stripped library and the population's
/// FMU are scratch files under the system's temporary folder); a run that
/// fails half-way (a file size limit: a full disk) exits 1 and removes the
/// folders it made.
#[test]
fn gearpump_fmu_leaves_nothing_but_its_output() {
    // the library is there, so no nested cargo build runs under the limit
    fmi_common::cdylib(gearpump::fmi2::FmuModel::GearPump);
    let dir = TempDir::new("fmu-paths");
    let csv = dir.path().join("small.csv");
    std::fs::write(
        &csv,
        "sample,tip_clearance_drive_um,tip_clearance_driven_um,bearing_clearance_drive_um,bearing_clearance_driven_um,pressure_bar,speed_rpm,temp_c,flow_lpm,torque_nm\n\
         N01,30,32,10,12,30,1000,60,13.5,\nN02,28,30,11,12,30,1000,60,13.5,\n",
    )
    .unwrap();
    let gearpump = |args: &[&std::ffi::OsStr], limit: Option<u64>| {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_gearpump"));
        cmd.args(args);
        if let Some(bytes) = limit {
            cmd.pre_exec_file_size_limit(bytes);
        }
        cmd.output().unwrap()
    };
    let os = |p: &std::path::Path| p.as_os_str().to_owned();
    let fmu = std::ffi::OsString::from("fmu");
    let population = std::ffi::OsString::from("--population");
    let flag = std::ffi::OsString::from("--out");
    let csv = os(&csv);

    // written: only the outputs, in the folders made for them
    let one = dir.path().join("a").join("b").join("x.fmu");
    let r = gearpump(&[&fmu, &flag, &os(&one)], None);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let ssp = dir.path().join("p").join("q").join("x.ssp");
    let r = gearpump(&[&fmu, &population, &csv, &flag, &os(&ssp)], None);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert_eq!(
        tree(dir.path()),
        [
            "a",
            "a/b",
            "a/b/x.fmu",
            "p",
            "p/q",
            "p/q/x.ssp",
            "small.csv"
        ]
    );

    // failing half-way: exit 1, the folders made for --out removed again
    let before = tree(dir.path());
    for args in [
        vec![&fmu, &flag, &os(&dir.path().join("new/deep/x.fmu"))],
        vec![
            &fmu,
            &population,
            &csv,
            &flag,
            &os(&dir.path().join("new/deep/x.ssp")),
        ],
        vec![
            &fmu,
            &population,
            &csv,
            &flag,
            &os(&dir.path().join("p/q/y.ssp")),
        ],
    ] {
        let args: Vec<&std::ffi::OsStr> = args.iter().map(|a| a.as_os_str()).collect();
        let r = gearpump(&args, Some(64 * 1024));
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(1), "{args:?}: {err}");
        assert_eq!(tree(dir.path()), before, "{args:?}: nothing left ({err})");
    }
}

/// Outputs read in Initialization mode, through the C functions as an
/// importer calls them (FMI 2.0 allows `fmi2GetReal` there; an importer
/// with an initial algebraic loop, or one recording t = 0 before the
/// first step, reads them): `Q_out` and `torque` (and the other outputs)
/// are the values read just after `fmi2ExitInitializationMode`, to the
/// bit, with either fidelity; with `start_periodic` (the default) they are
/// the periodic state's, within 0.5 % of the core model's `run_periodic`
/// at the same point (the map: within its 0.3 % of the LP model). A
/// higher delivery pressure set after a read gives less flow and more
/// torque at the next read, and an exit after such a change starts from
/// the changed inputs. `fmi2GetDirectionalDerivative` answers there too,
/// with `dQ_out_dp_out`. Before: every output read 0 in Initialization
/// mode and the directional derivative was refused.
#[test]
fn outputs_in_initialization_mode_are_the_values_after_exit() {
    use gearpump::fmi2::pump::{FIDELITY_LP, FIDELITY_MAP};
    use gearpump::model::{Inputs, Options, Pump, SampleClearances, Simulation};
    use std::sync::Arc;

    let dir = TempDir::new("import-init");
    let import: Fmi2Import = ok(fmi::import::from_path(fmu(&dir)), "import");
    const OUTPUTS: [u32; 14] = vr::REAL_OUTPUTS;
    // where Q_out, the torque and dQ_out/dp_out stand in it
    let at = |r: u32| OUTPUTS.iter().position(|&o| o == r).expect("an output");
    let (iq, it, idq) = (at(vr::Q_OUT), at(vr::TORQUE), at(vr::DQ_OUT_DP_OUT));
    let read = |inst: &mut Instance<CS>| -> Vec<u64> {
        let mut v = [0.0; OUTPUTS.len()];
        ok(Common::get_real(inst, &OUTPUTS, &mut v), "get_real outputs");
        v.iter().map(|x| x.to_bits()).collect()
    };
    let flag = |inst: &mut Instance<CS>| {
        let mut b = [0];
        ok(
            Common::get_boolean(inst, &[vr::OUT_OF_RANGE], &mut b),
            "get_boolean",
        );
        b[0]
    };
    let rated = rated();
    let set_p_out = |inst: &mut Instance<CS>, bar: f64| {
        ok(
            Common::set_real(inst, &[vr::P_OUT], &[ATMOSPHERE_PA + bar_to_pa(bar)]),
            "set p_out",
        )
    };
    // an instance in Initialization mode at the rated point
    let init = |name: &str, fidelity: i32, periodic: bool| {
        let mut inst = ok(import.instantiate_cs(name, false, true), "instantiate");
        ok(
            Common::setup_experiment(&mut inst, None, 0.0, None),
            "setup",
        );
        ok(
            Common::set_integer(&mut inst, &[vr::FIDELITY], &[fidelity]),
            "fidelity",
        );
        ok(
            Common::set_boolean(&mut inst, &[vr::START_PERIODIC], &[i32::from(periodic)]),
            "start_periodic",
        );
        ok(Common::enter_initialization_mode(&mut inst), "enter");
        let (vrs, vals): (Vec<u32>, Vec<f64>) = rated.iter().copied().unzip();
        ok(Common::set_real(&mut inst, &vrs, &vals), "set_real");
        inst
    };

    // the independent figure: the core model's periodic state
    let pump = Arc::new(Pump::new(gearpump::design::load(None, &[]).unwrap()));
    let inputs = Inputs::rig(1000.0, 30.0, 60.0);
    let sample = SampleClearances::nominal(&pump.design);
    let summary = Simulation::new(
        Arc::clone(&pump),
        inputs,
        sample,
        Options { micromotion: true },
    )
    .unwrap()
    .run_periodic()
    .unwrap();

    for (fidelity, periodic) in [
        (FIDELITY_LP, true),
        (FIDELITY_LP, false),
        (FIDELITY_MAP, true),
    ] {
        let what = format!("fidelity {fidelity}, start_periodic {periodic}");
        let mut inst = init(&format!("init-{fidelity}-{periodic}"), fidelity, periodic);
        let at_init = read(&mut inst);
        let (q, torque) = (f64::from_bits(at_init[iq]), f64::from_bits(at_init[it]));
        println!(
            "{what}: Q_out {:.4} l/min, torque {torque:.4} N m in Initialization mode; \
             run_periodic {:.4} l/min, {:.4} N m",
            m3_s_to_lpm(q),
            m3_s_to_lpm(summary.flow),
            summary.torque
        );
        // (the start-up transient's flows and torque are 0 until the
        // first step)
        assert_eq!(q > 0.0 && torque > 0.0, periodic, "{what}: {q} {torque}");
        if periodic {
            // the LP fidelity's last mesh period is the periodic state's
            // (the figures agree to 1e-5); the map is within 0.3 % of it
            let tol = if fidelity == FIDELITY_LP { 1e-3 } else { 5e-3 };
            let rel = |x: f64, r: f64| ((x - r) / r).abs();
            assert!(
                rel(q, summary.flow) < tol,
                "{what}: {q} vs {}",
                summary.flow
            );
            assert!(
                rel(torque, summary.torque) < tol,
                "{what}: {torque} vs {}",
                summary.torque
            );
        }
        let flag_at_init = flag(&mut inst);
        // the directional derivative there: the output dQ_out_dp_out
        let mut dd = [f64::NAN];
        ok(
            inst.get_directional_derivative(&[vr::Q_OUT], &[vr::P_OUT], &[1.0], &mut dd),
            "directional derivative in Initialization mode",
        );
        assert_eq!(dd[0].to_bits(), at_init[idq], "{what}");
        assert!(dd[0] < 0.0, "{what}: {}", dd[0]);

        // a higher delivery pressure: less flow, more torque
        set_p_out(&mut inst, 50.0);
        let high = read(&mut inst);
        let (q_hi, torque_hi) = (f64::from_bits(high[iq]), f64::from_bits(high[it]));
        assert!(
            (q_hi < q && torque_hi > torque) || !periodic,
            "{what}: 50 bar {q_hi} m3/s {torque_hi} N m, 30 bar {q} m3/s {torque} N m"
        );
        assert_ne!(high, at_init, "{what}");
        // back to 30 bar: the first values; the exit keeps them
        set_p_out(&mut inst, 30.0);
        assert_eq!(read(&mut inst), at_init, "{what}");
        ok(Common::exit_initialization_mode(&mut inst), "exit");
        assert_eq!(read(&mut inst), at_init, "{what}: after the exit");
        assert_eq!(flag(&mut inst), flag_at_init, "{what}");
        let mut t = 0.0;
        steps(&mut inst, &mut t, 1e-3, 2);
        assert!(real(&mut inst, vr::V_DELIVERED) > 0.0);

        // read at 30 bar, 50 bar set, exit without a read: 50 bar's start
        let mut inst = init(
            &format!("init-change-{fidelity}-{periodic}"),
            fidelity,
            periodic,
        );
        assert_eq!(read(&mut inst), at_init, "{what}");
        set_p_out(&mut inst, 50.0);
        ok(Common::exit_initialization_mode(&mut inst), "exit");
        assert_eq!(read(&mut inst), high, "{what}: exit after a change");
    }
}
