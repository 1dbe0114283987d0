//! The interpolation error of a pump map (`model::map`) against LP runs off
//! its nodes: builds the map of the bundled pump (nominal sample) on a grid
//! and compares mean flow and torque at Halton points over its range.
//!
//! `cargo run --release -p gearpump-core --example map_error -- [SPEED_NODES
//! DP_NODES TEMP_NODES CHECK_POINTS [lin] [nomicro]]` (default: the standard
//! grid, 60 points; `lin`: speed nodes evenly in rpm instead of its log).

use gearpump_core::design::Design;
use gearpump_core::model::map::{MapGrid, PumpMap};
use gearpump_core::model::{Options, Pump, SampleClearances};
use gearpump_core::units::{kelvin_to_celsius, pa_to_bar, rad_s_to_rpm};
use std::sync::Arc;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let num = |i: usize, d: usize| args.get(i).and_then(|a| a.parse().ok()).unwrap_or(d);
    let log = !args.iter().any(|a| a == "lin");
    let micromotion = !args.iter().any(|a| a == "nomicro");
    let std = MapGrid::standard();
    let grid = if args.is_empty() {
        std
    } else {
        let r = |a: &[f64]| (a[0], a[a.len() - 1]);
        let range = |key: &str, d: (f64, f64)| {
            args.iter()
                .find_map(|a| a.strip_prefix(key))
                .and_then(|v| v.split_once(':'))
                .map_or(d, |(a, b)| (a.parse().unwrap(), b.parse().unwrap()))
        };
        let (s, d, t) = (r(&std.speed), r(&std.dp), r(&std.temp));
        let s = range("s=", (rad_s_to_rpm(s.0), rad_s_to_rpm(s.1)));
        let d = range("p=", (pa_to_bar(d.0), pa_to_bar(d.1)));
        let t = range("t=", (kelvin_to_celsius(t.0), kelvin_to_celsius(t.1)));
        MapGrid::spanning(
            (s.0, s.1, num(0, 9), log),
            (d.0, d.1, num(1, 11)),
            (t.0, t.1, num(2, 9)),
        )
    };
    let n_check = num(3, 60);
    let pump = Arc::new(Pump::new(Design::seed()));
    let sample = SampleClearances::nominal(&pump.design);
    let options = Options { micromotion };
    let threads = std::thread::available_parallelism().map_or(1, |t| t.get());
    let t0 = Instant::now();
    let map = PumpMap::build(&pump, sample, options, &grid, threads).expect("map");
    println!(
        "grid {}x{}x{} = {} nodes (speed {}), micromotion {micromotion}: built in {:.2} s on {threads} threads",
        grid.speed.len(),
        grid.dp.len(),
        grid.temp.len(),
        grid.len(),
        if log { "log" } else { "even" },
        t0.elapsed().as_secs_f64()
    );
    let (mut flagged, mut eta_min) = (0, f64::INFINITY);
    for (i, &w) in grid.speed.iter().enumerate() {
        for &dp in &grid.dp {
            for &t in &grid.temp {
                let m = map.eval(w, dp, t);
                let eta_v = m.q_out / (pump.displacement * w / (2.0 * std::f64::consts::PI));
                eta_min = eta_min.min(eta_v);
                flagged += usize::from(m.flagged);
                let _ = i;
            }
        }
    }
    println!(
        "nodes with LP results out of sense (or next to one): {flagged}; lowest eta_v {eta_min:.3}"
    );
    let (mut eq, mut et, mut eqin) = (0.0f64, 0.0f64, 0.0f64);
    let (mut sq, mut st) = (0.0, 0.0);
    let mut worst = String::new();
    let points = grid.check_points(n_check);
    for &(w, dp, t) in &points {
        let lp = PumpMap::lp_point(&pump, sample, options, w, dp, t, grid.p_in).expect("LP");
        let m = map.eval(w, dp, t);
        let rq = (m.q_out - lp.q_out) / lp.q_out;
        let rt = (m.torque - lp.torque) / lp.torque;
        let ri = (m.q_in - lp.q_in) / lp.q_in;
        sq += rq * rq;
        st += rt * rt;
        eqin = eqin.max(ri.abs());
        if rq.abs().max(rt.abs()) > eq.max(et) {
            worst = format!(
                "{:.0} rpm, {:.1} bar, {:.1} degC: Q {:.4} l/min (LP {:.4}), T {:.4} N m (LP {:.4})",
                rad_s_to_rpm(w),
                pa_to_bar(dp),
                kelvin_to_celsius(t),
                m.q_out * 6e4,
                lp.q_out * 6e4,
                m.torque,
                lp.torque
            );
        }
        eq = eq.max(rq.abs());
        et = et.max(rt.abs());
    }
    let n = points.len() as f64;
    println!(
        "{} points: Q_out max {:.3} % rms {:.3} %; torque max {:.3} % rms {:.3} %; Q_in max {:.3} %",
        points.len(),
        100.0 * eq,
        100.0 * (sq / n).sqrt(),
        100.0 * et,
        100.0 * (st / n).sqrt(),
        100.0 * eqin
    );
    println!("worst: {worst}");
}
