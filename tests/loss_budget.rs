//! The loss budget (`gearpump::losses`) held against the model's own
//! delivered flow (it must close) and the tip leakage against a hand
//! calculation of series Couette-Poiseuille gaps over the sealing arc.

mod seed_common;
use gearpump::design::Design;
use gearpump::model::{Inputs, Options, Pump, SampleClearances, Simulation, Summary};
use seed_common::*;
use std::f64::consts::PI;
use std::sync::Arc;

fn run(p: &Arc<Pump>, i: Inputs, micromotion: bool) -> Summary {
    let mut sim = Simulation::new(
        Arc::clone(p),
        i,
        SampleClearances::nominal(&p.design),
        Options { micromotion },
    )
    .unwrap();
    sim.run_periodic().unwrap()
}

#[test]
fn the_budget_closes_at_the_14_conditions() {
    let p = Arc::new(Pump::new(Design::seed()));
    for (rpm, bar, t) in table2() {
        let s = run(&p, inputs(rpm, bar, t), true);
        let b = s.losses.expect("a budget under pressure");
        let sum: f64 = b.parts().iter().map(|(_, v)| v).sum();
        println!(
            "{rpm} rpm {bar} bar {t} C: eta_v {:.4}, deficit {:.5}, parts {:?}, closure {:.2e}",
            s.eta_v,
            1.0 - s.eta_v,
            b.parts().map(|(_, v)| (v * 1e4).round() / 1e4),
            b.closure
        );
        // the deficit is the one eta_v says
        assert!((b.deficit - (1.0 - s.eta_v)).abs() < 1e-12);
        assert!((sum - b.total).abs() < 1e-12);
        // the parts close to 0.1 % of Vm n
        assert!(
            b.closure.abs() < 1e-3,
            "{rpm} {bar} {t}: closure {}",
            b.closure
        );
        // pressure-driven tip leakage is a loss, the drag a gain
        assert!(b.tip_poiseuille > 0.0 && b.tip_couette < 0.0);
    }
}

#[test]
fn no_budget_without_a_pressure_rise() {
    let p = Arc::new(Pump::new(Design::seed()));
    assert!(run(&p, inputs(1000.0, 0.0, 60.0), false).losses.is_none());
}

/// The tip leakage of each gear by hand: the sealed tips of the arc from
/// the suction edge round to the delivery edge in series, each a parallel
/// gap of width b, height h and length L (its land) carrying
/// `b h^3 dp_tip / (12 mu L)` back and the drag `b h U / 2` forward, with
/// the rise shared equally, `dp_tip = dp / N`. N alternates between the
/// two whole numbers round `arc / pitch`; the mean of `1 / N` is taken.
#[test]
fn tip_leakage_matches_series_couette_poiseuille_gaps_by_hand() {
    let p = Arc::new(Pump::new(Design::seed()));
    let d = &p.design;
    let (rpm, bar, t) = (1000.0, 30.0, 60.0);
    let i = inputs(rpm, bar, t);
    let s = run(&p, i, false);
    let b = s.losses.unwrap();
    let mu = d.oil.dynamic_viscosity(i.temp_k);
    let dp = i.p_delivery - i.p_suction;
    let kinematic = p.displacement * rpm / 60.0;
    let (mut poiseuille, mut drag) = (0.0, 0.0);
    for k in 0..2 {
        let g = &p.pair.gears[k];
        let omega = i.omega * if k == 0 { 1.0 } else { p.pair.ratio() };
        let h = d.clearance.tip[k];
        let land = g.tip_land();
        // sealing arc: from the suction edge round the back to the delivery edge
        let arc = 2.0 * PI + d.gears[k].delivery_edge - d.gears[k].suction_edge;
        let x = arc / g.pitch_angle();
        // N tips sealed for a fraction of the time, N + 1 for the rest
        let n = x.floor();
        let frac_n = 1.0 - (x - n);
        let mean_inv_n = frac_n / n + (1.0 - frac_n) / (n + 1.0);
        poiseuille += d.face_width * h.powi(3) * dp * mean_inv_n / (12.0 * mu * land);
        drag += d.face_width * h * omega * g.ra / 2.0;
    }
    let model_p = b.tip_poiseuille * kinematic;
    let model_d = -b.tip_couette * kinematic;
    println!(
        "tip Poiseuille: model {:.4e}, hand {:.4e} m^3/s ({:+.1} %); drag: model {:.4e}, hand {:.4e} ({:+.1} %)",
        model_p,
        poiseuille,
        100.0 * (model_p / poiseuille - 1.0),
        model_d,
        drag,
        100.0 * (model_d / drag - 1.0)
    );
    assert!((model_p / poiseuille - 1.0).abs() < 0.15);
    assert!((model_d / drag - 1.0).abs() < 0.15);
    let net_model = model_p - model_d;
    let net_hand = poiseuille - drag;
    assert!(
        (net_model / net_hand - 1.0).abs() < 0.15,
        "{net_model} vs {net_hand}"
    );
}
