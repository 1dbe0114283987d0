//! The oil: viscosity, density and effective bulk modulus as pure functions of
//! temperature (and pressure for the density law).
//!
//! Viscosity follows the Walther equation (ASTM D341):
//! `log10(log10(nu + 0.7)) = A - B log10(T)`, nu in cSt, T in K, with A and B
//! fitted exactly through two datasheet points (usually 40 and 100 degC).
//! Density: `rho(T) = rho_ref / (1 + alpha (T - T_ref))` (volumetric thermal
//! expansion). Compressibility: a constant effective bulk modulus `B` (oil plus
//! casing compliance), so `rho(p) = rho(T) exp((p - p_atm)/B)`; below the
//! gas-release pressure the mixture becomes far more compliant (cavitation),
//! modelled by a second, much smaller modulus so that pockets expanding while
//! sealed stay at low pressures. The branch is exponential as well: it does
//! not bound the pressure from below, and a sealed pocket that grows by more
//! than about a tenth below the gas-release pressure goes below zero
//! absolute (docs/model.md, section 11).

use crate::units::{cst_to_m2_s, ATMOSPHERE_PA};

/// Width of the pressure band over which gas release sets in, Pa.
pub const GAS_RELEASE_BAND_PA: f64 = 1.0e4;

/// Validated oil properties (SI).
#[derive(Debug, Clone, PartialEq)]
pub struct Oil {
    /// Walther constant A (dimensionless).
    pub walther_a: f64,
    /// Walther constant B (dimensionless).
    pub walther_b: f64,
    /// Density at `t_ref_k`, kg/m^3.
    pub rho_ref: f64,
    /// Reference temperature of the density, K.
    pub t_ref_k: f64,
    /// Volumetric thermal expansion coefficient, 1/K.
    pub expansion_per_k: f64,
    /// Effective bulk modulus of the liquid, Pa.
    pub bulk_modulus: f64,
    /// Absolute pressure below which dissolved gas is released, Pa.
    pub gas_release_pa: f64,
    /// Bulk modulus of the gas-laden mixture below `gas_release_pa`, Pa.
    pub cavitation_modulus: f64,
    /// Valid temperature range of the viscosity fit, K.
    pub t_min_k: f64,
    pub t_max_k: f64,
    /// Multiplicative factors on the kinematic viscosity (viscosity_shift
    /// extension): applied as a log-linear interpolation in T between two
    /// reference temperatures. 1.0 = datasheet oil.
    pub nu_factor: (f64, f64),
    pub nu_factor_t_k: (f64, f64),
    /// Free (entrained) air volume fraction at atmospheric pressure (0 = base model).
    pub air_fraction: f64,
    /// Barus pressure-viscosity coefficient of the gaps, 1/Pa (applied per
    /// operating point by the campaign's effect model).
    pub pressure_viscosity: f64,
}

/// Walther constants (A, B) through two points (T in K, nu in cSt).
pub fn walther_fit(t1_k: f64, nu1_cst: f64, t2_k: f64, nu2_cst: f64) -> (f64, f64) {
    let w1 = (nu1_cst + 0.7).log10().log10();
    let w2 = (nu2_cst + 0.7).log10().log10();
    let b = (w1 - w2) / (t2_k.log10() - t1_k.log10());
    let a = w1 + b * t1_k.log10();
    (a, b)
}

impl Oil {
    /// Kinematic viscosity from the Walther fit, cSt (no extension factors).
    pub fn nu_datasheet_cst(&self, t_k: f64) -> f64 {
        let w = self.walther_a - self.walther_b * t_k.log10();
        10f64.powf(10f64.powf(w)) - 0.7
    }

    /// Kinematic viscosity, m^2/s, including the viscosity_shift factors.
    pub fn kinematic_viscosity(&self, t_k: f64) -> f64 {
        let (f1, f2) = self.nu_factor;
        let (t1, t2) = self.nu_factor_t_k;
        let factor = if (f1 - 1.0).abs() < 1e-15 && (f2 - 1.0).abs() < 1e-15 {
            1.0
        } else {
            // log-linear in T between the two references (extrapolated outside)
            let s = (t_k - t1) / (t2 - t1);
            (f1.ln() + s * (f2.ln() - f1.ln())).exp()
        };
        cst_to_m2_s(self.nu_datasheet_cst(t_k)) * factor
    }

    /// Density at atmospheric pressure, kg/m^3.
    pub fn density(&self, t_k: f64) -> f64 {
        self.rho_ref / (1.0 + self.expansion_per_k * (t_k - self.t_ref_k))
    }

    /// Dynamic viscosity at atmospheric pressure, Pa.s.
    pub fn dynamic_viscosity(&self, t_k: f64) -> f64 {
        self.kinematic_viscosity(t_k) * self.density(t_k)
    }

    pub fn in_range(&self, t_k: f64) -> bool {
        t_k.is_finite() && t_k >= self.t_min_k && t_k <= self.t_max_k
    }
}

/// Compressibility law of the liquid (with optional entrained air), giving the
/// density ratio rho(p)/rho_atm and its derivative. Mass-conservative pressure
/// build-up (Eq. 9) uses `m = rho(p) V`.
#[derive(Debug, Clone, Copy)]
pub struct Compressibility {
    pub bulk_modulus: f64,
    pub gas_release_pa: f64,
    pub cavitation_modulus: f64,
    pub air_fraction: f64,
}

impl Compressibility {
    pub fn from_oil(oil: &Oil) -> Self {
        Self {
            bulk_modulus: oil.bulk_modulus,
            gas_release_pa: oil.gas_release_pa,
            cavitation_modulus: oil.cavitation_modulus,
            air_fraction: oil.air_fraction,
        }
    }

    /// Density ratio rho(p)/rho(p_atm) and d(ratio)/dp.
    ///
    /// Liquid: exp((p - p_atm)/B). Entrained air (isothermal ideal gas, volume
    /// fraction `x0` at p_atm): the mixture density ratio is
    /// `(1 - x0) r_l + x0 p/p_atm` over... expressed as mass per unit volume of
    /// mixture: rho_mix/rho_mix,atm with the air's mass neglected, i.e.
    /// `V_mix(p) = (1-x0)/r_l(p) + x0 p_atm/p`, ratio = 1 / V_mix.
    pub fn density_ratio(&self, p: f64) -> (f64, f64) {
        // Liquid with a smooth gas-release branch: d ln r / dp = 1/B + (1/Bc - 1/B) s(p),
        // s the logistic function of (p_g - p)/w, so the compliance rises from the
        // liquid's to the gas-laden oil's over a band w around p_g without a kink.
        let w = GAS_RELEASE_BAND_PA;
        // the compliance 1/B as a product: one division per call, and the
        // same bits as `DensityLaw`'s precomputed one
        let inv_b = 1.0 / self.bulk_modulus;
        let k = 1.0 / self.cavitation_modulus - inv_b;
        if self.air_fraction <= 0.0 && p > self.gas_release_pa + 40.0 * w {
            // far above gas release the logistic term is below e^-40: pure liquid
            let x0 = (self.gas_release_pa - ATMOSPHERE_PA) / w;
            let r = exp_near_zero((p - ATMOSPHERE_PA) * inv_b + k * w * x0.exp().ln_1p());
            return (r, r * inv_b);
        }
        let xg = (self.gas_release_pa - p) / w;
        let x0 = (self.gas_release_pa - ATMOSPHERE_PA) / w;
        let (softplus_xg, logistic_xg) = softplus_logistic(xg);
        let ln_r = (p - ATMOSPHERE_PA) * inv_b - k * w * (softplus_xg - softplus_logistic(x0).0);
        let rl = exp_near_zero(ln_r);
        let drl = rl * (inv_b + k * logistic_xg);
        if self.air_fraction <= 0.0 {
            return (rl, drl);
        }
        let x0 = self.air_fraction;
        let pe = p.max(self.gas_release_pa);
        let dpe = if p >= self.gas_release_pa { 1.0 } else { 0.0 };
        let vmix = (1.0 - x0) / rl + x0 * ATMOSPHERE_PA / pe;
        let dvmix = -(1.0 - x0) * drl / (rl * rl) - x0 * ATMOSPHERE_PA / (pe * pe) * dpe;
        (1.0 / vmix, -dvmix / (vmix * vmix))
    }

    /// Effective bulk modulus rho / (d rho/dp) at pressure p, Pa.
    pub fn effective_modulus(&self, p: f64) -> f64 {
        let (r, dr) = self.density_ratio(p);
        r / dr
    }
}

/// The softplus ln(1 + e^x) (x itself beyond 30, where they agree to
/// round-off) and the logistic function 1 / (1 + e^-x) of the gas-release
/// branch, from one exponential: the logistic is 1 / (1 + 1/e^x), which
/// tends to 0 and 1 at the ends (e^x = 0 or infinity) without a NaN.
///
/// Below [`SERIES_BELOW`] (x < -6.9, a node above 0.89 bar absolute with
/// the seed oil's 0.2 bar gas release and 0.1 bar band: the pockets at the
/// suction) the softplus is its series `e - e^2/2 + ... - e^6/6` (the next
/// term is below 1.5e-19 of the sum) and the logistic `e / (1 + e)`:
/// within a few units in the last place of `ln_1p` and the quotient, for
/// the cost of a `ln_1p` call (3.7 % of an LP step at 4000 rpm).
#[inline]
pub fn softplus_logistic(x: f64) -> (f64, f64) {
    let e = x.exp();
    if e < SERIES_BELOW {
        const C: [f64; 5] = [1.0 / 2.0, 1.0 / 3.0, 1.0 / 4.0, 1.0 / 5.0, 1.0 / 6.0];
        let softplus = e * (1.0 - e * (C[0] - e * (C[1] - e * (C[2] - e * (C[3] - e * C[4])))));
        return (softplus, e / (1.0 + e));
    }
    let softplus = if x > 30.0 { x } else { e.ln_1p() };
    (softplus, 1.0 / (1.0 + 1.0 / e))
}

/// Where [`softplus_logistic`] takes its series: `e^x` below this.
const SERIES_BELOW: f64 = 1e-3;

/// `e^x - 1` by its series to the sixth power, Horner in `x` on the
/// reciprocal factorials (no division in the chain). The first omitted
/// term is `x^7 / 5040`: below 2e-19 of the sum for `|x| < 1e-3` (exact
/// to rounding as `e^x - 1`) and below 2e-18 of `e^x` for `|x| < 1e-2`
/// (exact to rounding as `e^x`, [`exp_near_zero`]).
#[inline]
pub fn expm1_series(x: f64) -> f64 {
    const C: [f64; 5] = [1.0 / 2.0, 1.0 / 6.0, 1.0 / 24.0, 1.0 / 120.0, 1.0 / 720.0];
    x * (1.0 + x * (C[0] + x * (C[1] + x * (C[2] + x * (C[3] + x * C[4])))))
}

/// Where [`exp_near_zero`] takes the series: `|x|` below this.
pub const EXP_SERIES_BELOW: f64 = 1e-2;

/// `e^x`, by [`expm1_series`] for `|x| <` [`EXP_SERIES_BELOW`] and by the
/// library's `exp` beyond (NaN included). The oil law's exponent is
/// `(p - p_atm) / B` and the gas-release term: below 1e-2 up to about 140
/// bar with a 1.4 GPa oil, so at every node of a pump at usual pressures.
/// Within one unit in the last place of `exp` (test
/// `exp_near_zero_is_exp_to_an_ulp`); the library call (a call, its error
/// checks and its table lookup) was 8.7 % of the instructions of an LP step
/// at 1000 rpm.
#[inline]
pub fn exp_near_zero(x: f64) -> f64 {
    if x.abs() < EXP_SERIES_BELOW {
        1.0 + expm1_series(x)
    } else {
        x.exp()
    }
}

/// Barus law: the factor `exp(alpha p)` on the viscosity of a film at gauge
/// pressure `p` (Pa, negative taken as 0), alpha in 1/Pa (oils: 1e-8 to
/// 3e-8). The base model leaves it out; the `pressure_viscosity` model
/// extension applies it to every gap.
pub fn barus_factor(alpha: f64, p_gauge: f64) -> f64 {
    (alpha * p_gauge.max(0.0)).exp()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::units::celsius_to_kelvin;

    /// Units in the last place between `a` and `b` (finite, same sign).
    fn ulps(a: f64, b: f64) -> u64 {
        a.to_bits().abs_diff(b.to_bits())
    }

    /// The series against the library's `exp` and `exp_m1` over their
    /// whole ranges (a million points each, both ends included), and the
    /// library beyond: one unit in the last place at most.
    #[test]
    fn exp_near_zero_is_exp_to_an_ulp() {
        let n = 1_000_000;
        let (mut worst_exp, mut worst_expm1) = (0, 0);
        for i in -n..=n {
            let x = EXP_SERIES_BELOW * (i as f64 / n as f64);
            if x.abs() < EXP_SERIES_BELOW {
                worst_exp = worst_exp.max(ulps(exp_near_zero(x), x.exp()));
            }
            let x = 1e-3 * (i as f64 / n as f64);
            if x != 0.0 {
                worst_expm1 = worst_expm1.max(ulps(expm1_series(x), x.exp_m1()));
            }
        }
        assert!(worst_exp <= 1, "exp: {worst_exp} ulps");
        assert!(worst_expm1 <= 1, "exp_m1: {worst_expm1} ulps");
        for x in [EXP_SERIES_BELOW, -EXP_SERIES_BELOW, 0.5, -3.0, 40.0] {
            assert_eq!(exp_near_zero(x), x.exp(), "x = {x}");
        }
        assert!(exp_near_zero(f64::NAN).is_nan());
        assert_eq!(exp_near_zero(f64::NEG_INFINITY), 0.0);
    }

    #[test]
    fn softplus_and_logistic_from_one_exponential() {
        for i in -1600..=1600 {
            let x = i as f64 * 0.5;
            let (sp, lg) = softplus_logistic(x);
            assert!(sp.is_finite() && lg.is_finite(), "x = {x}");
            assert!((0.0..=1.0).contains(&lg), "x = {x}");
            // the two-exponential forms where they are finite
            if x.abs() < 700.0 {
                let lg2 = 1.0 / (1.0 + (-x).exp());
                assert!(
                    (lg - lg2).abs() <= 4.0 * f64::EPSILON * lg2,
                    "logistic at {x}"
                );
                let sp2 = if x > 30.0 { x } else { x.exp().ln_1p() };
                assert!(
                    (sp - sp2).abs() <= 2.0 * f64::EPSILON * sp2,
                    "softplus at {x}: {sp} against {sp2}"
                );
            }
        }
        assert_eq!(softplus_logistic(-800.0).1, 0.0);
        assert_eq!(softplus_logistic(800.0).1, 1.0);
    }

    fn atf() -> Oil {
        let (a, b) = walther_fit(celsius_to_kelvin(40.0), 35.0, celsius_to_kelvin(100.0), 7.3);
        Oil {
            walther_a: a,
            walther_b: b,
            rho_ref: 853.0,
            t_ref_k: celsius_to_kelvin(20.0),
            expansion_per_k: 7.0e-4,
            bulk_modulus: 1.4e9,
            gas_release_pa: 2.0e4,
            cavitation_modulus: 2.0e5,
            t_min_k: celsius_to_kelvin(-20.0),
            t_max_k: celsius_to_kelvin(150.0),
            nu_factor: (1.0, 1.0),
            nu_factor_t_k: (celsius_to_kelvin(40.0), celsius_to_kelvin(100.0)),
            air_fraction: 0.0,
            pressure_viscosity: 0.0,
        }
    }

    #[test]
    fn walther_passes_through_its_points_and_matches_the_datasheet_spread() {
        let oil = atf();
        assert!((oil.nu_datasheet_cst(celsius_to_kelvin(40.0)) - 35.0).abs() < 1e-9);
        assert!((oil.nu_datasheet_cst(celsius_to_kelvin(100.0)) - 7.3).abs() < 1e-9);
        // docs/model.md section 2 quotes about 18.5 cSt at 60 C and 5.2 cSt at 120 C for such a fluid
        let n60 = oil.nu_datasheet_cst(celsius_to_kelvin(60.0));
        let n120 = oil.nu_datasheet_cst(celsius_to_kelvin(120.0));
        assert!((n60 - 18.5).abs() < 1.0, "nu(60C) = {n60}");
        assert!((n120 - 5.2).abs() < 0.4, "nu(120C) = {n120}");
    }

    #[test]
    fn density_falls_with_temperature_and_rises_with_pressure() {
        let oil = atf();
        assert!(oil.density(celsius_to_kelvin(120.0)) < oil.density(celsius_to_kelvin(60.0)));
        let c = Compressibility::from_oil(&oil);
        let (r1, d1) = c.density_ratio(ATMOSPHERE_PA + 4e6);
        // liquid law exp(dp/B) up to the gas-release branch's normalisation offset
        // k w softplus((p_g - p_atm)/w), about 1.5e-5 for this oil
        let w = GAS_RELEASE_BAND_PA;
        let offset = (1.0 / 2.0e5 - 1.0 / 1.4e9) * w * ((2.0e4 - ATMOSPHERE_PA) / w).exp().ln_1p();
        assert!(offset < 2e-5);
        assert!(r1 > 1.0 && (r1 - (4e6 / 1.4e9 + offset).exp()).abs() < 1e-12);
        assert!((c.effective_modulus(1e6) - 1.4e9).abs() / 1.4e9 < 1e-12);
        assert!(d1 > 0.0);
    }

    #[test]
    fn entrained_air_softens_the_mixture_most_at_low_pressure() {
        let mut oil = atf();
        oil.air_fraction = 0.01;
        let c = Compressibility::from_oil(&oil);
        let b_low = c.effective_modulus(2.0e5);
        let b_high = c.effective_modulus(4.0e6);
        assert!(b_low < b_high && b_high < 1.4e9);
        // derivative check
        let p = 3.0e5;
        let h = 1.0;
        let (r_p, d) = c.density_ratio(p);
        let (r_ph, _) = c.density_ratio(p + h);
        assert!(((r_ph - r_p) / h - d).abs() / d < 1e-4);
    }
}
