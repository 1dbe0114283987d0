//! Flow elements between control volumes (seed Sec. 2.2), pure functions.
//!
//! * Gap flow, Couette-Poiseuille (Eq. 10): `Q = w h^3 dp / (12 mu L) + w h U / 2`
//!   for a channel of width `w`, height `h`, length `L` in the flow direction,
//!   pressure drop `dp` (upstream minus downstream) and wall speed `U` (one wall
//!   moving, positive in the flow direction). Laminar: valid for the tooth tip,
//!   lateral and bearing gaps of a gear pump.
//! * Orifice flow (Eq. 11): `Q = Cd A sqrt(2 |dp| / rho) sign(dp)`, regularised
//!   near `dp = 0` as `Q = Cd A sqrt(2/rho) dp / (dp^2 + dp_t^2)^(1/4)`, which
//!   equals Eq. 11 for `|dp| >> dp_t` and has the finite slope
//!   `Cd A sqrt(2/rho) / sqrt(dp_t)` at zero, so the Newton Jacobian stays finite.
//!
//! Every function returns the flow and its derivative with respect to `dp`.

/// Poiseuille conductance `w h^3 / (12 mu L)` of a gap, m^3/(s Pa); the
/// gap's flow is this times the pressure drop plus the Couette flow
/// `w h U / 2` (the network's gap elements).
#[inline]
pub fn gap_conductance(w: f64, h: f64, l: f64, mu: f64) -> f64 {
    w * h * h * h / (12.0 * mu * l)
}

/// Ratio of the axial Poiseuille leakage of an eccentric annulus to that of
/// the concentric one, `1 + 1.5 eps^2` (the mean of `(1 + eps cos)^3` over
/// the circumference), `eps` the eccentricity ratio clamped to [0, 1] (NaN
/// taken as 0). The journal bearings' leakage.
#[inline]
pub fn eccentric_annulus_factor(eps: f64) -> f64 {
    let e = if eps.is_nan() {
        0.0
    } else {
        eps.abs().min(1.0)
    };
    1.0 + 1.5 * e * e
}

/// Regularised orifice flow (Eq. 11). `cd_a` = discharge coefficient x area
/// (m^2), `rho` density, `dp` pressure drop, `dp_t` transition pressure (Pa).
/// Returns `(Q, dQ/d(dp))`.
#[inline]
pub fn orifice_flow(cd_a: f64, rho: f64, dp: f64, dp_t: f64) -> (f64, f64) {
    if cd_a <= 0.0 {
        return (0.0, 0.0);
    }
    let k = cd_a * (2.0 / rho).sqrt();
    let s = dp * dp + dp_t * dp_t;
    let q4 = s.sqrt().sqrt(); // s^(1/4)
    let q = k * dp / q4;
    // d/d(dp) [dp s^(-1/4)] = s^(-1/4) - dp * (1/4) s^(-5/4) * 2 dp = s^(-5/4) (s - dp^2/2)
    let dq = k * (s - 0.5 * dp * dp) / (s * q4);
    (q, dq)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gap_conductance_matches_hand_calculation() {
        // w = 26 mm, h = 30 um, L = 0.7 mm, mu = 0.0155 Pa s: 1 bar drives
        let q = gap_conductance(0.026, 30e-6, 0.7e-3, 0.0155) * 1e5;
        let hand = 0.026 * 2.7e-14 / (12.0 * 0.0155 * 0.7e-3) * 1e5;
        assert!((q - hand).abs() / hand < 1e-12);
    }

    #[test]
    fn eccentric_annulus_factor_matches_the_integral_over_the_circumference() {
        for &eps in &[0.0, 0.3, 0.6, 0.95] {
            let n = 2000;
            let integral: f64 = (0..n)
                .map(|i| {
                    (1.0 + eps * (2.0 * std::f64::consts::PI * i as f64 / n as f64).cos()).powi(3)
                })
                .sum::<f64>()
                / n as f64;
            assert!((eccentric_annulus_factor(eps) / integral - 1.0).abs() < 1e-12);
        }
        assert_eq!(eccentric_annulus_factor(0.0), 1.0);
        assert_eq!(eccentric_annulus_factor(f64::NAN), 1.0);
        assert_eq!(eccentric_annulus_factor(7.0), 2.5);
    }

    #[test]
    fn orifice_tends_to_bernoulli_and_is_smooth_at_zero() {
        let (cda, rho) = (0.7 * 1e-5, 850.0);
        let dp = 2e5;
        let (q, _) = orifice_flow(cda, rho, dp, 100.0);
        let bern = cda * (2.0 * dp / rho).sqrt();
        assert!((q - bern).abs() / bern < 1e-6);
        let (qn, _) = orifice_flow(cda, rho, -dp, 100.0);
        assert!((qn + q).abs() < 1e-15);
        let (q0, d0) = orifice_flow(cda, rho, 0.0, 100.0);
        assert_eq!(q0, 0.0);
        assert!(d0.is_finite() && d0 > 0.0);
        // derivative against finite differences
        for x in [-3e3_f64, -50.0, 10.0, 700.0, 5e4] {
            let h = 1e-3 * (x.abs() + 1.0);
            let (a, d) = orifice_flow(cda, rho, x, 100.0);
            let (b, _) = orifice_flow(cda, rho, x + h, 100.0);
            assert!(((b - a) / h - d).abs() / d < 1e-3, "at {x}");
        }
    }
}
