//! The gear pair: placement, phasing, line of action, contact ratio, the
//! closed-form displacement and kinematic flow.
//!
//! Global frame (transverse section): driving gear centre O1 at the origin,
//! driven gear centre O2 at (a, 0). The driving gear turns counter-clockwise
//! by `theta`, the driven gear clockwise by `theta z1 / z2`. Teeth leave the
//! mesh towards +y, so the **suction side is +y and the delivery side -y**.
//!
//! Each gear has a *local angle* psi measured from the line of centres
//! (psi = 0 points at the mating gear), positive towards the suction side, so
//! that psi grows with rotation on both gears: for the driving gear psi is the
//! global polar angle about O1; for the driven gear psi = pi - (global polar
//! angle about O2). The casing port edges of the design are given in psi.
//!
//! Phasing: at theta = 0 tooth 0 of the driving gear points along +x and
//! space 0 of the driven gear faces it; the driven gear then lags by the
//! backlash so that the driving gear's leading flanks are in contact
//! (single-flank contact, seed Table 1).
//!
//! Line of action (driving gear turning counter-clockwise and driving): the
//! common tangent of the base circles through the pitch point P = (rw1, 0),
//! touching base circle 1 at T1 = rb1 (cos aw, -sin aw), direction
//! u = (sin aw, cos aw); contact points move along +u.
//!
//! Displacement, closed form for unequal gears (Manring & Kasaragadda 2003),
//! per driving-gear revolution:
//! `Vm = pi b [ra1^2 - rw1^2 + (rw1/rw2)(ra2^2 - rw2^2) - (1 + rw1/rw2) pbt^2/12]`,
//! and the instantaneous kinematic flow
//! `Q = (b w1 / 2) [ra1^2 - rw1^2 + (rw1/rw2)(ra2^2 - rw2^2) - (1 + rw1/rw2) l^2]`
//! with `l` the distance of the active contact from the pitch point, sweeping
//! -pbt/2..pbt/2 over a mesh period (ideal relief of the trapped volume).

use super::gear::Gear;
use super::involute::{inv, inv_inverse};
use std::f64::consts::PI;

pub type P2 = [f64; 2];

/// One gear's cut, SI (what [`PairSpec`] holds per gear).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GearBlank {
    pub z: usize,
    pub tip_radius: f64,
    pub root_radius: f64,
    /// Profile shift coefficient.
    pub shift: f64,
    /// Transverse thinning at the reference circle, m.
    pub thinning: f64,
}

/// What the gear pair is made from, SI: the geometry knows nothing of the
/// design file (`design::Design::pair_spec` fills it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairSpec {
    pub normal_module: f64,
    pub helix_angle: f64,
    pub normal_pressure_angle: f64,
    pub centre_distance: f64,
    pub face_width: f64,
    pub gears: [GearBlank; 2],
}

#[derive(Debug, Clone)]
pub struct Pair {
    pub gears: [Gear; 2],
    /// Operating centre distance, m.
    pub a: f64,
    /// Working transverse pressure angle, rad.
    pub alpha_w: f64,
    /// Operating pitch radii, m.
    pub rw: [f64; 2],
    /// Transverse base pitch, m.
    pub pbt: f64,
    /// Transverse contact ratio.
    pub eps_alpha: f64,
    /// Overlap (face) contact ratio.
    pub eps_beta: f64,
    /// Face width, m.
    pub b: f64,
    /// Helix angle, rad.
    pub beta: f64,
    /// Driven-gear lag behind the symmetric placement, rad (closes the backlash on the drive flanks).
    pub lag2: f64,
    /// Circular backlash on the operating pitch circle, m.
    pub backlash_t: f64,
}

impl Pair {
    pub fn new(d: &PairSpec) -> Pair {
        let g1 = Gear::new(d, 0);
        let g2 = Gear::new(d, 1);
        let a = d.centre_distance;
        let alpha_w = ((g1.rb + g2.rb) / a).acos();
        let rw = [g1.rb / alpha_w.cos(), g2.rb / alpha_w.cos()];
        let pbt = 2.0 * PI * g1.rb / g1.z as f64;
        let eps_alpha = ((g1.ra.powi(2) - g1.rb.powi(2)).sqrt()
            + (g2.ra.powi(2) - g2.rb.powi(2)).sqrt()
            - a * alpha_w.sin())
            / pbt;
        let eps_beta = d.face_width * d.helix_angle.sin() / (PI * d.normal_module);
        // circular backlash on the operating pitch circles
        let s1 = 2.0 * g1.half_angle(rw[0]) * rw[0];
        let s2 = 2.0 * g2.half_angle(rw[1]) * rw[1];
        let pw = 2.0 * PI * rw[0] / g1.z as f64;
        let backlash_t = pw - s1 - s2;
        let lag2 = 0.5 * backlash_t / rw[1];
        Pair {
            gears: [g1, g2],
            a,
            alpha_w,
            rw,
            pbt,
            eps_alpha,
            eps_beta,
            b: d.face_width,
            beta: d.helix_angle,
            lag2,
            backlash_t,
        }
    }

    /// Ratio of driven to driving angular speed, z1/z2.
    pub fn ratio(&self) -> f64 {
        self.gears[0].z as f64 / self.gears[1].z as f64
    }

    pub fn centre(&self, k: usize) -> P2 {
        if k == 0 {
            [0.0, 0.0]
        } else {
            [self.a, 0.0]
        }
    }

    /// Rotation of gear k's body (its local-angle offset) at driving angle theta.
    pub fn body_offset(&self, k: usize, theta: f64) -> f64 {
        if k == 0 {
            theta
        } else {
            theta * self.ratio() + PI / self.gears[1].z as f64 - self.lag2
        }
    }

    /// Global point of gear k at radius rho and local angle psi.
    pub fn local_to_global(&self, k: usize, rho: f64, psi: f64) -> P2 {
        if k == 0 {
            [rho * psi.cos(), rho * psi.sin()]
        } else {
            [self.a - rho * psi.cos(), rho * psi.sin()]
        }
    }

    /// (rho, psi) of a global point relative to gear k.
    pub fn global_to_local(&self, k: usize, x: P2) -> (f64, f64) {
        if k == 0 {
            (x[0].hypot(x[1]), x[1].atan2(x[0]))
        } else {
            let dx = self.a - x[0];
            (dx.hypot(x[1]), x[1].atan2(dx))
        }
    }

    /// Is a global point inside the solid of gear k at driving angle theta?
    pub fn solid_contains(&self, k: usize, theta: f64, x: P2) -> bool {
        // global_to_local's radius first: most points are told by it alone
        let g = &self.gears[k];
        let dx = if k == 0 { x[0] } else { self.a - x[0] };
        let rho = dx.hypot(x[1]);
        if rho <= g.rf {
            return true;
        }
        if rho > g.ra {
            return false;
        }
        g.contains_polar(rho, x[1].atan2(dx) - self.body_offset(k, theta))
    }

    /// Pitch point.
    pub fn pitch_point(&self) -> P2 {
        [self.rw[0], 0.0]
    }

    /// Unit direction of the line of action (contacts move along it).
    pub fn loa_dir(&self) -> P2 {
        [self.alpha_w.sin(), self.alpha_w.cos()]
    }

    /// Unit normal of the line of action pointing to the driven gear's side.
    pub fn loa_normal(&self) -> P2 {
        [self.alpha_w.cos(), -self.alpha_w.sin()]
    }

    /// Intersections of the tip circles (the casing cusps): (x, +y) and (x, -y).
    pub fn cusp(&self) -> P2 {
        let (r1, r2) = (self.gears[0].ra, self.gears[1].ra);
        let x = (self.a * self.a + r1 * r1 - r2 * r2) / (2.0 * self.a);
        [x, (r1 * r1 - x * x).max(0.0).sqrt()]
    }

    /// Local angle of the suction-side cusp on gear k (rad, > 0).
    pub fn cusp_angle(&self, k: usize) -> f64 {
        let c = self.cusp();
        self.global_to_local(k, c).1
    }

    /// Closed-form displacement per driving-gear revolution, m^3 (Manring & Kasaragadda 2003).
    pub fn displacement_closed_form(&self) -> f64 {
        let (ra1, ra2) = (self.gears[0].ra, self.gears[1].ra);
        let (rw1, rw2) = (self.rw[0], self.rw[1]);
        PI * self.b
            * (ra1 * ra1 - rw1 * rw1 + (rw1 / rw2) * (ra2 * ra2 - rw2 * rw2)
                - (1.0 + rw1 / rw2) * self.pbt * self.pbt / 12.0)
    }

    /// Closed-form instantaneous kinematic flow of a spur section of width
    /// `width` per unit driving speed (m^3/rad), at driving angle `theta`:
    /// the contact nearest the pitch point sits at l in [-pbt/2, pbt/2).
    pub fn kinematic_flow_section(&self, theta: f64, width: f64) -> f64 {
        let (ra1, ra2) = (self.gears[0].ra, self.gears[1].ra);
        let (rw1, rw2) = (self.rw[0], self.rw[1]);
        let l = self.contact_offset(theta);
        0.5 * width
            * (ra1 * ra1 - rw1 * rw1 + (rw1 / rw2) * (ra2 * ra2 - rw2 * rw2)
                - (1.0 + rw1 / rw2) * l * l)
    }

    /// Signed distance from the pitch point, along the line of action, of the
    /// active contact (the one within half a base pitch of the pitch point).
    pub fn contact_offset(&self, theta: f64) -> f64 {
        // Contact of the driving gear's leading flank of tooth m: the involute
        // of tooth 0's leading flank crosses the line of action at arc
        // distance rb1 * (theta + phase) from where it would pass the pitch point.
        let g = &self.gears[0];
        // polar angle of the leading flank at the pitch circle at theta = 0
        let flank_at_pitch = g.half_angle(self.rw[0]);
        // The leading flank passes the pitch point when theta + flank_at_pitch = 0 (mod pitch);
        // the contact then moves along the line of action by rb1 per radian.
        let s = g.rb * (theta + flank_at_pitch);
        let p = self.pbt;
        s - p * (s / p).round()
    }

    /// Kinematic flow of the helical pair per unit driving speed (m^3/rad):
    /// the spur formula averaged over `slices` slices of the face width.
    pub fn kinematic_flow(&self, theta: f64, slices: usize) -> f64 {
        let w = self.b / slices as f64;
        (0..slices)
            .map(|s| self.kinematic_flow_section(theta + self.slice_phase(s, slices), w))
            .sum()
    }

    /// Driving-angle shift of slice `s` of `n` (helix): z tan(beta) / r1 with z
    /// the slice's axial position from mid-face.
    pub fn slice_phase(&self, s: usize, n: usize) -> f64 {
        let z = ((s as f64 + 0.5) / n as f64 - 0.5) * self.b;
        z * self.beta.tan() / self.gears[0].r
    }

    /// Involute check: working pressure angle of a tight mesh of these gears.
    pub fn tight_mesh_pressure_angle(&self) -> f64 {
        let g = &self.gears;
        inv_inverse(
            inv(g[0].alpha_t)
                + 2.0 * g[0].alpha_n.tan() * (g[0].x + g[1].x) / (g[0].z + g[1].z) as f64,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seed_pump_closed_form_displacement_is_near_the_paper() {
        let p = crate::design::Design::seed().pair();
        let v = p.displacement_closed_form() * 1e6;
        assert!((v - 14.65).abs() / 14.65 < 0.01, "Vm = {v} cm^3");
        assert!(
            p.eps_alpha > 1.0 && p.eps_alpha < 1.6,
            "eps = {}",
            p.eps_alpha
        );
        assert!(
            p.backlash_t / 2.25e-3 > 0.1,
            "backlash/mn = {}",
            p.backlash_t / 2.25e-3
        );
    }

    #[test]
    fn mean_of_kinematic_flow_is_the_displacement() {
        let p = crate::design::Design::seed().pair();
        let n = 20000;
        let mut s = 0.0;
        for i in 0..n {
            s += p.kinematic_flow(2.0 * PI * (i as f64 + 0.5) / n as f64, 8);
        }
        let v = s * 2.0 * PI / n as f64;
        assert!((v - p.displacement_closed_form()).abs() / v < 1e-4);
    }
}
