//! Involute helical gear geometry in the transverse plane (docs/model.md section 3).
//!
//! Transverse module `mt = mn / cos(beta)`, transverse pressure angle
//! `tan(alpha_t) = tan(alpha_n) / cos(beta)`, reference radius `r = z mt / 2`,
//! base radius `rb = r cos(alpha_t)`. Tooth thickness at radius `rr`:
//! `s(rr) = 2 rr (s_t / (2 r) + inv(alpha_t) - inv(alpha_rr))`,
//! `cos(alpha_rr) = rb / rr`, with the transverse reference thickness
//! `s_t = mt (pi/2 + 2 x tan(alpha_n)) - thinning`.
//! Operating (tight-mesh) centre distance from the profile shifts:
//! `inv(alpha_w) = inv(alpha_t) + 2 tan(alpha_n) (x1 + x2) / (z1 + z2)`,
//! `a = (r1 + r2) cos(alpha_t) / cos(alpha_w)`.

use std::f64::consts::PI;

/// Involute function inv(a) = tan(a) - a.
#[inline]
pub fn inv(a: f64) -> f64 {
    a.tan() - a
}

/// Inverse of the involute function by Newton (converges for 0 < v < 1).
pub fn inv_inverse(v: f64) -> f64 {
    let mut a = (3.0 * v).cbrt().min(1.2); // series start: inv(a) ~ a^3/3
    for _ in 0..50 {
        let f = inv(a) - v;
        let df = a.tan().powi(2);
        let step = f / df;
        a -= step;
        if step.abs() < 1e-15 {
            break;
        }
    }
    a
}

/// Transverse pressure angle from the normal one.
pub fn transverse_pressure_angle(alpha_n: f64, beta: f64) -> f64 {
    (alpha_n.tan() / beta.cos()).atan()
}

/// Tight-mesh operating centre distance (zero backlash) for the profile shifts, m.
pub fn zero_backlash_centre_distance(
    z: [u32; 2],
    x: [f64; 2],
    mn: f64,
    beta: f64,
    alpha_n: f64,
) -> f64 {
    let alpha_t = transverse_pressure_angle(alpha_n, beta);
    let mt = mn / beta.cos();
    let r = (z[0] + z[1]) as f64 * mt / 2.0;
    let aw = working_pressure_angle_from_shifts(z, x, alpha_n, beta);
    r * alpha_t.cos() / aw.cos()
}

/// Working transverse pressure angle of a tight mesh with these shifts.
pub fn working_pressure_angle_from_shifts(
    z: [u32; 2],
    x: [f64; 2],
    alpha_n: f64,
    beta: f64,
) -> f64 {
    let alpha_t = transverse_pressure_angle(alpha_n, beta);
    inv_inverse(inv(alpha_t) + 2.0 * alpha_n.tan() * (x[0] + x[1]) / (z[0] + z[1]) as f64)
}

/// Transverse tooth thickness (arc) at radius `rr`, m.
pub fn tooth_thickness(
    r: f64,
    mt: f64,
    x: f64,
    alpha_n: f64,
    alpha_t: f64,
    thinning: f64,
    rr: f64,
) -> f64 {
    let constant = half_angle_constant(r, mt, x, alpha_n, alpha_t, thinning);
    let rb = r * alpha_t.cos();
    let a_rr = (rb / rr).clamp(-1.0, 1.0).acos();
    2.0 * rr * (constant - inv(a_rr))
}

/// The radius-free part of [`half_tooth_angle`]: `s_t / (2 r) + inv(alpha_t)`.
pub fn half_angle_constant(
    r: f64,
    mt: f64,
    x: f64,
    alpha_n: f64,
    alpha_t: f64,
    thinning: f64,
) -> f64 {
    let st = mt * (PI / 2.0 + 2.0 * x * alpha_n.tan()) - thinning;
    st / (2.0 * r) + inv(alpha_t)
}

/// [`half_tooth_angle`] from its radius-free part `constant`
/// ([`half_angle_constant`]) and the base radius: the same operations in the
/// same order, so the same value to the last bit.
#[inline]
pub fn half_tooth_angle_from(constant: f64, rb: f64, rr: f64) -> f64 {
    let a_rr = (rb / rr).clamp(-1.0, 1.0).acos();
    2.0 * rr * (constant - inv(a_rr)) / (2.0 * rr)
}

/// Half the angular thickness of the tooth at radius `rr` (rad, about the tooth
/// centre line): `s(rr) / (2 rr)`.
pub fn half_tooth_angle(
    r: f64,
    mt: f64,
    x: f64,
    alpha_n: f64,
    alpha_t: f64,
    thinning: f64,
    rr: f64,
) -> f64 {
    tooth_thickness(r, mt, x, alpha_n, alpha_t, thinning, rr) / (2.0 * rr)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn involute_inverse_round_trips() {
        for a in [0.1, 0.3, 0.5, 0.7] {
            assert!((inv_inverse(inv(a)) - a).abs() < 1e-12);
        }
    }

    #[test]
    fn standard_spur_tooth_is_half_the_pitch() {
        let (m, z, an) = (2.0e-3, 20u32, 20f64.to_radians());
        let r = z as f64 * m / 2.0;
        let s = tooth_thickness(r, m, 0.0, an, an, 0.0, r);
        assert!((s - PI * m / 2.0).abs() < 1e-15);
        // zero shifts give the reference centre distance
        let a = zero_backlash_centre_distance([20, 30], [0.0, 0.0], m, 0.0, an);
        assert!((a - 50.0e-3).abs() < 1e-12);
    }
}
