//! Gear micromotions: the quasi-static 4-DOF balance of the two gear centres
//! (seed Eq. 3), inertia neglected as in the seed (Eq. 2):
//!
//! `n_b F_b(e_k, omega_k, mu) + F_p,k + F_m,k = 0`, k = driving, driven,
//!
//! with `e_k` the offset of gear k's centre from its bore centre (global
//! frame, 2 DOF per gear), `F_b` the film force of one journal bearing
//! (`bearing::JournalBearing`, `n_b` = 2 bearings per gear), `F_p,k` the
//! pressure load and `F_m,k` the mesh force on the gear. Given the loads the
//! four equations are solved together by Newton with the bearings' analytic
//! Jacobian; it is block-diagonal (each gear's 2x2 block solved in closed
//! form) because the gears interact only through the loads, which the caller
//! iterates with the pressure field (seed Fig. 2).
//!
//! A load beyond what the film carries at `EPS_MAX` would mean metal contact;
//! the offset is then held at `EPS_MAX` in the load's direction and the
//! overload is reported.

use super::bearing::{JournalBearing, EPS_MAX};
use super::norm;

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

/// Newton on the balance: converged when every component of the correction
/// is below `TOL` times its bearing's clearance, each correction limited to
/// `MAX_STEP` clearances (one damping factor for all four components).
const TOL: f64 = 1e-9;
const MAX_STEP: f64 = 0.2;
const MAX_ITER: usize = 60;

/// Damped Newton on the 4-DOF balance from `e0`, the two gears' 2x2 blocks
/// of the block-diagonal Jacobian solved in closed form: (iterations,
/// converged, offsets).
fn newton_4dof(
    supports: &[Support; 2],
    loads: &[[f64; 2]; 2],
    mu: f64,
    e0: [[f64; 2]; 2],
) -> (usize, bool, [[f64; 2]; 2]) {
    let mut x = e0;
    for it in 1..=MAX_ITER {
        let mut dx = [[0.0; 2]; 2];
        let mut worst: f64 = 0.0;
        for k in 0..2 {
            let s = &supports[k];
            let (f, j) = s.bearing.force_and_jacobian(x[k], s.omega, mu);
            let r = [s.count * f[0] + loads[k][0], s.count * f[1] + loads[k][1]];
            if !(r[0].is_finite() && r[1].is_finite()) {
                return (it, false, x);
            }
            let j = j.map(|row| row.map(|v| s.count * v));
            let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            if det == 0.0 || !det.is_finite() {
                return (it, false, x);
            }
            dx[k] = [
                (j[1][1] * r[0] - j[0][1] * r[1]) / det,
                (j[0][0] * r[1] - j[1][0] * r[0]) / det,
            ];
            let c = s.bearing.clearance;
            worst = worst.max(dx[k][0].abs() / c).max(dx[k][1].abs() / c);
        }
        if !worst.is_finite() {
            return (it, false, x);
        }
        let damp = if worst > MAX_STEP {
            MAX_STEP / worst
        } else {
            1.0
        };
        for k in 0..2 {
            for a in 0..2 {
                x[k][a] -= damp * dx[k][a];
            }
        }
        if worst < TOL {
            return (it, true, x);
        }
    }
    (MAX_ITER, false, x)
}

/// Solves the balance for external loads `loads[k]` (pressure + mesh force on
/// gear k, N), starting from `e0`.
pub fn balance(
    supports: &[Support; 2],
    loads: [[f64; 2]; 2],
    mu: f64,
    e0: [[f64; 2]; 2],
) -> Balance {
    let (iterations, ok, x) = newton_4dof(supports, &loads, mu, e0);
    let iterations = if ok { iterations } else { MAX_ITER };
    let mut offset = x;
    let mut overload = false;
    for k in 0..2 {
        let c = supports[k].bearing.clearance;
        let e = norm(offset[k][0], offset[k][1]);
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
