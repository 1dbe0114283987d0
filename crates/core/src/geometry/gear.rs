//! One involute gear in its transverse section: outline polygon and an
//! analytic point-in-solid test.
//!
//! Body frame: tooth `m` is centred on body angle `2 pi m / z`; tooth space
//! `m` lies between teeth `m` and `m + 1` (centred on `2 pi (m + 1/2) / z`).
//! The flank is the involute from the base circle (or the root circle, when
//! it lies above the base circle) to the tip circle; below the base circle the
//! flank continues radially down to the root circle (a simplified fillet: it
//! carries no contact and its volume is small).

use super::involute::{self, transverse_pressure_angle};
use super::pair::PairSpec;
use std::f64::consts::PI;

#[derive(Debug, Clone)]
pub struct Gear {
    pub z: usize,
    /// Reference (generating pitch) radius, m.
    pub r: f64,
    /// Base radius, m.
    pub rb: f64,
    /// Tip radius, m.
    pub ra: f64,
    /// Root radius, m.
    pub rf: f64,
    /// Profile shift coefficient.
    pub x: f64,
    /// Transverse module, m.
    pub mt: f64,
    pub alpha_n: f64,
    pub alpha_t: f64,
    /// Transverse thinning at the reference circle, m.
    pub thinning: f64,
    /// The part of the half tooth angle that does not depend on the radius,
    /// `s_t / (2 r) + inv(alpha_t)` ([`involute::half_tooth_angle`]), worked
    /// out once: the flank tests of the pocket tables call
    /// [`Gear::half_angle`] hundreds of thousands of times.
    flank_constant: f64,
}

impl Gear {
    /// Gear `k` of the pair `d`.
    pub fn new(d: &PairSpec, k: usize) -> Gear {
        let g = &d.gears[k];
        let mt = d.normal_module / d.helix_angle.cos();
        let alpha_t = transverse_pressure_angle(d.normal_pressure_angle, d.helix_angle);
        let r = g.z as f64 * mt / 2.0;
        let flank_constant = involute::half_angle_constant(
            r,
            mt,
            g.shift,
            d.normal_pressure_angle,
            alpha_t,
            g.thinning,
        );
        Gear {
            z: g.z,
            r,
            rb: r * alpha_t.cos(),
            ra: g.tip_radius,
            rf: g.root_radius,
            x: g.shift,
            mt,
            alpha_n: d.normal_pressure_angle,
            alpha_t,
            thinning: g.thinning,
            flank_constant,
        }
    }

    /// Angular pitch, rad.
    pub fn pitch_angle(&self) -> f64 {
        2.0 * PI / self.z as f64
    }

    /// Half the angular tooth thickness at radius rho (rad); radial below the base circle.
    pub fn half_angle(&self, rho: f64) -> f64 {
        let rr = rho.max(self.rb).min(self.ra);
        involute::half_tooth_angle_from(self.flank_constant, self.rb, rr)
    }

    /// Tooth thickness (arc) at the tip, m.
    pub fn tip_land(&self) -> f64 {
        2.0 * self.half_angle(self.ra) * self.ra
    }

    /// Is the point at radius `rho` and body angle `alpha` inside the solid gear?
    pub fn contains_polar(&self, rho: f64, alpha: f64) -> bool {
        if rho <= self.rf {
            return true;
        }
        if rho > self.ra {
            return false;
        }
        let p = self.pitch_angle();
        let a = alpha - p * nearest_integer(alpha / p);
        a.abs() <= self.half_angle(rho)
    }

    /// Radii at which the flank is sampled (root to tip), `n` points.
    fn flank_radii(&self, n: usize) -> Vec<f64> {
        let start = self.rf;
        let inv_start = self.rb.max(self.rf);
        let mut v = Vec::with_capacity(n + 1);
        if inv_start > start {
            v.push(start);
        }
        // involute part: denser near the base circle where curvature is high
        for i in 0..n {
            let s = i as f64 / (n - 1) as f64;
            let t = s * s * (3.0 - 2.0 * s) * 0.5 + 0.5 * s; // mild clustering at both ends
            v.push(inv_start + (self.ra - inv_start) * t);
        }
        v
    }

    /// Outline of the whole gear in body polar coordinates (rho, alpha),
    /// counter-clockwise, `nf` points per flank, `na` points per arc.
    pub fn outline_polar(&self, nf: usize, na: usize) -> Vec<(f64, f64)> {
        let radii = self.flank_radii(nf);
        let p = self.pitch_angle();
        let mut pts = Vec::new();
        for m in 0..self.z {
            let c = m as f64 * p;
            // trailing side of tooth m (alpha < c), root to tip
            for &rho in &radii {
                pts.push((rho, c - self.half_angle(rho)));
            }
            // tip arc
            let ha = self.half_angle(self.ra);
            for i in 1..na {
                let s = i as f64 / na as f64;
                pts.push((self.ra, c - ha + 2.0 * ha * s));
            }
            // leading side, tip to root
            for &rho in radii.iter().rev() {
                pts.push((rho, c + self.half_angle(rho)));
            }
            // root arc to the next tooth
            let hf = self.half_angle(self.rf);
            let a0 = c + hf;
            let a1 = c + p - hf;
            for i in 1..na {
                let s = i as f64 / na as f64;
                pts.push((self.rf, a0 + (a1 - a0) * s));
            }
        }
        pts
    }

    /// Tooth space `m` closed by the tip circle, body polar coordinates,
    /// counter-clockwise: down the leading flank of tooth m, along the root,
    /// up the trailing flank of tooth m+1, back along the tip circle.
    pub fn space_polar(&self, m: usize, nf: usize, na: usize) -> Vec<(f64, f64)> {
        let radii = self.flank_radii(nf);
        let p = self.pitch_angle();
        let c0 = m as f64 * p;
        let c1 = c0 + p;
        let mut pts = Vec::new();
        for &rho in radii.iter().rev() {
            pts.push((rho, c0 + self.half_angle(rho)));
        }
        let hf = self.half_angle(self.rf);
        for i in 1..na {
            let s = i as f64 / na as f64;
            pts.push((self.rf, c0 + hf + (p - 2.0 * hf) * s));
        }
        for &rho in &radii {
            pts.push((rho, c1 - self.half_angle(rho)));
        }
        let ha = self.half_angle(self.ra);
        let nt = 4 * na;
        for i in 1..nt {
            let s = i as f64 / nt as f64;
            pts.push((self.ra, c1 - ha - (p - 2.0 * ha) * s));
        }
        // the loop above runs from inner to outer radius on the leading side
        // of the space; reverse to make it counter-clockwise
        pts.reverse();
        pts
    }

    /// Area of one tooth space inside the tip circle, m^2 (exact quadrature of
    /// the polar integral, used to check the polygons).
    pub fn space_area(&self) -> f64 {
        // integral over rho of (pitch - 2 half_angle(rho)) rho d rho
        let p = self.pitch_angle();
        self.root_to_tip_integral(|rho| (p - 2.0 * self.half_angle(rho)) * rho)
    }

    /// `integral f(rho) d rho` from the root to the tip circle, Simpson's
    /// rule on 4000 intervals (the integrands of the tooth profile are
    /// smooth but for the kink of the tooth angle at the base circle).
    pub fn root_to_tip_integral(&self, f: impl Fn(f64) -> f64) -> f64 {
        let n = 4000;
        let h = (self.ra - self.rf) / n as f64;
        let mut s = f(self.rf) + f(self.ra);
        for i in 1..n {
            let rho = self.rf + i as f64 * h;
            s += if i % 2 == 1 { 4.0 } else { 2.0 } * f(rho);
        }
        s * h / 3.0
    }
}

/// `x` rounded to the nearest integer, ties to even (|x| < 2^51): the
/// tooth tests' `round`, without the library call. It differs from
/// `f64::round` only on exact ties, where the angle lies half a pitch from a
/// tooth's centre line, outside any tooth either way, so no test changes.
#[inline]
pub fn nearest_integer(x: f64) -> f64 {
    const SHIFT: f64 = 6_755_399_441_055_744.0; // 1.5 * 2^52
    (x + SHIFT) - SHIFT
}

/// `floor(x)` for |x| < 2^63, exactly, without the library call.
#[inline]
pub fn floor_exact(x: f64) -> f64 {
    let t = x as i64 as f64;
    if t > x {
        t - 1.0
    } else {
        t
    }
}
