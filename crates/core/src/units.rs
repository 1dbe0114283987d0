//! Named unit conversions, used only at the edges (CLI flags, CSV columns,
//! reports, FMI display units). Everything inside the library is SI.

use std::f64::consts::PI;

/// Standard atmosphere, Pa: the default suction pressure (absolute).
pub const ATMOSPHERE_PA: f64 = 101_325.0;
/// 0 degC in kelvin.
pub const ZERO_CELSIUS_K: f64 = 273.15;

pub fn rpm_to_rad_s(rpm: f64) -> f64 {
    rpm * 2.0 * PI / 60.0
}
pub fn rad_s_to_rpm(w: f64) -> f64 {
    w * 60.0 / (2.0 * PI)
}
pub fn bar_to_pa(bar: f64) -> f64 {
    bar * 1.0e5
}
pub fn pa_to_bar(pa: f64) -> f64 {
    pa * 1.0e-5
}
pub fn celsius_to_kelvin(c: f64) -> f64 {
    c + ZERO_CELSIUS_K
}
pub fn kelvin_to_celsius(k: f64) -> f64 {
    k - ZERO_CELSIUS_K
}
pub fn mm_to_m(mm: f64) -> f64 {
    mm * 1.0e-3
}
pub fn m_to_mm(m: f64) -> f64 {
    m * 1.0e3
}
pub fn um_to_m(um: f64) -> f64 {
    um * 1.0e-6
}
pub fn m_to_um(m: f64) -> f64 {
    m * 1.0e6
}
pub fn deg_to_rad(d: f64) -> f64 {
    d.to_radians()
}
pub fn lpm_to_m3_s(lpm: f64) -> f64 {
    lpm / 60_000.0
}
pub fn m3_s_to_lpm(q: f64) -> f64 {
    q * 60_000.0
}
pub fn mm2_to_m2(a: f64) -> f64 {
    a * 1.0e-6
}
pub fn cm3_to_m3(v: f64) -> f64 {
    v * 1.0e-6
}
pub fn m3_to_cm3(v: f64) -> f64 {
    v * 1.0e6
}
/// Kinematic viscosity: centistokes (mm^2/s) to m^2/s.
pub fn cst_to_m2_s(nu: f64) -> f64 {
    nu * 1.0e-6
}
pub fn m2_s_to_cst(nu: f64) -> f64 {
    nu * 1.0e6
}
/// Dynamic viscosity, Pa s -> mPa s (= cP).
pub fn pa_s_to_mpa_s(mu: f64) -> f64 {
    mu * 1e3
}
pub fn gpa_to_pa(g: f64) -> f64 {
    g * 1.0e9
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn round_trips_and_known_values() {
        assert!((rpm_to_rad_s(1000.0) - 104.719_755).abs() < 1e-5);
        assert!((rad_s_to_rpm(rpm_to_rad_s(1234.5)) - 1234.5).abs() < 1e-9);
        assert_eq!(bar_to_pa(30.0), 3.0e6);
        assert!((m3_s_to_lpm(lpm_to_m3_s(14.65)) - 14.65).abs() < 1e-12);
        assert!((celsius_to_kelvin(60.0) - 333.15).abs() < 1e-12);
    }
}
