//! Finite-length plain journal bearing, closed form: film force, its Jacobian,
//! friction torque and static equilibrium of a gear shaft in its bushing, for
//! the gear micromotion balance (seed Sec. 2.1, Eq. 3). Called at every
//! angular step, so no numerical Reynolds solution here; the closed form is
//! calibrated against and checked with the finite-difference solution of
//! [`super::reynolds`].
//!
//! # Governing equations
//! Steady incompressible Reynolds equation of an aligned journal (radius `R`,
//! length `L`, radial clearance `c`, eccentricity `e = eps c`, speed `omega`,
//! viscosity `mu`), half-Sommerfeld (Gumbel) cavitation, as in the seed. The
//! film force on the journal has a radial component `W_r` (against the
//! eccentricity) and a tangential one `W_t` (90 deg ahead of the eccentricity
//! in the sense of rotation), written non-dimensionally as
//! `W = mu |omega| R^3 L / c^2 * w(eps, L/D)`. The two classical limits are
//! (Hamrock et al. 2004, chs. 8 and 10; `lambda = L/D`, `l2 = (L/R)^2 = 4 lambda^2`):
//!
//! ```text
//! short (Ocvirk):     w_r,s = l2 eps^2 / (1 - eps^2)^2
//!                     w_t,s = l2 pi eps / (4 (1 - eps^2)^1.5)
//! long (Sommerfeld):  w_r,l = 12 eps^2 / ((2 + eps^2)(1 - eps^2))
//!                     w_t,l = 6 pi eps / ((2 + eps^2) sqrt(1 - eps^2))
//! ```
//!
//! # Finite-length model (the formula used here)
//! Per component `k in {r, t}`:
//!
//! ```text
//! w_k = w_k,s * s_k * K_k,      s_k = w_k,l / (w_k,s + w_k,l)   (so w_k,s s_k is the harmonic
//!                                                               combination w_s w_l / (w_s + w_l))
//! K_k = 1 - s_k (1 - s_k) Q_k(x, y),  Q_k = sum_{i<=4, j<=3} a_k,ij x^i y^j,
//! x = 1 - (1 - eps^2)^(1/4),          y = ln(L/D) clamped to [ln 0.2, ln 3]
//! ```
//!
//! Origin and reasoning: the seed uses Bastani & de Queiroz (J. Tribol. 132
//! (2010) 014502, doi 10.1115/1.4000389; DSCC 2009), who multiply the
//! infinitely-short or -long solution by correction functions, low-order
//! polynomials in the eccentricity and aspect ratios fitted to the ratio of
//! numerical 2-D Reynolds forces to the limiting ones. Their coefficients were not available to us, so the same
//! construction is rebuilt here: (i) the base is the harmonic combination of
//! the two limits: the wedge source is relieved by circumferential and axial
//! pressure flow acting in parallel (their conductances add), each limit keeps
//! only one path, so `1/w = 1/w_s + 1/w_l` is exact wherever the two pressure
//! shapes coincide and tends to the right limit at both ends; it alone is 3-30 %
//! too high in the transition range `0.25 < L/D < 2`. (ii) The correction
//! `K_k` vanishes (`K -> 1`) in both limits through the weight
//! `s (1 - s)` and is a polynomial in the stretched eccentricity variable `x`
//! (which resolves the steep behaviour towards `eps -> 1`) and in `ln(L/D)`.
//! The 2 x 20 coefficients `a_k,ij` are a least-squares fit of `1 - w_FD / (w_s s)`
//! to the half-Sommerfeld finite-difference solution
//! ([`super::reynolds::solve_nondim`], 360 x 80 grid, 1440 x 80 above eps =
//! 0.9) on `L/D = 0.2 .. 3.0` (step 0.1) x `eps = 0.0125, 0.05 .. 0.95`
//! (step 0.05), `0.97, 0.98, 0.99, 0.995`; the ignored test
//! `recalibrate_correction_coefficients` regenerates them.
//!
//! Agreement with the finite-difference solution (load magnitude, attitude
//! angle): over the whole calibration range within 1 % and 0.25 deg (checked
//! at 1.2 % and 0.4 deg on a coarser grid by `closed_form_tracks_fd_over_calibration_range`);
//! for the pump bearings (`L/D = 0.75` and `1.0`, `eps = 0.1 .. 0.9`) within
//! 0.75 % and 0.2 deg (`closed_form_matches_fd_for_pump_bearings` prints the
//! table); at `eps = 0.999`, `L/D = 0.75 .. 1`, within 2 %. Outside
//! `0.2 <= L/D <= 3` the correction fades and the model tends to the plain
//! harmonic combination: +4 % at `L/D = 4`, +6 % at `L/D = 10`; exact in the
//! short limit, but at `L/D = 0.1` it falls 5-15 % low for `eps >= 0.99`.
//!
//! # Force in a fixed frame
//! With `u = e / c`, `eps = |u|`, `J` the counter-clockwise quarter turn and
//! `sigma = sign(omega)` (mirror symmetry for clockwise rotation):
//!
//! ```text
//! F = mu |omega| R^3 L / c^2 * ( -g_r(eps) u + sigma g_t(eps) J u ),   g_k = w_k / eps
//! dF/de = mu |omega| R^3 L / c^3 * ( -g_r I + sigma g_t J + (-g_r' u + sigma g_t' J u) u^T / eps )
//! ```
//!
//! `g_r ~ eps` and `g_t -> const` as `eps -> 0`, so the force vanishes smoothly
//! and linearly at the centre. The derivatives `g'` are exact (forward-mode
//! dual numbers through the closed form). Beyond `EPS_MAX = 0.999` each `g_k` is
//! continued linearly with its slope at `EPS_MAX` (a steep but finite growth,
//! C1), up to `eps = 2` (the journal would be far through the wall); beyond,
//! the magnitude is held at its `eps = 2` value and only the direction follows
//! `e`; the force is never NaN (results of arithmetic overflow are
//! saturated at `+-f64::MAX`).
//!
//! # Friction torque
//! Torque resisting the journal rotation (Couette over the full
//! circumference, cavitated zone as full film, Petroff-style, plus Poiseuille;
//! see [`super::reynolds`]):
//! `T = mu |omega| R^3 L / c * (2 pi / sqrt(1 - eps^2) + eps w_t / 2)`,
//! with `eps` clamped at `EPS_MAX`; at `eps = 0` it is Petroff's
//! `2 pi mu omega R^3 L / c`.
//!
//! # Axial leakage
//! Axial Poiseuille flow through the eccentric annulus, relative to the
//! concentric one: `int (1 + eps cos theta)^3 dtheta / 2 pi = 1 + 1.5 eps^2`.

use super::norm;
use std::f64::consts::PI;
use std::ops::{Add, Div, Mul, Sub};
use thiserror::Error;

/// Largest eccentricity ratio of the closed form; beyond it the force is
/// continued linearly (see the module documentation).
pub const EPS_MAX: f64 = 0.999;
/// Eccentricity ratio beyond which the continued force is held constant.
const EPS_SATURATE: f64 = 2.0;
/// Calibration range of the correction in L/D.
const LD_MIN: f64 = 0.2;
const LD_MAX: f64 = 3.0;

/// Correction coefficients `a_r,ij` (radial), row `i` = power of `x`, column
/// `j` = power of `y = ln(L/D)`. Fitted to the FD solution, see module doc.
const A_RADIAL: [[f64; 4]; 5] = [
    [
        7.153806590349925e-1,
        5.214097009063977e-2,
        2.6264370997326925e-1,
        1.3784010781367625e-1,
    ],
    [
        2.9713111040745244e-1,
        1.492844320657599e0,
        1.6154983268851892e0,
        8.029715097641121e-2,
    ],
    [
        9.451492840138108e0,
        7.316086549728125e0,
        2.2536232069531943e0,
        8.681013071455367e-1,
    ],
    [
        -3.1130313017245463e1,
        -1.5595999648675908e1,
        -8.450915883977704e0,
        -2.7289096117191742e0,
    ],
    [
        5.65717072556922e1,
        4.1737603237778785e1,
        2.1315104705487947e1,
        5.401189091405003e0,
    ],
];

/// Correction coefficients `a_t,ij` (tangential), layout as [`A_RADIAL`].
const A_TANGENTIAL: [[f64; 4]; 5] = [
    [
        2.6454485619789436e-1,
        5.9729728305965527e-2,
        1.296910260444437e-1,
        7.435386116681508e-2,
    ],
    [
        3.663491046544614e0,
        -2.479411229752779e0,
        1.0351472091724703e0,
        7.738948455401365e-1,
    ],
    [
        1.4509886167634867e0,
        1.7652709264425045e1,
        3.9440650469338356e0,
        -2.3859609920572877e0,
    ],
    [
        -3.468459222465213e1,
        -3.453615199518252e1,
        -1.1725878839839607e1,
        2.663308341615185e0,
    ],
    [
        7.177437551527228e1,
        6.154819075932649e1,
        2.4915289981232988e1,
        2.1182863293055636e0,
    ],
];

/// Plain journal bearing geometry (SI).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JournalBearing {
    /// Journal radius `R`, m.
    pub radius: f64,
    /// Bearing (bushing) length `L`, m.
    pub length: f64,
    /// Radial clearance `c` (bush radius minus journal radius), m.
    pub clearance: f64,
    /// The correction polynomials at the slenderness of `new` (used while
    /// `radius` and `length` keep it).
    slenderness: Slenderness,
}

/// The finite-length correction at one slenderness `L / D`: the rows of
/// `A_RADIAL` and `A_TANGENTIAL` summed over the powers of
/// `y = ln(L / D)` (Horner in y, as [`g_functions`] did it at every call).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Slenderness {
    l_over_d: f64,
    radial: [f64; 5],
    tangential: [f64; 5],
}

impl Slenderness {
    fn new(l_over_d: f64) -> Self {
        let y = l_over_d.clamp(LD_MIN, LD_MAX).ln();
        let rows =
            |a: &[[f64; 4]; 5]| a.map(|row| row.iter().rev().fold(0.0, |s, &aij| s * y + aij));
        Slenderness {
            l_over_d,
            radial: rows(&A_RADIAL),
            tangential: rows(&A_TANGENTIAL),
        }
    }
}

/// Film force on the journal, its Jacobian and the friction torque.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BearingForce {
    /// Hydrodynamic force of the oil film on the journal, N, in the frame of
    /// the offset `e` (it opposes the load carried).
    pub force: [f64; 2],
    /// `jacobian[i][j] = d force_i / d e_j`, N/m.
    pub jacobian: [[f64; 2]; 2],
    /// Viscous torque resisting the journal rotation (magnitude), N m.
    pub friction_torque: f64,
}

impl BearingForce {
    const ZERO: Self = Self {
        force: [0.0; 2],
        jacobian: [[0.0; 2]; 2],
        friction_torque: 0.0,
    };
}

/// Errors of the bearing model.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum BearingError {
    /// A geometric parameter is not finite and positive.
    #[error("bearing {name} = {value} m must be finite and positive")]
    Geometry { name: &'static str, value: f64 },
    /// An operating input is not acceptable.
    #[error("input {name} = {value} is not acceptable (must be finite{extra})")]
    Input {
        name: &'static str,
        value: f64,
        extra: &'static str,
    },
    /// The load exceeds the film capacity at `EPS_MAX`.
    #[error(
        "load {load} N exceeds the film capacity {capacity} N at eccentricity ratio {eps_max}"
    )]
    Overload {
        load: f64,
        capacity: f64,
        eps_max: f64,
    },
    /// Newton did not converge.
    #[error("bearing equilibrium: Newton did not converge in {iterations} iterations (residual {residual} N)")]
    NotConverged { iterations: usize, residual: f64 },
}

/// Non-dimensional finite-length loads and their derivatives with respect to
/// `eps` (scaling `W c^2 / (mu omega R^3 L)`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NondimLoad {
    /// Radial load `w_r` (against the eccentricity).
    pub radial: f64,
    /// Tangential load `w_t` (ahead of the eccentricity in the sense of rotation).
    pub tangential: f64,
    /// `d w_r / d eps`.
    pub d_radial: f64,
    /// `d w_t / d eps`.
    pub d_tangential: f64,
}

impl NondimLoad {
    /// Load magnitude `sqrt(w_r^2 + w_t^2)`.
    pub fn load(&self) -> f64 {
        norm(self.radial, self.tangential)
    }

    /// Attitude angle `atan2(w_t, w_r)`, rad; its limit `pi / 2` at the centre.
    pub fn attitude(&self) -> f64 {
        if self.radial == 0.0 && self.tangential == 0.0 {
            0.5 * PI
        } else {
            self.tangential.atan2(self.radial)
        }
    }
}

/// Closed-form finite-length loads (module doc formula) at `eps` in
/// `[0, EPS_MAX]` (clamped) and slenderness `l_over_d > 0`.
pub fn finite_length_nondim(eps: f64, l_over_d: f64) -> NondimLoad {
    nondim_at(eps, &Slenderness::new(l_over_d))
}

/// [`finite_length_nondim`] with the slenderness's polynomials at hand.
fn nondim_at(eps: f64, slenderness: &Slenderness) -> NondimLoad {
    let eps = clamp_eps(eps);
    let (gr, gt) = g_functions(Dual::var(eps), slenderness);
    NondimLoad {
        radial: eps * gr.v,
        tangential: eps * gt.v,
        d_radial: gr.v + eps * gr.d,
        d_tangential: gt.v + eps * gt.d,
    }
}

impl JournalBearing {
    /// Validated construction: all dimensions finite and positive.
    pub fn new(radius: f64, length: f64, clearance: f64) -> Result<Self, BearingError> {
        let b = Self::unchecked(radius, length, clearance);
        b.check()?;
        Ok(b)
    }

    /// Construction without the checks of [`new`](Self::new), as setting
    /// the fields would be (the force and torque of invalid dimensions are
    /// zero).
    pub fn unchecked(radius: f64, length: f64, clearance: f64) -> Self {
        Self {
            radius,
            length,
            clearance,
            slenderness: Slenderness::new(length / (2.0 * radius)),
        }
    }

    /// This bearing with radial clearance `clearance` (unchecked, as the
    /// fields are).
    pub fn with_clearance(&self, clearance: f64) -> Self {
        Self { clearance, ..*self }
    }

    /// The correction polynomials at this bearing's slenderness: those of
    /// `new`, or computed afresh if `radius` or `length` changed since.
    fn with_slenderness<T>(&self, f: impl FnOnce(&Slenderness) -> T) -> T {
        let ld = self.l_over_d();
        if self.slenderness.l_over_d.to_bits() == ld.to_bits() {
            f(&self.slenderness)
        } else {
            f(&Slenderness::new(ld))
        }
    }

    fn check(&self) -> Result<(), BearingError> {
        for (name, value) in [
            ("radius", self.radius),
            ("length", self.length),
            ("clearance", self.clearance),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(BearingError::Geometry { name, value });
            }
        }
        Ok(())
    }

    /// Slenderness `L / D`.
    pub fn l_over_d(&self) -> f64 {
        self.length / (2.0 * self.radius)
    }

    /// Force scale `mu |omega| R^3 L / c^2`, N.
    fn force_scale(&self, omega: f64, mu: f64) -> f64 {
        mu * omega.abs() * self.radius.powi(3) * self.length / (self.clearance * self.clearance)
    }

    /// Petroff torque of the concentric journal `2 pi mu |omega| R^3 L / c`, N m.
    pub fn petroff_torque(&self, omega: f64, mu: f64) -> f64 {
        2.0 * PI * mu * omega.abs() * self.radius.powi(3) * self.length / self.clearance
    }

    /// Non-dimensional loads of this bearing at `eps` (clamped to `[0, EPS_MAX]`).
    pub fn nondim_load(&self, eps: f64) -> NondimLoad {
        self.with_slenderness(|s| nondim_at(eps, s))
    }

    /// Load capacity (film force magnitude) at eccentricity ratio `eps`, N.
    pub fn load_capacity(&self, eps: f64, omega: f64, mu: f64) -> f64 {
        self.force_scale(omega, mu) * self.nondim_load(eps).load()
    }

    /// Friction torque resisting the journal rotation at `eps`, N m (magnitude).
    pub fn friction_torque(&self, eps: f64, omega: f64, mu: f64) -> f64 {
        let e = clamp_eps(eps);
        // the tangential load alone, without the derivatives: the value of
        // `nondim_load(e).tangential`, to the bit (`e` is clamped already)
        let (_, gt) = self.with_slenderness(|s| g_functions(e, s));
        let w_tangential = e * gt;
        let scale = self.petroff_torque(omega, mu) / (2.0 * PI);
        saturate(scale * (2.0 * PI / (1.0 - e * e).sqrt() + 0.5 * e * w_tangential))
    }

    /// Film force on the journal at offset `e` (m, fixed frame) for journal
    /// speed `omega` (rad/s, positive counter-clockwise in that frame) and
    /// viscosity `mu` (Pa s), with its Jacobian and the friction torque.
    /// Non-finite inputs, non-positive viscosity or invalid geometry give a zero
    /// result.
    pub fn force(&self, e: [f64; 2], omega: f64, mu: f64) -> BearingForce {
        let finite = e.iter().all(|v| v.is_finite()) && omega.is_finite() && mu.is_finite();
        if !finite || mu <= 0.0 || self.check().is_err() {
            return BearingForce::ZERO;
        }
        let (force, jacobian) = self.film_force(e, omega, mu);
        let c = self.clearance;
        let eps = norm(e[0] / c, e[1] / c);
        BearingForce {
            force,
            jacobian,
            friction_torque: self.friction_torque(eps, omega, mu),
        }
    }

    /// The film force of [`force`](Self::force) and its Jacobian, without
    /// the friction torque (the micromotion balance needs only these).
    pub fn force_and_jacobian(
        &self,
        e: [f64; 2],
        omega: f64,
        mu: f64,
    ) -> ([f64; 2], [[f64; 2]; 2]) {
        let finite = e.iter().all(|v| v.is_finite()) && omega.is_finite() && mu.is_finite();
        if !finite || mu <= 0.0 || self.check().is_err() {
            let z = BearingForce::ZERO;
            return (z.force, z.jacobian);
        }
        self.film_force(e, omega, mu)
    }

    /// Film force and Jacobian for valid, finite inputs.
    fn film_force(&self, e: [f64; 2], omega: f64, mu: f64) -> ([f64; 2], [[f64; 2]; 2]) {
        let c = self.clearance;
        let mut u = [e[0] / c, e[1] / c];
        let eps = norm(u[0], u[1]);
        // beyond EPS_SATURATE the force is held: evaluate at the saturation
        // radius in the same direction
        let held = eps > EPS_SATURATE;
        if held {
            u = [u[0] * EPS_SATURATE / eps, u[1] * EPS_SATURATE / eps];
        }
        let (gr, gt) = self.g_continued(eps);
        let sigma = if omega < 0.0 { -1.0 } else { 1.0 };
        let k = self.force_scale(omega, mu);
        let ju = [-u[1], u[0]];
        let force = [
            saturate(k * (-gr.v * u[0] + sigma * gt.v * ju[0])),
            saturate(k * (-gr.v * u[1] + sigma * gt.v * ju[1])),
        ];
        // dF/de = k/c [ -g_r I + sigma g_t J + (-g_r' u + sigma g_t' J u) u^T / eps ]
        let mut jac = [[-gr.v, -sigma * gt.v], [sigma * gt.v, -gr.v]];
        if eps > 0.0 {
            let uhat = [e[0] / (c * eps), e[1] / (c * eps)];
            if held {
                // only the direction changes: times (EPS_SATURATE / eps)(I - uhat uhat^T)
                let f = EPS_SATURATE / eps;
                let p = [
                    [1.0 - uhat[0] * uhat[0], -uhat[0] * uhat[1]],
                    [-uhat[1] * uhat[0], 1.0 - uhat[1] * uhat[1]],
                ];
                let a = jac;
                for (i, row) in jac.iter_mut().enumerate() {
                    for (j, x) in row.iter_mut().enumerate() {
                        *x = f * (a[i][0] * p[0][j] + a[i][1] * p[1][j]);
                    }
                }
            } else {
                let v = [
                    -gr.d * u[0] + sigma * gt.d * ju[0],
                    -gr.d * u[1] + sigma * gt.d * ju[1],
                ];
                for (row, vi) in jac.iter_mut().zip(v) {
                    row[0] += vi * uhat[0];
                    row[1] += vi * uhat[1];
                }
            }
        }
        let kc = k / c;
        let jacobian = jac.map(|row| row.map(|x| saturate(kc * x)));
        (force, jacobian)
    }

    /// `g_k = w_k / eps` and `d g_k / d eps`, continued linearly beyond
    /// `EPS_MAX` and held beyond `EPS_SATURATE`.
    fn g_continued(&self, eps: f64) -> (Dual, Dual) {
        if eps <= EPS_MAX {
            return self.with_slenderness(|s| g_functions(Dual::var(eps), s));
        }
        let (gr, gt) = self.with_slenderness(|s| g_functions(Dual::var(EPS_MAX), s));
        let (de, slope) = if eps < EPS_SATURATE {
            (eps - EPS_MAX, 1.0)
        } else {
            (EPS_SATURATE - EPS_MAX, 0.0)
        };
        let cont = |g: Dual| Dual {
            v: g.v + g.d * de,
            d: g.d * slope,
        };
        (cont(gr), cont(gt))
    }

    /// Offset `e` (m) at which the film force balances the external `load` on
    /// the journal (`force(e) + load = 0`), by damped Newton with the analytic
    /// Jacobian from `e0`. The step is limited so that the eccentricity ratio
    /// covers at most half the remaining distance to `EPS_MAX` per iteration
    /// and is halved until the residual decreases. Should Newton from `e0`
    /// fail, it is restarted once from the isotropic solution (magnitude from
    /// the monotone `W(eps) = |load|` by bisection, direction = load direction
    /// turned by the attitude angle in the sense of rotation).
    pub fn equilibrium(
        &self,
        load: [f64; 2],
        omega: f64,
        mu: f64,
        e0: [f64; 2],
    ) -> Result<[f64; 2], BearingError> {
        self.check()?;
        let inputs = [
            ("load_x", load[0], ""),
            ("load_y", load[1], ""),
            ("omega", omega, ""),
            ("mu", mu, " and non-negative"),
            ("e0_x", e0[0], ""),
            ("e0_y", e0[1], ""),
        ];
        for (name, value, extra) in inputs {
            if !value.is_finite() || (name == "mu" && value < 0.0) {
                return Err(BearingError::Input { name, value, extra });
            }
        }
        let w = norm(load[0], load[1]);
        if w == 0.0 {
            return Ok([0.0, 0.0]);
        }
        let capacity = self.load_capacity(EPS_MAX, omega, mu);
        if w >= capacity {
            return Err(BearingError::Overload {
                load: w,
                capacity,
                eps_max: EPS_MAX,
            });
        }
        let first = self.newton(load, omega, mu, e0);
        let (iters1, res1) = match first {
            Ok(e) => return Ok(e),
            Err(x) => x,
        };
        let start = self.isotropic_equilibrium(load, omega, mu);
        self.newton(load, omega, mu, start)
            .map_err(|(iters2, res2)| BearingError::NotConverged {
                iterations: iters1 + iters2,
                residual: res1.min(res2),
            })
    }

    /// Damped Newton; on failure returns (iterations, best residual).
    fn newton(
        &self,
        load: [f64; 2],
        omega: f64,
        mu: f64,
        e0: [f64; 2],
    ) -> Result<[f64; 2], (usize, f64)> {
        const MAX_ITER: usize = 60;
        let c = self.clearance;
        let w = norm(load[0], load[1]);
        let tol = 1e-10 * w;
        let residual = |e: [f64; 2]| {
            let f = self.force(e, omega, mu);
            ([f.force[0] + load[0], f.force[1] + load[1]], f.jacobian)
        };
        // start inside the admissible region
        let mut e = e0;
        let eps0 = norm(e[0], e[1]) / c;
        if eps0 > 0.9 * EPS_MAX {
            let s = 0.9 * EPS_MAX / eps0;
            e = [e[0] * s, e[1] * s];
        }
        let (mut r, mut jac) = residual(e);
        let mut nr = norm(r[0], r[1]);
        for it in 0..MAX_ITER {
            if nr <= tol {
                return Ok(e);
            }
            let det = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
            if !(det.is_finite() && det.abs() > 0.0) {
                return Err((it, nr));
            }
            let d = [
                -(jac[1][1] * r[0] - jac[0][1] * r[1]) / det,
                -(-jac[1][0] * r[0] + jac[0][0] * r[1]) / det,
            ];
            let eps = norm(e[0], e[1]) / c;
            let limit = 0.5 * (eps + EPS_MAX);
            let mut t = 1.0;
            let mut accepted = false;
            for _ in 0..40 {
                let mut cand = [e[0] + t * d[0], e[1] + t * d[1]];
                let ec = norm(cand[0], cand[1]) / c;
                if ec > limit {
                    let s = limit / ec;
                    cand = [cand[0] * s, cand[1] * s];
                }
                let (rc, jc) = residual(cand);
                let nc = norm(rc[0], rc[1]);
                if nc < (1.0 - 1e-4 * t) * nr || nc <= tol {
                    e = cand;
                    r = rc;
                    jac = jc;
                    nr = nc;
                    accepted = true;
                    break;
                }
                t *= 0.5;
            }
            if !accepted {
                return Err((it + 1, nr));
            }
        }
        if nr <= tol {
            Ok(e)
        } else {
            Err((MAX_ITER, nr))
        }
    }

    /// Isotropic solution: `eps` from `W(eps) = |load|` (bisection, `W`
    /// monotone), direction = load direction turned by `sign(omega) phi(eps)`.
    fn isotropic_equilibrium(&self, load: [f64; 2], omega: f64, mu: f64) -> [f64; 2] {
        let w = norm(load[0], load[1]);
        let k = self.force_scale(omega, mu);
        let (mut lo, mut hi) = (0.0, EPS_MAX);
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if k * self.nondim_load(mid).load() < w {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let eps = 0.5 * (lo + hi);
        let phi = self.nondim_load(eps).attitude() * if omega < 0.0 { -1.0 } else { 1.0 };
        let (s, co) = phi.sin_cos();
        let l = [load[0] / w, load[1] / w];
        let r = eps * self.clearance;
        [r * (co * l[0] - s * l[1]), r * (s * l[0] + co * l[1])]
    }
}

/// `eps` clamped to `[0, EPS_MAX]` (NaN -> 0).
fn clamp_eps(eps: f64) -> f64 {
    if eps.is_nan() {
        0.0
    } else {
        eps.clamp(0.0, EPS_MAX)
    }
}

/// NaN -> 0, infinities -> +-f64::MAX.
fn saturate(x: f64) -> f64 {
    if x.is_nan() {
        0.0
    } else {
        x.clamp(-f64::MAX, f64::MAX)
    }
}

/// `g_k = w_k / eps` of the finite-length model, for `eps` in `[0,
/// EPS_MAX]` and `l_over_d > 0`, with its derivative (`eps` a [`Dual`]
/// variable) or without (`eps` an `f64`: the same values to the bit, as a
/// dual number's value part is the plain arithmetic). Returns `(g_r, g_t)`.
fn g_functions<T: Real>(eps: T, slenderness: &Slenderness) -> (T, T) {
    let one = T::cst(1.0);
    let l_over_d = slenderness.l_over_d;
    let l2 = 4.0 * l_over_d * l_over_d;
    let e2 = eps * eps;
    let q = one - e2;
    let sq = q.sqrt();
    let two_e2 = e2 + 2.0;
    // short-bearing g's and the ratios short / long
    let grs = eps * l2 / (q * q);
    let gts = T::cst(l2 * PI / 4.0) / (q * sq);
    let rho_r = two_e2 * (l2 / 12.0) / q;
    let rho_t = two_e2 * (l2 / 24.0) / q;
    let s_r = one / (rho_r + 1.0);
    let s_t = one / (rho_t + 1.0);
    // correction polynomial
    let x = one - sq.sqrt();
    let k_r = one - s_r * (one - s_r) * poly(&slenderness.radial, x);
    let k_t = one - s_t * (one - s_t) * poly(&slenderness.tangential, x);
    (grs * s_r * k_r, gts * s_t * k_t)
}

/// `sum_ij a_ij x^i y^j` (Horner in both) from its rows' sums over the
/// powers of y, `rows[i] = sum_j a_ij y^j` ([`Slenderness`]).
fn poly<T: Real>(rows: &[f64; 5], x: T) -> T {
    let mut acc = T::cst(0.0);
    for &cy in rows.iter().rev() {
        acc = acc * x + cy;
    }
    acc
}

/// The arithmetic [`g_functions`] needs: plain numbers, or [`Dual`]
/// numbers that carry a derivative along.
trait Real:
    Copy
    + Add<Output = Self>
    + Add<f64, Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Mul<f64, Output = Self>
    + Div<Output = Self>
{
    fn cst(v: f64) -> Self;
    fn sqrt(self) -> Self;
}

impl Real for f64 {
    fn cst(v: f64) -> Self {
        v
    }
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
}

impl Real for Dual {
    fn cst(v: f64) -> Self {
        Dual::cst(v)
    }
    fn sqrt(self) -> Self {
        Dual::sqrt(self)
    }
}

/// Forward-mode dual number `v + d * epsilon` for exact derivatives in `eps`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Dual {
    v: f64,
    d: f64,
}

impl Dual {
    fn var(v: f64) -> Self {
        Self { v, d: 1.0 }
    }
    fn cst(v: f64) -> Self {
        Self { v, d: 0.0 }
    }
    fn sqrt(self) -> Self {
        let s = self.v.sqrt();
        Self {
            v: s,
            d: self.d / (2.0 * s),
        }
    }
}

impl Add for Dual {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self {
            v: self.v + o.v,
            d: self.d + o.d,
        }
    }
}
impl Add<f64> for Dual {
    type Output = Self;
    fn add(self, o: f64) -> Self {
        Self {
            v: self.v + o,
            d: self.d,
        }
    }
}
impl Sub for Dual {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Self {
            v: self.v - o.v,
            d: self.d - o.d,
        }
    }
}
impl Mul for Dual {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        Self {
            v: self.v * o.v,
            d: self.d * o.v + self.v * o.d,
        }
    }
}
impl Mul<f64> for Dual {
    type Output = Self;
    fn mul(self, o: f64) -> Self {
        Self {
            v: self.v * o,
            d: self.d * o,
        }
    }
}
impl Div for Dual {
    type Output = Self;
    /// The quotient rule as `(a' - (a / b) b') / b`: the value as before,
    /// to the bit, and one division less than `(a' b - a b') / b^2` (the
    /// g-functions' six quotients were the bulk of their time).
    fn div(self, o: Self) -> Self {
        let v = self.v / o.v;
        Self {
            v,
            d: (self.d - v * o.d) / o.v,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::reynolds::{
        long_bearing_nondim, short_bearing_nondim, solve_nondim, FdOptions,
    };
    use super::*;

    const PUMP_BEARINGS: [(&str, f64, f64, f64); 2] = [
        ("L/D 0.75", 8e-3, 12e-3, 12e-6),
        ("L/D 1.00", 6e-3, 12e-3, 12e-6),
    ];

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    /// The key check: closed form vs FD (half-Sommerfeld) for the pump's bearings.
    #[test]
    fn closed_form_matches_fd_for_pump_bearings() {
        let (omega, mu) = (150.0, 0.016);
        let (mut worst_load, mut worst_phi) = (0.0_f64, 0.0_f64);
        for (name, r, l, c) in PUMP_BEARINGS {
            let b = JournalBearing::new(r, l, c).unwrap();
            println!("{name}: R {r} m, L {l} m, c {c} m, omega {omega} rad/s, mu {mu} Pa s");
            println!("  eps |  FD load N | model load N | err % | phi FD deg | phi model deg");
            for k in 1..=9 {
                let eps = 0.1 * k as f64;
                let fd = super::super::reynolds::solve(
                    r,
                    l,
                    c,
                    eps,
                    omega,
                    mu,
                    &FdOptions::half_sommerfeld(360, 80),
                )
                .unwrap();
                // the model through the public Cartesian API
                let f = b.force([eps * c, 0.0], omega, mu);
                let load = norm(f.force[0], f.force[1]);
                // film force = -W_r e_hat + W_t J e_hat with e_hat = x
                let phi = f.force[1].atan2(-f.force[0]);
                let err = (load / fd.load - 1.0) * 100.0;
                let dphi = (phi - fd.attitude_angle).to_degrees();
                println!(
                    "  {eps:.1} | {:10.2} | {load:12.2} | {err:5.2} | {:10.2} | {:13.2}",
                    fd.load,
                    fd.attitude_angle.to_degrees(),
                    phi.to_degrees()
                );
                worst_load = worst_load.max(err.abs());
                worst_phi = worst_phi.max(dphi.abs());
            }
        }
        println!("worst: load {worst_load:.2} %, attitude {worst_phi:.2} deg");
        assert!(worst_load < 1.0, "load error {worst_load} %");
        assert!(worst_phi < 0.3, "attitude error {worst_phi} deg");
    }

    #[test]
    fn closed_form_tracks_fd_over_calibration_range() {
        let mut worst = (0.0_f64, 0.0_f64);
        for &ld in &[0.25, 0.5, 1.5, 2.5] {
            for &eps in &[0.05, 0.3, 0.6, 0.8, 0.95, 0.99] {
                let nt = if eps > 0.9 { 1440 } else { 240 };
                let fd = solve_nondim(eps, ld, &FdOptions::half_sommerfeld(nt, 60)).unwrap();
                let m = finite_length_nondim(eps, ld);
                worst.0 = worst.0.max(rel(m.load(), fd.load()));
                worst.1 = worst
                    .1
                    .max((m.attitude() - fd.attitude()).abs().to_degrees());
            }
        }
        println!(
            "calibration range: worst load {:.4}, attitude {:.3} deg",
            worst.0, worst.1
        );
        assert!(worst.0 < 0.015 && worst.1 < 0.4, "{worst:?}");
    }

    #[test]
    fn tends_to_short_and_long_limits() {
        for &eps in &[0.2, 0.6, 0.9] {
            let (sr, st) = short_bearing_nondim(eps, 0.02);
            let m = finite_length_nondim(eps, 0.02);
            assert!(rel(m.radial, sr) < 0.01 && rel(m.tangential, st) < 0.01);
            let (lr, lt) = long_bearing_nondim(eps);
            let m = finite_length_nondim(eps, 200.0);
            assert!(rel(m.radial, lr) < 0.01 && rel(m.tangential, lt) < 0.01);
        }
    }

    #[test]
    fn force_opposes_load_at_equilibrium() {
        let b = JournalBearing::new(8e-3, 12e-3, 12e-6).unwrap();
        let mu = 0.016;
        for &omega in &[104.7, -104.7, 418.9] {
            for &(wx, wy) in &[
                (0.0, -500.0),
                (1200.0, 300.0),
                (-20.0, 5.0),
                (-3000.0, -4000.0),
            ] {
                let load = [wx, wy];
                let e = b.equilibrium(load, omega, mu, [0.0, 0.0]).unwrap();
                let f = b.force(e, omega, mu);
                let w = norm(load[0], load[1]);
                let res = norm(f.force[0] + wx, f.force[1] + wy);
                assert!(res < 1e-8 * w, "residual {res}");
                // force opposite to the load
                let dot = f.force[0] * wx + f.force[1] * wy;
                assert!((dot / (w * w) + 1.0).abs() < 1e-8);
                // the journal centre lies past the load line in the sense of rotation
                let cross = wx * e[1] - wy * e[0];
                assert!(cross * omega > 0.0);
                let eps = norm(e[0], e[1]) / b.clearance;
                let phi = (cross / (w * eps * b.clearance)).asin().abs();
                assert!((phi - b.nondim_load(eps).attitude()).abs() < 1e-6);
                // warm start from a poor guess converges to the same point
                let e2 = b
                    .equilibrium(load, omega, mu, [-0.95 * 12e-6, 0.3e-6])
                    .unwrap();
                assert!((e2[0] - e[0]).hypot(e2[1] - e[1]) < 1e-9 * b.clearance);
            }
        }
    }

    #[test]
    fn plain_newton_converges_from_the_centre() {
        // without the isotropic restart, from e0 = 0, up to eps = 0.995
        for (_, r, l, c) in PUMP_BEARINGS {
            let b = JournalBearing::new(r, l, c).unwrap();
            for k in 1..=20 {
                let eps = (0.05 * k as f64).min(0.995);
                let w = b.load_capacity(eps, 300.0, 0.01);
                let load = [0.6 * w, -0.8 * w];
                let e = b.newton(load, 300.0, 0.01, [0.0, 0.0]);
                let e = e.unwrap_or_else(|(it, res)| panic!("eps {eps}: {it} iterations, {res}"));
                assert!(rel(e[0].hypot(e[1]) / c, eps) < 1e-7);
            }
        }
    }

    #[test]
    fn equilibrium_near_the_wall_and_errors() {
        let b = JournalBearing::new(8e-3, 12e-3, 12e-6).unwrap();
        let (omega, mu) = (52.0, 0.0044);
        let cap = b.load_capacity(0.995, omega, mu);
        let e = b.equilibrium([0.0, -cap], omega, mu, [0.0, 0.0]).unwrap();
        assert!(rel(e[0].hypot(e[1]) / b.clearance, 0.995) < 1e-8);
        let too_much = 1.01 * b.load_capacity(EPS_MAX, omega, mu);
        assert!(matches!(
            b.equilibrium([too_much, 0.0], omega, mu, [0.0, 0.0]),
            Err(BearingError::Overload { .. })
        ));
        assert!(matches!(
            b.equilibrium([1.0, 0.0], 0.0, mu, [0.0, 0.0]),
            Err(BearingError::Overload { .. })
        ));
        assert!(matches!(
            b.equilibrium([f64::NAN, 0.0], omega, mu, [0.0, 0.0]),
            Err(BearingError::Input { .. })
        ));
        assert!(matches!(
            b.equilibrium([1.0, 0.0], omega, -1.0, [0.0, 0.0]),
            Err(BearingError::Input { .. })
        ));
        let bad = JournalBearing {
            clearance: 0.0,
            ..b
        };
        assert!(matches!(
            bad.equilibrium([1.0, 0.0], omega, mu, [0.0, 0.0]),
            Err(BearingError::Geometry { .. })
        ));
        assert!(JournalBearing::new(1e-3, f64::INFINITY, 1e-6).is_err());
        assert_eq!(
            b.equilibrium([0.0, 0.0], omega, mu, [1e-6, 0.0]),
            Ok([0.0, 0.0])
        );
    }

    /// The g-functions in plain numbers are the value part of the dual
    /// ones to the bit (the friction torque takes the plain ones), over the
    /// whole range of eccentricity ratios and both pump bearings.
    #[test]
    fn the_plain_g_functions_are_the_dual_values_to_the_bit() {
        for (name, r, l, c) in PUMP_BEARINGS {
            let b = JournalBearing::new(r, l, c).unwrap();
            for i in 0..=1000 {
                let eps = EPS_MAX * i as f64 / 1000.0;
                let (pr, pt) = b.with_slenderness(|s| g_functions(eps, s));
                let (dr, dt) = b.with_slenderness(|s| g_functions(Dual::var(eps), s));
                assert_eq!(pr.to_bits(), dr.v.to_bits(), "{name}: radial at {eps}");
                assert_eq!(pt.to_bits(), dt.v.to_bits(), "{name}: tangential at {eps}");
                assert_eq!(
                    b.nondim_load(eps).tangential.to_bits(),
                    (eps * pt).to_bits(),
                    "{name}: load at {eps}"
                );
            }
        }
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let (omega, mu) = (-230.0, 0.02);
        for (_, r, l, c) in PUMP_BEARINGS {
            let b = JournalBearing::new(r, l, c).unwrap();
            for &(ex, ey) in &[
                (0.0, 0.0),
                (1e-3, -2e-3),
                (0.3, 0.2),
                (-0.5, 0.6),
                (0.0, -0.95),
                (0.7, -0.7),
                (0.99, 0.05),
                (1.2, 0.3),
                (-2.5, 1.0),
            ] {
                let e = [ex * c, ey * c];
                let f = b.force(e, omega, mu);
                let h = 1e-7 * c;
                let scale = f
                    .jacobian
                    .iter()
                    .flatten()
                    .fold(0.0_f64, |a, v| a.max(v.abs()));
                for j in 0..2 {
                    let (mut ep, mut em) = (e, e);
                    ep[j] += h;
                    em[j] -= h;
                    let (fp, fm) = (b.force(ep, omega, mu), b.force(em, omega, mu));
                    for i in 0..2 {
                        let fd = (fp.force[i] - fm.force[i]) / (2.0 * h);
                        let err = (fd - f.jacobian[i][j]).abs() / scale;
                        assert!(
                            err < 1e-5,
                            "e = ({ex}, {ey}) [{i}][{j}]: {fd} vs {}",
                            f.jacobian[i][j]
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn load_grows_monotonically_with_eps() {
        for &ld in &[0.1, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 5.0] {
            let b = JournalBearing::new(5e-3, 10e-3 * ld, 5e-6).unwrap();
            let mut prev = -1.0;
            for k in 0..=1200 {
                let eps = k as f64 * 1.5 / 1200.0;
                let f = b.force([eps * b.clearance, 0.0], 100.0, 0.01);
                let w = f.force[0].hypot(f.force[1]);
                assert!(w > prev, "L/D {ld} eps {eps}: {w} <= {prev}");
                prev = w;
                if eps <= EPS_MAX {
                    let m = b.nondim_load(eps);
                    assert!((m.d_radial >= 0.0 && m.d_tangential >= 0.0) || eps == 0.0);
                    let phi = m.attitude();
                    assert!(phi > 0.0 && phi <= 0.5 * PI + 1e-12);
                }
            }
        }
    }

    #[test]
    fn negative_omega_is_mirror_image() {
        let b = JournalBearing::new(6e-3, 12e-3, 12e-6).unwrap();
        for &(ex, ey) in &[(3e-6, 4e-6), (-7e-6, 1e-6), (0.0, -11e-6)] {
            let f = b.force([ex, ey], 300.0, 0.01);
            let g = b.force([ex, -ey], -300.0, 0.01);
            // reflection about the x axis: M = diag(1, -1)
            assert!((g.force[0] - f.force[0]).abs() < 1e-12 * f.force[0].abs().max(1.0));
            assert!((g.force[1] + f.force[1]).abs() < 1e-12 * f.force[1].abs().max(1.0));
            assert!((g.jacobian[0][0] - f.jacobian[0][0]).abs() <= 1e-9 * f.jacobian[0][0].abs());
            assert!((g.jacobian[0][1] + f.jacobian[0][1]).abs() <= 1e-9 * f.jacobian[0][1].abs());
            assert!((g.jacobian[1][0] + f.jacobian[1][0]).abs() <= 1e-9 * f.jacobian[1][0].abs());
            assert!((g.jacobian[1][1] - f.jacobian[1][1]).abs() <= 1e-9 * f.jacobian[1][1].abs());
            assert_eq!(g.friction_torque, f.friction_torque);
        }
    }

    #[test]
    fn friction_torque_petroff_and_fd() {
        let (omega, mu) = (200.0, 0.016);
        for (_, r, l, c) in PUMP_BEARINGS {
            let b = JournalBearing::new(r, l, c).unwrap();
            let petroff = b.petroff_torque(omega, mu);
            let expected = mu * omega * r.powi(3) * 2.0 * PI * l / c;
            assert!(rel(petroff, expected) < 1e-12);
            let t0 = b.force([0.0, 0.0], omega, mu).friction_torque;
            assert!(rel(t0, petroff) < 1e-12);
            let t = b.force([0.05 * c, 0.0], omega, mu).friction_torque;
            assert!(rel(t, petroff) < 0.005);
            for &eps in &[0.3, 0.7, 0.9] {
                let fd = super::super::reynolds::solve(
                    r,
                    l,
                    c,
                    eps,
                    omega,
                    mu,
                    &FdOptions::half_sommerfeld(240, 60),
                )
                .unwrap();
                let m = b.friction_torque(eps, omega, mu);
                assert!(rel(m, fd.friction_torque) < 0.005, "eps {eps}");
                assert!(m > petroff);
            }
        }
    }

    #[test]
    fn smooth_at_centre_and_never_nan() {
        let b = JournalBearing::new(8e-3, 12e-3, 12e-6).unwrap();
        let f0 = b.force([0.0, 0.0], 100.0, 0.02);
        assert_eq!(f0.force, [0.0, 0.0]);
        // linear near the centre: F = J0 e
        let e = [1e-12, -2e-12];
        let f = b.force(e, 100.0, 0.02);
        for i in 0..2 {
            let lin = f0.jacobian[i][0] * e[0] + f0.jacobian[i][1] * e[1];
            assert!((f.force[i] - lin).abs() < 1e-6 * lin.abs().max(1e-30));
        }
        let big = f64::MAX / 4.0;
        for &(e, w, mu) in &[
            ([big, big], 1e300, 1e300),
            ([1e-3, 0.0], 100.0, 0.02),
            ([f64::NAN, 0.0], 100.0, 0.02),
            ([0.0, 1e-6], f64::INFINITY, 0.02),
            ([0.0, 1e-6], 100.0, -1.0),
            ([-3e-5, 1e-6], -1e-300, 1e-300),
        ] {
            let f = b.force(e, w, mu);
            assert!(f
                .force
                .iter()
                .chain(f.jacobian.iter().flatten())
                .all(|v| !v.is_nan()));
            assert!(!f.friction_torque.is_nan());
        }
        let bad = JournalBearing {
            radius: 0.0,
            length: 1.0,
            clearance: -1.0,
            slenderness: Slenderness::new(f64::INFINITY),
        };
        assert_eq!(bad.force([1.0, 1.0], 1.0, 1.0), BearingForce::ZERO);
        // beyond EPS_MAX the force keeps growing, beyond EPS_SATURATE it is held
        let w = |eps: f64| {
            let f = b.force([eps * 12e-6, 0.0], 100.0, 0.02);
            f.force[0].hypot(f.force[1])
        };
        assert!(w(1.0) > w(EPS_MAX) && w(1.5) > w(1.0));
        assert_eq!(w(3.0), w(10.0));
    }

    /// Regenerates `A_RADIAL` and `A_TANGENTIAL` from the FD solution
    /// (`cargo test --lib recalibrate -- --ignored --nocapture`).
    #[test]
    #[ignore]
    fn recalibrate_correction_coefficients() {
        use nalgebra::{DMatrix, DVector};
        let lds: Vec<f64> = (2..=30).map(|k| 0.1 * k as f64).collect();
        let mut epss: Vec<f64> = (1..=19).map(|k| 0.05 * k as f64).collect();
        epss.extend([0.0125, 0.97, 0.98, 0.99, 0.995]);
        let mut rows = [Vec::new(), Vec::new()];
        let mut rhs = [Vec::new(), Vec::new()];
        for &ld in &lds {
            for &eps in &epss {
                let nt = if eps > 0.9 { 1440 } else { 360 };
                let fd = solve_nondim(eps, ld, &FdOptions::half_sommerfeld(nt, 80)).unwrap();
                let short = short_bearing_nondim(eps, ld);
                let long = long_bearing_nondim(eps);
                let x = 1.0 - (1.0 - eps * eps).powf(0.25);
                let y = ld.ln();
                for (k, (fs, fl, f)) in [
                    (short.0, long.0, fd.radial),
                    (short.1, long.1, fd.tangential),
                ]
                .into_iter()
                .enumerate()
                {
                    let s = fl / (fs + fl);
                    let w = s * (1.0 - s);
                    for i in 0..5 {
                        for j in 0..4 {
                            rows[k].push(w * x.powi(i) * y.powi(j));
                        }
                    }
                    rhs[k].push(1.0 - f / (fs * s));
                }
            }
        }
        for k in 0..2 {
            let n = rhs[k].len();
            let a = DMatrix::from_row_slice(n, 20, &rows[k]);
            let sol = a
                .svd(true, true)
                .solve(&DVector::from_vec(rhs[k].clone()), 1e-14)
                .unwrap();
            println!("{}:", ["A_RADIAL", "A_TANGENTIAL"][k]);
            for i in 0..5 {
                let r: Vec<String> = (0..4).map(|j| format!("{:e}", sol[i * 4 + j])).collect();
                println!("    [{}],", r.join(", "));
            }
        }
    }
}
