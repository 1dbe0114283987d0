//! GearPump.fmu of any design (issue 16 points 1, 2 and 6) through the
//! model's safe API: an FMU built from a design file with extension keys
//! and a sample's clearances runs what `gearpump simulate --design` runs
//! (the campaign's effect model), its clearance parameters start at the
//! design's, it ships its design's section tables; the outputs engineers
//! expect (`Q_in`, `P_shaft`, `P_hyd`, `p_pocket_min`, `cavitation_margin`,
//! `out_of_range`) against hand calculations; bad design input at `gearpump
//! fmu` time.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use gearpump::campaign::effects::EffectModel;
use gearpump::fmi2::pump::{vr, GearPumpFmu, TABLES_FILE};
use gearpump::fmi2::{CoSimModel, PumpDesign};
use gearpump::model::{Inputs, Options, Pump, SampleClearances};
use gearpump::units::*;

/// A fresh folder under the system's temporary folder.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("gearpump-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The design file of the test: the bundled pump with other nominal
/// clearances and extension keys of every kind (clearance growth with
/// temperature and pressure, Barus, viscosity factors), written to a file;
/// `--set` adds one more on the command line's path.
fn design_file(dir: &Path) -> (PathBuf, Vec<String>) {
    let text = gearpump::design::SEED_PUMP_TOML
        .replace("tip_um = 30.0 ", "tip_um = 33.5 ")
        .replace("bearing_um = 12.0 ", "bearing_um = 14.0 ")
        .replace(
            "thermal_growth_um_per_k = 0.0 ",
            "thermal_growth_um_per_k = 0.05 ",
        )
        .replace(
            "pressure_viscosity_per_pa = 0.0 ",
            "pressure_viscosity_per_pa = 2.0e-8 ",
        );
    assert_ne!(text, gearpump::design::SEED_PUMP_TOML);
    let path = dir.join("sample_design.toml");
    std::fs::write(&path, text).unwrap();
    let sets = vec![
        "clearance.pressure_growth_um_per_bar=0.1".to_string(),
        "clearance.pressure_growth_on=tips".to_string(),
        "oil.viscosity_factor_60c=0.9".to_string(),
    ];
    (path, sets)
}

/// An instance as an importer gets it: the FMU's resources/ written from
/// the files packaging ships for `d`, instantiated from that folder; and
/// the instantiation log.
fn instance_of(d: &PumpDesign, dir: &Path) -> (GearPumpFmu, String) {
    let res = dir.join("resources");
    std::fs::create_dir_all(&res).unwrap();
    for (name, bytes) in GearPumpFmu::resource_files_for(&d.toml, d.design.clone()) {
        std::fs::write(res.join(name), bytes).unwrap();
    }
    let log = std::cell::RefCell::new(String::new());
    let m = GearPumpFmu::instantiate(&res, &|s: &str| log.borrow_mut().push_str(s)).unwrap();
    (m, log.into_inner())
}

fn get(m: &GearPumpFmu, r: u32) -> f64 {
    m.get_real(r).unwrap()
}

/// Mean Q_out of the model over `periods` whole mesh periods of 1 ms
/// steps (the last one shorter), from `t`.
fn mean_q_out(m: &mut GearPumpFmu, pump: &Pump, omega: f64, t: &mut f64, periods: f64) -> f64 {
    let period = 2.0 * std::f64::consts::PI / pump.tables.z[0] as f64 / omega;
    let (v0, t0) = (get(m, vr::V_DELIVERED), *t);
    let end = t0 + periods * period;
    while *t < end - 1e-12 {
        let h = 1e-3f64.min(end - *t);
        m.do_step(*t, h).unwrap();
        *t += h;
    }
    (get(m, vr::V_DELIVERED) - v0) / (*t - t0)
}

/// What `gearpump simulate --design FILE --set ... --sample-clearances
/// ...` computes at `inputs`: the effect model on the design (its keys act
/// per operating point), the sample's measured clearances, run to the
/// periodic state.
fn simulate(d: &PumpDesign, sample: SampleClearances, inputs: Inputs) -> f64 {
    let pump = Arc::new(Pump::new(d.design.clone()));
    let model = EffectModel::on(&pump, &[]).unwrap();
    let mut sim = model
        .simulation(inputs, sample, Options { micromotion: true })
        .unwrap();
    sim.run_periodic().unwrap().flow
}

fn inputs(rpm: f64, bar: f64, degc: f64) -> Inputs {
    Inputs {
        omega: rpm_to_rad_s(rpm),
        p_suction: ATMOSPHERE_PA,
        p_delivery: ATMOSPHERE_PA + bar_to_pa(bar),
        temp_k: celsius_to_kelvin(degc),
        measured_torque: None,
    }
}

/// Point 1's "done when": an FMU of a design file with extension keys and
/// a sample's clearances gives the mean Q_out of `gearpump simulate` with
/// the same design within 0.1 %, at the start values and after the oil
/// temperature and the delivery pressure changed during the run (the
/// growth laws and Barus follow the inputs); its clearance parameters
/// start at the sample's and its section tables are read, not built.
#[test]
fn an_fmu_of_a_design_with_extension_keys_matches_simulate_within_0_1_percent() {
    let dir = temp_dir("fmu-design");
    let (file, sets) = design_file(&dir);
    let d = PumpDesign::load(Some(&file), &sets).unwrap();
    // the shipped text alone loads to the design (the --set overrides in it)
    assert_eq!(
        gearpump::design::from_toml_str(&d.toml, &[]).unwrap(),
        d.design
    );
    assert!(d.design.clearance.growth.thermal > 0.0);
    assert!(d.design.clearance.growth.pressure > 0.0);
    assert!(d.design.oil.pressure_viscosity > 0.0);
    let (mut m, log) = instance_of(&d, &dir);
    assert!(log.contains("section tables read from"), "{log}");
    // the clearance parameters start at the design's clearances
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs();
    for (r, um) in [
        (vr::TIP_DRIVE, 33.5),
        (vr::TIP_DRIVEN, 33.5),
        (vr::BEARING_DRIVE, 14.0),
        (vr::BEARING_DRIVEN, 14.0),
        (vr::LATERAL, 15.0),
    ] {
        assert!(close(get(&m, r), um_to_m(um)), "vr {r}: {}", get(&m, r));
    }
    // a pump sample's measured clearances (as simulate's --sample-clearances)
    let sample = SampleClearances {
        tip: [um_to_m(33.5), um_to_m(27.0)],
        bearing: [um_to_m(14.0), um_to_m(11.5)],
        lateral: um_to_m(15.0),
    };
    m.set_real(vr::TIP_DRIVEN, sample.tip[1]).unwrap();
    m.set_real(vr::BEARING_DRIVEN, sample.bearing[1]).unwrap();
    // ... and the XML of that FMU says so
    let vars = GearPumpFmu::variables_for(&d.design);
    let xml = gearpump::fmi2::xml::model_description_xml_for::<GearPumpFmu>(
        &vars,
        &GearPumpFmu::guid_for_design(&d.toml),
    );
    assert!(
        xml.contains("start=\"0.0000335\""),
        "tip start not in the XML"
    );

    let pump = Pump::new(d.design.clone());
    m.exit_initialization().unwrap();
    let mut t = 0.0;
    let nominal = inputs(1000.0, 30.0, 60.0);
    let q_fmu = mean_q_out(&mut m, &pump, nominal.omega, &mut t, 10.0);
    let q_sim = simulate(&d, sample, nominal);
    let rel = (q_fmu - q_sim) / q_sim;
    println!(
        "60 degC / 30 bar: FMU {:.5} l/min, simulate {:.5} l/min (relative {:+.2e})",
        m3_s_to_lpm(q_fmu),
        m3_s_to_lpm(q_sim),
        rel
    );
    assert!(rel.abs() < 1e-3, "{rel}");

    // hotter oil and a higher pressure during the run: the clearances open
    // with both laws, Barus thickens the gaps
    let hot = inputs(1000.0, 60.0, 90.0);
    m.set_real(vr::T_OIL, hot.temp_k).unwrap();
    m.set_real(vr::P_OUT, hot.p_delivery).unwrap();
    mean_q_out(&mut m, &pump, hot.omega, &mut t, 20.0); // settle
    let q_fmu = mean_q_out(&mut m, &pump, hot.omega, &mut t, 10.0);
    let q_sim = simulate(&d, sample, hot);
    let rel = (q_fmu - q_sim) / q_sim;
    println!(
        "90 degC / 60 bar: FMU {:.5} l/min, simulate {:.5} l/min (relative {:+.2e})",
        m3_s_to_lpm(q_fmu),
        m3_s_to_lpm(q_sim),
        rel
    );
    assert!(rel.abs() < 1e-3, "{rel}");
    // the keys matter there: the same sample without them delivers more
    let plain = PumpDesign::load(
        Some(&file),
        &[
            "clearance.thermal_growth_um_per_k=0".into(),
            "oil.pressure_viscosity_per_pa=0".into(),
        ],
    )
    .unwrap();
    let q_plain = simulate(&plain, sample, hot);
    assert!(
        (q_plain - q_sim) / q_sim > 5e-3,
        "keys change nothing: {q_plain} vs {q_sim}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A design that fails to load is refused by `gearpump fmu` with exit
/// code 2 and a message naming the file or the key, before anything is
/// built.
#[test]
fn gearpump_fmu_refuses_a_design_that_does_not_load() {
    let dir = temp_dir("fmu-bad-design");
    let bad_value = dir.join("bad.toml");
    std::fs::write(
        &bad_value,
        gearpump::design::SEED_PUMP_TOML.replace("bearing_um = 12.0 ", "bearing_um = -3.0 "),
    )
    .unwrap();
    let missing = dir.join("missing.toml");
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec!["--design".into(), missing.display().to_string()],
            "missing.toml",
        ),
        (
            vec!["--design".into(), bad_value.display().to_string()],
            "bearing_um",
        ),
        (
            vec!["--set".into(), "clearance.no_such_key=1".into()],
            "no_such_key",
        ),
        (
            vec![
                "--model".into(),
                "transmission-circuit".into(),
                "--set".into(),
                "clearance.tip_um=31".into(),
            ],
            "gear pump only",
        ),
    ];
    for (args, needle) in cases {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_gearpump"))
            .arg("fmu")
            .args(&args)
            .arg("--out")
            .arg(dir.join("never.fmu"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "one line: {err}");
        assert!(!dir.join("never.fmu").exists());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Point 2: the tables shipped with an FMU of a design are that design's
/// (instantiation reads them, they equal the built ones), and another
/// design's tables under the name are refused.
#[test]
fn an_fmu_of_a_design_ships_its_own_section_tables() {
    let dir = temp_dir("fmu-design-tables");
    let d = PumpDesign::load(None, &["gears.face_width_mm=24".into()]).unwrap();
    let (m, log) = instance_of(&d, &dir);
    assert!(log.contains("section tables read from"), "{log}");
    assert_eq!(m.pump().sections, Pump::new(d.design.clone()).sections);
    // the bundled design's tables under the name: refused, built
    let bundled = GearPumpFmu::resource_files();
    let (_, tables) = bundled.iter().find(|(n, _)| n == TABLES_FILE).unwrap();
    std::fs::write(dir.join("resources").join(TABLES_FILE), tables).unwrap();
    let log = std::cell::RefCell::new(String::new());
    let m2 = GearPumpFmu::instantiate(&dir.join("resources"), &|s: &str| {
        log.borrow_mut().push_str(s)
    })
    .unwrap();
    assert!(log.borrow().contains("refused"), "{}", log.borrow());
    assert_eq!(m2.pump().sections, m.pump().sections);
    let _ = std::fs::remove_dir_all(&dir);
}

fn bundled_model() -> GearPumpFmu {
    let d = PumpDesign::load(None, &[]).unwrap();
    GearPumpFmu::with_pump(Arc::new(Pump::new(d.design)))
}

/// Point 6: the outputs at t = 0 are the periodic state's and each
/// follows its hand calculation: P_hyd = Q_out (p_out - p_in), P_shaft =
/// torque * speed at every step; over whole mesh periods Q_in rho(p_in) =
/// Q_out rho(p_out) (the mass balance at the periodic state);
/// cavitation_margin = p_pocket_min / gas-release pressure; nothing out of
/// range at the nominal point.
#[test]
fn power_inlet_flow_and_filling_outputs_follow_their_hand_calculations() {
    let mut m = bundled_model();
    m.exit_initialization().unwrap();
    let oil = m.pump().design.oil.clone();
    let z0 = m.pump().tables.z[0];
    let check_step = |m: &GearPumpFmu| {
        let dp = get(m, vr::P_OUT) - get(m, vr::P_IN);
        let rel = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs();
        assert!(rel(get(m, vr::P_HYD), get(m, vr::Q_OUT) * dp));
        assert!(rel(
            get(m, vr::P_SHAFT),
            get(m, vr::TORQUE) * get(m, vr::SPEED)
        ));
        assert!(rel(
            get(m, vr::CAVITATION_MARGIN),
            get(m, vr::P_POCKET_MIN) / oil.gas_release_pa
        ));
    };
    // from t = 0: the periodic state's values
    for r in [vr::Q_IN, vr::P_SHAFT, vr::P_HYD, vr::P_POCKET_MIN] {
        assert!(get(&m, r) > 0.0, "vr {r} at t = 0: {}", get(&m, r));
    }
    check_step(&m);
    assert!(!m.get_boolean(vr::OUT_OF_RANGE).unwrap());
    // eta_hm = P_hyd / P_shaft over a whole period with constant inputs
    let eta = get(&m, vr::P_HYD) / get(&m, vr::P_SHAFT);
    assert!(
        (eta - get(&m, vr::ETA_HM) * get(&m, vr::ETA_V)).abs() < 1e-9,
        "P_hyd/P_shaft {eta} vs eta_v eta_hm {}",
        get(&m, vr::ETA_HM) * get(&m, vr::ETA_V)
    );
    let omega = get(&m, vr::SPEED);
    let period = 2.0 * std::f64::consts::PI / z0 as f64 / omega;
    let (mut t, mut v_in, mut v_out) = (0.0, 0.0, 0.0);
    let end = 5.0 * period;
    while t < end - 1e-12 {
        let h = 7e-4f64.min(end - t);
        m.do_step(t, h).unwrap();
        t += h;
        check_step(&m);
        v_in += get(&m, vr::Q_IN) * h;
        v_out += get(&m, vr::Q_OUT) * h;
    }
    let comp = gearpump::oil::Compressibility::from_oil(&oil);
    let ratio = comp.density_ratio(get(&m, vr::P_OUT)).0 / comp.density_ratio(get(&m, vr::P_IN)).0;
    let rel = (v_in / (v_out * ratio)) - 1.0;
    println!(
        "Q_in {:.5} l/min, Q_out {:.5} l/min, rho_out/rho_in {ratio:.6}: mass balance {rel:+.2e}",
        m3_s_to_lpm(v_in / t),
        m3_s_to_lpm(v_out / t)
    );
    assert!(rel.abs() < 1e-5, "{rel}");
    assert!(ratio > 1.0);
    let margin = get(&m, vr::CAVITATION_MARGIN);
    println!(
        "nominal: p_pocket_min {:.4} bar, margin {margin:.3}",
        pa_to_bar(get(&m, vr::P_POCKET_MIN))
    );
    assert!(margin > 1.0, "{margin}");
    assert!(!m.get_boolean(vr::OUT_OF_RANGE).unwrap());
}

/// The filling indicator drops below 1 at a low inlet pressure and a high
/// speed, and stays above 1 at the nominal point (above).
#[test]
fn the_cavitation_margin_drops_below_one_at_low_inlet_pressure_and_high_speed() {
    let mut m = bundled_model();
    m.set_real(vr::SPEED, rpm_to_rad_s(4000.0)).unwrap();
    m.set_real(vr::P_IN, bar_to_pa(0.3)).unwrap();
    m.set_real(vr::P_OUT, bar_to_pa(0.3 + 30.0)).unwrap();
    m.exit_initialization().unwrap();
    let margin = get(&m, vr::CAVITATION_MARGIN);
    println!(
        "4000 rpm, p_in 0.3 bar: p_pocket_min {:.4} bar, margin {margin:.3}",
        pa_to_bar(get(&m, vr::P_POCKET_MIN))
    );
    assert!(margin < 1.0, "{margin}");
}

/// `out_of_range` follows the journal bearings' load: with 1 mm long
/// bearings (`--set bearings.length_mm=1`) the film cannot carry the load
/// at 200 bar, 1000 rpm, 60 degC (the periodic start says so) and carries
/// it at 10 bar; stepped at 200 bar the output is set at every call, and
/// it clears once the pump is back at 10 bar (it is over the last call's
/// steps, the results' flags over the last mesh period), where before it
/// stayed set for the rest of the run.
#[test]
fn out_of_range_clears_when_the_bearings_carry_the_load_again() {
    let d = PumpDesign::load(None, &["bearings.length_mm=1".to_string()]).unwrap();
    let mut m = GearPumpFmu::with_pump(Arc::new(Pump::new(d.design)));
    m.set_real(vr::P_OUT, ATMOSPHERE_PA + bar_to_pa(200.0))
        .unwrap();
    m.exit_initialization().unwrap();
    assert!(
        m.get_boolean(vr::OUT_OF_RANGE).unwrap(),
        "200 bar at the start"
    );
    let h = 1.0e-3;
    let mut t = 0.0;
    let mut run = |m: &mut GearPumpFmu, bar: f64, calls: usize| {
        m.set_real(vr::P_OUT, ATMOSPHERE_PA + bar_to_pa(bar))
            .unwrap();
        let mut flags = Vec::new();
        for _ in 0..calls {
            m.do_step(t, h).unwrap();
            t += h;
            flags.push(m.get_boolean(vr::OUT_OF_RANGE).unwrap());
        }
        flags
    };
    // a mesh period at 1000 rpm is 4.3 ms
    let high = run(&mut m, 200.0, 10);
    assert!(high.iter().all(|&f| f), "at 200 bar: {high:?}");
    let low = run(&mut m, 10.0, 20);
    assert!(!low[19], "back at 10 bar: {low:?}");
}

/// FMUs of different designs built from one binary carry different GUIDs
/// (importers cache and match FMUs by GUID), the bundled design's FMU
/// keeps the model's own, and an instance refuses a GUID that is not its
/// resources' design's: the GUID of another design's XML with these
/// resources is a "GUID mismatch" at `fmi2Instantiate`, its own is taken.
#[test]
fn fmus_of_different_designs_carry_different_guids() {
    use gearpump::fmi2::instance::{Instance, Logger};
    use gearpump::fmi2::types::{fmi2CallbackFunctions, fmi2CoSimulation};
    let seed = PumpDesign::load(None, &[]).unwrap();
    let a = PumpDesign::load(None, &["clearance.tip_um=33.5".into()]).unwrap();
    let b = PumpDesign::load(None, &["clearance.tip_um=35".into()]).unwrap();
    let (gs, ga, gb) = (
        GearPumpFmu::guid_for_design(&seed.toml),
        GearPumpFmu::guid_for_design(&a.toml),
        GearPumpFmu::guid_for_design(&b.toml),
    );
    assert_eq!(gs, GearPumpFmu::GUID);
    assert!(ga != gs && gb != gs && ga != gb, "{gs} {ga} {gb}");
    // the form of a GUID: {8-4-4-4-12 hex digits}
    for g in [&ga, &gb] {
        let inner = g.strip_prefix('{').and_then(|s| s.strip_suffix('}'));
        let groups: Vec<&str> = inner.expect("braces").split('-').collect();
        let lens: Vec<usize> = groups.iter().map(|s| s.len()).collect();
        assert_eq!(lens, [8, 4, 4, 4, 12], "{g}");
        assert!(groups
            .iter()
            .all(|s| s.chars().all(|c| c.is_ascii_hexdigit())));
    }
    // the XML of each names its own
    let xml_a = gearpump::fmi2::xml::model_description_xml_for::<GearPumpFmu>(
        &GearPumpFmu::variables_for(&a.design),
        &ga,
    );
    assert!(xml_a.contains(&format!("guid=\"{ga}\"")));
    // resources of design a: the instance expects a's GUID
    let dir = temp_dir("fmu-guid");
    let res = dir.join("resources");
    std::fs::create_dir_all(&res).unwrap();
    for (name, bytes) in GearPumpFmu::resource_files_for(&a.toml, a.design.clone()) {
        std::fs::write(res.join(name), bytes).unwrap();
    }
    assert_eq!(GearPumpFmu::guid_for_resources(&res), ga);
    let uri = format!("file://{}", res.display());
    let functions = fmi2CallbackFunctions {
        logger: None,
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: std::ptr::null_mut(),
    };
    let new = |guid: &str| {
        Instance::<GearPumpFmu>::new(
            "guid",
            fmi2CoSimulation,
            guid,
            &uri,
            Logger::new(&functions),
            false,
        )
    };
    for other in [&gb, &gs] {
        let err = new(other).err().expect("another design's GUID refused");
        assert!(
            err.contains("GUID mismatch") && err.contains(ga.as_str()),
            "{err}"
        );
    }
    assert!(new(&ga).is_ok());
}
