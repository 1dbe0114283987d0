//! `gearpump simulate` through the real binary: the JSON contract of
//! docs/interfaces.md section 3, the acceptance points, and bad input (exit 2 with a
//! message naming the field).

mod campaign_common;
use campaign_common::{gearpump, gearpump_env, with_args, POINT_1000_30_60};
use serde_json::Value;
use std::sync::Arc;

fn simulate_json(extra: &[&str]) -> Value {
    let mut args = vec!["simulate", "--json", "--no-micromotion"];
    args.extend_from_slice(extra);
    let out = gearpump(&args);
    assert!(
        out.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert_eq!(
        text.trim().lines().count(),
        1,
        "exactly one JSON object on stdout"
    );
    serde_json::from_str(&text).expect("valid JSON")
}

fn num(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("key {key} missing or not a number in {v}"))
}

#[test]
fn simulate_json_has_every_contract_key_and_plausible_values() {
    let v = simulate_json(&POINT_1000_30_60);
    for key in [
        "speed_rpm",
        "pressure_bar",
        "temp_c",
        "displacement_cm3",
        "flow_lpm",
        "eta_v",
        "torque_nm",
        "eta_hm",
        "flow_ripple_lpm",
        "revolutions",
        "coupling_iterations_mean",
        "wall_ms",
        "setup_ms",
        "solve_ms",
    ] {
        assert!(v[key].is_number(), "{key} in {v}");
    }
    // wall time split into the set-up (design, tables) and the solve
    let (wall, setup, solve) = (num(&v, "wall_ms"), num(&v, "setup_ms"), num(&v, "solve_ms"));
    assert!(setup > 0.0 && solve > 0.0, "setup {setup} solve {solve}");
    assert!(
        setup + solve <= wall + 1e-9,
        "setup {setup} + solve {solve} > wall {wall}"
    );
    assert_eq!(
        v["tables"], "built",
        "the tests run with the table cache off"
    );
    assert!(v["eccentricity"]["drive"].as_array().map(|a| a.len()) == Some(2));
    assert!(v["eccentricity"]["driven"].as_array().map(|a| a.len()) == Some(2));
    let vm = num(&v, "displacement_cm3");
    assert!((vm - 14.65).abs() / 14.65 < 0.01, "displacement {vm}");
    let eta = num(&v, "eta_v");
    assert!(eta > 0.8 && eta < 0.99, "eta_v {eta}");
    // eta_v = flow / (Vm n)
    let flow = num(&v, "flow_lpm");
    assert!((flow / (vm * 1e-3 * 1000.0) - eta).abs() < 1e-9);
    assert!(num(&v, "flow_ripple_lpm") > 0.0);
    let t_ideal = vm * 1e-6 * 30e5 / (2.0 * std::f64::consts::PI);
    assert!(num(&v, "torque_nm") > 0.9 * t_ideal);
    // the loss budget: six shares of Vm n adding up to 1 - eta_v
    let losses = v["losses"].as_object().expect("a losses object");
    let mut sum = 0.0;
    for key in [
        "tip_poiseuille",
        "tip_couette",
        "lateral",
        "bearings",
        "mesh_zone",
        "compressibility",
    ] {
        sum += losses[key]
            .as_f64()
            .unwrap_or_else(|| panic!("losses.{key}"));
    }
    assert_eq!(losses.len(), 6, "{losses:?}");
    assert!((sum - (1.0 - eta)).abs() < 1e-3, "{sum} vs {}", 1.0 - eta);
    // drag forward: a gain
    assert!(losses["tip_couette"].as_f64().unwrap() < 0.0);
}

#[test]
fn simulate_text_shows_where_the_flow_goes() {
    let out = gearpump(&with_args(&["simulate"], &POINT_1000_30_60));
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("where the flow goes"), "{text}");
    for label in [
        "tip gaps, pressure-driven",
        "tip gaps, drag",
        "lateral faces",
        "1 - Q/(Vm n)",
    ] {
        assert!(text.contains(label), "{label} in {text}");
    }
}

#[test]
fn simulate_orders_eta_v_as_the_physics_says() {
    let eta = |speed: &str, p: &str, t: &str| {
        num(
            &simulate_json(&["--speed", speed, "--pressure", p, "--temp", t]),
            "eta_v",
        )
    };
    assert!(eta("1000", "10", "60") > eta("1000", "40", "60"));
    assert!(eta("500", "30", "60") < eta("4000", "30", "60"));
    assert!(eta("1000", "30", "60") > eta("1000", "30", "120"));
}

#[test]
fn sample_clearances_and_set_change_the_result() {
    let base = num(&simulate_json(&POINT_1000_30_60), "eta_v");
    let wide = num(
        &simulate_json(&with_args(
            &POINT_1000_30_60,
            &["--sample-clearances", "40,40,12,12"],
        )),
        "eta_v",
    );
    assert!(wide < base);
    let lat = num(
        &simulate_json(&with_args(
            &POINT_1000_30_60,
            &["--set", "clearance.lateral_um=40"],
        )),
        "eta_v",
    );
    assert!(lat < base);
}

fn refused(args: &[&str], needle: &str) {
    let out = gearpump(args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "args {args:?}: stderr {err}");
    assert!(
        err.contains(needle),
        "args {args:?}: `{needle}` not in: {err}"
    );
    assert!(out.stdout.is_empty(), "nothing on stdout for bad input");
}

#[test]
fn bad_input_is_refused_with_exit_2_naming_the_field() {
    let ok = with_args(&["simulate"], &POINT_1000_30_60);
    // (a change to the valid command line, the field the message must name)
    let with = |flag: &'static str, value: &'static str| -> Vec<&'static str> {
        let mut a: Vec<&str> = ok.to_vec();
        match a.iter().position(|x| *x == flag) {
            Some(i) => a[i + 1] = value,
            None => a.extend_from_slice(&[flag, value]),
        }
        a
    };
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (with("--speed", "-5"), "--speed"),
        (with("--speed", "abc"), "--speed"),
        (with("--speed", "NaN"), "--speed"),
        (
            vec!["simulate", "--speed", "1000", "--temp", "60"],
            "--pressure",
        ),
        (with("--temp", "400"), "--temp"),
        (with("--inlet-pressure", "0"), "--inlet-pressure"),
        (
            with("--sample-clearances", "30,30,12"),
            "--sample-clearances",
        ),
        (with("--sample-clearances", "30,-1,12,12"), "TIP2"),
        (with("--set", "clearance.nope=3"), "clearance.nope"),
        (with("--set", "oil.nu_40c_cst=thick"), "oil.nu_40c_cst"),
        (
            with("--set", "gears.tip_radius_driven_mm=14.5"),
            "gears.tip_radius_driven_mm",
        ),
        (
            with("--design", "/nonexistent/pump.toml"),
            "/nonexistent/pump.toml",
        ),
    ];
    for (args, field) in &cases {
        refused(args, field);
    }
    // a design file with a missing key and one with a wrong type
    let dir = std::env::temp_dir().join(format!("gearpump-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = gearpump::design::SEED_PUMP_TOML;
    let missing = dir.join("missing.toml");
    std::fs::write(&missing, text.replace("bearing_um = 12.0", "")).unwrap();
    let mut a = ok.to_vec();
    let m = missing.to_str().unwrap().to_string();
    a.extend_from_slice(&["--design", &m]);
    refused(&a, "bearing_um");
    let wrong = dir.join("wrong.toml");
    std::fs::write(
        &wrong,
        text.replace("z_drive = 14", "z_drive = \"fourteen\""),
    )
    .unwrap();
    let w = wrong.to_str().unwrap().to_string();
    let mut a = ok.to_vec();
    a.extend_from_slice(&["--design", &w]);
    refused(&a, "gears.z_drive");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn trace_writes_pocket_pressures_over_a_revolution() {
    let dir = std::env::temp_dir().join(format!("gearpump-trace-{}", std::process::id()));
    let d = dir.to_str().unwrap().to_string();
    // with micromotion (the default), so the centre loci are real
    let out = gearpump(&with_args(
        &["simulate", "--json", "--trace", &d],
        &POINT_1000_30_60,
    ));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(v["flow_lpm"].is_number());
    let text = std::fs::read_to_string(dir.join("trace.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header.len(), 4 + 14 + 9 + 4 + 14 + 9);
    for col in [
        "p_drive_space00_bar",
        "p_driven_space08_bar",
        "x_drive_um",
        "y_driven_um",
        "h_tip_drive_tooth13_um",
        "h_tip_driven_tooth00_um",
    ] {
        assert!(header.contains(&col), "{col}");
    }
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 714);
    // one tooth space sees suction and delivery pressure in a revolution
    let col = 4;
    let max = rows.iter().map(|r| r[col]).fold(f64::MIN, f64::max);
    let min = rows.iter().map(|r| r[col]).fold(f64::MAX, f64::min);
    assert!(
        max > 25.0 && min < 2.0,
        "space 0 pressure range {min}..{max} bar"
    );
    // the gear centre moves inside its bearing clearance, so every tip
    // clearance stays within the design tip clearance +- the bearing clearance,
    // and the centres sit off the bore centre
    let design = gearpump::design::Design::seed();
    let (tip, brg) = (
        design.clearance.tip[0] * 1e6,
        design.clearance.bearing[0] * 1e6,
    );
    let h_col = header
        .iter()
        .position(|c| *c == "h_tip_drive_tooth00_um")
        .unwrap();
    let y_col = header.iter().position(|c| *c == "y_drive_um").unwrap();
    for r in &rows {
        assert!(
            r[h_col] > tip - brg && r[h_col] < tip + brg,
            "h = {}",
            r[h_col]
        );
        assert!(r[y_col].abs() > 0.1 * brg, "y = {}", r[y_col]);
    }
    for svg in ["centre_loci.svg", "pocket_pressure.svg"] {
        let text = std::fs::read_to_string(dir.join(svg)).unwrap();
        assert!(text.starts_with("<svg") && text.len() > 1000, "{svg}");
    }
    let loci = std::fs::read_to_string(dir.join("centre_loci.svg")).unwrap();
    for bar in ["10 bar", "20 bar", "30 bar", "40 bar"] {
        assert!(loci.contains(bar), "{bar} in the loci plot");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue acceptance: at 40 bar both gears sit farther off-centre than at
/// 10 bar, the coupling converged, torque and eta_hm are reported, and eta_v
/// differs from the run without micromotion.
#[test]
fn micromotion_acceptance_at_10_and_40_bar() {
    let run = |p: &str, extra: &[&str]| {
        let mut args = vec![
            "simulate",
            "--json",
            "--speed",
            "1000",
            "--pressure",
            p,
            "--temp",
            "60",
        ];
        args.extend_from_slice(extra);
        let out = gearpump(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice::<Value>(&out.stdout).unwrap()
    };
    let lo = run("10", &[]);
    let hi = run("40", &[]);
    let off = run("40", &["--no-micromotion"]);
    let ecc = |v: &Value, g: &str| {
        let a = v["eccentricity"][g].as_array().unwrap();
        a[0].as_f64().unwrap().hypot(a[1].as_f64().unwrap())
    };
    for g in ["drive", "driven"] {
        assert!(
            ecc(&hi, g) > ecc(&lo, g),
            "{g}: {} vs {}",
            ecc(&hi, g),
            ecc(&lo, g)
        );
    }
    assert_eq!(hi["coupling_unconverged_steps"].as_u64(), Some(0));
    assert!(num(&hi, "coupling_iterations_mean") > 1.0);
    assert!(num(&hi, "torque_nm") > num(&lo, "torque_nm"));
    let eta_hm = num(&hi, "eta_hm");
    assert!(eta_hm > 0.8 && eta_hm < 0.97);
    assert!((num(&hi, "eta_v") - num(&off, "eta_v")).abs() > 1e-3);
    assert_eq!(off["micromotion"].as_bool(), Some(false));
    assert_eq!(num(&off, "coupling_iterations_mean"), 0.0);
}

/// The CLI reports exactly what the library computes for the same point.
#[test]
fn cli_matches_the_library() {
    use gearpump::model::{Inputs, Options, Pump, SampleClearances, Simulation};
    use gearpump::units::*;
    let v = simulate_json(&POINT_1000_30_60);
    let pump = Arc::new(Pump::new(gearpump::design::Design::seed()));
    let i = Inputs {
        omega: rpm_to_rad_s(1000.0),
        p_suction: ATMOSPHERE_PA,
        p_delivery: ATMOSPHERE_PA + bar_to_pa(30.0),
        temp_k: celsius_to_kelvin(60.0),
        measured_torque: None,
    };
    // simulate_json runs with --no-micromotion
    let opts = Options { micromotion: false };
    let s = Simulation::new(
        Arc::clone(&pump),
        i,
        SampleClearances::nominal(&pump.design),
        opts,
    )
    .unwrap()
    .run_periodic()
    .unwrap();
    assert!((num(&v, "eta_v") - s.eta_v).abs() < 1e-12);
    assert!((num(&v, "torque_nm") - s.torque).abs() < 1e-9);
    assert!((num(&v, "eta_hm") - s.eta_hm).abs() < 1e-12);
}

/// Repeated calls read the section tables from the cache folder
/// (`GEARPUMP_TABLE_CACHE`) and give the same results to the bit; a damaged
/// file is refused with a note, the tables are built again and the file
/// replaced.
#[test]
fn the_table_cache_serves_repeated_calls_and_refuses_a_damaged_file() {
    let dir = std::env::temp_dir().join(format!("gearpump-cli-cache-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let cache = dir.to_str().unwrap();
    let run = || {
        let out = gearpump_env(
            &[
                "simulate",
                "--json",
                "--no-micromotion",
                "--speed",
                "1500",
                "--pressure",
                "20",
                "--temp",
                "80",
            ],
            &[("GEARPUMP_TABLE_CACHE", cache)],
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: Value = serde_json::from_slice(&out.stdout).unwrap();
        (v, String::from_utf8_lossy(&out.stderr).into_owned())
    };
    let same = |a: &Value, b: &Value| {
        for key in ["eta_v", "torque_nm", "flow_ripple_lpm", "flow_lpm"] {
            assert_eq!(num(a, key).to_bits(), num(b, key).to_bits(), "{key}");
        }
    };
    let (first, _) = run();
    assert_eq!(first["tables"], "built");
    let files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(files.len(), 1, "one table file: {files:?}");
    let (second, _) = run();
    assert_eq!(second["tables"], "cached");
    same(&first, &second);
    // one byte of the stored tables changed
    let mut bytes = std::fs::read(&files[0]).unwrap();
    let i = bytes.len() / 2;
    bytes[i] ^= 0x01;
    std::fs::write(&files[0], bytes).unwrap();
    let (third, stderr) = run();
    assert!(
        third["tables"]
            .as_str()
            .unwrap()
            .starts_with("built (cache refused: damaged"),
        "{}",
        third["tables"]
    );
    assert!(
        stderr.contains("table cache") && stderr.contains("refused"),
        "{stderr}"
    );
    same(&first, &third);
    let (fourth, _) = run();
    assert_eq!(fourth["tables"], "cached");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A step the solver cannot carry is reported as what it is, with the
/// remedy. A two-zone layout with the channel along the spaces closed
/// (`casing.axial_flow = "none"`, every zone a sealed space of its own in
/// the mesh) at 1000 rpm / 1 bar has steps that neither Newton nor its
/// damped retries solve at the design's 0.5 deg; since 2026-11-29 such a
/// step is marched in sub-steps (docs/model.md section 7), so the point
/// runs, and its eta_v agrees with a run at half the step within 1e-3
/// (measured 0.999318 against 0.999260). At a 5 deg step with the meshing-zone
/// passages at the narrowest gap (`casing.mesh_passage = "gap"`) even 32
/// sub-steps fail: exit 1 (not a refusal of the input), and the message
/// names the angle step in use.
#[test]
fn a_step_the_solver_cannot_carry_names_the_angle_step() {
    let layout = [
        "simulate",
        "--speed",
        "1000",
        "--pressure",
        "1",
        "--temp",
        "60",
        "--set",
        "numerics.axial_nodes=2",
        "--set",
        "casing.axial_flow=none",
        "--json",
    ];
    let eta_v = |step: &str| -> f64 {
        let mut args = layout.to_vec();
        args.extend_from_slice(&["--set", step]);
        let out = gearpump(&args);
        assert!(
            out.status.success(),
            "{step}: stderr: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        v["eta_v"].as_f64().unwrap()
    };
    let (design, half) = (
        eta_v("numerics.angle_step_deg=0.5"),
        eta_v("numerics.angle_step_deg=0.25"),
    );
    assert!((design - half).abs() < 1e-3, "{design} against {half}");
    let mut coarse = layout.to_vec();
    coarse.extend_from_slice(&[
        "--set",
        "numerics.angle_step_deg=5",
        "--set",
        "casing.mesh_passage=gap",
    ]);
    let out = gearpump(&coarse);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "stderr: {err}");
    assert!(
        err.contains("solver failed at driving angle")
            && err.contains("numerics.angle_step_deg than the 5.1429 deg in use"),
        "stderr: {err}"
    );
}
