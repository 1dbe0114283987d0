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
    fn equal_gears_use_eq5() {
        let fm = mesh_force([12e-3, 12e-3], [-3.0, 1.5], 99.0);
        assert!((fm - 1.5 / 12e-3).abs() < 1e-9);
    }
}
