//! One operating point (1000 rpm, 30 bar, 60 degC) to the periodic steady
//! state, without and with micromotion, on the bundled design. The design's look-up
//! tables are built once outside the timed loop (a campaign reuses them).
//!
//! The FMU benches step [`GearPumpFmu`] through its `CoSimModel` API (no C
//! layer, no Python) over 0.25 s of simulated time at 1 ms communication
//! steps, 30 bar, 60 degC, with micromotion, at 1000 and 4000 rpm, from the
//! periodic start (initialisation outside the timed loop): the real-time
//! factor is 0.25 s over the measured time. Before the benches the
//! machine-independent counts per angular step (Newton iterations, LU
//! factorisations, micromotion coupling iterations) are printed.
//!
//! `simulate_1000rpm_30bar_60C_micromotion_strict_start` is the micromotion
//! point with every mesh period solved at the design's tolerances (the
//! relaxed start of `run_periodic` off), for the comparison in the same run.
//!
//! `GEARPUMP_BENCH_START=1` runs none of them: it compares the relaxed and
//! the strict start over the paper's 14 conditions (see [`start_probe`]).
//!
//! `build_design_tables` times `Pump::new` on the bundled design (its pocket
//! tables: run it under `taskset -c 0` for one core), and
//! `design_tables_from_cache` the same with the section tables read from a
//! table file.
//!
//! `fmu_start_periodic` and `fmu_start_transient` time what an importer
//! waits for before the first step (issue 16 point 2): `instantiate` from a
//! resources folder as packaging writes it (the design and its section
//! tables, which are read, not built) and `exit_initialization` at 1000
//! rpm, 30 bar, 60 degC with micromotion, with `start_periodic` true (the
//! march to the periodic state) and false.
//!
//! `GEARPUMP_BENCH_PROFILE=<rpm>` runs none of them: it steps the FMU model
//! alone over 100 calls of 1 ms for an instruction profile (see
//! [`profile_only`] and docs/benchmarks.md).
//!
//! `fmu_map_*` step the `map` fidelity (issue 16 point 3; the map read
//! from a resources folder as packaging writes it) over 1 s of simulated
//! time at 1 ms steps, 30 bar, 60 degC, with and without the mesh ripple:
//! the real-time factor is 1 s over the measured time;
//! `fmu_map_1s_1ms_varying_inputs*` the same with speed, delivery pressure
//! and temperature changed before every step from a drive cycle's table
//! ([`drive_cycle`]; each step interpolates anew and the outlet volume's
//! compressibility acts). Before them the
//! real-time factors over 100 s of simulated time are printed on wall and
//! CPU time (`GEARPUMP_BENCH_PROBE_ONLY=1`: only these).
//!
//! `GEARPUMP_BENCH_SET="key=value ..."` overrides the bundled design for the
//! LP FMU benches and probes (e.g. `numerics.angle_step_deg=1.0`).
//!
//! Run: `cargo bench --bench simulate` (`-- fmu` for the FMU benches only,
//! `-- fmu_start` for the start, `-- fmu_map` for the map fidelity).

use std::sync::Arc;

use criterion::{criterion_group, Criterion};
use gearpump::design::Design;
use gearpump::fmi2::pump::{vr, GearPumpFmu};
use gearpump::fmi2::CoSimModel;
use gearpump::model::{Inputs, Options, Pump, SampleClearances, Simulation};
use gearpump::units::*;

/// Simulated time of one FMU bench iteration, s.
const FMU_SPAN: f64 = 0.25;
/// Communication step, s.
const FMU_STEP: f64 = 1.0e-3;

fn inputs(rpm: f64) -> Inputs {
    Inputs {
        omega: rpm_to_rad_s(rpm),
        p_suction: ATMOSPHERE_PA,
        p_delivery: ATMOSPHERE_PA + bar_to_pa(30.0),
        temp_k: celsius_to_kelvin(60.0),
        measured_torque: None,
    }
}

/// An FMU model at `rpm`, 30 bar, 60 degC, initialised at the periodic state.
fn fmu(pump: &Arc<Pump>, rpm: f64, micromotion: bool) -> GearPumpFmu {
    let mut m = GearPumpFmu::with_pump(Arc::clone(pump));
    m.set_boolean(vr::MICROMOTION, micromotion).unwrap();
    m.set_real(vr::SPEED, rpm_to_rad_s(rpm)).unwrap();
    m.set_real(vr::P_OUT, ATMOSPHERE_PA + bar_to_pa(30.0))
        .unwrap();
    m.set_real(vr::T_OIL, celsius_to_kelvin(60.0)).unwrap();
    m.exit_initialization().unwrap();
    m
}

/// Steps `m` over [`FMU_SPAN`] at [`FMU_STEP`] from time `t`; returns the end time.
fn fmu_span(m: &mut GearPumpFmu, mut t: f64) -> f64 {
    let n = (FMU_SPAN / FMU_STEP).round() as usize;
    for _ in 0..n {
        m.do_step(t, FMU_STEP).unwrap();
        t += FMU_STEP;
        std::hint::black_box(m.get_real(vr::Q_OUT).unwrap());
    }
    t
}

/// Counts per angular step over one revolution at the periodic state.
fn print_counts(pump: &Arc<Pump>, rpm: f64, micromotion: bool) {
    let sample = SampleClearances::nominal(&pump.design);
    let mut sim = Simulation::new(
        Arc::clone(pump),
        inputs(rpm),
        sample,
        Options { micromotion },
    )
    .unwrap();
    let summary = sim.run_periodic().unwrap();
    eprintln!(
        "{rpm:.0} rpm, micromotion {micromotion}: periodic state eta_v {:.10}, torque {:.10} N m, \
         eta_hm {:.10}, {:.2} coupling iterations per step",
        summary.eta_v, summary.torque, summary.eta_hm, summary.coupling_iterations_mean
    );
    let before = sim.solver_stats();
    let n = pump.steps_per_period() * pump.tables.z[0];
    for _ in 0..n {
        sim.step().unwrap();
    }
    let s = sim.solver_stats().since(&before);
    eprintln!(
        "{rpm:.0} rpm, micromotion {micromotion}: per angular step {:.2} pressure solves, \
         {:.2} Newton iterations, {:.2} LU factorisations, {:.2} coupling iterations",
        s.pressure_solves as f64 / s.steps as f64,
        s.newton_iterations as f64 / s.steps as f64,
        s.factorisations as f64 / s.steps as f64,
        s.coupling_iterations as f64 / s.steps as f64,
    );
}

fn bench(c: &mut Criterion) {
    let pump = Arc::new(Pump::new(Design::seed()));
    let sample = SampleClearances::nominal(&pump.design);
    let options = Options { micromotion: false };
    eprintln!(
        "steps per revolution: {}",
        pump.steps_per_period() * pump.tables.z[0]
    );
    c.bench_function("simulate_1000rpm_30bar_60C_no_micromotion", |b| {
        b.iter(|| {
            let mut sim =
                Simulation::new(Arc::clone(&pump), inputs(1000.0), sample, options).unwrap();
            sim.run_periodic().unwrap()
        })
    });
    let with = Options { micromotion: true };
    let probe = Simulation::new(Arc::clone(&pump), inputs(1000.0), sample, with)
        .unwrap()
        .run_periodic()
        .unwrap();
    eprintln!(
        "with micromotion: {:.2} coupling iterations per step, {:.2} revolutions",
        probe.coupling_iterations_mean, probe.revolutions
    );
    c.bench_function("simulate_1000rpm_30bar_60C_micromotion", |b| {
        b.iter(|| {
            let mut sim = Simulation::new(Arc::clone(&pump), inputs(1000.0), sample, with).unwrap();
            sim.run_periodic().unwrap()
        })
    });
    // the same with every period at the design's tolerances (no relaxed
    // start: `model::RELAXED_PERIODS`), back to back with the one above
    c.bench_function("simulate_1000rpm_30bar_60C_micromotion_strict_start", |b| {
        b.iter(|| {
            let mut sim = Simulation::new(Arc::clone(&pump), inputs(1000.0), sample, with).unwrap();
            sim.run_periodic_relaxing(0).unwrap()
        })
    });
    c.bench_function("build_design_tables", |b| {
        b.iter(|| Pump::new(Design::seed()))
    });
    // the same pump with its section tables read from a table file
    // (geometry::cache: what repeated CLI calls and the FMU do)
    let dir = std::env::temp_dir().join(format!("gearpump-bench-tables-{}", std::process::id()));
    let cache = gearpump::geometry::cache::TableCache::new(&dir);
    let _ = Pump::with_cache(Design::seed(), &cache);
    c.bench_function("design_tables_from_cache", |b| {
        b.iter(|| Pump::with_cache(Design::seed(), &cache))
    });
    let _ = std::fs::remove_dir_all(&dir);
}

/// CPU time of this thread, s.
fn thread_cpu_time() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: a valid clock id and a valid pointer to a timespec.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}

/// Real-time factors of one FMU span on wall and CPU time (less sensitive
/// to other load on the machine), best of three.
fn print_fmu_factors(pump: &Arc<Pump>, rpm: f64, micromotion: bool) {
    let mut m = fmu(pump, rpm, micromotion);
    let (mut t, mut wall, mut cpu) = (0.0, f64::INFINITY, f64::INFINITY);
    for _ in 0..3 {
        let (w0, c0) = (std::time::Instant::now(), thread_cpu_time());
        t = fmu_span(&mut m, t);
        wall = wall.min(w0.elapsed().as_secs_f64());
        cpu = cpu.min(thread_cpu_time() - c0);
    }
    eprintln!(
        "FMU {rpm:.0} rpm, micromotion {micromotion}: real-time factor {:.2} (wall), {:.2} (CPU)",
        FMU_SPAN / wall,
        FMU_SPAN / cpu
    );
}

/// The bundled design with the overrides of `GEARPUMP_BENCH_SET` (`key=value`
/// items separated by spaces, as `--set` takes them), e.g.
/// `numerics.angle_step_deg=1.0` for the LP fidelity at a coarser step.
fn bench_design() -> Design {
    let sets: Vec<String> = std::env::var("GEARPUMP_BENCH_SET")
        .map(|v| v.split_whitespace().map(str::to_string).collect())
        .unwrap_or_default();
    if !sets.is_empty() {
        eprintln!("design overrides: {sets:?}");
    }
    gearpump::design::from_toml_str(gearpump::design::SEED_PUMP_TOML, &sets)
        .expect("GEARPUMP_BENCH_SET: a valid override of the bundled design")
}

fn bench_fmu(c: &mut Criterion) {
    let pump = Arc::new(Pump::new(bench_design()));
    for rpm in [1000.0, 4000.0] {
        for micromotion in [true, false] {
            print_counts(&pump, rpm, micromotion);
        }
    }
    for rpm in [1000.0, 4000.0] {
        for micromotion in [true, false] {
            print_fmu_factors(&pump, rpm, micromotion);
        }
    }
    if std::env::var_os("GEARPUMP_BENCH_PROBE_ONLY").is_some() {
        return;
    }
    for rpm in [1000.0, 4000.0] {
        for micromotion in [true, false] {
            let name = format!(
                "fmu_{}s_1ms_{rpm:.0}rpm_30bar_60C{}",
                FMU_SPAN,
                if micromotion {
                    "_micromotion"
                } else {
                    "_no_micromotion"
                }
            );
            let mut m = fmu(&pump, rpm, micromotion);
            let mut t = 0.0;
            c.bench_function(&name, |b| b.iter(|| t = fmu_span(&mut m, t)));
        }
    }
}

/// Instantiate + exit initialisation of the bundled GearPump.fmu, from its
/// resources folder, with and without the periodic start.
fn bench_fmu_start(c: &mut Criterion) {
    let dir = std::env::temp_dir().join(format!("gearpump-bench-start-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, bytes) in GearPumpFmu::resource_files() {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    for periodic in [true, false] {
        let name = if periodic {
            "fmu_start_periodic"
        } else {
            "fmu_start_transient"
        };
        c.bench_function(name, |b| {
            b.iter(|| {
                let mut m = GearPumpFmu::instantiate(&dir, &|_: &str| {}).unwrap();
                m.set_boolean(vr::START_PERIODIC, periodic).unwrap();
                m.exit_initialization().unwrap();
                m
            })
        });
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A map-fidelity instance from the resources in `dir` at `rpm`, 30 bar,
/// 60 degC.
fn map_fmu(dir: &std::path::Path, rpm: f64, ripple: bool) -> GearPumpFmu {
    let mut m = GearPumpFmu::instantiate(dir, &|_: &str| {}).unwrap();
    m.set_integer(vr::FIDELITY, gearpump::fmi2::pump::FIDELITY_MAP)
        .unwrap();
    m.set_boolean(vr::MAP_RIPPLE, ripple).unwrap();
    m.set_real(vr::SPEED, rpm_to_rad_s(rpm)).unwrap();
    m.set_real(vr::P_OUT, ATMOSPHERE_PA + bar_to_pa(30.0))
        .unwrap();
    m.set_real(vr::T_OIL, celsius_to_kelvin(60.0)).unwrap();
    m.exit_initialization().unwrap();
    m
}

/// A drive cycle's inputs at every 1 ms step over 100 s, as a system
/// simulation reads them from a table: speed 1500-3500 rpm, delivery 30-130
/// bar and 40-80 degC (SI), all three following `sin(7 t)`.
fn drive_cycle() -> Vec<[f64; 3]> {
    (0..100_000)
        .map(|i| {
            let s = (7.0 * i as f64 * FMU_STEP).sin();
            [
                rpm_to_rad_s(2500.0 + 1000.0 * s),
                ATMOSPHERE_PA + bar_to_pa(80.0 + 50.0 * s),
                celsius_to_kelvin(60.0 + 20.0 * s),
            ]
        })
        .collect()
}

/// `n` steps of 1 ms from `t` (with `cycle`: its inputs set before every
/// step, from its row of the step's index, read in turn as a master reads
/// a table, not by a division per step); returns the end time.
fn map_span(m: &mut GearPumpFmu, mut t: f64, n: usize, cycle: Option<&[[f64; 3]]>) -> f64 {
    let len = cycle.map_or(1, <[_]>::len);
    let mut row = (t / FMU_STEP).round() as usize % len;
    for _ in 0..n {
        if let Some(cycle) = cycle {
            let [speed, p_out, t_oil] = cycle[row];
            row = if row + 1 == len { 0 } else { row + 1 };
            m.set_real(vr::SPEED, speed).unwrap();
            m.set_real(vr::P_OUT, p_out).unwrap();
            m.set_real(vr::T_OIL, t_oil).unwrap();
        }
        m.do_step(t, FMU_STEP).unwrap();
        t += FMU_STEP;
        std::hint::black_box(m.get_real(vr::Q_OUT).unwrap());
    }
    t
}

/// The map fidelity stepped at 1 ms over 1 s (see the module docs); before
/// the benches, the real-time factors over 100 s of simulated time on wall
/// and CPU time (best of three).
fn bench_fmu_map(c: &mut Criterion) {
    let dir = std::env::temp_dir().join(format!("gearpump-bench-map-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, bytes) in GearPumpFmu::resource_files() {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    let cases = [
        ("1000rpm_30bar_60C", 1000.0, false, false),
        ("1000rpm_30bar_60C_ripple", 1000.0, true, false),
        ("4000rpm_30bar_60C", 4000.0, false, false),
        ("4000rpm_30bar_60C_ripple", 4000.0, true, false),
        ("varying_inputs", 2500.0, false, true),
        ("varying_inputs_ripple", 2500.0, true, true),
    ];
    let cycle = drive_cycle();
    for (label, rpm, ripple, varying) in cases {
        let mut m = map_fmu(&dir, rpm, ripple);
        let (mut t, mut wall, mut cpu) = (0.0, f64::INFINITY, f64::INFINITY);
        for _ in 0..3 {
            let (w0, c0) = (std::time::Instant::now(), thread_cpu_time());
            t = map_span(&mut m, t, 100_000, varying.then_some(&cycle[..]));
            wall = wall.min(w0.elapsed().as_secs_f64());
            cpu = cpu.min(thread_cpu_time() - c0);
        }
        eprintln!(
            "map fidelity {label}: real-time factor {:.0} (wall), {:.0} (CPU)",
            100.0 / wall,
            100.0 / cpu
        );
    }
    if std::env::var_os("GEARPUMP_BENCH_PROBE_ONLY").is_some() {
        let _ = std::fs::remove_dir_all(&dir);
        return;
    }
    for (label, rpm, ripple, varying) in cases {
        let mut m = map_fmu(&dir, rpm, ripple);
        let mut t = 0.0;
        c.bench_function(&format!("fmu_map_1s_1ms_{label}"), |b| {
            b.iter(|| t = map_span(&mut m, t, 1000, varying.then_some(&cycle[..])))
        });
    }
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_group! {
    name = fmu_benches;
    config = Criterion::default().sample_size(10);
    targets = bench_fmu
}
criterion_group! {
    name = fmu_start_benches;
    config = Criterion::default().sample_size(20);
    targets = bench_fmu_start
}
criterion_group! {
    name = fmu_map_benches;
    config = Criterion::default().sample_size(20);
    targets = bench_fmu_map
}
/// `GEARPUMP_BENCH_PROFILE=<rpm>`: only steps the FMU (micromotion on, 30
/// bar, 60 degC, periodic start) over 0.1 s at 1 ms in [`profile_span`], for
/// an instruction profile of the steps alone:
/// `valgrind --tool=callgrind --toggle-collect='*profile_span*' BENCH`.
/// With `GEARPUMP_BENCH_PROFILE_RAMP=<rpm>` the speed ramps to that value
/// over the 0.1 s, set before every step (a drive cycle's inputs); with
/// `GEARPUMP_BENCH_PROFILE_PRESSURE=<bar>` the delivery pressure ramps from
/// 30 bar to that value the same way (a circuit's pressure as a coupled
/// simulation hands it over); `GEARPUMP_BENCH_PROFILE_STEPS=<n>` makes it n calls instead of 100 (for
/// a sampling profiler, e.g. `perf record -e cpu-clock`, which needs the
/// steps to outweigh the start).
fn profile_only() -> bool {
    let Some(rpm) = std::env::var_os("GEARPUMP_BENCH_PROFILE") else {
        return false;
    };
    let rpm: f64 = rpm
        .to_str()
        .and_then(|s| s.parse().ok())
        .expect("GEARPUMP_BENCH_PROFILE=<rpm>");
    let ramp_to: Option<f64> = std::env::var_os("GEARPUMP_BENCH_PROFILE_RAMP").map(|r| {
        r.to_str()
            .and_then(|s| s.parse().ok())
            .expect("GEARPUMP_BENCH_PROFILE_RAMP=<rpm at the end>")
    });
    let bar_to: Option<f64> = std::env::var_os("GEARPUMP_BENCH_PROFILE_PRESSURE").map(|r| {
        r.to_str()
            .and_then(|s| s.parse().ok())
            .expect("GEARPUMP_BENCH_PROFILE_PRESSURE=<bar gauge at the end>")
    });
    let pump = Arc::new(Pump::new(Design::seed()));
    let mut m = fmu(&pump, rpm, true);
    let steps: usize = match std::env::var_os("GEARPUMP_BENCH_PROFILE_STEPS") {
        Some(n) => n
            .to_str()
            .and_then(|s| s.parse().ok())
            .expect("GEARPUMP_BENCH_PROFILE_STEPS=<number of 1 ms calls>"),
        None => 100,
    };
    let before = m.solver_stats().expect("initialised");
    let q = profile_span(&mut m, steps, rpm, ramp_to, bar_to);
    let s = m.solver_stats().expect("initialised").since(&before);
    let torque = m.get_real(vr::TORQUE).unwrap();
    let how = match (ramp_to, bar_to) {
        (None, None) => "inputs held".to_string(),
        (speed, bar) => format!(
            "{}{}, set before every step",
            speed.map_or(String::new(), |end| format!("speed ramped to {end} rpm ")),
            bar.map_or(String::new(), |end| format!("delivery ramped to {end} bar")),
        ),
    };
    eprintln!(
        "{rpm} rpm: {steps} steps of 1 ms ({how}), last Q_out {q:e} m^3/s, torque {torque:e} N m"
    );
    let per = |n: u64| n as f64 / s.steps as f64;
    eprintln!(
        "per angular step ({} steps): {:.3} pressure solves, {:.3} Newton iterations, \
         {:.3} LU factorisations, {:.3} coupling iterations",
        s.steps,
        per(s.pressure_solves),
        per(s.newton_iterations),
        per(s.factorisations),
        per(s.coupling_iterations),
    );
    true
}

/// `steps` FMU steps of [`FMU_STEP`] from t = 0, the speed ramped linearly
/// from `rpm` to `ramp_to` and the delivery pressure from 30 bar to
/// `bar_to` (set before every step, as a drive cycle or a coupled circuit
/// does) or held; the last mean outlet flow.
#[inline(never)]
fn profile_span(
    m: &mut GearPumpFmu,
    steps: usize,
    rpm: f64,
    ramp_to: Option<f64>,
    bar_to: Option<f64>,
) -> f64 {
    let mut t = 0.0;
    for i in 0..steps {
        let s = (i + 1) as f64 / steps as f64;
        if let Some(end) = ramp_to {
            m.set_real(vr::SPEED, rpm_to_rad_s(rpm + s * (end - rpm)))
                .unwrap();
        }
        if let Some(end) = bar_to {
            m.set_real(
                vr::P_OUT,
                ATMOSPHERE_PA + bar_to_pa(30.0 + s * (end - 30.0)),
            )
            .unwrap();
        }
        m.do_step(t, FMU_STEP).unwrap();
        t += FMU_STEP;
    }
    m.get_real(vr::Q_OUT).unwrap()
}

/// `GEARPUMP_BENCH_START=1`: the relaxed start of `run_periodic` against
/// every period at the design's tolerances (`model::RELAXED_PERIODS`),
/// back to back: the seed paper's 14 conditions for five samples (the
/// nominal clearances and four with the tips, bearings and lateral gap
/// scaled by 0.8-1.2), micromotion on, three alternating rounds; prints the
/// thread's CPU time per point of each round, the Newton iterations and
/// factorisations, and the largest difference of eta_v and of torque.
fn start_probe() -> bool {
    if std::env::var_os("GEARPUMP_BENCH_START").is_none() {
        return false;
    }
    let pump = Arc::new(Pump::new(Design::seed()));
    let nominal = SampleClearances::nominal(&pump.design);
    let samples: Vec<SampleClearances> = [
        (1.0, 1.0, 1.0),
        (0.8, 1.2, 0.9),
        (1.2, 0.8, 1.1),
        (0.9, 0.9, 1.2),
        (1.1, 1.1, 0.8),
    ]
    .iter()
    .map(|&(t, b, l)| SampleClearances {
        tip: nominal.tip.map(|h| t * h),
        bearing: nominal.bearing.map(|h| b * h),
        lateral: l * nominal.lateral,
    })
    .collect();
    let mut conditions: Vec<(f64, f64, f64)> = Vec::new();
    for t in [60.0, 120.0] {
        for bar in [10.0, 20.0, 30.0, 40.0] {
            conditions.push((1000.0, bar, t));
        }
        for rpm in [500.0, 2000.0, 4000.0] {
            conditions.push((rpm, 30.0, t));
        }
    }
    let run = |relaxed: usize| {
        let c0 = thread_cpu_time();
        let (mut newton, mut fact, mut out) = (0, 0, Vec::new());
        for sample in &samples {
            for &(rpm, bar, t) in &conditions {
                let at = Inputs {
                    p_delivery: ATMOSPHERE_PA + bar_to_pa(bar),
                    temp_k: celsius_to_kelvin(t),
                    ..inputs(rpm)
                };
                let options = Options { micromotion: true };
                let mut sim = Simulation::new(Arc::clone(&pump), at, *sample, options).unwrap();
                let r = sim.run_periodic_relaxing(relaxed).unwrap();
                let st = sim.solver_stats();
                newton += st.newton_iterations;
                fact += st.factorisations;
                out.push((r.eta_v, r.torque));
            }
        }
        (thread_cpu_time() - c0, newton, fact, out)
    };
    let points = (samples.len() * conditions.len()) as f64;
    for round in 1..=3 {
        let (cs, ns, fs, strict) = run(0);
        let (cr, nr, fr, relaxed) = run(gearpump::model::RELAXED_PERIODS);
        let d_eta = strict
            .iter()
            .zip(&relaxed)
            .map(|(a, b)| (a.0 - b.0).abs())
            .fold(0.0, f64::max);
        let d_t = strict
            .iter()
            .zip(&relaxed)
            .map(|(a, b)| (b.1 / a.1 - 1.0).abs())
            .fold(0.0, f64::max);
        eprintln!(
            "round {round}: strict start {:.3} ms CPU per point ({ns} Newton iterations, {fs} factorisations); \
             relaxed {:.3} ms ({nr}, {fr}); {:.0} / {:.0} points per CPU second; largest |d eta_v| {d_eta:.1e}, |d torque|/torque {d_t:.1e}",
            1e3 * cs / points,
            1e3 * cr / points,
            points / cs,
            points / cr
        );
    }
    true
}

fn main() {
    if profile_only() || start_probe() {
        return;
    }
    benches();
    fmu_benches();
    fmu_start_benches();
    fmu_map_benches();
    Criterion::default().configure_from_args().final_summary();
}
