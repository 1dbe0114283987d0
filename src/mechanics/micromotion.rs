//! Gear micromotions: the quasi-static 4-DOF balance of the two gear centres
//! (seed Eq. 3), inertia neglected as in the seed (Eq. 2):
//!
//! `n_b F_b(e_k, omega_k, mu) + F_p,k + F_m,k = 0`, k = driving, driven,
//!
//! with `e_k` the offset of gear k's centre from its bore centre (global
//! frame, 2 DOF per gear), `F_b` the film force of one journal bearing
//! (`bearing::JournalBearing`, `n_b` = 2 bearings per gear), `F_p,k` the
//! pressure load and `F_m,k` the mesh force on the gear. Given the loads the
//! four equations are solved together by Newton (nalgebra LU) with the
//! bearings' analytic Jacobian; the block-diagonal structure reflects that
//! the gears interact only through the loads, which the caller iterates with
//! the pressure field (seed Fig. 2).
//!
//! A load beyond what the film carries at `EPS_MAX` would mean metal contact;
//! the offset is then held at `EPS_MAX` in the load's direction and the
//! overload is reported.

use super::bearing::{JournalBearing, EPS_MAX};
use crate::solver::{newton, NewtonOptions, NewtonProblem};
use nalgebra::{DMatrix, DVector};

/// The journal support of one gear.
#[derive(Debug, Clone, Copy)]
pub struct Support {
    pub bearing: JournalBearing,
    /// Number of identical bearings carrying the gear.
    pub count: f64,
    /// Signed angular speed of the journal (counter-clockwise positive), rad/s.
    pub omega: f64,
}

/// Result of the balance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Balance {
    /// Gear centre offsets, m.
    pub offset: [[f64; 2]; 2],
    /// Newton iterations.
    pub iterations: usize,
    /// True when a load exceeded the film's capacity at EPS_MAX.
    pub overload: bool,
}

struct Problem<'a> {
    supports: &'a [Support; 2],
    loads: [[f64; 2]; 2],
    mu: f64,
}

impl NewtonProblem for Problem<'_> {
    fn dim(&self) -> usize {
        4
    }
    fn eval(&mut self, x: &DVector<f64>, r: &mut DVector<f64>, j: &mut DMatrix<f64>) {
        j.fill(0.0);
        for k in 0..2 {
            let s = &self.supports[k];
            let bf = s.bearing.force([x[2 * k], x[2 * k + 1]], s.omega, self.mu);
            for a in 0..2 {
                r[2 * k + a] = s.count * bf.force[a] + self.loads[k][a];
                for b in 0..2 {
                    j[(2 * k + a, 2 * k + b)] = s.count * bf.jacobian[a][b];
                }
            }
        }
    }
    fn scale(&self, i: usize) -> f64 {
        self.supports[i / 2].bearing.clearance
    }
}

/// Solves the balance for external loads `loads[k]` (pressure + mesh force on
/// gear k, N), starting from `e0`.
pub fn balance(
    supports: &[Support; 2],
    loads: [[f64; 2]; 2],
    mu: f64,
    e0: [[f64; 2]; 2],
) -> Balance {
    let mut x = DVector::from_vec(vec![e0[0][0], e0[0][1], e0[1][0], e0[1][1]]);
    let mut prob = Problem {
        supports,
        loads,
        mu,
    };
    let opt = NewtonOptions {
        tol: 1e-9,
        max_iter: 60,
        max_step: 0.2,
    };
    let mut iterations = opt.max_iter;
    let mut ok = false;
    if let Ok(rep) = newton(&mut prob, &mut x, &opt) {
        iterations = rep.iterations;
        ok = true;
    }
    let mut offset = [[x[0], x[1]], [x[2], x[3]]];
    let mut overload = false;
    for k in 0..2 {
        let c = supports[k].bearing.clearance;
        let e = offset[k][0].hypot(offset[k][1]);
        if !ok || !e.is_finite() || e > EPS_MAX * c {
            // per-gear fallback: the bearing's own robust equilibrium, or the
            // wall in the load's direction when the film cannot carry it
            let s = &supports[k];
            let per = [loads[k][0] / s.count, loads[k][1] / s.count];
            match s.bearing.equilibrium(per, s.omega, mu, [0.0, 0.0]) {
                Ok(e) => offset[k] = e,
                Err(_) => {
                    let n = loads[k][0].hypot(loads[k][1]).max(1e-300);
                    offset[k] = [EPS_MAX * c * loads[k][0] / n, EPS_MAX * c * loads[k][1] / n];
                    overload = true;
                }
            }
        }
    }
    Balance {
        offset,
        iterations,
        overload,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn supports() -> [Support; 2] {
        [
            Support {
                bearing: JournalBearing::new(8e-3, 12e-3, 12e-6).unwrap(),
                count: 2.0,
                omega: 104.7,
            },
            Support {
                bearing: JournalBearing::new(6e-3, 12e-3, 12e-6).unwrap(),
                count: 2.0,
                omega: -162.9,
            },
        ]
    }

    #[test]
    fn balance_satisfies_the_force_equations() {
        let s = supports();
        let loads = [[-300.0, 1200.0], [250.0, 900.0]];
        let b = balance(&s, loads, 0.0155, [[0.0; 2]; 2]);
        assert!(!b.overload);
        for k in 0..2 {
            let f = s[k].bearing.force(b.offset[k], s[k].omega, 0.0155).force;
            for a in 0..2 {
                assert!((2.0 * f[a] + loads[k][a]).abs() < 1e-6 * 1200.0, "gear {k}");
            }
            // the gear moves roughly along its load (plus the attitude angle)
            let dot = b.offset[k][0] * loads[k][0] + b.offset[k][1] * loads[k][1];
            assert!(dot > 0.0);
        }
    }

    #[test]
    fn larger_load_gives_larger_eccentricity() {
        let s = supports();
        let small = balance(&s, [[0.0, 300.0], [0.0, 300.0]], 0.0155, [[0.0; 2]; 2]);
        let big = balance(&s, [[0.0, 1200.0], [0.0, 1200.0]], 0.0155, [[0.0; 2]; 2]);
        for k in 0..2 {
            let e = |b: &Balance| b.offset[k][0].hypot(b.offset[k][1]);
            assert!(e(&big) > e(&small));
        }
    }

    #[test]
    fn an_impossible_load_is_held_at_the_wall_and_reported() {
        let s = supports();
        let b = balance(&s, [[0.0, 1e9], [0.0, 10.0]], 0.0155, [[0.0; 2]; 2]);
        assert!(b.overload);
        let e = b.offset[0][0].hypot(b.offset[0][1]);
        assert!(e <= EPS_MAX * 12e-6 * (1.0 + 1e-12));
    }
}
