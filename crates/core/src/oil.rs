//! The oil: viscosity, density and effective bulk modulus as pure functions of
//! temperature (and pressure for the density law).
//!
//! Viscosity follows the Walther equation (ASTM D341):
//! `log10(log10(nu + 0.7)) = A - B log10(T)`, nu in cSt, T in K, with A and B
//! fitted exactly through two datasheet points (usually 40 and 100 degC).
//! Density: `rho(T) = rho_ref / (1 + alpha (T - T_ref))` (volumetric thermal
//! expansion). Compressibility: a constant effective bulk modulus `B` (oil plus
//! casing compliance), so the liquid's `rho(p) = rho(T) exp((p - p_atm)/B)`;
//! below the gas-release pressure the oil releases dissolved air in
//! proportion to the pressure drop (Henry), which expands as an isothermal
//! ideal gas ([`DensityLaw`]): its volume goes as 1/p, so a sealed pocket
//! that grows keeps a positive pressure (docs/model.md, section 2).

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

    /// Density ratio rho(p)/rho(p_atm) and d(ratio)/dp: the law of
    /// [`DensityLaw`], its constants worked out for this call.
    pub fn density_ratio(&self, p: f64) -> (f64, f64) {
        DensityLaw::new(*self).ratio(p)
    }

    /// Effective bulk modulus rho / (d rho/dp) at pressure p, Pa.
    pub fn effective_modulus(&self, p: f64) -> f64 {
        let (r, dr) = self.density_ratio(p);
        r / dr
    }

    /// The width of the gas-release band, Pa: [`GAS_RELEASE_BAND_PA`], or
    /// half the gas-release pressure where that is less, so that the
    /// smoothed release stays a release below `p_g` (a band wider than
    /// `p_g` would put most of its gas above it).
    pub fn band(&self) -> f64 {
        GAS_RELEASE_BAND_PA.min(0.5 * self.gas_release_pa)
    }

    /// The released gas's coefficient `a = p_g / B_c`: the gas volume, per
    /// unit volume of oil, released and expanded at `p` is
    /// `a (p_g - p) / p` (Henry: the release grows with the pressure drop;
    /// isothermal ideal gas: its volume goes as 1/p), so that the mixture's
    /// modulus at the onset is `p_g / a = B_c`.
    pub fn gas_coefficient(&self) -> f64 {
        self.gas_release_pa / self.cavitation_modulus
    }

    /// The pressure below which the law continues exponentially with its
    /// modulus there, Pa: a hundredth of the gas-release pressure, where
    /// a sealed volume of the seed's oil has grown elevenfold. Newton's
    /// trials may go below it, and find a smooth, monotone law there
    /// instead of the pole of `1/p` at zero.
    pub fn floor(&self) -> f64 {
        self.gas_release_pa / 100.0
    }
}

/// The oil's density law, `rho(p) / rho(p_atm)` and its derivative, with
/// its constants precomputed (docs/model.md section 2).
///
/// Per unit mass, the mixture's volume is the liquid's,
/// `exp(-(p - p_atm) / B)`, plus the gas released below the gas-release
/// pressure `p_g`: by Henry's law the released amount grows with the
/// pressure drop `(p_g - p)`, and as an isothermal ideal gas it takes the
/// volume `a (p_g - p) / p`, with `a = p_g / B_c` (B_c the mixture's
/// modulus at the onset of the release). The drop is smoothed over a band
/// `w`, `(p_g - p)+ ~ w softplus((p_g - p) / w)`, so
///
/// `v(p) = exp(-(p - p_atm) / B) + a w softplus((p_g - p) / w) / p`,
/// `r(p) = v(p_atm) / v(p)`.
///
/// The gas term goes as `1/p`, so a sealed pocket that grows keeps a
/// positive pressure down to the floor (elevenfold growth from `p_g` for
/// the seed's oil; zero absolute beyond about twentyfold, through the
/// floor's continuation), where the exponential branch this replaced
/// reached zero absolute at about a tenth of growth. Below the
/// [`floor`](Compressibility::floor) `ln r` goes on linearly with its
/// slope there (continuous value and derivative). Far above the release
/// (`p > p_g + 40 w`, the gas term below `e^-40` of the liquid's) the law
/// is `exp((p - p_atm) / B + ln v(p_atm))`, one exponential and no
/// division.
///
/// Entrained air (volume fraction `x0` at p_atm, isothermal ideal gas, its
/// mass neglected) is mixed in as `V_mix(p) = (1 - x0) / r(p) + x0 p_atm /
/// p`, ratio `1 / V_mix`, down to the floor, below which the mixture's
/// `ln r` goes on linearly. (Until 2026-11-28 the air stopped expanding at
/// `p_g`, `max(p, p_g)`: a kink in the law, and free bubbles that no
/// longer grew as the pressure fell.)
#[derive(Debug, Clone, Copy)]
pub struct DensityLaw {
    comp: Compressibility,
    /// The liquid branch applies above this pressure, Pa.
    liquid_above: f64,
    /// `ln v(p_atm)`, the constant of the liquid branch.
    c: f64,
    /// `v(p_atm)`.
    v_atm: f64,
    /// `1/B`, 1/Pa.
    inv_b: f64,
    /// The gas coefficient `a` and `a w`.
    a: f64,
    a_w: f64,
    /// The band `w`, Pa.
    w: f64,
    /// The floor, Pa, and the ratio and `d ln r / dp` there.
    floor: f64,
    r_floor: f64,
    slope_floor: f64,
}

impl DensityLaw {
    pub fn new(comp: Compressibility) -> Self {
        let w = comp.band();
        let inv_b = 1.0 / comp.bulk_modulus;
        let a = comp.gas_coefficient();
        let x0 = (comp.gas_release_pa - ATMOSPHERE_PA) / w;
        let v_gas_atm = a * w * softplus_logistic(x0).0 / ATMOSPHERE_PA;
        let mut law = DensityLaw {
            comp,
            liquid_above: if comp.air_fraction <= 0.0 {
                comp.gas_release_pa + 40.0 * w
            } else {
                f64::INFINITY
            },
            c: v_gas_atm.ln_1p(),
            v_atm: 1.0 + v_gas_atm,
            inv_b,
            a,
            a_w: a * w,
            w,
            floor: comp.floor(),
            r_floor: 1.0,
            slope_floor: 0.0,
        };
        let (r, dr) = law.with_air(law.floor);
        law.r_floor = r;
        law.slope_floor = dr / r;
        law
    }

    /// Density ratio rho(p)/rho(p_atm) and its derivative. The liquid
    /// branch inline (a few multiply-adds: most nodes at most pressures),
    /// the others behind a call.
    #[inline(always)]
    pub fn ratio(&self, p: f64) -> (f64, f64) {
        if p > self.liquid_above {
            let r = exp_near_zero((p - ATMOSPHERE_PA) * self.inv_b + self.c);
            (r, r * self.inv_b)
        } else {
            self.ratio_below_liquid(p)
        }
    }

    /// [`ratio`](Self::ratio) off the pure-liquid branch: the mixture
    /// above the floor, its continuation below.
    #[inline(never)]
    fn ratio_below_liquid(&self, p: f64) -> (f64, f64) {
        if p > self.floor {
            self.with_air(p)
        } else {
            let r = self.r_floor * exp_near_zero((p - self.floor) * self.slope_floor);
            (r, r * self.slope_floor)
        }
    }

    /// The oil with its released gas and the entrained air, `p > 0`. The
    /// air is an isothermal ideal gas at every pressure: its volume per
    /// unit volume of mixture at p_atm is `x0 p_atm / p`.
    #[inline]
    fn with_air(&self, p: f64) -> (f64, f64) {
        let (rl, drl) = self.mixture(p);
        let x0 = self.comp.air_fraction;
        if x0 <= 0.0 {
            return (rl, drl);
        }
        let air = x0 * ATMOSPHERE_PA / p;
        let vmix = (1.0 - x0) / rl + air;
        let dvmix = -(1.0 - x0) * drl / (rl * rl) - air / p;
        (1.0 / vmix, -dvmix / (vmix * vmix))
    }

    /// `v(p_atm) / v(p)` and its derivative, `p > 0`.
    #[inline]
    fn mixture(&self, p: f64) -> (f64, f64) {
        let x = (self.comp.gas_release_pa - p) / self.w;
        let (softplus, logistic) = softplus_logistic(x);
        let q = 1.0 / p;
        let liquid = exp_near_zero((ATMOSPHERE_PA - p) * self.inv_b);
        // the released gas's volume a w softplus / p
        let gas = self.a_w * softplus * q;
        let inv_v = 1.0 / (liquid + gas);
        let r = self.v_atm * inv_v;
        // -dv/dp = liquid / B + a (logistic / p + w softplus / p^2)
        let compliance = (liquid * self.inv_b + q * (self.a * logistic + gas)) * inv_v;
        (r, r * compliance)
    }

    /// The share of the oil in a fixed volume that compression from `p0`
    /// to `p1` adds, `1 - rho(p0) / rho(p1)` (negative when the pressure
    /// falls). On the liquid branch it is `-expm1((p0 - p1) / B)`, worked
    /// out without the difference of two nearly equal ratios; for the small
    /// steps of a communication step (`|x| < 1e-3`) by its series to the
    /// sixth power, exact to rounding (the next term is below `x^6 / 5040`
    /// relative), and by `exp_m1` beyond.
    #[inline]
    pub fn compressed_share(&self, p0: f64, p1: f64) -> f64 {
        if p0 > self.liquid_above && p1 > self.liquid_above {
            let x = (p0 - p1) / self.comp.bulk_modulus;
            let expm1 = if x.abs() < 1e-3 {
                expm1_series(x)
            } else {
                x.exp_m1()
            };
            -expm1
        } else {
            1.0 - self.ratio(p0).0 / self.ratio(p1).0
        }
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
        // liquid law exp(dp/B) up to the normalisation by the mixture's
        // volume at p_atm, 1 + a w softplus((p_g - p_atm)/w) / p_atm with
        // a = p_g / B_c: about 2.9e-6 for this oil
        let w = GAS_RELEASE_BAND_PA;
        let a = 2.0e4 / 2.0e5;
        let offset = (a * w * ((2.0e4 - ATMOSPHERE_PA) / w).exp().ln_1p() / ATMOSPHERE_PA).ln_1p();
        assert!(offset > 2e-6 && offset < 4e-6, "{offset}");
        assert!(r1 > 1.0 && (r1 - (4e6 / 1.4e9 + offset).exp()).abs() < 1e-12);
        assert!((c.effective_modulus(1e6) - 1.4e9).abs() / 1.4e9 < 1e-12);
        assert!(d1 > 0.0);
    }

    /// The smallest `p` in `[lo, hi]` with `r(p) >= target` (the law is
    /// increasing), by bisection.
    fn pressure_at_ratio(law: &DensityLaw, target: f64, mut lo: f64, mut hi: f64) -> f64 {
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if law.ratio(mid).0 < target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }

    /// A sealed volume of oil that grows below the gas-release pressure,
    /// against the closed form of the mechanism written out here: the
    /// released gas grows with the pressure drop (Henry), `a (p_g - p)`
    /// at `p_g` per unit volume with `a = p_g / B_c`, and expands as an
    /// isothermal ideal gas, so the volume per unit mass is
    /// `exp(-(p - p_atm) / B) + a (p_g - p) / p`, without the law's
    /// smoothing. An oil releasing at 1 bar (band 0.1 bar) puts the
    /// states five bands and more below `p_g`, where the smoothing is
    /// below 1e-3 of the gas. Also: the modulus at those states, and the
    /// growth at which the pressure reaches zero absolute with the seed's
    /// oil (the exponential branch this replaced reached it at 1.105).
    #[test]
    fn a_sealed_volume_that_grows_follows_henry_and_the_isothermal_gas() {
        let mut oil = atf();
        oil.gas_release_pa = 1.0e5;
        oil.cavitation_modulus = 2.0e5;
        let comp = Compressibility::from_oil(&oil);
        let law = DensityLaw::new(comp);
        let (p_g, a, b) = (1.0e5, 0.5, 1.4e9);
        let v = |p: f64| (-(p - ATMOSPHERE_PA) / b).exp() + a * (p_g - p) / p;
        let p0 = 0.5e5;
        for f in [1.01, 1.1, 1.5, 2.0, 5.0, 10.0, 20.0] {
            let p1 = pressure_at_ratio(&law, law.ratio(p0).0 / f, -1.0e5, p0);
            // the closed form's state at f times the volume (v decreasing)
            let (mut lo, mut hi) = (1.0, p0);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if v(mid) > f * v(p0) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let want = 0.5 * (lo + hi);
            assert!(p1 > 0.0, "grown {f}-fold: {p1} Pa");
            assert!(
                (p1 - want).abs() < 2e-3 * want,
                "grown {f}-fold: {p1} Pa against {want} Pa"
            );
            // the modulus there, v / (-dv/dp) = v p^2 / (a p_g)
            let modulus = v(want) * want * want / (a * p_g);
            let got = comp.effective_modulus(p1);
            assert!(
                (got - modulus).abs() < 5e-3 * modulus,
                "modulus at {p1} Pa: {got} against {modulus}"
            );
        }
        // the seed's oil: from the gas-release pressure, zero absolute is
        // reached only beyond twentyfold growth (the floor's continuation)
        let seed = DensityLaw::new(Compressibility::from_oil(&atf()));
        let growth_to_zero = seed.ratio(2.0e4).0 / seed.ratio(0.0).0;
        assert!(growth_to_zero > 20.0, "{growth_to_zero}");
    }

    /// The law and its derivative across every branch (the floor's
    /// continuation, the released gas, the band, the liquid), with and
    /// without entrained air and for an oil releasing at 1 mbar (the band
    /// narrowed to half of it): increasing, continuous at the branch
    /// limits, and the derivative the central difference of the ratio
    /// (with entrained air too: until 2026-11-28 its expansion stopped at
    /// `p_g`, a kink this test had to step over).
    #[test]
    fn the_law_is_increasing_and_smooth_and_its_derivative_is_its_slope() {
        let base = Compressibility::from_oil(&atf());
        for comp in [
            base,
            Compressibility {
                air_fraction: 0.01,
                ..base
            },
            Compressibility {
                gas_release_pa: 100.0,
                cavitation_modulus: 2.0e4,
                ..base
            },
        ] {
            let law = DensityLaw::new(comp);
            let liquid_above = comp.gas_release_pa + 40.0 * comp.band();
            let mut last = 0.0;
            let mut p = -5.0 * comp.floor();
            while p < 1.0e7 {
                let (r, dr) = law.ratio(p);
                assert!(r > last && dr > 0.0, "{comp:?} at {p} Pa");
                last = r;
                let h = 1e-4 * p.abs().max(comp.floor());
                let slope = (law.ratio(p + h).0 - law.ratio(p - h).0) / (2.0 * h);
                // the floor's continuation has the value and slope there,
                // not the curvature: differences across it are checked below
                let kink = (p - comp.floor()).abs() <= h;
                assert!(
                    kink || (slope - dr).abs() < 1e-5 * dr,
                    "{comp:?} at {p} Pa: {dr} against {slope}"
                );
                p = if p < comp.gas_release_pa {
                    p + 0.01 * comp.gas_release_pa
                } else {
                    p * 1.05
                };
            }
            for edge in [comp.floor(), liquid_above] {
                let (below, above) = (law.ratio(edge).0, law.ratio(edge * (1.0 + 1e-15)).0);
                assert!(
                    (above - below).abs() < 1e-12 * below,
                    "{comp:?} at {edge} Pa"
                );
            }
        }
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

    /// Free air is an isothermal ideal gas at every pressure, below the
    /// gas release too: per unit volume of the mixture at p_atm, the
    /// mixture's volume less the oil's share is `x0 p_atm / p`, Boyle's
    /// law, from the delivery down to a pocket at a hundredth of an
    /// atmosphere; above the release's band the mixture is the closed form
    /// of an exponential liquid and the gas.
    #[test]
    fn entrained_air_expands_as_boyle_at_every_pressure() {
        let x0 = 0.02;
        let oil = Compressibility::from_oil(&atf());
        let with_air = DensityLaw::new(Compressibility {
            air_fraction: x0,
            ..oil
        });
        let without = DensityLaw::new(oil);
        let b = oil.bulk_modulus;
        for p in [
            1.0e3, 5.0e3, 1.5e4, 2.0e4, 3.0e4, 1.0e5, 1.0e6, 4.0e6, 3.0e7,
        ] {
            let air = 1.0 / with_air.ratio(p).0 - (1.0 - x0) / without.ratio(p).0;
            let boyle = x0 * ATMOSPHERE_PA / p;
            // to round-off of the mixture's volume (about 1 at the delivery)
            let v = 1.0 / with_air.ratio(p).0;
            assert!(
                (air - boyle).abs() < 1e-12 * v,
                "{p} Pa: {air} against {boyle}"
            );
            if p > oil.gas_release_pa + 40.0 * oil.band() {
                // the liquid's reference state at p_atm holds the release's
                // tail there, a w softplus((p_g - p_atm) / w) / p_atm (3e-6)
                let (a, w) = (oil.gas_release_pa / oil.cavitation_modulus, oil.band());
                let tail = a * w * ((oil.gas_release_pa - ATMOSPHERE_PA) / w).exp().ln_1p()
                    / ATMOSPHERE_PA;
                let liquid = (-(p - ATMOSPHERE_PA) / b).exp() / (1.0 + tail);
                let closed = 1.0 / ((1.0 - x0) * liquid + boyle);
                let r = with_air.ratio(p).0;
                assert!(
                    (r / closed - 1.0).abs() < 1e-12,
                    "{p} Pa: {r} against {closed}"
                );
            }
        }
    }
}
