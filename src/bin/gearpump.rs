#![forbid(unsafe_code)]
//! The `gearpump` command line: parses, calls the library, prints.
//! Exit codes: 0 success, 2 bad input (message names the field), 1 otherwise.

use clap::{Args, Parser, Subcommand};
use gearpump::design::{self, Design};
use gearpump::model::{Inputs, Options, Pump, SampleClearances, Simulation};
use gearpump::units::*;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Instant;

#[derive(Parser)]
#[command(
    name = "gearpump",
    version,
    about = "Lumped-parameter model of external gear pumps (Battarra & Mucchi 2020)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate one operating point to the periodic steady state.
    Simulate(SimulateArgs),
    /// Simulate every test of a measured campaign with its own clearances (trace-driven) and compute the seed's statistics.
    Campaign(CampaignArgs),
    /// Write a synthetic measured campaign: a drawn population, a truth model with optional hidden effects, rig noise.
    Synth(SynthArgs),
    /// Diagnose a measured campaign: what the simulation gets wrong, the physical cause, the extended model and its gain.
    Diagnose(DiagnoseArgs),
    /// Evaluate the diagnosis: detection rate per hidden effect and false-alarm rate over random synthetic campaigns.
    EvalDiagnosis(EvalArgs),
    /// Monte Carlo tolerance analysis: clearances drawn from distributions, per condition the spread of eta_v, flow and torque, the yield against a specification and each clearance's share of the variance (Sobol indices).
    Montecarlo(MontecarloArgs),
    /// Write GearPump.fmu (or, with --model transmission-circuit, TransmissionCircuit.fmu; FMI 2.0 co-simulation) from this build's libraries.
    Fmu(FmuArgs),
}

#[derive(Args)]
struct FmuArgs {
    /// Where to write the FMU (default: target/fmu/<modelIdentifier>.fmu).
    #[arg(long, value_name = "PATH")]
    out: Option<PathBuf>,
    /// Which FMU: gear-pump (GearPump.fmu) or transmission-circuit (TransmissionCircuit.fmu).
    #[arg(long, value_name = "NAME", default_value = "gear-pump")]
    model: String,
    /// Pump design (TOML) the FMU is built for, with its extension keys and a sample's clearances (gear-pump only); the bundled seed-paper pump when omitted.
    #[arg(long, value_name = "FILE")]
    design: Option<PathBuf>,
    /// Override a design value by its dotted TOML path (repeatable), e.g. clearance.tip_um=32.
    #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
    set: Vec<String>,
    /// Write a population instead: an SSP file (default: target/fmu/<CSV stem>.ssp) holding GearPump.fmu and one SSV parameter set per pump sample of this measured campaign CSV (its clearances).
    #[arg(long, value_name = "CAMPAIGN.csv")]
    population: Option<PathBuf>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
struct DesignArgs {
    /// Pump design (TOML); the bundled seed-paper pump when omitted.
    #[arg(long, value_name = "FILE")]
    design: Option<PathBuf>,
    /// Override a design value by its dotted TOML path (repeatable), e.g. clearance.lateral_um=12.
    #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
    set: Vec<String>,
}

#[derive(Args)]
struct SimulateArgs {
    #[command(flatten)]
    design: DesignArgs,
    /// Driving shaft speed, rpm.
    #[arg(long, value_name = "RPM")]
    speed: f64,
    /// Delivery pressure, bar gauge (above the inlet pressure).
    #[arg(long, value_name = "BAR", allow_negative_numbers = true)]
    pressure: f64,
    /// Oil temperature, degC.
    #[arg(long, value_name = "DEGC", allow_negative_numbers = true)]
    temp: f64,
    /// Suction (inlet) pressure, bar absolute.
    #[arg(long, value_name = "BAR_ABS", default_value_t = 1.01325)]
    inlet_pressure: f64,
    /// A pump sample's measured clearances, um: TIP1,TIP2,BRG1,BRG2.
    #[arg(long, value_name = "TIP1,TIP2,BRG1,BRG2")]
    sample_clearances: Option<String>,
    /// Keep the gear centres at the bearing centres.
    #[arg(long)]
    no_micromotion: bool,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
    /// Write per-angle CSV traces into this directory.
    #[arg(long, value_name = "DIR")]
    trace: Option<PathBuf>,
}

/// An error with its exit code.
struct Failure {
    code: u8,
    message: String,
}

fn bad(message: impl Into<String>) -> Failure {
    Failure {
        code: 2,
        message: message.into(),
    }
}

fn fail(message: impl Into<String>) -> Failure {
    Failure {
        code: 1,
        message: message.into(),
    }
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    let result = match cli.command {
        Command::Simulate(a) => simulate(a),
        Command::Fmu(a) => fmu(a),
        Command::Campaign(a) => campaign(a),
        Command::Synth(a) => synth(a),
        Command::Diagnose(a) => diagnose(a),
        Command::EvalDiagnosis(a) => eval_diagnosis(a),
        Command::Montecarlo(a) => montecarlo(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            eprintln!("gearpump: {}", f.message);
            ExitCode::from(f.code)
        }
    }
}

/// `gearpump fmu`: packages the cdylib built beside this executable (see
/// `gearpump::fmi2::package::build_fmu_beside_exe`).
fn fmu(a: FmuArgs) -> Result<(), Failure> {
    use gearpump::fmi2::FmuModel;
    let model = FmuModel::from_name(&a.model).ok_or_else(|| {
        bad(format!(
            "--model: unknown model {:?} (gear-pump or transmission-circuit)",
            a.model
        ))
    })?;
    let design = if a.design.is_some() || !a.set.is_empty() {
        if model != FmuModel::GearPump {
            return Err(bad(format!(
                "--design/--set: apply to the gear pump only, not to {}",
                model.model_identifier()
            )));
        }
        let d = gearpump::fmi2::PumpDesign::load(a.design.as_deref(), &a.set)
            .map_err(|e| bad(format!("--design: {e}")))?;
        Some(d)
    } else {
        None
    };
    if let Some(csv) = &a.population {
        if model != FmuModel::GearPump {
            return Err(bad(format!(
                "--population: applies to the gear pump only, not to {}",
                model.model_identifier()
            )));
        }
        return fmu_population(csv, a.out.as_deref(), design.as_ref(), a.json);
    }
    // an impossible --out is bad input, found before anything is built;
    // the folders the packaging makes for it are removed when it fails
    let new_dirs = match &a.out {
        Some(out) => fmu_out_path(out)?,
        None => Vec::new(),
    };
    let p = gearpump::fmi2::package::build_model_fmu_beside_exe_with(
        model,
        a.out.as_deref(),
        design.as_ref(),
    )
    .map_err(|e| {
        remove_new_dirs(&new_dirs);
        fail(e.to_string())
    })?;
    if p.debug_build {
        eprintln!(
            "gearpump: note: packaged a debug build of the library (slow); use `cargo run --release -- fmu`"
        );
    }
    if a.json {
        let out = json!({"fmu": p.path, "model_identifier": model.model_identifier(),
                         "guid": model.guid(), "stripped": p.stripped});
        println!("{out}");
    } else {
        println!("{}", p.path.display());
    }
    Ok(())
}

/// Checks `--out PATH` of `gearpump fmu` before any work (exit 2 naming
/// `--out` and the path): a file path, not an existing folder nor a name
/// ending in a separator, whose parent is a folder or can be made (its
/// nearest existing ancestor is a folder). Returns the folders that do not
/// exist yet, innermost first (see [`remove_new_dirs`]).
fn fmu_out_path(out: &Path) -> Result<Vec<PathBuf>, Failure> {
    check_out("--out", out, true)?;
    // the folders the write will make, innermost first
    let mut new_dirs = Vec::new();
    let mut dir = out.parent();
    while let Some(d) = dir.filter(|d| !d.as_os_str().is_empty() && !d.exists()) {
        new_dirs.push(d.to_path_buf());
        dir = d.parent();
    }
    Ok(new_dirs)
}

/// Removes the folders [`fmu_out_path`] found missing, innermost first,
/// when they are empty (a failed `gearpump fmu` leaves no folder behind).
fn remove_new_dirs(new_dirs: &[PathBuf]) {
    for d in new_dirs {
        let _ = std::fs::remove_dir(d);
    }
}

/// `gearpump fmu --population CSV`: the pumps of a measured campaign (one
/// per sample, its clearances) as an SSP file around GearPump.fmu
/// (`gearpump::fmi2::ssp`). Every input is checked before anything is
/// built or any folder made: the campaign as `campaign` reads it (exit 2
/// naming the file, row and column; a sample id of at most
/// `limits::SAMPLE_ID_MAX_CHARS` characters), at least one pump, each
/// sample's clearances the same on all its rows, each id fit to name an
/// SSP component (`ssp::check_pumps`), `--out` a file path that can be
/// written. The FMU is built in a scratch folder under the system's
/// temporary folder; the folders made for `--out` are removed on failure.
fn fmu_population(
    csv: &std::path::Path,
    out: Option<&std::path::Path>,
    design: Option<&gearpump::fmi2::PumpDesign>,
    json: bool,
) -> Result<(), Failure> {
    use gearpump::fmi2::ssp::{check_pumps, write_population_ssp, PopulationPump, SspError};
    let campaign = gearpump::campaign::data::read_campaign(csv)
        .map_err(|e| bad(format!("--population: {e}")))?;
    let mut pumps: Vec<PopulationPump> = Vec::new();
    for r in &campaign.rows {
        let p = PopulationPump {
            sample: r.sample.clone(),
            tip: r.tip_clearance,
            bearing: r.bearing_clearance,
        };
        match pumps.iter().find(|q| q.sample == p.sample) {
            None => pumps.push(p),
            Some(q) if *q == p => {}
            Some(_) => {
                return Err(bad(format!(
                "--population: {}: row {}: sample {} has other clearances than on its first row",
                campaign.file, r.row, r.sample
            )))
            }
        }
    }
    if pumps.is_empty() {
        return Err(bad(format!(
            "--population: {}: no pumps (no data rows)",
            campaign.file
        )));
    }
    if let Err(e) = check_pumps(&pumps) {
        // the first row of the sample named, when there is one
        let row = match &e {
            SspError::BadName(s) => campaign.rows.iter().find(|r| &r.sample == s),
            _ => None,
        }
        .map(|r| r.row);
        return Err(bad(match row {
            Some(row) => format!(
                "--population: {}: row {row}, column sample: {e}",
                campaign.file
            ),
            None => format!("--population: {}: {e}", campaign.file),
        }));
    }
    let stem = csv
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("population")
        .to_string();
    let out = out
        .map(std::path::Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("target/fmu").join(format!("{stem}.ssp")));
    let new_dirs = fmu_out_path(&out)?;
    // the FMU in a scratch folder while it is packed (removed with it)
    let scratch = gearpump::fmi2::package::ScratchDir::new("population")
        .map_err(|e| fail(format!("{}: {e}", std::env::temp_dir().display())))?;
    let fmu_tmp = scratch.path().join("GearPump.fmu");
    let written = gearpump::fmi2::package::build_model_fmu_beside_exe_with(
        gearpump::fmi2::FmuModel::GearPump,
        Some(&fmu_tmp),
        design,
    )
    .map_err(|e| fail(e.to_string()))
    .and_then(|p| {
        if let Some(parent) = new_dirs.first() {
            std::fs::create_dir_all(parent)
                .map_err(|e| fail(format!("{}: {e}", parent.display())))?;
        }
        write_population_ssp(&out, &stem, &p.path, &pumps)
            .map_err(|e| match e {
                SspError::Io { .. } | SspError::Zip(_) => fail(e.to_string()),
                _ => bad(format!("--population: {}: {e}", campaign.file)),
            })
            .map(|()| p)
    });
    drop(scratch);
    if written.is_err() {
        remove_new_dirs(&new_dirs);
    }
    let p = written?;
    if p.debug_build {
        eprintln!(
            "gearpump: note: packaged a debug build of the library (slow); use `cargo run --release -- fmu`"
        );
    }
    if json {
        let samples: Vec<&str> = pumps.iter().map(|p| p.sample.as_str()).collect();
        println!(
            "{}",
            json!({"ssp": out, "pumps": samples.len(), "samples": samples})
        );
    } else {
        println!("{}", out.display());
    }
    Ok(())
}

/// Checks an output path before any work
/// (`gearpump::campaign::io::check_out`: a folder must not be a file, a
/// file must not be a folder, the nearest existing part must be writable).
/// Exit 2 naming `flag` and the path otherwise.
fn check_out(flag: &str, path: &Path, file: bool) -> Result<(), Failure> {
    gearpump::campaign::io::check_out(path, file).map_err(|why| bad(format!("{flag}: {why}")))
}

fn load_design(a: &DesignArgs) -> Result<Design, Failure> {
    design::load(a.design.as_deref(), &a.set).map_err(|e| bad(e.to_string()))
}

fn finite(name: &str, v: f64) -> Result<f64, Failure> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(bad(format!("--{name}: must be a finite number, got {v}")))
    }
}

fn parse_sample(text: &str) -> Result<[f64; 4], Failure> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if parts.len() != 4 {
        return Err(bad(format!(
            "--sample-clearances: expected four values TIP1,TIP2,BRG1,BRG2 in um, got `{text}`"
        )));
    }
    let names = ["TIP1", "TIP2", "BRG1", "BRG2"];
    let mut v = [0.0; 4];
    for i in 0..4 {
        let x: f64 = parts[i].parse().map_err(|_| {
            bad(format!(
                "--sample-clearances: {} is not a number: `{}`",
                names[i], parts[i]
            ))
        })?;
        if !(x.is_finite() && x > 0.0) {
            return Err(bad(format!(
                "--sample-clearances: {} must be > 0 um, got {x}",
                names[i]
            )));
        }
        v[i] = x;
    }
    Ok(v)
}

/// The pump of `design`, its section tables from the table cache
/// (`geometry::cache`: `$GEARPUMP_TABLE_CACHE`, `off` for none, else the
/// user's cache folder), and where they came from: "built", "cached" or
/// "built (cache refused: why)". A refused or unwritable cache only costs
/// the build; it is said on stderr when a file was refused.
fn pump_with_table_cache(design: Design) -> (Pump, String) {
    let (pump, source) = Pump::with_env_cache(design);
    if let gearpump::geometry::cache::Source::Refused(path, why) = &source {
        eprintln!(
            "gearpump: note: table cache {} refused ({why}); tables built afresh",
            path.display()
        );
    }
    (pump, source.label())
}

fn simulate(a: SimulateArgs) -> Result<(), Failure> {
    if let Some(dir) = &a.trace {
        check_out("--trace", dir, false)?;
    }
    let start = Instant::now();
    let design = load_design(&a.design)?;
    let limit = |flag: &str, range: gearpump::limits::Range, v: f64| {
        range.check(v).map_err(|e| bad(format!("--{flag}: {e}")))
    };
    let speed = limit("speed", gearpump::limits::SPEED_RPM, a.speed)?;
    let pressure = limit("pressure", gearpump::limits::PRESSURE_BAR, a.pressure)?;
    let temp = finite("temp", a.temp)?;
    let t_k = celsius_to_kelvin(temp);
    if !design.oil.in_range(t_k) {
        return Err(bad(format!(
            "--temp: {temp} degC is outside the oil model's range [{}, {}] degC",
            kelvin_to_celsius(design.oil.t_min_k),
            kelvin_to_celsius(design.oil.t_max_k)
        )));
    }
    let p_in = limit(
        "inlet-pressure",
        gearpump::limits::INLET_BAR_ABS,
        a.inlet_pressure,
    )?;
    gearpump::limits::delivery_bar_abs(p_in, pressure)
        .map_err(|e| bad(format!("--pressure with --inlet-pressure: {e}")))?;
    let mut sample = SampleClearances::nominal(&design);
    if let Some(s) = &a.sample_clearances {
        let v = parse_sample(s)?;
        for (x, name) in v.iter().zip(["TIP1", "TIP2", "BRG1", "BRG2"]) {
            limit("sample-clearances", gearpump::limits::clearance(name), *x)?;
        }
        sample.tip = [um_to_m(v[0]), um_to_m(v[1])];
        sample.bearing = [um_to_m(v[2]), um_to_m(v[3])];
    }
    let inputs = Inputs {
        omega: rpm_to_rad_s(speed),
        p_suction: bar_to_pa(p_in),
        p_delivery: bar_to_pa(p_in + pressure),
        temp_k: t_k,
        measured_torque: None,
    };
    let (pump, tables) = pump_with_table_cache(design);
    let pump = Arc::new(pump);
    warn_groove_bridge(&pump);
    let options = Options {
        micromotion: !a.no_micromotion,
    };
    // the design's clearance growth and Barus keys act per operating point
    // (the effect model of campaigns)
    let model =
        gearpump::campaign::effects::EffectModel::on(&pump, &[]).map_err(|e| bad(e.to_string()))?;
    let mut sim = model
        .simulation(inputs, sample, options)
        .map_err(|e| bad(e.to_string()))?;
    let setup_ms = start.elapsed().as_secs_f64() * 1e3;
    let summary = sim.run_periodic().map_err(|e| fail(e.to_string()))?;
    let solve_ms = start.elapsed().as_secs_f64() * 1e3 - setup_ms;
    let warnings = summary.warnings(sim.unconverged_coupling_steps(), sim.bearing_overload());
    for w in &warnings {
        eprintln!("gearpump: warning: {w}");
    }
    let torque = summary.torque;
    let eta_hm = summary.eta_hm;
    if let Some(dir) = &a.trace {
        write_trace(dir, &mut sim, &pump)?;
    }
    use gearpump::campaign::point::{point_json, PointSpec, PointTimes};
    let wall_ms = start.elapsed().as_secs_f64() * 1e3;
    let point = PointSpec {
        speed_rpm: speed,
        pressure_bar: pressure,
        temp_c: temp,
        inlet_pressure_bar_abs: p_in,
        micromotion: !a.no_micromotion,
    };
    let times = PointTimes {
        wall_ms,
        setup_ms,
        solve_ms,
        tables: tables.clone(),
    };
    let out = point_json(&pump, &sim, &summary, &sample, &point, &warnings, &times);
    if a.json {
        println!("{out}");
    } else {
        println!(
            "displacement      {:.4} cm^3/rev",
            m3_to_cm3(pump.displacement)
        );
        println!("delivered flow    {:.4} l/min", m3_s_to_lpm(summary.flow));
        println!("eta_v             {:.4}", summary.eta_v);
        println!(
            "flow ripple       {:.4} l/min peak-to-peak",
            m3_s_to_lpm(summary.flow_ripple)
        );
        println!("shaft torque      {:.4} N m (eta_hm {:.4})", torque, eta_hm);
        println!(
            "revolutions       {:.2} ({:.0} ms: setup {:.0} ms with the tables {tables}, solve {:.0} ms)",
            summary.revolutions, wall_ms, setup_ms, solve_ms
        );
        print_losses(summary.losses.as_ref());
    }
    Ok(())
}

/// The loss budget as text: where the flow goes.
fn print_losses(b: Option<&gearpump::losses::LossBudget>) {
    let Some(b) = b else {
        println!("loss budget       not defined without a pressure rise");
        return;
    };
    println!("where the flow goes (% of Vm n; negative = gained):");
    let label = |name: &str| match name {
        "tip_poiseuille" => "tip gaps, pressure-driven",
        "tip_couette" => "tip gaps, drag",
        "lateral" => "lateral faces",
        "bearings" => "bearings and by-pass",
        "mesh_zone" => "meshing zone, grooves",
        _ => "compressibility, ports",
    };
    for (name, v) in b.parts() {
        println!("  {:<28}{:>8.3}", label(name), 100.0 * v);
    }
    println!("  {:<28}{:>8.3}", "total", 100.0 * b.total);
    println!("  {:<28}{:>8.3}", "1 - Q/(Vm n)", 100.0 * b.deficit);
}

/// Warns on stderr when the relief grooves bridge delivery and suction.
fn warn_groove_bridge(pump: &Pump) {
    if let Some(b) = &pump.groove_bridge {
        let ranges: Vec<String> = b
            .ranges_deg
            .iter()
            .map(|(a, z)| format!("{a:.2}-{z:.2} deg"))
            .collect();
        let rho = pump.design.oil.density(celsius_to_kelvin(60.0));
        let share = b.flow(30.0e5, rho) / (pump.displacement * 1000.0 / 60.0);
        eprintln!(
            "gearpump: warning: the relief grooves bridge delivery and suction through the trapped volume at {} of each mesh period ({:.0} % of it): up to {:.1} % of Vm n at 1000 rpm / 30 bar (set casing.*_groove_edge_mm = \"auto\")",
            ranges.join(", "),
            100.0 * b.period_fraction,
            100.0 * share
        );
    }
}

/// Marches one more revolution recording every step and writes into `dir`:
/// `trace.csv` (angle, delivered flow, chamber pressures, gauge pressure of
/// every tooth space, gear centre positions and the tip clearance of every
/// tooth, at mid face width; columns follow physical spaces and teeth round
/// the casing), `pocket_pressure.svg` (one space of each gear round its
/// revolution), `trapped_volume.svg` (over a mesh period: the highest and
/// lowest pressure of the pockets in the meshing zone and the relief
/// grooves' Cd*A open to the trapped ones, those with no bore opening) and `centre_loci.svg` (gear centre loci over
/// a mesh period at 10, 20, 30 and 40 bar at the run's speed and
/// temperature).
fn write_trace(dir: &Path, sim: &mut Simulation, pump: &Pump) -> Result<(), Failure> {
    use gearpump::plots::{panels, Series};
    std::fs::create_dir_all(dir).map_err(|e| fail(format!("--trace {}: {e}", dir.display())))?;
    let z = pump.tables.z;
    let per = pump.steps_per_period();
    let n = per * z[0];
    let p_s = sim.inputs().p_suction;
    let mut csv = String::from("theta_deg,flow_lpm,p_inlet_bar,p_outlet_bar");
    for (g, name) in [(0usize, "drive"), (1, "driven")] {
        for k in 0..z[g] {
            csv.push_str(&format!(",p_{name}_space{k:02}_bar"));
        }
    }
    csv.push_str(",x_drive_um,y_drive_um,x_driven_um,y_driven_um");
    for (g, name) in [(0usize, "drive"), (1, "driven")] {
        for k in 0..z[g] {
            csv.push_str(&format!(",h_tip_{name}_tooth{k:02}_um"));
        }
    }
    csv.push('\n');
    let mut space_p: [Vec<(f64, f64)>; 2] = [Vec::new(), Vec::new()];
    // over the first mesh period: the highest and lowest pressure of the
    // pockets in the meshing zone, and the relief grooves' Cd*A open to them
    let mut mesh_p: [Vec<(f64, f64)>; 2] = [Vec::new(), Vec::new()];
    let mut groove_a: [Vec<(f64, f64)>; 2] = [Vec::new(), Vec::new()];
    for step in 0..n {
        let o = sim.step().map_err(|e| fail(e.to_string()))?;
        let tp = sim.trace(&o);
        if step < per {
            let angle = (step + 1) as f64 * pump.tables.dtheta.to_degrees();
            for (v, p) in mesh_p.iter_mut().zip(tp.meshing_pressure) {
                v.push((angle, pa_to_bar(p - p_s)));
            }
            for (v, a) in groove_a.iter_mut().zip(tp.trapped_groove_cda) {
                v.push((angle, a * 1e6));
            }
        }
        csv.push_str(&format!(
            "{},{},{},{}",
            tp.theta.to_degrees(),
            m3_s_to_lpm(tp.q_out),
            pa_to_bar(tp.p_inlet - p_s),
            pa_to_bar(tp.p_outlet - p_s)
        ));
        for (g, (pressures, first)) in tp.space_pressure.iter().zip(&mut space_p).enumerate() {
            for (space, &p) in pressures.iter().enumerate() {
                let p = pa_to_bar(p - p_s);
                csv.push_str(&format!(",{p}"));
                if space == 0 {
                    let psi = pump
                        .pair
                        .space_centre(g, 0, tp.theta)
                        .to_degrees()
                        .rem_euclid(360.0);
                    first.push((psi, p));
                }
            }
        }
        for e in tp.offset {
            csv.push_str(&format!(",{},{}", m_to_um(e[0]), m_to_um(e[1])));
        }
        for h in tp.tip_clearance.iter().flatten() {
            csv.push_str(&format!(",{}", m_to_um(*h)));
        }
        csv.push('\n');
    }
    let path = dir.join("trace.csv");
    gearpump::campaign::io::atomic_write_text(&path, &csv)
        .map_err(|e| fail(format!("{}: {e}", path.display())))?;
    for v in space_p.iter_mut() {
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    let [p1, p2] = space_p;
    panels(
        &dir.join("pocket_pressure.svg"),
        &[
            (
                "driving gear: one tooth space",
                vec![Series {
                    label: "pressure".into(),
                    points: p1,
                }],
            ),
            (
                "driven gear: one tooth space",
                vec![Series {
                    label: "pressure".into(),
                    points: p2,
                }],
            ),
        ],
        "space centre angle from the line of centres, deg (suction side first)",
        "gauge pressure, bar",
        false,
    )
    .map_err(|e| fail(format!("pocket_pressure.svg: {e}")))?;
    let [hi, lo] = mesh_p;
    let [gd, gs] = groove_a;
    panels(
        &dir.join("trapped_volume.svg"),
        &[
            (
                "pockets in the meshing zone: gauge pressure, bar",
                vec![
                    Series {
                        label: "highest".into(),
                        points: hi,
                    },
                    Series {
                        label: "lowest".into(),
                        points: lo,
                    },
                ],
            ),
            (
                "relief grooves open to the trapped pockets: Cd A, mm^2",
                vec![
                    Series {
                        label: "delivery groove".into(),
                        points: gd,
                    },
                    Series {
                        label: "suction groove".into(),
                        points: gs,
                    },
                ],
            ),
        ],
        "driving-gear angle within the mesh period, deg",
        "bar | mm^2",
        false,
    )
    .map_err(|e| fail(format!("trapped_volume.svg: {e}")))?;
    // centre loci over one mesh period at four delivery pressures
    let mut loci: [Vec<Series>; 2] = [Vec::new(), Vec::new()];
    for bar in [10.0, 20.0, 30.0, 40.0] {
        let mut inputs = *sim.inputs();
        inputs.p_delivery = inputs.p_suction + bar_to_pa(bar);
        let mut s = Simulation::new(
            Arc::clone(sim.shared_pump()),
            inputs,
            sim.sample(),
            sim.options(),
        )
        .map_err(|e| fail(e.to_string()))?;
        s.run_periodic().map_err(|e| fail(e.to_string()))?;
        let mut pts: [Vec<(f64, f64)>; 2] = [Vec::new(), Vec::new()];
        for _ in 0..=per {
            let o = s.step().map_err(|e| fail(e.to_string()))?;
            for (pt, e) in pts.iter_mut().zip(o.offset) {
                pt.push((m_to_um(e[0]), m_to_um(e[1])));
            }
        }
        let [a, b] = pts;
        loci[0].push(Series {
            label: format!("{bar} bar"),
            points: a,
        });
        loci[1].push(Series {
            label: format!("{bar} bar"),
            points: b,
        });
    }
    let [l1, l2] = loci;
    panels(
        &dir.join("centre_loci.svg"),
        &[
            ("driving gear centre over a mesh period", l1),
            ("driven gear centre over a mesh period", l2),
        ],
        "x, um (towards the driven gear)",
        "y, um (towards the suction port)",
        true,
    )
    .map_err(|e| fail(format!("centre_loci.svg: {e}")))?;
    Ok(())
}

// ------------------------------------------------------------ campaign, synth

#[derive(Args)]
struct CampaignArgs {
    #[command(flatten)]
    input: CampaignInput,
    /// Output folder: tests.csv, conditions.csv, report.md, plots (and the resume journal while running).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
}

/// What `campaign` and `diagnose` simulate, and how.
#[derive(Args)]
struct CampaignInput {
    #[command(flatten)]
    design: DesignArgs,
    /// Measured campaign CSV (one row per test; see README).
    #[arg(long, value_name = "CSV")]
    data: PathBuf,
    /// Parallel simulations (default: all cores; more than the cores available is clamped to them, with a note).
    #[arg(long, value_name = "N")]
    jobs: Option<usize>,
    /// Keep the gear centres at the bearing centres (faster; for diagnose: the base model and every candidate).
    #[arg(long)]
    no_micromotion: bool,
}

impl CampaignInput {
    fn source(&self) -> Result<gearpump::campaign::run::DesignSource, Failure> {
        gearpump::campaign::run::DesignSource::load(self.design.design.as_deref(), &self.design.set)
            .map_err(run_failure)
    }
}

#[derive(Args)]
struct SynthArgs {
    #[command(flatten)]
    design: DesignArgs,
    /// The campaign CSV to write.
    #[arg(long, value_name = "CSV")]
    out: PathBuf,
    /// Number of pump samples.
    #[arg(long, value_name = "N", default_value_t = 20)]
    samples: usize,
    /// Seed of the random draws (same seed, same file).
    #[arg(long, value_name = "S", default_value_t = 1)]
    seed: u64,
    /// Hidden effect of the truth model (repeatable), e.g. thermal_clearance=0.15 (um/K).
    #[arg(long = "effect", value_name = "NAME=VALUE")]
    effect: Vec<String>,
    /// Relative 1-sigma noise of the readings: REL (flow and torque) or FLOW,TORQUE.
    #[arg(long, value_name = "REL", default_value = "0.005,0.002")]
    noise: String,
    /// Working conditions: `paper` (seed Table 2) or a CSV with pressure_bar,speed_rpm,temp_c.
    #[arg(long, value_name = "paper|FILE", default_value = "paper")]
    conditions: String,
    /// Parallel simulations (default: all cores; more than the cores available is clamped to them, with a note).
    #[arg(long, value_name = "N")]
    jobs: Option<usize>,
    /// Truth model without gear micromotion.
    #[arg(long)]
    no_micromotion: bool,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
}

/// `--jobs`: 0 refused, more than the cores clamped with a note on stderr
/// (docs/interfaces.md section 2).
fn jobs(requested: Option<usize>) -> Result<Option<usize>, Failure> {
    let (n, asked) = gearpump::campaign::run::pool_size(requested).map_err(run_failure)?;
    if let Some(asked) = asked {
        eprintln!("gearpump: note: --jobs {asked} is more than the {n} cores available: using {n}");
    }
    Ok(Some(n))
}

fn run_failure(e: gearpump::campaign::run::RunError) -> Failure {
    use gearpump::campaign::run::{RunError, Setting};
    // the library names its settings in its own terms; here they are flags
    if let RunError::Setting { setting, message } = &e {
        let flag = match setting {
            Setting::Jobs => "--jobs",
            Setting::Samples => "--samples",
            Setting::Noise => "--noise",
            Setting::Data => "--data",
            Setting::Output => "--out",
            Setting::Effects => "--effects",
            Setting::Trials => "--trials",
            Setting::Only => "--only",
            Setting::Families => "--families",
        };
        return bad(format!("{flag}: {message}"));
    }
    if e.is_bad_input() {
        bad(e.to_string())
    } else {
        fail(e.to_string())
    }
}

fn campaign(a: CampaignArgs) -> Result<(), Failure> {
    check_out("--out", &a.out, false)?;
    gearpump::campaign::io::result_places_free(&a.out).map_err(|e| bad(format!("--out: {e}")))?;
    use gearpump::campaign::run::{run_campaign, CampaignOptions};
    let start = Instant::now();
    let source = a.input.source()?;
    let options = CampaignOptions {
        jobs: jobs(a.input.jobs)?,
        micromotion: !a.input.no_micromotion,
    };
    let progress = ProgressObserver::stderr("campaign");
    let result =
        run_campaign(&source, &a.input.data, &a.out, options, &progress).map_err(run_failure)?;
    for f in &result.failed {
        eprintln!(
            "gearpump: warning: row {} (sample {}): no simulated result: {}",
            f.row, f.sample, f.message
        );
    }
    for w in &result.warnings {
        eprintln!("gearpump: warning: {w}");
    }
    let wall_ms = start.elapsed().as_secs_f64() * 1e3;
    if a.json {
        println!("{}", result.to_json(&a.out, wall_ms));
    } else {
        println!("{}", result.summary_text(&a.out));
    }
    failed_rows(result.failed.len(), result.campaign.rows.len(), &a.out)
}

/// Exit 1 when rows of the campaign could not be simulated: the outputs
/// are written (those rows with empty simulated cells, left out of the
/// statistics), but they are not the whole campaign (docs/interfaces.md
/// section 5).
fn failed_rows(failed: usize, rows: usize, out: &Path) -> Result<(), Failure> {
    if failed == 0 {
        return Ok(());
    }
    Err(fail(format!(
        "{failed} of {rows} rows could not be simulated (listed above and in {}): their simulated cells are empty and they are left out of the statistics",
        out.join("report.md").display()
    )))
}

fn synth(a: SynthArgs) -> Result<(), Failure> {
    check_out("--out", &a.out, true)?;
    use gearpump::campaign::effects::parse_effects;
    use gearpump::campaign::synth::{conditions_from_arg, run_synth, Noise, SynthOptions};
    let design = load_design(&a.design)?;
    let options = SynthOptions {
        samples: a.samples,
        seed: a.seed,
        // the library says "effect NAME=VALUE: ..."; here it is the flag
        effects: parse_effects(&a.effect).map_err(|e| bad(format!("--{e}")))?,
        noise: Noise::parse(&a.noise).map_err(run_failure)?,
        conditions: conditions_from_arg(&a.conditions)
            .map_err(|e| bad(format!("--conditions: {}: {e}", a.conditions)))?,
        conditions_label: a.conditions.clone(),
        micromotion: !a.no_micromotion,
        jobs: jobs(a.jobs)?,
    };
    let progress = ProgressObserver::stderr("synth");
    let v = run_synth(&design, &options, &a.out, &progress).map_err(run_failure)?;
    if a.json {
        println!("{v}");
    } else {
        println!(
            "wrote {} synthetic tests ({} samples x {} conditions) to {}",
            v["tests"],
            a.samples,
            options.conditions.len(),
            a.out.display()
        );
    }
    Ok(())
}

// ---------------------------------------------------------------- montecarlo

#[derive(Args)]
struct MontecarloArgs {
    #[command(flatten)]
    design: DesignArgs,
    /// Pumps to draw (the distributions and yields use them all; the sensitivity indices pair them up).
    #[arg(long, value_name = "N", default_value_t = 200)]
    pumps: usize,
    /// Seed of the draws: pump i is drawn from its own stream of this seed (same seed, same pumps).
    #[arg(long, value_name = "S", default_value_t = 1)]
    seed: u64,
    /// Clearance distributions fitted to a measured campaign CSV (normal, each clearance's mean and standard deviation over its pumps).
    #[arg(long, value_name = "CSV", conflicts_with = "distributions")]
    fit: Option<PathBuf>,
    /// Clearance distributions from a TOML file (tables tip1_um, tip2_um, bearing1_um, bearing2_um with dist = normal|uniform|fixed; see docs/interfaces.md).
    #[arg(long, value_name = "TOML")]
    distributions: Option<PathBuf>,
    /// Working conditions: `paper` (seed Table 2) or a CSV with pressure_bar,speed_rpm,temp_c.
    #[arg(long, value_name = "paper|FILE", default_value = "paper")]
    conditions: String,
    /// A specification (repeatable; a pump must meet all), e.g. "eta_v>=0.85@500rpm,30bar,120degC"; quantities eta_v, flow_lpm, torque_nm.
    #[arg(long = "spec", value_name = "SPEC")]
    spec: Vec<String>,
    /// Skip the pick-freeze runs of the sensitivity indices (a third of the runs).
    #[arg(long)]
    no_sensitivity: bool,
    /// Pumps per chunk (one journal entry each; a resumed study redoes at most the chunks in flight).
    #[arg(long, value_name = "N", default_value_t = 8)]
    chunk: usize,
    /// Output folder: montecarlo.json, percentiles.csv, sensitivity.csv, pumps.csv, cdf.svg, tornado.svg (and the resume journal while running).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Parallel simulations (default: all cores; more than the cores available is clamped to them, with a note).
    #[arg(long, value_name = "N")]
    jobs: Option<usize>,
    /// Keep the gear centres at the bearing centres.
    #[arg(long)]
    no_micromotion: bool,
    /// Print one JSON object on stdout (the content of montecarlo.json, with the counts).
    #[arg(long)]
    json: bool,
}

fn mc_failure(e: gearpump::campaign::montecarlo::MonteCarloError) -> Failure {
    use gearpump::campaign::montecarlo::MonteCarloError as E;
    match e {
        E::Run(r) => run_failure(r),
        E::Setting { setting, message } => bad(format!("--{setting}: {message}")),
        e if e.is_bad_input() => bad(e.to_string()),
        e => fail(e.to_string()),
    }
}

fn montecarlo(a: MontecarloArgs) -> Result<(), Failure> {
    check_out("--out", &a.out, false)?;
    use gearpump::campaign::montecarlo::{
        run_study, study_json, Population, RunOptions, Spec, Study,
    };
    use gearpump::campaign::synth::conditions_from_arg;
    let start = Instant::now();
    let source =
        gearpump::campaign::run::DesignSource::load(a.design.design.as_deref(), &a.design.set)
            .map_err(run_failure)?;
    let population = if let Some(csv) = &a.fit {
        let c = gearpump::campaign::read_campaign(csv).map_err(|e| bad(format!("--fit: {e}")))?;
        Population::fitted(&c).map_err(|e| bad(format!("--fit: {e}")))?
    } else if let Some(toml) = &a.distributions {
        Population::from_toml_file(&source.design, toml)
            .map_err(|e| bad(format!("--distributions: {e}")))?
    } else {
        Population::paper(&source.design)
    };
    let specs = a
        .spec
        .iter()
        .map(|s| Spec::parse(s).map_err(|e| bad(format!("--spec: {e}"))))
        .collect::<Result<Vec<_>, _>>()?;
    let conditions =
        conditions_from_arg(&a.conditions).map_err(|e| bad(format!("--conditions: {e}")))?;
    let study = Study::new(
        &source.design,
        population,
        conditions,
        a.pumps,
        a.seed,
        !a.no_sensitivity,
        specs,
        !a.no_micromotion,
    )
    .map_err(mc_failure)?;
    let options = RunOptions {
        jobs: jobs(a.jobs)?,
        chunk: a.chunk,
    };
    let progress = ProgressObserver::stderr("montecarlo");
    let r = run_study(&source, &study, &a.out, options, &progress).map_err(mc_failure)?;
    let wall_s = start.elapsed().as_secs_f64();
    use gearpump::campaign::run::Observer;
    progress.summary(&format!(
        "montecarlo: {} runs ({} simulated, {} resumed, {} failed) in {wall_s:.1} s",
        r.summary.runs, r.simulated, r.reused, r.summary.failed_runs
    ));
    for (row, m) in r.outputs.errors.iter().take(5) {
        eprintln!("gearpump: warning: run {row}: simulation failed: {m}");
    }
    if a.json {
        let mut v = study_json(&source.label, &source.sets, &study, &r.summary);
        if let Some(m) = v.as_object_mut() {
            m.insert("out".into(), json!(a.out.display().to_string()));
            m.insert("simulated".into(), json!(r.simulated));
            m.insert("reused".into(), json!(r.reused));
            m.insert("wall_s".into(), json!(wall_s));
            m.insert(
                "files".into(),
                json!(r
                    .files
                    .iter()
                    .map(|f| f.display().to_string())
                    .collect::<Vec<_>>()),
            );
        }
        println!("{v}");
    } else {
        println!("{}", r.summary_text(&a.out));
    }
    if r.summary.failed_runs > 0 {
        return Err(fail(format!(
            "{} of {} runs could not be simulated (left out of the statistics; a failed pump fails the spec)",
            r.summary.failed_runs, r.summary.runs
        )));
    }
    Ok(())
}

// ------------------------------------------------------------------ diagnose

#[derive(Args)]
struct DiagnoseArgs {
    #[command(flatten)]
    input: CampaignInput,
    /// Output folder: the campaign's files, diagnosis.json, report.md, diagnosis.svg, extended/.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Print one line per stage and model run on stderr.
    #[arg(long, short)]
    verbose: bool,
    /// Print one JSON object on stdout (the content of diagnosis.json).
    #[arg(long)]
    json: bool,
}

fn diagnose(a: DiagnoseArgs) -> Result<(), Failure> {
    check_out("--out", &a.out, false)?;
    gearpump::campaign::io::result_places_free(&a.out).map_err(|e| bad(format!("--out: {e}")))?;
    use gearpump::diagnosis::diagnose::{run_diagnosis, DiagnoseOptions};
    let source = a.input.source()?;
    let options = DiagnoseOptions {
        jobs: jobs(a.input.jobs)?,
        micromotion: !a.input.no_micromotion,
        verbose: a.verbose,
        ..DiagnoseOptions::default()
    };
    let progress = ProgressObserver::stderr("baseline");
    let d =
        run_diagnosis(&source, &a.input.data, &a.out, options, &progress).map_err(run_failure)?;
    let failed = d.json["failed_rows"].as_u64().unwrap_or(0) as usize;
    // `tests` counts the rows the diagnosis used: the failed ones are not in it
    let rows = failed + d.json["tests"].as_u64().unwrap_or(0) as usize;
    if a.json {
        let mut v = d.json.clone();
        if let Some(m) = v.as_object_mut() {
            m.insert("out".into(), json!(a.out.display().to_string()));
        }
        println!("{v}");
        return failed_rows(failed, rows, &a.out);
    }
    let v = &d.json;
    let fmt_params = |c: &serde_json::Value| {
        c["params"]
            .as_object()
            .map(|m| {
                m.iter()
                    .map(|(k, x)| format!("{k} = {:.4e}", x.as_f64().unwrap_or(f64::NAN)))
                    .collect::<Vec<_>>()
                    .join(", ")
            })
            .unwrap_or_default()
    };
    let causes = v["causes"].as_array().cloned().unwrap_or_default();
    if let Some(first) = causes.first() {
        println!(
            "cause: {} ({}); RMSE of d {:.5} -> {:.5} (ratio {:.3}){}",
            first["effect"].as_str().unwrap_or("?"),
            fmt_params(first),
            v["gain"]["rmse_before"].as_f64().unwrap_or(f64::NAN),
            v["gain"]["rmse_after"].as_f64().unwrap_or(f64::NAN),
            v["gain"]["rmse_ratio"].as_f64().unwrap_or(f64::NAN),
            if d.out_of_family.is_empty() {
                String::new()
            } else {
                format!(" without {}", d.out_of_family.join(", "))
            }
        );
        for c in &causes[1..] {
            println!(
                "  and then: {} ({})",
                c["effect"].as_str().unwrap_or("?"),
                fmt_params(c)
            );
        }
    } else if let Some(p) = v["partial"]["effect"].as_str() {
        println!(
            "cause: none; {p} improves the fit (RMSE ratio {:.3}) but {}",
            v["partial"]["gain"]["rmse_ratio"]
                .as_f64()
                .unwrap_or(f64::NAN),
            v["partial"]["why_not_cause"].as_str().unwrap_or("")
        );
    } else if d.unexplained {
        println!("cause: none; no candidate improves the fit significantly");
    } else {
        println!(
            "cause: none (no material discrepancy); RMSE of d {:.5}",
            d.baseline_rmse
        );
    }
    if v["unexplained_by_torque"] == true {
        println!("  not explained: the measured torque contradicts the causes, and no alternative fits eta_v that it does not contradict");
    } else if d.unexplained {
        let st = &v["structure"];
        println!(
            "  not explained: material structure remains in {}{}",
            v["unexplained_features"],
            match st["share_left"].as_f64() {
                Some(share) if st["final"]["structure"].as_f64() < st["threshold"].as_f64() =>
                    format!(
                        " ({share:.2} of the discrepancy left: below one test's scatter, but more than a mechanism of the right kind leaves)"
                    ),
                _ => String::new(),
            }
        );
    }
    for x in v["remaining"].as_array().into_iter().flatten() {
        println!(
            "  remaining: {} ({}) {:.2} eta_v points{}",
            x["feature"].as_str().unwrap_or("?"),
            x["kind"].as_str().unwrap_or("?"),
            x["effect_points"].as_f64().unwrap_or(f64::NAN),
            if x["material"].as_bool() == Some(true) {
                ", material"
            } else {
                ""
            }
        );
    }
    if !d.out_of_family.is_empty() {
        println!(
            "  out-of-family pumps: {} (set aside: the verdict above is without them); with them in: cause {}, unexplained {}",
            d.out_of_family.join(", "),
            v["with_out_of_family"]["cause"].as_str().unwrap_or("none"),
            v["with_out_of_family"]["unexplained"]
        );
    }
    for c in v["population"]["cannot_tell"]
        .as_array()
        .into_iter()
        .flatten()
    {
        println!(
            "  with {} pump(s) this cannot tell {}",
            v["population"]["pumps_analysed"],
            c.as_str().unwrap_or("?")
        );
    }
    for x in v["ambiguous_with"].as_array().into_iter().flatten() {
        println!(
            "  indistinguishable from {}: {}",
            x["effect"].as_str().unwrap_or("?"),
            x["measurement"].as_str().unwrap_or("-")
        );
    }
    let tq = &v["torque"];
    if tq.is_object() {
        let params: Vec<String> = tq["params"]
            .as_array()
            .into_iter()
            .flatten()
            .map(|p| {
                format!(
                    "{} {:+.3} ({:+.3} .. {:+.3})",
                    p["candidate"].as_str().unwrap_or("?"),
                    p["theta"].as_f64().unwrap_or(f64::NAN),
                    p["interval_95"][0].as_f64().unwrap_or(f64::NAN),
                    p["interval_95"][1].as_f64().unwrap_or(f64::NAN)
                )
            })
            .collect();
        println!(
            "torque: {}; RMSE {:.4} N m{}{}",
            if params.is_empty() {
                "no cause".to_string()
            } else {
                format!("cause {}", params.join(" then "))
            },
            tq["baseline_rmse_nm"].as_f64().unwrap_or(f64::NAN),
            tq["rmse_after_nm"]
                .as_f64()
                .map(|r| format!(" -> {r:.4}"))
                .unwrap_or_default(),
            if tq["unexplained"] == true {
                "; not explained"
            } else {
                ""
            }
        );
        let check = &tq["flow_causes_check"];
        if check["worsened"] == true {
            println!(
                "  the measured torque contradicts the flow's causes: their model's torque RMSE {:.4} N m against the base model's {:.4}",
                check["extended_rmse_nm"].as_f64().unwrap_or(f64::NAN),
                check["base_rmse_nm"].as_f64().unwrap_or(f64::NAN)
            );
            let alt = &check["flowmeter_alternative"];
            if alt.is_object() {
                println!(
                    "  the instrument's alternative: a flowmeter reading {:+.2} % would leave a cross-validated RMSE of eta_v of {:.5} (the first cause's {:.5}) and the torque as measured",
                    100.0 * alt["gain"].as_f64().unwrap_or(f64::NAN),
                    alt["cv_rmse"].as_f64().unwrap_or(f64::NAN),
                    alt["cause_cv_rmse"].as_f64().unwrap_or(f64::NAN)
                );
            }
        }
    }
    for c in &causes {
        if let Some(site) = c["acts_on"].as_str() {
            println!(
                "  {} acts on: {} (the data chose among tips, bearings, lateral, radial = tips and bearings, all)",
                c["kind"].as_str().unwrap_or("?"),
                site
            );
        }
    }
    let site = &v["site_by_torque"];
    if site.is_object() {
        println!(
            "  the torque chose the site: {} leaves a torque structure of {:.4} N m against {:.4} for {}, which the flow preferred by less than its noise floor",
            v["cause"].as_str().unwrap_or("?"),
            site["torque_structure_nm"]["chosen"].as_f64().unwrap_or(f64::NAN),
            site["torque_structure_nm"]["flow_pick"].as_f64().unwrap_or(f64::NAN),
            site["flow_pick"].as_str().unwrap_or("?"),
        );
    }
    println!(
        "wrote {} (and report.md, diagnosis.svg{})",
        a.out.join("diagnosis.json").display(),
        if v["extended_design"].is_string() {
            format!(
                ", and the extended model as {}: run it with --design",
                a.out.join("extended_design.toml").display()
            )
        } else {
            String::new()
        }
    );
    failed_rows(failed, rows, &a.out)
}

#[derive(Args)]
struct EvalArgs {
    #[command(flatten)]
    design: DesignArgs,
    /// Trials per effect (and as many without an effect).
    #[arg(long, value_name = "N", default_value_t = 5)]
    trials: usize,
    /// Seed of the draws (effects, magnitudes, campaign seeds).
    #[arg(long, value_name = "S", default_value_t = 1)]
    seed: u64,
    /// Effects to hide with synth's own code, comma-separated (default, when
    /// --families is not given either: all, and `none`).
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    effects: Vec<String>,
    /// Families of campaigns made by other mechanisms: mismatched,
    /// two_effects, noise_x3, out_of_family, outside, flow_and_torque
    /// (default, when --effects is not given either: all).
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    families: Vec<String>,
    /// Pumps per synthetic campaign.
    #[arg(long, value_name = "N", default_value_t = 20)]
    samples: usize,
    /// Output folder: eval.json, eval.md and every trial's campaign and diagnosis (a trial whose folder already holds the same campaign and its diagnosis by this build is taken as it is: a stopped evaluation resumes)
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Parallel simulations (default: all cores; more than the cores available is clamped to them, with a note).
    #[arg(long, value_name = "N")]
    jobs: Option<usize>,
    /// Truth and diagnosis without gear micromotion (about twice as fast).
    #[arg(long)]
    no_micromotion: bool,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
    /// Run only these trials of the plan, by folder name (e.g.
    /// two_effects-8), comma-separated: the same campaigns as in the whole
    /// evaluation with the same seed, trials and groups.
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    only: Vec<String>,
}

fn eval_diagnosis(a: EvalArgs) -> Result<(), Failure> {
    check_out("--out", &a.out, false)?;
    use gearpump::campaign::effects::EFFECT_NAMES;
    use gearpump::campaign::run::DesignSource;
    use gearpump::diagnosis::eval::{
        run_eval, summarize_trials, table, EvalOptions, FAMILIES, NO_EFFECT,
    };
    let source =
        DesignSource::load(a.design.design.as_deref(), &a.design.set).map_err(run_failure)?;
    let both_default = a.effects.is_empty() && a.families.is_empty();
    let effects: Vec<String> = if both_default {
        EFFECT_NAMES
            .iter()
            .map(|s| s.to_string())
            .chain([NO_EFFECT.to_string()])
            .collect()
    } else {
        a.effects.iter().map(|s| s.trim().to_string()).collect()
    };
    let families: Vec<String> = if both_default {
        FAMILIES.iter().map(|s| s.to_string()).collect()
    } else {
        a.families.iter().map(|s| s.trim().to_string()).collect()
    };
    let groups: Vec<String> = effects.iter().chain(&families).cloned().collect();
    let options = EvalOptions {
        trials: a.trials,
        seed: a.seed,
        effects,
        families,
        samples: a.samples,
        jobs: jobs(a.jobs)?,
        micromotion: !a.no_micromotion,
        only: a.only.iter().map(|s| s.trim().to_string()).collect(),
    };
    let v = run_eval(&source, &a.out, &options, &mut |i, n, t| {
        if let Some(e) = &t.error {
            eprintln!(
                "eval-diagnosis: [{i}/{n}] {}: trial failed: {e}",
                t.truth.as_deref().unwrap_or("no effect")
            );
            return;
        }
        eprintln!(
            "eval-diagnosis: [{i}/{n}] {}: {}{}{}; torque: {}{}{} ({:.0} s)",
            t.truth.as_deref().unwrap_or("no effect"),
            if t.causes.is_empty() {
                "cause null".to_string()
            } else {
                format!("causes {}", t.causes.join(" + "))
            },
            if t.unexplained { ", unexplained" } else { "" },
            t.rmse_ratio
                .map(|r| format!(
                    ", RMSE ratio {r:.2}{}",
                    match (t.truth_rmse_ratio, t.floor_rmse_ratio) {
                        (Some(x), Some(f)) => format!(
                            " ({x:.2} against the noise-free truth; the truth itself scores {f:.2} on the data)"
                        ),
                        _ => String::new(),
                    }
                ))
                .unwrap_or_default(),
            if t.torque_causes.is_empty() {
                "no cause".to_string()
            } else {
                format!("causes {}", t.torque_causes.join(" + "))
            },
            if t.torque_unexplained {
                ", unexplained"
            } else {
                ""
            },
            if t.torque_false_alarm() {
                " (torque false alarm)"
            } else {
                ""
            },
            t.wall_s
        )
    })
    .map_err(run_failure)?;
    if a.json {
        println!("{v}");
    } else {
        let trials: Vec<gearpump::diagnosis::eval::Trial> =
            serde_json::from_value(v["trials"].clone()).unwrap_or_default();
        print!("{}", table(&summarize_trials(&groups, &trials)));
        println!("wrote {}", a.out.join("eval.md").display());
    }
    Ok(())
}

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;

/// A progress bar on stderr when stderr is a terminal; silent otherwise.
#[derive(Debug)]
pub struct ProgressObserver {
    bar: ProgressBar,
}

impl ProgressObserver {
    /// `label` prefixes the bar (e.g. `campaign`).
    pub fn stderr(label: &str) -> Self {
        let bar = ProgressBar::hidden();
        if std::io::stderr().is_terminal() {
            bar.set_draw_target(ProgressDrawTarget::stderr());
        }
        if let Ok(style) =
            ProgressStyle::with_template("{prefix} [{bar:40}] {pos}/{len} rows ({eta} left)")
        {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.set_prefix(label.to_string());
        ProgressObserver { bar }
    }
}

impl gearpump::campaign::run::Observer for ProgressObserver {
    fn begin(&self, total: usize, reused: usize) {
        self.bar.set_length(total as u64);
        self.bar.set_position(reused as u64);
        self.bar.reset_eta();
    }
    fn advance(&self) {
        self.bar.inc(1);
    }
    fn end(&self) {
        self.bar.finish_and_clear();
    }
    fn message(&self, text: &str) {
        // above the bar, which redraws itself below
        self.bar.suspend(|| eprintln!("{text}"));
    }
    fn stage(&self, label: &str, total: usize) {
        if let Ok(style) =
            ProgressStyle::with_template("{prefix} [{bar:40}] {pos}/{len} ({eta} left)")
        {
            self.bar.set_style(style.progress_chars("=> "));
        }
        self.bar.set_prefix(label.to_string());
        self.bar.reset();
        self.bar.set_length(total as u64);
        self.bar.set_position(0);
    }
    fn summary(&self, line: &str) {
        self.bar.suspend(|| eprintln!("{line}"));
    }
}
