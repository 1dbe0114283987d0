//! A hand calculation of the bundled pump's losses from textbook gear
//! geometry and lubrication theory, for `tests/references.rs`.
//!
//! It reads the numbers of the bundled design file itself (its TOML text,
//! units as written there) and uses nothing of the model but that text: no
//! table, no geometry, oil or network code. Every formula is written out
//! here with its derivation; docs/references.md compares its figures with
//! the model's.
#![allow(dead_code)] // each test uses a part

use gearpump::campaign::CampaignRecord;
use gearpump::design::SEED_PUMP_TOML;
use std::f64::consts::PI;

/// `inv(a) = tan(a) - a`, the involute function.
pub fn inv(a: f64) -> f64 {
    a.tan() - a
}

/// The design's numbers, SI, read from the bundled TOML text.
#[derive(Debug, Clone)]
pub struct Hand {
    pub z: [f64; 2],
    pub mn: f64,
    pub beta: f64,
    pub alpha_n: f64,
    pub b: f64,
    pub x: [f64; 2],
    pub ra: [f64; 2],
    pub rf: [f64; 2],
    /// Normal backlash, m.
    pub jn: f64,
    /// Port edges on each gear's own angle (0 towards the mating gear,
    /// positive towards the suction and in the sense of rotation), rad.
    pub suction_edge: [f64; 2],
    pub delivery_edge: [f64; 2],
    /// Journal radius, m, bearing length, m.
    pub rj: [f64; 2],
    pub bearing_length: f64,
    pub tip: f64,
    pub bearing: f64,
    pub lateral: f64,
    pub nu40: f64,
    pub nu100: f64,
    pub rho20: f64,
    pub expansion: f64,
    pub bulk_modulus: f64,
    pub slices: usize,
    /// Driving-gear angle per step, rad, and pressure nodes of every tooth
    /// space along the face width (the numerics of the design file).
    pub angle_step: f64,
    pub axial_nodes: usize,
}

fn num(v: &toml::Value, path: &str) -> f64 {
    let mut x = v;
    for key in path.split('.') {
        x = x.get(key).unwrap_or_else(|| panic!("{path} in the design"));
    }
    x.as_float()
        .or_else(|| x.as_integer().map(|i| i as f64))
        .unwrap_or_else(|| panic!("{path} is a number"))
}

impl Hand {
    pub fn seed() -> Hand {
        let v: toml::Value = toml::from_str(SEED_PUMP_TOML).expect("the bundled design parses");
        let mm = 1e-3;
        let um = 1e-6;
        let deg = PI / 180.0;
        Hand {
            z: [num(&v, "gears.z_drive"), num(&v, "gears.z_driven")],
            mn: num(&v, "gears.normal_module_mm") * mm,
            beta: num(&v, "gears.helix_angle_deg") * deg,
            alpha_n: num(&v, "gears.normal_pressure_angle_deg") * deg,
            b: num(&v, "gears.face_width_mm") * mm,
            x: [
                num(&v, "gears.profile_shift_drive"),
                num(&v, "gears.profile_shift_driven"),
            ],
            ra: [
                num(&v, "gears.tip_radius_drive_mm") * mm,
                num(&v, "gears.tip_radius_driven_mm") * mm,
            ],
            rf: [
                num(&v, "gears.root_radius_drive_mm") * mm,
                num(&v, "gears.root_radius_driven_mm") * mm,
            ],
            jn: num(&v, "gears.backlash_normal_mm") * mm,
            suction_edge: [
                num(&v, "casing.suction_port_edge_drive_deg") * deg,
                num(&v, "casing.suction_port_edge_driven_deg") * deg,
            ],
            delivery_edge: [
                num(&v, "casing.delivery_port_edge_drive_deg") * deg,
                num(&v, "casing.delivery_port_edge_driven_deg") * deg,
            ],
            rj: [
                0.5 * num(&v, "bearings.diameter_drive_mm") * mm,
                0.5 * num(&v, "bearings.diameter_driven_mm") * mm,
            ],
            bearing_length: num(&v, "bearings.length_mm") * mm,
            tip: num(&v, "clearance.tip_um") * um,
            bearing: num(&v, "clearance.bearing_um") * um,
            lateral: num(&v, "clearance.lateral_um") * um,
            nu40: num(&v, "oil.nu_40c_cst"),
            nu100: num(&v, "oil.nu_100c_cst"),
            rho20: num(&v, "oil.density_20c_kg_m3"),
            expansion: num(&v, "oil.expansion_per_k"),
            bulk_modulus: num(&v, "oil.bulk_modulus_gpa") * 1e9,
            slices: num(&v, "numerics.helical_slices") as usize,
            angle_step: num(&v, "numerics.angle_step_deg") * deg,
            axial_nodes: num(&v, "numerics.axial_nodes") as usize,
        }
    }

    // ------------------------------------------------------------ geometry
    /// Transverse module `mn / cos(beta)` and pressure angle
    /// `tan(alpha_t) = tan(alpha_n) / cos(beta)`.
    pub fn mt(&self) -> f64 {
        self.mn / self.beta.cos()
    }
    pub fn alpha_t(&self) -> f64 {
        (self.alpha_n.tan() / self.beta.cos()).atan()
    }
    /// Reference radius `z mt / 2` and base radius `r cos(alpha_t)`.
    pub fn r(&self, k: usize) -> f64 {
        self.z[k] * self.mt() / 2.0
    }
    pub fn rb(&self, k: usize) -> f64 {
        self.r(k) * self.alpha_t().cos()
    }
    /// Working pressure angle of the tight mesh:
    /// `inv(alpha_w) = inv(alpha_t) + 2 tan(alpha_n) (x1 + x2) / (z1 + z2)`
    /// (the operating pitch circles carry tooth thickness + space = pitch),
    /// solved by Newton (`d inv / d a = tan^2 a`).
    pub fn alpha_w(&self) -> f64 {
        let target = inv(self.alpha_t())
            + 2.0 * self.alpha_n.tan() * (self.x[0] + self.x[1]) / (self.z[0] + self.z[1]);
        let mut a = 0.5;
        for _ in 0..60 {
            a -= (inv(a) - target) / a.tan().powi(2);
        }
        a
    }
    /// Centre distance `(r1 + r2) cos(alpha_t) / cos(alpha_w)`.
    pub fn centre_distance(&self) -> f64 {
        (self.r(0) + self.r(1)) * self.alpha_t().cos() / self.alpha_w().cos()
    }
    /// Operating pitch radius `rb / cos(alpha_w)`.
    pub fn rw(&self, k: usize) -> f64 {
        self.rb(k) / self.alpha_w().cos()
    }
    /// Transverse base pitch `2 pi rb1 / z1`.
    pub fn pbt(&self) -> f64 {
        2.0 * PI * self.rb(0) / self.z[0]
    }
    /// Displacement per driving-gear revolution (Manring and Kasaragadda
    /// 2003): the flow `b w1/2 [ra1^2 - rho1^2 + (w2/w1)(ra2^2 - rho2^2)]`
    /// (rho the contact's distances from the centres) with
    /// `rho_k^2 = rw_k^2 +- 2 l rw_k sin(alpha_w) + l^2`: the linear terms
    /// cancel (w2 rw2 = w1 rw1) and the mean of `l^2` over `l` uniform in
    /// `+-pbt/2` is `pbt^2 / 12`.
    pub fn displacement(&self) -> f64 {
        let (rw1, rw2) = (self.rw(0), self.rw(1));
        let i = rw1 / rw2;
        PI * self.b
            * (self.ra[0].powi(2) - rw1 * rw1 + i * (self.ra[1].powi(2) - rw2 * rw2)
                - (1.0 + i) * self.pbt().powi(2) / 12.0)
    }
    /// Transverse tooth thickness at the reference circle:
    /// `mt (pi/2 + 2 x tan(alpha_n))`, the driving gear thinned for the
    /// backlash. The normal backlash `jn` (feeler gauge, normal to the flanks
    /// along the line of action) opened by an angular thinning `dpsi` of gear
    /// 1 is `dpsi rb1 cos(beta_b)`; at the reference circle that thinning is
    /// `dpsi r1 = jn / (cos(alpha_t) cos(beta_b)) = jn / (cos(alpha_n) cos(beta))`
    /// (`cos(beta_b) = cos(beta) cos(alpha_n) / cos(alpha_t)`).
    pub fn s_ref(&self, k: usize) -> f64 {
        let s = self.mt() * (PI / 2.0 + 2.0 * self.x[k] * self.alpha_n.tan());
        if k == 0 {
            s - self.jn / (self.alpha_n.cos() * self.beta.cos())
        } else {
            s
        }
    }
    /// Half the angular tooth thickness at radius `rr`:
    /// `s_ref / (2 r) + inv(alpha_t) - inv(alpha_rr)`, `cos(alpha_rr) = rb / rr`;
    /// the flank taken radial below the base circle.
    pub fn half_angle(&self, k: usize, rr: f64) -> f64 {
        let rr = rr.max(self.rb(k));
        let a = (self.rb(k) / rr).acos();
        self.s_ref(k) / (2.0 * self.r(k)) + inv(self.alpha_t()) - inv(a)
    }
    /// Tip land (arc) `2 ra psi(ra)`.
    pub fn land(&self, k: usize) -> f64 {
        2.0 * self.ra[k] * self.half_angle(k, self.ra[k])
    }
    /// Mid-height radius and the tooth thickness (arc) there.
    pub fn r_mid(&self, k: usize) -> f64 {
        0.5 * (self.ra[k] + self.rf[k])
    }
    pub fn s_mid(&self, k: usize) -> f64 {
        2.0 * self.r_mid(k) * self.half_angle(k, self.r_mid(k))
    }
    /// The angle a tooth's root arc spans on the root circle (the flank
    /// taken radial below the base circle).
    pub fn tooth_root_angle(&self, k: usize) -> f64 {
        2.0 * self.half_angle(k, self.rf[k])
    }
    /// Volume of one tooth space between the root and the tip circle:
    /// `b [pi (ra^2 - rf^2) / z - integral(2 psi(r) r dr)]` over `rf..ra`
    /// (the tooth's area from its half angular thickness `psi`, radial
    /// flanks below the base circle; midpoint rule, 20,000 points).
    pub fn space_volume(&self, k: usize) -> f64 {
        let n = 20_000;
        let dr = (self.ra[k] - self.rf[k]) / n as f64;
        let tooth: f64 = (0..n)
            .map(|j| {
                let rr = self.rf[k] + (j as f64 + 0.5) * dr;
                2.0 * self.half_angle(k, rr) * rr * dr
            })
            .sum();
        self.b * (PI * (self.ra[k].powi(2) - self.rf[k].powi(2)) / self.z[k] - tooth)
    }
    /// The share of `Vm n` lost to pressurising the tooth spaces from the
    /// suction `p_s` to the delivery `p_d` (absolute, Pa) when the oil
    /// carries free air, volume fraction `x0` at the atmosphere's pressure
    /// (isothermal ideal gas, its mass neglected), with ideal relief. Per
    /// unit mass the mixture's volume is
    /// `v(p) = (1 - x0) exp(-(p - p_atm) / K) + x0 p_atm / p`; a space of
    /// volume `V` fills at `p_s` and delivers the mass `V / v(p_s)` less what
    /// the trapped volume carries back at `p_d`, so the delivered volume
    /// falls short of the swept one by `V (1 - v(p_d) / v(p_s))` per space,
    /// and `z1` spaces of each gear pass per driving revolution:
    /// `z1 (V1 + V2) (1 - v(p_d) / v(p_s)) / Vm`. With `x0 = 0` it is the
    /// oil's compressibility alone.
    pub fn pressurising_share(&self, x0: f64, p_s: f64, p_d: f64) -> f64 {
        const P_ATM: f64 = 101_325.0;
        let v = |p: f64| (1.0 - x0) * (-(p - P_ATM) / self.bulk_modulus).exp() + x0 * P_ATM / p;
        self.z[0] * (self.space_volume(0) + self.space_volume(1)) / self.displacement()
            * (1.0 - v(p_d) / v(p_s))
    }
    /// Gear speeds for a driving speed `omega`: the driven gear z1/z2 times as fast.
    pub fn omegas(&self, omega: f64) -> [f64; 2] {
        [omega, omega * self.z[0] / self.z[1]]
    }

    // ------------------------------------------------------------ oil
    /// Walther (ASTM D341) through the two datasheet points:
    /// `log10(log10(nu + 0.7)) = A - B log10(T)`, nu in cSt, T in K.
    pub fn nu_cst(&self, temp_c: f64) -> f64 {
        let y = |nu: f64| (nu + 0.7).log10().log10();
        let (t1, t2) = (313.15f64.log10(), 373.15f64.log10());
        let bw = (y(self.nu40) - y(self.nu100)) / (t2 - t1);
        let aw = y(self.nu40) + bw * t1;
        10f64.powf(10f64.powf(aw - bw * (temp_c + 273.15).log10())) - 0.7
    }
    /// Density with a volumetric expansion from 20 degC:
    /// `rho20 / (1 + alpha (T - 20))`.
    pub fn rho(&self, temp_c: f64) -> f64 {
        self.rho20 / (1.0 + self.expansion * (temp_c - 20.0))
    }
    pub fn mu(&self, temp_c: f64) -> f64 {
        self.nu_cst(temp_c) * 1e-6 * self.rho(temp_c)
    }
}

/// The leakage and the viscous torques by hand at one operating point.
#[derive(Debug, Clone, Copy, Default)]
pub struct HandLosses {
    /// Shares of `Vm n`, weighted as the model's loss budget weights them
    /// (each element's flow times the share of the pressure rise it
    /// crosses; their sum is the flow lost from the delivery).
    pub tip_poiseuille: f64,
    pub tip_couette: f64,
    /// Lateral: pockets to the hubs (radial sectors) and across the teeth.
    pub lateral_hub: f64,
    pub lateral_tooth: f64,
    /// The face film below the roots solved as a whole annulus (Laplace,
    /// circumferential flow included) instead of radial sectors.
    pub lateral_hub_annulus: f64,
    /// Tip shear torques on the driving shaft, N m: the Couette stress
    /// `mu U / h` over the lands under the bore, and the pressure-driven wall stress
    /// `h dp_i / (2 L)` of each sealing land (`b h dp / 2` per gear's chain).
    pub torque_tip_couette: f64,
    pub torque_tip_pressure: f64,
    /// Per gear, the mean of `mu(p) / mu` over the faces' shear (teeth,
    /// disc below the roots); 1 without a pressure-viscosity law
    /// ([`hand_losses_barus`]).
    pub face_viscosity_factor: [[f64; 2]; 2],
}

/// Options of the hand calculation.
#[derive(Debug, Clone, Copy)]
pub struct Point {
    pub rpm: f64,
    pub bar: f64,
    pub temp_c: f64,
    /// Gear centre offsets (m) in the frame where x points from the driving
    /// gear's centre to the driven gear's and y towards the suction; the
    /// tip clearance of a land at direction d is `c - e . d`.
    pub offset: [[f64; 2]; 2],
    /// Angular positions per pitch averaged over.
    pub positions: usize,
}

/// The tooth-tip chain of each gear, by hand.
///
/// Per gear, the casing bore seals from the suction port edge round the back
/// to the delivery port edge. The tips are gaps in series between the
/// pockets: `Q = G (p_behind - p_ahead) + C` with, per slice of the face
/// width (the helix turns slice `zeta` by `zeta tan(beta) / r`), the
/// Poiseuille conductance `w h^3 / (12 mu L)` (L the covered part of the
/// land, held at 5 % of it like the model, where the laminar law stops
/// holding) and the Couette flow `w h U / 2` forward with the teeth (the
/// clearance annulus is fixed in the casing frame, docs/model.md section 4).
/// In parallel with each tip, the lateral gaps across the tooth (both faces,
/// width `ra - rf`, length the thickness at mid-height, drag `w h U_mid / 2`);
/// from every pocket a radial sector of the face film down to the hub
/// (`dphi h^3 / (12 mu ln(rf / R_journal))` per face, the hub at suction
/// through its by-pass grooves).
///
/// Idealisations: the pockets are incompressible and quasi-steady (the
/// chain's pressures are its steady solution at each position); a pocket is
/// at its port's pressure as soon as a land bounding it has left the bore in
/// any slice (the model throttles that opening); the pockets outside the
/// chain are at the delivery pressure from the delivery edge to the line of
/// centres and at the suction pressure beyond it (the trapped pocket's
/// pressure is not known by hand).
pub fn hand_losses(h: &Hand, pt: Point) -> HandLosses {
    hand_losses_barus(h, pt, 0.0)
}

/// Barus's law's reduced pressure, `psi(p) = (1 - exp(-alpha p)) / alpha`
/// (p itself when alpha is 0), and its inverse.
pub fn barus_reduced(p: f64, alpha: f64) -> f64 {
    if alpha == 0.0 {
        p
    } else {
        -(-alpha * p).exp_m1() / alpha
    }
}

fn barus_pressure(psi: f64, alpha: f64) -> f64 {
    if alpha == 0.0 {
        psi
    } else {
        -(-alpha * psi).ln_1p() / alpha
    }
}

/// The mean of `exp(alpha p)` along a uniform film whose reduced pressure
/// runs linearly from `psi_a` to `psi_b`: `(p_b - p_a) / (psi_b - psi_a)`.
pub fn barus_mean_factor(psi_a: f64, psi_b: f64, alpha: f64) -> f64 {
    if alpha == 0.0 {
        return 1.0;
    }
    let (pa, pb) = (barus_pressure(psi_a, alpha), barus_pressure(psi_b, alpha));
    if (psi_b - psi_a).abs() <= 1e-9 * psi_a.abs().max(psi_b.abs()).max(1.0) {
        (alpha * 0.5 * (pa + pb)).exp()
    } else {
        (pb - pa) / (psi_b - psi_a)
    }
}

/// [`hand_losses`] with the oil's viscosity rising with the local film
/// pressure by Barus's law, `mu(p) = mu exp(alpha p)` (p above the
/// suction). In a film of uniform clearance the Reynolds equation
/// `div(h^3 / (12 mu(p)) grad p) = 0` (the faces' and tips' drag terms have
/// no divergence) is Laplace's equation in the reduced pressure
/// `psi = (1 - exp(-alpha p)) / alpha`, and along a land or a radial sector
/// the Poiseuille flow is `G (psi_a - psi_b)` with the conductance of the
/// oil's own viscosity. The tip chains, the gaps across the teeth and the
/// face film below the roots are therefore the clean oil's, with the
/// delivery pressure replaced by `psi(dp)`, exactly: the flows are those of
/// [`hand_losses`] at that pressure. The torques take the real pressures:
/// the pressure-driven wall stress is `h/2 dp/dx` whatever the viscosity,
/// and the Couette stress of a land is `mu U / h` times the mean of
/// `exp(alpha p)` along it ([`barus_mean_factor`], psi linear along it);
/// the faces' factor ([`HandLosses::face_viscosity_factor`]) takes each
/// tooth's faces at the mean along the tooth between the pockets beside it
/// and the disc below the roots as the radial sectors (psi from the
/// pocket's down to the hub's zero with the logarithm of the radius),
/// weighted by `r^3` as the shear torque is.
pub fn hand_losses_barus(h: &Hand, pt: Point, alpha: f64) -> HandLosses {
    let dp = barus_reduced(pt.bar * 1e5, alpha);
    let omega = pt.rpm * PI / 30.0;
    let w = h.omegas(omega);
    let mu = h.mu(pt.temp_c);
    let q_th = h.displacement() * pt.rpm / 60.0;
    let n = h.slices;
    let bs = h.b / n as f64;
    let mut out = HandLosses::default();
    for k in 0..2 {
        let z = h.z[k] as usize;
        let pitch = 2.0 * PI / h.z[k];
        let refer = w[k] / w[0];
        let u = w[k] * h.ra[k];
        let land = h.land(k);
        let psi_a = land / (2.0 * h.ra[k]);
        let (lo, hi) = (h.suction_edge[k], 2.0 * PI + h.delivery_edge[k]);
        let shift: Vec<f64> = (0..n)
            .map(|s| ((s as f64 + 0.5) / n as f64 - 0.5) * h.b * h.beta.tan() / h.r(k))
            .collect();
        // across a tooth (both faces) and one pitch's sector to the hub (both faces)
        let g_lt = 2.0 * (h.ra[k] - h.rf[k]) * h.lateral.powi(3) / (12.0 * mu * h.s_mid(k));
        let c_lt = 2.0 * (h.ra[k] - h.rf[k]) * h.lateral / 2.0 * w[k] * h.r_mid(k);
        let g_hub = 2.0 * pitch * h.lateral.powi(3) / (12.0 * mu * (h.rf[k] / h.rj[k]).ln());
        let e = pt.offset[k];
        // the land direction in the offsets' frame: the driving gear's angle
        // runs from +x towards +y (suction), the driven gear's from -x towards +y
        let dir = |t: f64| -> [f64; 2] {
            if k == 0 {
                [t.cos(), t.sin()]
            } else {
                [-t.cos(), t.sin()]
            }
        };
        let nt = z + 5;
        let (mut s_p, mut s_c, mut s_hub, mut s_lt, mut s_ann) = (0.0, 0.0, 0.0, 0.0, 0.0);
        let (mut t_c, mut t_p) = (0.0, 0.0);
        let (mut f_teeth, mut f_disc) = (0.0, 0.0);
        for ip in 0..pt.positions {
            let th0 = (ip as f64 + 0.5) / pt.positions as f64 * pitch;
            let tip_at = |j: usize| th0 + (j as f64 - 2.0) * pitch;
            // covered fraction and clearance of every tip and slice
            let mut cov = vec![vec![0.0; n]; nt];
            let mut hh = vec![vec![h.tip; n]; nt];
            for j in 0..nt {
                for s in 0..n {
                    let t = tip_at(j) + shift[s];
                    let a = (t - psi_a).max(lo);
                    let bnd = (t + psi_a).min(hi);
                    cov[j][s] = ((bnd - a) / (2.0 * psi_a)).clamp(0.0, 1.0);
                    let d = dir(t);
                    hh[j][s] = h.tip - (e[0] * d[0] + e[1] * d[1]);
                }
            }
            // pocket j lies between tip j (behind) and tip j + 1 (ahead)
            let suction_open = |j: usize| (0..n).any(|s| tip_at(j) + shift[s] + psi_a <= lo);
            let delivery_open = |j: usize| (0..n).any(|s| tip_at(j + 1) + shift[s] - psi_a >= hi);
            let js = (0..nt - 1).filter(|&j| suction_open(j)).max().unwrap();
            let jd = (0..nt - 1).find(|&j| delivery_open(j)).unwrap();
            // tips js+1 ..= jd seal the chain
            let mut g = vec![0.0; nt];
            let mut c = vec![0.0; nt];
            let (mut g_tip, mut c_tip) = (vec![0.0; nt], vec![0.0; nt]);
            for i in js + 1..=jd {
                for s in 0..n {
                    if cov[i][s] > 0.0 {
                        let l = cov[i][s].max(0.05) * land;
                        g_tip[i] += bs * hh[i][s].powi(3) / (12.0 * mu * l);
                        c_tip[i] += bs * hh[i][s] * u / 2.0;
                    }
                }
                g[i] = g_tip[i] + g_lt;
                c[i] = c_tip[i] + c_lt;
            }
            // pressures: tridiagonal solve (Thomas) of the inner pockets
            let mut p = vec![0.0; nt - 1];
            for pj in p.iter_mut().skip(jd) {
                *pj = dp;
            }
            let inner: Vec<usize> = (js + 1..jd).collect();
            let m = inner.len();
            if m > 0 {
                let (mut a, mut bb, mut cc, mut r) =
                    (vec![0.0; m], vec![0.0; m], vec![0.0; m], vec![0.0; m]);
                for (q, &j) in inner.iter().enumerate() {
                    // in through tip j from pocket j-1, out through tip j+1, out to the hub
                    bb[q] = g[j] + g[j + 1] + g_hub;
                    r[q] = c[j] - c[j + 1];
                    if q > 0 {
                        a[q] = -g[j];
                    }
                    if q + 1 < m {
                        cc[q] = -g[j + 1];
                    } else {
                        r[q] += g[j + 1] * dp;
                    }
                }
                for q in 1..m {
                    let f = a[q] / bb[q - 1];
                    bb[q] -= f * cc[q - 1];
                    r[q] -= f * r[q - 1];
                }
                let mut x = vec![0.0; m];
                x[m - 1] = r[m - 1] / bb[m - 1];
                for q in (0..m - 1).rev() {
                    x[q] = (r[q] - cc[q] * x[q + 1]) / bb[q];
                }
                for (q, &j) in inner.iter().enumerate() {
                    p[j] = x[q];
                }
            }
            // budget weights: flow behind -> ahead times (phi_behind - phi_ahead)
            for i in js + 1..=jd {
                let dphi = (p[i - 1] - p[i]) / dp;
                s_p += g_tip[i] * dp * dphi * dphi;
                s_c += c_tip[i] * dphi;
                // the pressure-driven wall stress on the sealing lands
                let real = barus_pressure(p[i], alpha) - barus_pressure(p[i - 1], alpha);
                for hs in &hh[i] {
                    t_p += refer * bs * hs / 2.0 * real * h.ra[k];
                }
            }
            // the Couette stress on every land under the bore (sealing or not)
            for j in 0..nt {
                // land j lies between pocket j - 1 and pocket j
                let behind = p[j.saturating_sub(1).min(nt - 2)];
                let ahead = p[j.min(nt - 2)];
                let f = barus_mean_factor(behind, ahead, alpha);
                for s in 0..n {
                    t_c += refer * f * mu * u / hh[j][s] * bs * cov[j][s] * land * h.ra[k];
                }
            }
            // the ring of one revolution's pockets (centres in [0, 2 pi)),
            // in the sense of rotation; the last is beside the mesh on the
            // delivery side, the first beside it on the suction side
            let ring: Vec<(f64, f64)> = (0..nt - 1)
                .map(|j| (tip_at(j) + pitch / 2.0, p[j] / dp))
                .filter(|&(cen, _)| (0.0..2.0 * PI).contains(&cen))
                .collect();
            assert_eq!(ring.len(), z);
            if alpha != 0.0 {
                let (teeth, disc) = face_factors(h, k, &ring, dp, alpha);
                f_teeth += teeth;
                f_disc += disc;
            }
            for q in 0..z {
                let (phi_b, phi_a) = (ring[q].1, ring[(q + 1) % z].1);
                // the tooth between (the last one is the tooth in the mesh)
                let flow = g_lt * dp * (phi_b - phi_a) + c_lt;
                s_lt += flow * (phi_b - phi_a);
                s_hub += g_hub * dp * ring[q].1 * ring[q].1;
            }
            // the face film below the roots as one annulus, Rj < r < rf, the
            // hub at 0 and the root circle at the pockets' pressures: each
            // pocket's over its space width there, and across each tooth's
            // root arc a linear change from the pocket behind to the one
            // ahead (the film goes on up the tooth face, where the lateral
            // gap across the tooth carries that linear fall; a jump at the
            // tooth's centre instead would make the flux grow with the
            // logarithm of the number of modes kept). Mode n of the boundary
            // pressure, cos(n theta), sends the flux (h^3 / 12 mu) k_n per
            // radian of the root circle into the film, k_0 = 1 / ln(rf / Rj),
            // k_n = n (1 + rho^2n) / (1 - rho^2n), rho = Rj / rf; the radial
            // sectors give every mode k_0. Weighted by phi as the budget:
            // sum over faces of (h^3 / 12 mu) dp integral(phi L[phi]).
            s_ann += 2.0 * h.lateral.powi(3) / (12.0 * mu)
                * dp
                * annulus_power(
                    &ring,
                    pitch,
                    h.tooth_root_angle(k),
                    h.rj[k] / h.rf[k],
                    ANNULUS_MODES,
                );
        }
        let np = pt.positions as f64;
        out.tip_poiseuille += s_p / np / q_th;
        out.tip_couette += s_c / np / q_th;
        out.lateral_hub += s_hub / np / q_th;
        out.lateral_tooth += s_lt / np / q_th;
        out.lateral_hub_annulus += s_ann / np / q_th;
        out.torque_tip_couette += t_c / np;
        out.torque_tip_pressure += t_p / np;
        out.face_viscosity_factor[k] = if alpha == 0.0 {
            [1.0, 1.0]
        } else {
            [f_teeth / np, f_disc / np]
        };
    }
    out
}

/// The faces' mean viscosity factors of gear `k` at one position
/// ([`hand_losses_barus`]): `ring` the pockets' (centre, psi / dp_psi).
fn face_factors(h: &Hand, k: usize, ring: &[(f64, f64)], dp_psi: f64, alpha: f64) -> (f64, f64) {
    let z = ring.len();
    // each tooth between two pockets: the mean along it
    let teeth = (0..z)
        .map(|q| barus_mean_factor(ring[q].1 * dp_psi, ring[(q + 1) % z].1 * dp_psi, alpha))
        .sum::<f64>()
        / z as f64;
    // the disc, radial sectors from each pocket's psi at the root circle to
    // the hub's zero, weighted by r^3
    let m = 200;
    let (rj, rf) = (h.rj[k], h.rf[k]);
    let (mut num, mut den) = (0.0, 0.0);
    for i in 0..m {
        let r = rj + (i as f64 + 0.5) / m as f64 * (rf - rj);
        let share = (r / rj).ln() / (rf / rj).ln();
        let f = ring
            .iter()
            .map(|&(_, phi)| (alpha * barus_pressure(phi * dp_psi * share, alpha)).exp())
            .sum::<f64>()
            / z as f64;
        num += f * r.powi(3);
        den += r.powi(3);
    }
    (teeth, num / den)
}

/// Fourier modes of the root circle's pressure kept by the annulus
/// solution (its truncation error is checked against twice as many in
/// `tests/references.rs`).
pub const ANNULUS_MODES: usize = 400;

/// `integral(phi L[phi]) dtheta` of the face-film annulus below the roots
/// (`L` its Dirichlet-to-Neumann map, per unit `h^3 / 12 mu`) for the
/// root-circle pressure `phi` made of the pockets' values `ring` (centre
/// angle, phi) each over the space width `pitch - tooth`, joined linearly
/// across the teeth's root arcs of angle `tooth`; `rho = Rj / rf`, modes
/// 0..`modes`. The profile is piecewise linear, so its Fourier coefficients
/// are those of its slope changes `ds_j` at the corners `t_j` over `-n^2`:
/// `a_n = -(1 / (pi n^2)) sum ds_j cos(n t_j)` and `b_n` with sines.
pub fn annulus_power(ring: &[(f64, f64)], pitch: f64, tooth: f64, rho: f64, modes: usize) -> f64 {
    let z = ring.len();
    let space = pitch - tooth;
    // the mean: each pocket over its space, each ramp at its mid value
    let mut mean = 0.0;
    let mut corners: Vec<(f64, f64)> = Vec::with_capacity(2 * z);
    for q in 0..z {
        let (cen, phi) = ring[q];
        let phi_next = ring[(q + 1) % z].1;
        mean += (phi * space + 0.5 * (phi + phi_next) * tooth) / (2.0 * PI);
        let slope = (phi_next - phi) / tooth;
        corners.push((cen + space / 2.0, slope));
        corners.push((cen + pitch - space / 2.0, -slope));
    }
    let mut power = 2.0 * PI * mean * mean / (1.0 / rho).ln();
    for mode in 1..modes {
        let nf = mode as f64;
        let (mut a, mut b) = (0.0, 0.0);
        for &(t, ds) in &corners {
            a -= ds * (nf * t).cos();
            b -= ds * (nf * t).sin();
        }
        let scale = 1.0 / (PI * nf * nf);
        let r2n = rho.powf(2.0 * nf);
        let kn = nf * (1.0 + r2n) / (1.0 - r2n);
        power += kn * PI * ((a * scale).powi(2) + (b * scale).powi(2));
    }
    power
}

/// Lateral shear on both faces of both gears (N m on the driving shaft):
/// `integral mu omega r / h r dA` over the solid face, the disc from the
/// journal radius to the root circle and the teeth
/// (`z integral 2 psi(r) r^3 dr` from root to tip; the spaces' fluid moves
/// with the gear).
pub fn lateral_shear_torque(h: &Hand, rpm: f64, temp_c: f64) -> f64 {
    lateral_shear_torque_with(h, rpm, temp_c, [[1.0; 2]; 2])
}

/// [`lateral_shear_torque`] with each gear's teeth and disc at their mean
/// viscosity factor (`[gear][teeth, disc]`).
pub fn lateral_shear_torque_with(h: &Hand, rpm: f64, temp_c: f64, factor: [[f64; 2]; 2]) -> f64 {
    let w = h.omegas(rpm * PI / 30.0);
    let mu = h.mu(temp_c);
    (0..2)
        .map(|k| {
            let m = 4000;
            let dr = (h.ra[k] - h.rf[k]) / m as f64;
            let teeth: f64 = (0..m)
                .map(|i| {
                    let rr = h.rf[k] + (i as f64 + 0.5) * dr;
                    2.0 * h.half_angle(k, rr) * rr.powi(3) * dr
                })
                .sum::<f64>()
                * h.z[k];
            let disc = 2.0 * PI * (h.rf[k].powi(4) - h.rj[k].powi(4)) / 4.0;
            2.0 * mu * w[k] / h.lateral * (factor[k][0] * teeth + factor[k][1] * disc) * w[k] / w[0]
        })
        .sum()
}

/// Petroff: two concentric journal bearings per gear,
/// `T = 2 pi mu omega R^3 L / c` each (N m on the driving shaft).
pub fn petroff_torque(h: &Hand, rpm: f64, temp_c: f64) -> f64 {
    let w = h.omegas(rpm * PI / 30.0);
    let mu = h.mu(temp_c);
    (0..2)
        .map(|k| {
            2.0 * 2.0 * PI * mu * w[k] * h.rj[k].powi(3) * h.bearing_length / h.bearing * w[k]
                / w[0]
        })
        .sum()
}

/// Load capacity (N) of a finite journal bearing at eccentricity ratio
/// `eps`: the Reynolds equation
/// `(1/R^2) d/dth(h^3 dp/dth) + d/dz(h^3 dp/dz) = 6 mu omega dh/dth`,
/// `h = c (1 + eps cos th)`, ambient pressure at both ends `z = +-L/2`,
/// solved by finite differences (`nth` x `nz` nodes, periodic in th) with
/// successive over-relaxation, negative pressures set to zero at every
/// sweep (Christopherson's method: the Reynolds cavitation condition); the
/// film force integrated over the bearing.
#[allow(clippy::too_many_arguments)] // the bearing's physical inputs and the grid
pub fn reynolds_load(
    eps: f64,
    radius: f64,
    length: f64,
    c: f64,
    mu: f64,
    omega: f64,
    nth: usize,
    nz: usize,
) -> f64 {
    let dth = 2.0 * PI / nth as f64;
    let dz = length / (nz + 1) as f64;
    let hat = |t: f64| c * (1.0 + eps * t.cos());
    let ax = 1.0 / (radius * dth).powi(2);
    let az = 1.0 / (dz * dz);
    // per th node: h^3 half a step ahead and behind, h^3, source
    let coef: Vec<(f64, f64, f64, f64)> = (0..nth)
        .map(|i| {
            let t = i as f64 * dth;
            let src = -6.0 * mu * omega * c * eps * t.sin(); // 6 mu omega dh/dth
            (
                hat(t + 0.5 * dth).powi(3),
                hat(t - 0.5 * dth).powi(3),
                hat(t).powi(3),
                src,
            )
        })
        .collect();
    let mut p = vec![0.0; nth * nz];
    let relax = 1.8;
    for _sweep in 0..20000 {
        let mut change: f64 = 0.0;
        let mut scale: f64 = 0.0;
        for i in 0..nth {
            let (hp, hm, h3, src) = coef[i];
            let (ip, im) = ((i + 1) % nth, (i + nth - 1) % nth);
            for j in 0..nz {
                let up = if j + 1 < nz { p[i * nz + j + 1] } else { 0.0 };
                let dn = if j > 0 { p[i * nz + j - 1] } else { 0.0 };
                let gs = (ax * (hp * p[ip * nz + j] + hm * p[im * nz + j]) + az * h3 * (up + dn)
                    - src)
                    / (ax * (hp + hm) + 2.0 * az * h3);
                let old = p[i * nz + j];
                let new = (old + relax * (gs - old)).max(0.0);
                change = change.max((new - old).abs());
                scale = scale.max(new);
                p[i * nz + j] = new;
            }
        }
        if change <= 1e-9 * scale {
            break;
        }
    }
    let (mut fx, mut fy) = (0.0, 0.0);
    for i in 0..nth {
        let t = i as f64 * dth;
        let s: f64 = p[i * nz..(i + 1) * nz].iter().sum();
        fx -= s * t.cos() * radius * dth * dz;
        fy -= s * t.sin() * radius * dth * dz;
    }
    fx.hypot(fy)
}

/// The eccentricity ratio at which [`reynolds_load`] carries `load`, by
/// bisection in [0.01, 0.995].
#[allow(clippy::too_many_arguments)] // the bearing's physical inputs and the grid
pub fn reynolds_eccentricity(
    load: f64,
    radius: f64,
    length: f64,
    c: f64,
    mu: f64,
    omega: f64,
    nth: usize,
    nz: usize,
) -> f64 {
    let (mut lo, mut hi) = (0.01, 0.995);
    for _ in 0..30 {
        let mid = 0.5 * (lo + hi);
        if reynolds_load(mid, radius, length, c, mu, omega, nth, nz) < load {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

// ---------------------------------------------------------------- pressure loads
//
// The pressure loads on the gears by Gauss's theorem: a uniform pressure p
// on an open stretch of a rigid outline from A to B (face width w) pushes
// with `p w R(B - A)`, R the rotation by +90 degrees when the stretch runs
// counter-clockwise round the solid (the solid on its left), and turns it
// about the centre O by `p w (|B - O|^2 - |A - O|^2) / 2`. (Proof: the
// force on the solid is `-p n ds` with n its outward normal; running
// counter-clockwise, `n ds = (dy, -dx)`, so `dF = p (-dy, dx)` and
// `r x dF = p (x dx + y dy) = p d(|r|^2 / 2)`. Check: the upper half of a
// circle of radius r, from (r, 0) to (-r, 0), is pushed by `p w (0, -2 r)`,
// down, and not turned.) So a pocket's load needs only where the stretch of
// each gear's outline it wets begins and ends.

/// A pressure node of the model's network as the hand names it: the
/// chambers, and tooth space `space` of gear `gear` in axial zone `zone`
/// (the spaces numbered as the model numbers its pockets: at driving angle
/// `theta` in the current mesh period, space `m` of the driving gear is
/// centred at local angle `theta + (m + 1/2) pitch1`, space `i` of the
/// driven gear at `theta z1 / z2 - lag + (i + 1) pitch2`;
/// `crates/core/src/hydraulics/steps.rs`, module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Node {
    Inlet,
    Outlet,
    Space {
        gear: usize,
        space: usize,
        zone: usize,
    },
}

/// Loads per unit pressure of one node: force on the driving gear (x, y),
/// its torque, force on the driven gear (x, y), its torque (m^2 and m^3;
/// torques counter-clockwise positive about each gear's own centre).
pub type LoadCoef = [f64; 6];

/// Choices of the closed form (the deliberate errors of the test among them).
#[derive(Debug, Clone, Copy)]
pub struct ContourRules {
    /// The tip lands wet (false: a deliberate error, the lands left out).
    pub lands: bool,
    /// The meshing zone: a stretch of outline inside the mating gear's tip
    /// circle on the mating gear's side of the line of action is wet by the
    /// mating gear's space there (false: a deliberate error, every stretch
    /// wet by its own gear's space, as if the gears did not mesh).
    pub mesh_zone: bool,
    /// A land inside the mating gear's tip circle also carries the mean of
    /// its own two spaces, on top of the mating space that wets it (the
    /// model's tip-land term, which it applies to every land wherever it
    /// is; false: the land carries only what wets it).
    pub lands_in_mesh_twice: bool,
}

impl ContourRules {
    pub const PLAIN: ContourRules = ContourRules {
        lands: true,
        mesh_zone: true,
        lands_in_mesh_twice: false,
    };
}

/// What wets a stretch of a gear's outline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Wet {
    /// The fluid of space `.1` of gear `.0` (for a stretch's own gear the
    /// space it bounds; [`Placement::wet`] leaves its number to the walk).
    Space(usize, usize),
    /// A tip land sealing under the bore (tooth m, between its gear's
    /// spaces m - 1 and m): the gap's pressure falls linearly from one
    /// space to the other, so the land carries their mean.
    Land,
    Inlet,
    Outlet,
}

/// A stretch of gear `gear`'s outline in one slice (axial zone `zone`),
/// from `from` to `to` in the order of the gear's local angle, in the
/// pitch of tooth `tooth` (its land, or from its leading flank to the next
/// tooth's trailing flank), wet by `wet`.
#[derive(Debug, Clone, Copy)]
pub struct Stretch {
    pub gear: usize,
    pub zone: usize,
    pub tooth: usize,
    pub land: bool,
    pub from: [f64; 2],
    pub to: [f64; 2],
    pub wet: Wet,
}

/// Samples per stretch of outline (a flank, a root arc, a tip land) at
/// which what wets it is looked at; each change is then found by bisection.
const OUTLINE_SAMPLES: usize = 200;

impl Hand {
    /// Driven-gear lag: the circular backlash on the operating pitch
    /// circles `jt = 2 pi rw1 / z1 - s1w - s2w` (`s_kw` the tooth thickness
    /// there) closed on the drive flanks. With a driving tooth centred on the
    /// line of centres its leading flank crosses its pitch circle `s1w / 2`
    /// ahead of the pitch point, and the driven flank it touches must cross
    /// the driven pitch circle as far ahead (conjugate flanks reach the
    /// pitch point together), so the driven space round it, `pw - s2w` wide,
    /// is centred `jt / 2` behind the line of centres: the angle `jt / (2 rw2)`.
    pub fn lag(&self) -> f64 {
        let (rw1, rw2) = (self.rw(0), self.rw(1));
        let jt = 2.0 * PI * rw1 / self.z[0]
            - 2.0 * rw1 * self.half_angle(0, rw1)
            - 2.0 * rw2 * self.half_angle(1, rw2);
        jt / (2.0 * rw2)
    }
    /// Angular pitch, rad.
    pub fn pitch_angle(&self, k: usize) -> f64 {
        2.0 * PI / self.z[k]
    }
    /// The pair's placement and the casing's angles, worked out once.
    pub fn placement(&self) -> Placement {
        let aw = self.alpha_w();
        let a = self.centre_distance();
        let cusp_x = (a * a + self.ra[0].powi(2) - self.ra[1].powi(2)) / (2.0 * a);
        let cusp_y = (self.ra[0].powi(2) - cusp_x * cusp_x).sqrt();
        Placement {
            a,
            rw1: self.rw(0),
            cos_aw: aw.cos(),
            sin_aw: aw.sin(),
            lag: self.lag(),
            z: self.z,
            ra: self.ra,
            suction_edge: self.suction_edge,
            delivery_edge: self.delivery_edge,
            cusp: [cusp_x, cusp_y],
        }
    }
    /// [`Placement::body_offset`].
    pub fn body_offset(&self, k: usize, theta: f64) -> f64 {
        self.placement().body_offset(k, theta)
    }
    /// Driving-angle shift of slice `s` of the face width: the helix on the
    /// reference cylinder advances `zeta tan(beta)` at axial position `zeta`
    /// from mid-face, i.e. `zeta tan(beta) / r1` of the driving gear's angle
    /// (and `zeta tan(beta) / r2` of the driven gear's).
    pub fn slice_phase(&self, s: usize) -> f64 {
        let zeta = ((s as f64 + 0.5) / self.slices as f64 - 0.5) * self.b;
        zeta * self.beta.tan() / self.r(0)
    }
    /// The angle at which the loads of step `istep` (of the mesh period)
    /// are taken: the middle of the step, `(istep - 1/2) dtheta`, with
    /// `dtheta` the driving pitch over a whole number of steps.
    pub fn step_angle(&self, istep: usize) -> f64 {
        let p1 = self.pitch_angle(0);
        let n = (p1 / self.angle_step).round();
        (istep as f64 - 0.5) * p1 / n
    }
    /// Steps per mesh period.
    pub fn steps_per_period(&self) -> usize {
        (self.pitch_angle(0) / self.angle_step).round() as usize
    }
    /// [`Placement::centre`].
    pub fn centre(&self, k: usize) -> [f64; 2] {
        self.placement().centre(k)
    }
    /// [`Placement::polar`].
    pub fn polar(&self, k: usize, x: [f64; 2]) -> (f64, f64) {
        self.placement().polar(k, x)
    }
    /// [`Placement::cusp_angle`].
    pub fn cusp_angle(&self, k: usize) -> f64 {
        self.placement().cusp_angle(k)
    }

    /// The pressure loads at driving angle `theta` (the mid-face section's)
    /// as loads per unit pressure of every node, by Gauss's theorem on the
    /// stretches of each gear's outline ([`Hand::outline_stretches`]).
    pub fn contour_loads(&self, theta: f64, rules: ContourRules) -> Vec<(Node, LoadCoef)> {
        let dz = self.b / self.slices as f64;
        let pl = self.placement();
        let mut out: Vec<(Node, LoadCoef)> = Vec::new();
        let mut add = |node: Node, k: usize, w: f64, f: [f64; 2], t: f64| {
            let i = match out.iter().position(|(m, _)| *m == node) {
                Some(i) => i,
                None => {
                    out.push((node, [0.0; 6]));
                    out.len() - 1
                }
            };
            out[i].1[3 * k] += w * f[0];
            out[i].1[3 * k + 1] += w * f[1];
            out[i].1[3 * k + 2] += w * t;
        };
        for st in self.outline_stretches(theta, rules) {
            let k = st.gear;
            let (a, b) = (st.from, st.to);
            // counter-clockwise round the solid: local angles grow
            // counter-clockwise on the driving gear, clockwise on the driven
            let sense = if k == 0 { 1.0 } else { -1.0 };
            let d = [sense * (b[0] - a[0]), sense * (b[1] - a[1])];
            let f = [-d[1] * dz, d[0] * dz];
            let o = pl.centre(k);
            let r2 = |x: [f64; 2]| (x[0] - o[0]).powi(2) + (x[1] - o[1]).powi(2);
            let t = sense * dz * 0.5 * (r2(b) - r2(a));
            let z = self.z[k] as usize;
            let space = |gear: usize, m: usize| Node::Space {
                gear,
                space: m % self.z[gear] as usize,
                zone: st.zone,
            };
            let mean = |add: &mut dyn FnMut(Node, usize, f64, [f64; 2], f64)| {
                add(space(k, st.tooth + z - 1), k, 0.5, f, t);
                add(space(k, st.tooth), k, 0.5, f, t);
            };
            match st.wet {
                Wet::Space(g, i) => {
                    add(space(g, i), k, 1.0, f, t);
                    if st.land && rules.lands_in_mesh_twice && g != k {
                        mean(&mut add);
                    }
                }
                Wet::Land => mean(&mut add),
                Wet::Inlet => add(Node::Inlet, k, 1.0, f, t),
                Wet::Outlet => add(Node::Outlet, k, 1.0, f, t),
            }
        }
        out
    }

    /// Each gear's outline at driving angle `theta`, slice by slice of the
    /// face width (each slice a spur section at its helix phase), cut into
    /// stretches each wet by one thing. The outline is walked tooth by
    /// tooth: tip land, leading flank (involute above the base circle,
    /// radial below it), root arc, the next tooth's trailing flank; where
    /// what wets it changes (the contact points and the other crossings of
    /// the line of action, the mating tip circle, the port edges) the
    /// stretch is cut, found by bisection on the exact profile between
    /// [`OUTLINE_SAMPLES`] samples per stretch.
    pub fn outline_stretches(&self, theta: f64, rules: ContourRules) -> Vec<Stretch> {
        let n = self.slices;
        let zones = self.axial_nodes.clamp(1, n);
        let pl = self.placement();
        let mut out = Vec::new();
        for s in 0..n {
            let th = theta + self.slice_phase(s);
            let zone = s * zones / n;
            for k in 0..2 {
                let z = self.z[k] as usize;
                let p = self.pitch_angle(k);
                let (ra, rf) = (self.ra[k], self.rf[k]);
                let (ha, hf) = (self.half_angle(k, ra), self.half_angle(k, rf));
                for m in 0..z {
                    let c0 = pl.body_offset(k, th) + m as f64 * p;
                    let c1 = c0 + p;
                    // the four stretches from tooth m's land to tooth m + 1's,
                    // each (rho, psi) of a parameter in [0, 1]
                    let profile = |q: usize, t: f64| -> (f64, f64) {
                        match q {
                            0 => (ra, c0 - ha + 2.0 * ha * t),
                            1 => {
                                let r = ra - (ra - rf) * t;
                                (r, c0 + self.half_angle(k, r))
                            }
                            2 => (rf, c0 + hf + (p - 2.0 * hf) * t),
                            _ => {
                                let r = rf + (ra - rf) * t;
                                (r, c1 - self.half_angle(k, r))
                            }
                        }
                    };
                    for q in 0..4 {
                        let land = q == 0;
                        if land && !rules.lands {
                            continue;
                        }
                        let at = |t: f64| {
                            let (r, psi) = profile(q, t);
                            pl.point(k, r, psi)
                        };
                        let wet = |t: f64| pl.wet(k, th, at(t), land, rules.mesh_zone);
                        let mut emit = |t0: f64, t1: f64, w: Wet| {
                            out.push(Stretch {
                                gear: k,
                                zone,
                                tooth: m,
                                land,
                                from: at(t0),
                                to: at(t1),
                                wet: match w {
                                    // a flank or root arc bounds space m
                                    Wet::Space(g, _) if g == k => Wet::Space(k, m),
                                    w => w,
                                },
                            });
                        };
                        // walk the samples; cut the stretch where the wetting changes
                        let (mut t_start, mut w_start) = (0.0, wet(0.0));
                        let mut t_prev = 0.0;
                        for i in 1..=OUTLINE_SAMPLES {
                            let t1 = i as f64 / OUTLINE_SAMPLES as f64;
                            while wet(t1) != w_start {
                                let (mut lo, mut hi) = (t_prev, t1);
                                for _ in 0..60 {
                                    let mid = 0.5 * (lo + hi);
                                    if wet(mid) == w_start {
                                        lo = mid;
                                    } else {
                                        hi = mid;
                                    }
                                }
                                emit(t_start, hi, w_start);
                                t_start = hi;
                                t_prev = hi;
                                w_start = wet(hi);
                            }
                            t_prev = t1;
                        }
                        emit(t_start, 1.0, w_start);
                    }
                }
            }
        }
        out
    }
}

/// The pair's placement and the casing's angles ([`Hand::placement`]), for
/// the walks round the gears' outlines. Frame: the driving gear's centre at
/// the origin, the driven gear's at `(a, 0)`, y towards the suction; each
/// gear's local angle 0 towards the mating gear, growing towards the
/// suction (with the rotation) on both gears.
#[derive(Debug, Clone, Copy)]
pub struct Placement {
    pub a: f64,
    pub rw1: f64,
    pub cos_aw: f64,
    pub sin_aw: f64,
    pub lag: f64,
    pub z: [f64; 2],
    pub ra: [f64; 2],
    pub suction_edge: [f64; 2],
    pub delivery_edge: [f64; 2],
    /// The suction-side crossing of the tip circles (x, y > 0).
    pub cusp: [f64; 2],
}

impl Placement {
    /// Local angle of tooth 0 of gear k at driving angle `theta` (tooth m at
    /// `+ m pitch`, space m between teeth m and m + 1): the driving gear's
    /// tooth 0 on the line of centres at `theta = 0`, the driven gear's
    /// space centred `lag` behind it (numbered as the model numbers them).
    pub fn body_offset(&self, k: usize, theta: f64) -> f64 {
        if k == 0 {
            theta
        } else {
            theta * self.z[0] / self.z[1] + PI / self.z[1] - self.lag
        }
    }
    /// Gear centres: the driving gear's at the origin, the driven gear's at
    /// `(a, 0)`; y towards the suction.
    pub fn centre(&self, k: usize) -> [f64; 2] {
        [if k == 0 { 0.0 } else { self.a }, 0.0]
    }
    /// The point of gear k at radius `rho` and local angle `psi` (0 towards
    /// the mating gear, growing towards the suction on both gears).
    pub fn point(&self, k: usize, rho: f64, psi: f64) -> [f64; 2] {
        if k == 0 {
            [rho * psi.cos(), rho * psi.sin()]
        } else {
            [self.a - rho * psi.cos(), rho * psi.sin()]
        }
    }
    /// Radius and local angle (in (-pi, pi]) of a point about gear k.
    pub fn polar(&self, k: usize, x: [f64; 2]) -> (f64, f64) {
        let dx = if k == 0 { x[0] } else { self.a - x[0] };
        (dx.hypot(x[1]), x[1].atan2(dx))
    }
    /// Local angle on gear k of the suction-side cusp, where the tip
    /// circles cross (the delivery-side one at minus it).
    pub fn cusp_angle(&self, k: usize) -> f64 {
        self.polar(k, self.cusp).1
    }
    /// Is the point on the driven gear's side of the line of action? The
    /// line runs through the pitch point `(rw1, 0)` along
    /// `u = (sin aw, cos aw)`, tangent to both base circles; its normal
    /// `(cos aw, -sin aw)` points to the driven gear.
    pub fn on_driven_side(&self, x: [f64; 2]) -> bool {
        (x[0] - self.rw1) * self.cos_aw - x[1] * self.sin_aw > 0.0
    }
    /// The space of gear k (its number) whose angular sector holds the point.
    pub fn space_at(&self, k: usize, theta: f64, x: [f64; 2]) -> usize {
        let u = (self.polar(k, x).1 - self.body_offset(k, theta)) * self.z[k] / (2.0 * PI);
        (u.floor() as i64).rem_euclid(self.z[k] as i64) as usize
    }
    /// What wets gear k's outline at the point `x` (slice angle `theta`).
    /// The fluid of the meshing zone is
    /// split between the gears by the line of action inside the lens where
    /// the tip circles overlap (docs/model.md section 3): a flank or root
    /// point inside the mating tip circle on the mating side of the line is
    /// wet by the mating gear's space there; a land point (on gear k's own
    /// tip circle, its fluid just outside it) inside the mating tip circle
    /// is wet by the mating gear's space on either side of the line. A land
    /// under the bore carries its gap's mean, one facing a port (from the
    /// cusp to the port's edge) the port's pressure.
    pub fn wet(&self, k: usize, theta: f64, x: [f64; 2], land: bool, mesh: bool) -> Wet {
        let o = 1 - k;
        let c = self.centre(o);
        let in_mating_circle = (x[0] - c[0]).hypot(x[1] - c[1]) < self.ra[o];
        if mesh && in_mating_circle && (land || self.on_driven_side(x) == (o == 1)) {
            return Wet::Space(o, self.space_at(o, theta, x));
        }
        if !land {
            // the space this stretch bounds (its number set by the caller)
            return Wet::Space(k, usize::MAX);
        }
        let psi = self.polar(k, x).1;
        if psi >= self.suction_edge[k] || psi <= self.delivery_edge[k] {
            Wet::Land
        } else if psi > 0.0 {
            Wet::Inlet
        } else {
            Wet::Outlet
        }
    }
}

/// Shares of `Vm n` lost by the tip chains and the lateral gaps of the
/// concentric gears of `h` ([`hand_losses_barus`], the face film below the
/// roots solved as an annulus, 60 positions per pitch), and the tip and
/// lateral shear torques on the driving shaft (N m), with tip clearance
/// `tip_um` on both gears and lateral clearance `lateral_um` (um), and the
/// oil's viscosity rising with the film pressure by Barus's law,
/// coefficient `alpha` (1/Pa; 0 for the clean oil).
pub fn gap_loss_and_torque(
    h: &Hand,
    tip_um: f64,
    lateral_um: f64,
    rpm: f64,
    bar: f64,
    temp_c: f64,
    alpha: f64,
) -> (f64, f64) {
    let mut h = h.clone();
    h.tip = tip_um * 1e-6;
    h.lateral = lateral_um * 1e-6;
    let l = hand_losses_barus(
        &h,
        Point {
            rpm,
            bar,
            temp_c,
            offset: [[0.0; 2]; 2],
            positions: 60,
        },
        alpha,
    );
    let loss = l.tip_poiseuille + l.tip_couette + l.lateral_tooth + l.lateral_hub_annulus;
    let torque = l.torque_tip_couette
        + l.torque_tip_pressure
        + lateral_shear_torque_with(&h, rpm, temp_c, l.face_viscosity_factor);
    (loss, torque)
}

/// Moves a campaign record's flow and torque by what the hand calculation
/// of `h` gives for an oil whose viscosity rises with the film pressure by
/// Barus's law, coefficient `alpha` (1/Pa), in the tip chains and the
/// lateral films ([`hand_losses_barus`]: the local pressure of every film,
/// where the model's candidate scales every gap's viscosity by the factor
/// at half the pressure rise), the gaps as recorded (the mean of the two
/// measured tips, `h`'s lateral clearance). The bearings' films are left
/// alone, as in the model: their pressure is their own hydrodynamic one,
/// which neither calculation resolves.
///
/// The torque also carries what the oil does to the cavity trapped in the
/// mesh ([`trapped_barus`]): its lateral films and the throats between the
/// teeth thicken with its pressure, which reaches several times the
/// delivery pressure at speed, so less of the squeeze leaks away and its
/// pressure work rises (at 4000 rpm / 30 bar, alpha 1e-7: +0.018 N m at
/// 60 degC, +0.029 at 120 degC).
pub fn plant_barus(h: &Hand, r: &mut CampaignRecord, alpha: f64) {
    let tip = 0.5 * (r.tip_clearance_drive_um + r.tip_clearance_driven_um);
    let lateral = h.lateral * 1e6;
    let (p, n, t) = (r.pressure_bar, r.speed_rpm, r.temp_c);
    let base = gap_loss_and_torque(h, tip, lateral, n, p, t, 0.0);
    let real = gap_loss_and_torque(h, tip, lateral, n, p, t, alpha);
    let within = BarusIn::FilmsAndThroats;
    let trapped = trapped_barus(n, p, t, lateral, alpha, within)
        - trapped_barus(n, p, t, lateral, 0.0, within);
    move_record(h, r, base, (real.0, real.1 + trapped));
}

/// Moves `r`'s flow by the change of the gaps' loss (shares of `Vm n`) and
/// its measured torque by the change of their torque, `real` against
/// `base` (each `(loss, torque)` of [`gap_loss_and_torque`]).
fn move_record(h: &Hand, r: &mut CampaignRecord, base: (f64, f64), real: (f64, f64)) {
    let vm_n_lpm = h.displacement() * r.speed_rpm * 1e3;
    r.flow_lpm -= (real.0 - base.0) * vm_n_lpm;
    if let Some(torque) = r.torque_nm.as_mut() {
        *torque += real.1 - base.1;
    }
}

/// Moves a campaign record's flow and torque by what the hand calculation
/// of `h` gives for the gaps the pump really had (`tip_um` on both gears,
/// `lateral_um`) against those it was recorded with (the mean of its two
/// measured tips, `h`'s lateral clearance): an effect made by another
/// mechanism than the model's code (concentric gears, incompressible
/// pockets, the tip chain's steady solution).
///
/// The torque also carries the trapped volume's relief by the lateral gaps
/// ([`trapped_relief`]): a wider gap lets the cavity closed in the mesh
/// leak to its neighbours and to the hubs, and its pressure work falls.
pub fn plant_gaps(h: &Hand, r: &mut CampaignRecord, tip_um: f64, lateral_um: f64) {
    let recorded_tip = 0.5 * (r.tip_clearance_drive_um + r.tip_clearance_driven_um);
    let recorded_lateral = h.lateral * 1e6;
    let (p, n, t) = (r.pressure_bar, r.speed_rpm, r.temp_c);
    let base = gap_loss_and_torque(h, recorded_tip, recorded_lateral, n, p, t, 0.0);
    let real = gap_loss_and_torque(h, tip_um, lateral_um, n, p, t, 0.0);
    let relief = trapped_relief(n, p, t, lateral_um) - trapped_relief(n, p, t, recorded_lateral);
    move_record(h, r, base, (real.0, real.1 + relief));
}

/// The pressure work of the cavity trapped in the mesh over its whole life
/// (N m on the driving shaft, the excess over the ideal torque) at `rpm`,
/// delivery `bar` gauge and `temp_c`, with both plates' lateral films at
/// `lateral_um`: the independent trapped-volume model
/// (`scripts/reference/trapped_torque`, its lateral films in `lateral.py`)
/// tabulated by `lateral_relief.py` at the seed campaign's 14 conditions
/// for 10-35 um, linear in between. Only its changes with the gap are used.
/// Panics at a condition or a gap the table does not hold.
pub fn trapped_relief(rpm: f64, bar: f64, temp_c: f64, lateral_um: f64) -> f64 {
    let table = include_str!("../../scripts/reference/trapped_torque/lateral_relief.csv");
    let at = [("rpm", rpm), ("bar", bar), ("temp_c", temp_c)];
    reference_table(table, &at, ("h_um", lateral_um), "total_nm")
}

/// Where a piezoviscous oil's viscosity rises with the pressure in the
/// trapped volume's openings ([`trapped_barus`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BarusIn {
    /// The lateral films only (the films the model's candidate scales).
    LateralFilms,
    /// The lateral films and the laminar part of the throats between the
    /// teeth past the ends of the path of contact.
    FilmsAndThroats,
}

/// The trapped cavity's pressure work over its whole life (N m on the
/// driving shaft, the excess over the ideal torque) at `rpm`, delivery
/// `bar` gauge and `temp_c`, both plates' lateral films at `lateral_um`
/// (the table holds the design's 15 um only), with an oil whose viscosity rises with the local pressure by
/// Barus's law, coefficient `alpha` (1/Pa), in the openings `within`: the
/// independent trapped-volume model (`scripts/reference/trapped_torque`,
/// `lateral.py`'s `barus_psi` and `barus_film_factor`) tabulated by
/// `barus_relief.py` at the seed campaign's 14 conditions for alpha 0 to
/// 1.25e-7, linear in between. A more viscous film lets less of the
/// squeeze out of the cavity, and its pressure work rises. Only its
/// changes with alpha are used. Panics at a condition, a gap or an alpha
/// the table does not hold.
pub fn trapped_barus(
    rpm: f64,
    bar: f64,
    temp_c: f64,
    lateral_um: f64,
    alpha: f64,
    within: BarusIn,
) -> f64 {
    let table = include_str!("../../scripts/reference/trapped_torque/barus_relief.csv");
    let column = match within {
        BarusIn::LateralFilms => "lat_nm",
        BarusIn::FilmsAndThroats => "all_nm",
    };
    let at = [
        ("rpm", rpm),
        ("bar", bar),
        ("temp_c", temp_c),
        ("h_um", lateral_um),
    ];
    reference_table(table, &at, ("alpha_per_pa", alpha), column)
}

/// Column `y` of a reference table (CSV) on the rows whose columns `at`
/// hold the values given (the working condition, and any other fixed
/// input), at `x.1` of the column `x.0`: a tabulated row as it stands,
/// linear between the two rows that bracket it. Panics when the table
/// lacks a column, those rows or a bracket.
fn reference_table(table: &str, at: &[(&str, f64)], x: (&str, f64), y: &str) -> f64 {
    let mut lines = table.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|c| *c == name)
            .unwrap_or_else(|| panic!("the reference table has no column {name}"))
    };
    let keys: Vec<(usize, f64)> = at.iter().map(|&(name, v)| (col(name), v)).collect();
    let (c_x, c_y) = (col(x.0), col(y));
    let mut points: Vec<(f64, f64)> = Vec::new();
    for line in lines {
        let v: Vec<f64> = line
            .split(',')
            .map(|x| x.parse().expect("a number"))
            .collect();
        let same = |a: f64, b: f64| (a - b).abs() < 1e-9 * b.abs().max(1.0);
        if keys.iter().all(|&(c, want)| same(v[c], want)) {
            points.push((v[c_x], v[c_y]));
        }
    }
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    let x = x.1;
    if let Some(&(_, w)) = points.iter().find(|p| p.0 == x) {
        return w;
    }
    let at = points
        .windows(2)
        .find(|w| (w[0].0..=w[1].0).contains(&x))
        .unwrap_or_else(|| panic!("the reference table holds no {y} bracketing {x:e} at {at:?}"));
    let s = (x - at[0].0) / (at[1].0 - at[0].0);
    at[0].1 + s * (at[1].1 - at[0].1)
}

/// Temperature at which a flowmeter's slip is quoted, degC (the hotter of
/// the seed's two test temperatures, where the slip is largest).
pub const METER_SLIP_REF_C: f64 = 120.0;

/// The flow a positive-displacement flowmeter lets past its rotors without
/// counting it, l/min, at `temp_c`: its slip `slip_ref_lpm` at
/// [`METER_SLIP_REF_C`] scaled by the oil's viscosity.
///
/// A gear or screw meter counts the volume its rotors sweep; what passes
/// through its own clearances is not counted. That slip is a laminar
/// leak, `q = G dp_m / mu`, driven by the pressure drop the rotors need to
/// turn, `dp_m`. On a rig's meter running near its nominal flow, that drop is
/// mostly the rotors' bearing and seal friction, a torque that hardly
/// depends on the flow or on the oil. So the slip is `q(T) = q_ref
/// mu(T_ref) / mu(T)`: the same in l/min at every speed and delivery
/// pressure of one temperature, larger on a thinner oil. (The part of
/// `dp_m` that is viscous, `R mu Q`, gives a slip proportional to the flow,
/// a constant calibration factor, which a rig's calibration removes.)
///
/// Nothing of the pump is in it, and no candidate of the diagnosis has its
/// form: the gaps' leaks grow with the delivery pressure, free air and a
/// displacement error scale with the flow.
pub fn meter_slip_lpm(h: &Hand, temp_c: f64, slip_ref_lpm: f64) -> f64 {
    slip_ref_lpm * h.mu(METER_SLIP_REF_C) / h.mu(temp_c)
}

/// Delivery pressure (bar gauge) and temperature (degC) at which a relief
/// valve's seepage is quoted.
pub const SEEP_REF: (f64, f64) = (30.0, 60.0);

/// The flow that seeps from the delivery back to the suction past the seat
/// of a pump's relief valve, l/min, at `pressure_bar` and `temp_c`: its
/// seepage `seep_ref_lpm` at [`SEEP_REF`] through a sharp-edged orifice,
/// `Q = Cd A sqrt(2 dp / rho)`.
///
/// A seat that a chip or wear holds a little open is a short passage,
/// not a long film: the flow through it is inertial, so it grows with the
/// square root of the pressure drop and the oil's viscosity does not enter
/// (only its density, a few per cent between the two test temperatures).
/// The pump's own gaps are long films whose leak grows in proportion to the
/// pressure drop and to the oil's fluidity (three to four times from 60 to
/// 120 degC), and no candidate has an inertial leak.
pub fn valve_seep_lpm(h: &Hand, pressure_bar: f64, temp_c: f64, seep_ref_lpm: f64) -> f64 {
    let (p_ref, t_ref) = SEEP_REF;
    seep_ref_lpm * (pressure_bar.max(0.0) / p_ref).sqrt() * (h.rho(t_ref) / h.rho(temp_c)).sqrt()
}
