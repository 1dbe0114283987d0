//! Mesh force from the torque balance of the two gears (seed Eqs. 4-8).
//!
//! Conventions (global frame, see `geometry::pair`): the driving gear turns
//! counter-clockwise and drives through the line of action
//! `u = (sin aw, cos aw)`, tangent to base circle 1 at `rb1 (cos aw, -sin aw)`.
//! The mesh force of magnitude `Fm >= 0` acts as `-Fm u` on the driving gear
//! (torque `-rb1 Fm` about O1) and `+Fm u` on the driven gear (torque
//! `-rb2 Fm` about O2, which turns it clockwise). With `T_p1`, `T_p2` the
//! pressure torques (counter-clockwise positive) and `Tp1' = -T_p1`,
//! `Tp2' = +T_p2` the torques they oppose to each gear's rotation:
//!
//! * driving gear: `T_shaft - T_f1 - Tp1' = rb1 Fm`
//! * driven gear:  `rb2 Fm = Tp2' + T_f2`
//!
//! Subtracting (Eq. 6) and writing the friction as `T_f1 + T_f2 = T_shaft (1 - eta_hm)`
//! (Eq. 7) gives Eq. 8: `Fm = (eta_hm T_shaft - Tp1' - Tp2') / (rb1 - rb2)`.
//! Here `eta_hm T_shaft` is the shaft torque less friction: with a measured
//! torque, the measurement less the modelled friction; otherwise the ideal
//! torque `Vm dp / (2 pi)` (the torque model's shaft torque less its friction).
//! For equal gears (`rb1 = rb2`) Eq. 8 is singular and Eq. 5 applies:
//! `Fm = Tp2' / rb` (friction of the driven gear neglected, as in the seed).
//! A negative result would mean the coast flanks take over; single-flank
//! contact is kept by clamping at zero.
//!
//! Which torque enters, and what its error costs: `T_net = eta_hm T_shaft`,
//! the shaft torque less the friction of both gears. Without a measurement
//! it is the ideal torque, independent of the loss model. With a measured
//! torque it is `T_meas - T_f(model)`, so an error `dT` of the measurement or
//! of the modelled friction moves the mesh force by `dT / (rb1 - rb2)`:
//! 186 N per N m for the seed pump (rb1 - rb2 = 5.39 mm), i.e. 0.3 N m of
//! torque error (4 % of the shaft torque at 30 bar) becomes 56 N, about a
//! fifth of the mesh force. The unequal gears make Eq. 8 a small difference
//! of two large torques. `tests/mechanics.rs` measures what that does to the
//! gear positions and to eta_v.

/// Mesh force magnitude, N.
pub fn mesh_force(rb: [f64; 2], pressure_torque: [f64; 2], net_shaft_torque: f64) -> f64 {
    let tp1 = -pressure_torque[0];
    let tp2 = pressure_torque[1];
    let fm = if ((rb[0] - rb[1]) / rb[0]).abs() < 1e-6 {
        tp2 / rb[1]
    } else {
        (net_shaft_torque - tp1 - tp2) / (rb[0] - rb[1])
    };
    fm.max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unequal_gears_balance_both_torque_equations_without_friction() {
        // driven gear: rb2 Fm = Tp2' ; driving: T = Tp1' + rb1 Fm
        let rb = [15.0e-3, 9.6e-3];
        let (tp1, tp2) = (4.0, 2.0); // resisting torques
        let fm_true = tp2 / rb[1];
        let shaft = tp1 + rb[0] * fm_true;
        let fm = mesh_force(rb, [-tp1, tp2], shaft);
        assert!((fm - fm_true).abs() / fm_true < 1e-12);
    }

    #[test]
    fn a_torque_error_moves_the_mesh_force_by_its_ratio_to_the_base_radius_difference() {
        let rb = [15.097e-3, 9.705e-3];
        let tp = [-4.0, 2.0];
        let base = mesh_force(rb, tp, 7.7);
        for dt in [-0.3, 0.1, 0.3] {
            let moved = mesh_force(rb, tp, 7.7 + dt);
            let want = dt / (rb[0] - rb[1]);
            assert!(((moved - base) - want).abs() < 1e-9 * want.abs(), "{dt}");
        }
    }

    #[test]
    fn equal_gears_use_eq5() {
        let fm = mesh_force([12e-3, 12e-3], [-3.0, 1.5], 99.0);
        assert!((fm - 1.5 / 12e-3).abs() < 1e-9);
    }
}
