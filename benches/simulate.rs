//! One operating point (1000 rpm, 30 bar, 60 degC) to the periodic steady
//! state, without and with micromotion, on the bundled design. The design's look-up
//! tables are built once outside the timed loop (a campaign reuses them).
//! Run: `cargo bench --bench simulate`.

use criterion::{criterion_group, criterion_main, Criterion};
use gearpump::design::Design;
use gearpump::model::{Inputs, Options, Pump, SampleClearances, Simulation};
use gearpump::units::*;

fn bench(c: &mut Criterion) {
    let pump = Pump::new(Design::seed());
    let inputs = Inputs {
        omega: rpm_to_rad_s(1000.0),
        p_suction: ATMOSPHERE_PA,
        p_delivery: ATMOSPHERE_PA + bar_to_pa(30.0),
        temp_k: celsius_to_kelvin(60.0),
        measured_torque: None,
    };
    let sample = SampleClearances::nominal(&pump.design);
    let options = Options { micromotion: false };
    eprintln!(
        "steps per revolution: {}",
        pump.steps_per_period() * pump.tables.z[0]
    );
    c.bench_function("simulate_1000rpm_30bar_60C_no_micromotion", |b| {
        b.iter(|| {
            let mut sim = Simulation::new(&pump, inputs, sample, options).unwrap();
            sim.run_periodic().unwrap()
        })
    });
    let with = Options { micromotion: true };
    let probe = Simulation::new(&pump, inputs, sample, with)
        .unwrap()
        .run_periodic()
        .unwrap();
    eprintln!(
        "with micromotion: {:.2} coupling iterations per step, {:.2} revolutions",
        probe.coupling_iterations_mean, probe.revolutions
    );
    c.bench_function("simulate_1000rpm_30bar_60C_micromotion", |b| {
        b.iter(|| {
            let mut sim = Simulation::new(&pump, inputs, sample, with).unwrap();
            sim.run_periodic().unwrap()
        })
    });
    c.bench_function("build_design_tables", |b| {
        b.iter(|| Pump::new(Design::seed()))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
