use gearpump::design::{from_toml_str, SEED_PUMP_TOML};
use gearpump::model::{Inputs, Options, Pump, SampleClearances, Simulation};
use std::sync::Arc;
fn main() {
    for &(rpm, bar, t) in &[
        (1000.0, 30.0, 60.0),
        (4000.0, 30.0, 60.0),
        (1000.0, 30.0, 120.0),
        (4000.0, 30.0, 120.0),
    ] {
        for mm in [true, false] {
            let mut prev: Option<(f64, f64, [f64; 6])> = None;
            for lat in [15.0, 27.26] {
                let p = Arc::new(Pump::new(
                    from_toml_str(SEED_PUMP_TOML, &[format!("clearance.lateral_um={lat}")])
                        .unwrap(),
                ));
                let s = SampleClearances {
                    tip: [28.3e-6, 30.4e-6],
                    bearing: [13.7e-6, 15.2e-6],
                    lateral: lat * 1e-6,
                };
                let mut sim =
                    Simulation::new(p, Inputs::rig(rpm, bar, t), s, Options { micromotion: mm })
                        .unwrap();
                let r = sim.run_periodic().unwrap();
                let l = r.torque_losses;
                let v = [l.tip, l.lateral, l.bearings, l.mesh, l.churning, l.plate];
                println!("{rpm} {bar} {t} mm={mm} lat={lat}: T {:.4} hyd {:.4} tip {:.4} lat {:.4} brg {:.4} mesh {:.4} churn {:.4} plate {:.4} ecc {:?}", r.torque, r.torque_hydraulic, v[0], v[1], v[2], v[3], v[4], v[5], r.eccentricity);
                if let Some((t0, h0, v0)) = prev {
                    println!(
                        "   delta T {:+.4} hyd {:+.4} comps {:?}",
                        r.torque - t0,
                        r.torque_hydraulic - h0,
                        (0..6)
                            .map(|k| format!("{:+.4}", v[k] - v0[k]))
                            .collect::<Vec<_>>()
                    );
                }
                prev = Some((r.torque, r.torque_hydraulic, v));
            }
        }
    }
}
