//! Finite-difference solution of the steady Reynolds equation for a plain,
//! finite-length journal bearing: the reference against which the fast
//! closed-form bearing model of [`super::bearing`] is calibrated and checked.
//!
//! # Governing equation
//! Aligned journal of radius `R` turning at `omega` inside a stationary bush of
//! length `L`, radial clearance `c`, eccentricity `e = eps c`, incompressible
//! isoviscous oil (viscosity `mu`). With `x = R theta` along the surface
//! (`theta` measured from the line of centres at the position of maximum film,
//! in the sense of rotation) and `z` axial, the film is
//! `h = c (1 + eps cos theta)` and the Reynolds equation reads
//!
//! ```text
//! d/dx (h^3 dp/dx) + d/dz (h^3 dp/dz) = 6 mu U dh/dx,   U = omega R
//! ```
//!
//! Multiplying by `R^2` and introducing `H = h / c`, `Z = z / L in [0, 1]`,
//! `P = p c^2 / (mu omega R^2)`:
//!
//! ```text
//! d/dtheta (H^3 dP/dtheta) + (R/L)^2 d/dZ (H^3 dP/dZ) = 6 dH/dtheta
//! ```
//!
//! with `P = 0` at both bearing ends (`Z = 0, 1`, ambient reference) and `P`
//! periodic in `theta`.
//!
//! # Discretisation and cavitation
//! Conservative central differences on a uniform `n_theta x n_z` grid (nodes
//! `theta_i = 2 pi i / n_theta`, `Z_j = j / n_z`), `H^3` at the cell faces in
//! `theta`, the source `6 (H_{i+1/2} - H_{i-1/2}) / dtheta` (so the discrete
//! source integrates exactly to zero over a period).
//! * [`Cavitation::FullSommerfeld`] and [`Cavitation::HalfSommerfeld`]: the
//!   linear problem is solved directly, with a discrete sine transform in `Z`
//!   (`H` does not depend on `Z`) and one cyclic tridiagonal solve in `theta`
//!   per axial mode; the half-Sommerfeld field is the full field with negative
//!   pressures set to zero afterwards (the Gumbel condition).
//! * [`Cavitation::Reynolds`] (Swift-Stieber): projected SOR (`P >= 0`
//!   enforced at every Gauss-Seidel update; the free boundary then satisfies
//!   `P = dP/dn = 0` in the limit), started from the half-Sommerfeld field.
//!
//! # Loads, attitude and friction
//! The film force on the journal is `F = -int p n dA` (`n` the outward journal
//! normal). Its components in the line-of-centres frame are reported as
//! * radial `W_r = -int p cos(theta) R dtheta dz` (positive = pushing the
//!   journal back towards the bush centre, against the eccentricity),
//! * tangential `W_t = int p sin(theta) R dtheta dz` (positive = at 90 deg from
//!   the eccentricity in the sense of rotation),
//!
//! non-dimensionally `w = W c^2 / (mu omega R^3 L)`; the attitude angle is
//! `phi = atan2(W_t, W_r)`, the angle between the load line and the line of
//! centres (the journal centre lies `phi` past the load line in the sense of
//! rotation).
//!
//! Friction torque resisting the journal rotation, from the wall shear stress
//! on the journal `tau = mu U / h + (h / 2) dp/dx`:
//!
//! ```text
//! T = int (mu U / h) R dA + int (h / 2R) dp/dtheta R dA
//!   = 2 pi mu omega R^3 L / (c sqrt(1 - eps^2))  +  e W_t / 2      (Couette + Poiseuille)
//! ```
//!
//! Choice: the Couette term is integrated over the full circumference, i.e.
//! the cavitated zone is treated as full film for friction (Petroff-style; the
//! striated film of a submerged gear pump carries some shear there and the
//! choice is conservative, it overestimates friction by at most the cavitated
//! fraction of the Couette term). The Poiseuille term uses the computed
//! (cavitated) pressure; the FD code evaluates it by differences and the
//! identity with `e W_t / 2` is checked in a test.
//!
//! # References
//! Hamrock, Schmid & Jacobson, *Fundamentals of Fluid Film Lubrication*, 2nd
//! ed. (2004), chs. 7 and 10 (Reynolds equation, long and short bearings,
//! cavitation conditions); Christopherson (1941) for projected SOR; seed paper
//! Battarra & Mucchi (2020) Sec. 2.1 for the use in the gear micromotion
//! balance.

use std::f64::consts::PI;
use thiserror::Error;

/// Cavitation (film rupture) condition.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cavitation {
    /// Full Sommerfeld: negative pressures kept (antisymmetric field).
    FullSommerfeld,
    /// Half-Sommerfeld (Gumbel): negative pressures set to zero after solving.
    HalfSommerfeld,
    /// Reynolds (Swift-Stieber) via projected SOR: `p >= 0` during the iteration.
    Reynolds,
}

/// Grid and iteration parameters of the finite-difference solution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FdOptions {
    /// Number of circumferential intervals (periodic), >= 8.
    pub n_theta: usize,
    /// Number of axial intervals across the bearing length, >= 2.
    pub n_z: usize,
    /// Cavitation condition.
    pub cavitation: Cavitation,
    /// Over-relaxation factor of projected SOR, in (0, 2). Reynolds condition only.
    pub relaxation: f64,
    /// Convergence tolerance of projected SOR: largest update divided by the
    /// largest pressure. Reynolds condition only.
    pub tolerance: f64,
    /// Maximum number of projected SOR sweeps. Reynolds condition only.
    pub max_iterations: usize,
}

impl Default for FdOptions {
    fn default() -> Self {
        Self {
            n_theta: 120,
            n_z: 40,
            cavitation: Cavitation::HalfSommerfeld,
            relaxation: 1.9,
            tolerance: 1e-9,
            max_iterations: 200_000,
        }
    }
}

impl FdOptions {
    /// Half-Sommerfeld solution on an `n_theta x n_z` grid.
    pub fn half_sommerfeld(n_theta: usize, n_z: usize) -> Self {
        Self {
            n_theta,
            n_z,
            ..Self::default()
        }
    }

    /// Reynolds (Swift-Stieber) solution on an `n_theta x n_z` grid.
    pub fn reynolds(n_theta: usize, n_z: usize) -> Self {
        Self {
            n_theta,
            n_z,
            cavitation: Cavitation::Reynolds,
            ..Self::default()
        }
    }
}

/// Errors of the finite-difference bearing solution.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ReynoldsError {
    /// The grid is too coarse.
    #[error("grid too coarse: n_theta = {n_theta} (>= 8 needed), n_z = {n_z} (>= 2 needed)")]
    Grid { n_theta: usize, n_z: usize },
    /// Eccentricity ratio outside [0, 1).
    #[error("eccentricity ratio {eps} outside [0, 1)")]
    Eccentricity { eps: f64 },
    /// A geometric or operating parameter is not finite and positive.
    #[error("parameter {name} = {value} must be finite and positive")]
    Parameter { name: &'static str, value: f64 },
    /// A relaxation parameter is out of range.
    #[error("relaxation {relaxation} outside (0, 2) or tolerance {tolerance} not positive")]
    Relaxation { relaxation: f64, tolerance: f64 },
    /// Projected SOR did not converge.
    #[error("projected SOR did not converge in {iterations} sweeps (relative update {update:e})")]
    NotConverged { iterations: usize, update: f64 },
}

/// Non-dimensional finite-difference solution.
#[derive(Debug, Clone, PartialEq)]
pub struct NondimSolution {
    /// Radial load `W_r c^2 / (mu omega R^3 L)` (positive against the eccentricity).
    pub radial: f64,
    /// Tangential load `W_t c^2 / (mu omega R^3 L)` (positive 90 deg ahead of
    /// the eccentricity in the sense of rotation).
    pub tangential: f64,
    /// Couette part of the journal friction torque, `T c / (mu omega R^3 L)`.
    pub friction_couette: f64,
    /// Poiseuille part of the journal friction torque, `T c / (mu omega R^3 L)`.
    pub friction_poiseuille: f64,
    /// Number of circumferential intervals.
    pub n_theta: usize,
    /// Number of axial intervals.
    pub n_z: usize,
    /// Pressure `P = p c^2 / (mu omega R^2)` at node `(i, j)`, stored at
    /// `i * (n_z + 1) + j`, `i < n_theta`, `j <= n_z`.
    pub pressure: Vec<f64>,
    /// Projected SOR sweeps (0 for the direct solutions).
    pub iterations: usize,
}

impl NondimSolution {
    /// Non-dimensional load magnitude `sqrt(w_r^2 + w_t^2)`.
    pub fn load(&self) -> f64 {
        self.radial.hypot(self.tangential)
    }

    /// Attitude angle (rad) between load line and line of centres.
    pub fn attitude(&self) -> f64 {
        self.tangential.atan2(self.radial)
    }

    /// Non-dimensional friction torque on the journal, `T c / (mu omega R^3 L)`.
    pub fn friction(&self) -> f64 {
        self.friction_couette + self.friction_poiseuille
    }

    /// Pressure `P` at node `(i, j)`; zero outside the grid.
    pub fn pressure_at(&self, i: usize, j: usize) -> f64 {
        if i < self.n_theta && j <= self.n_z {
            self.pressure[i * (self.n_z + 1) + j]
        } else {
            0.0
        }
    }

    /// Largest non-dimensional pressure.
    pub fn max_pressure(&self) -> f64 {
        self.pressure.iter().fold(0.0_f64, |a, &p| a.max(p))
    }
}

/// Dimensional finite-difference result (SI).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FdBearingResult {
    /// Eccentricity ratio `e / c`.
    pub eps: f64,
    /// Radial film force on the journal, N (positive against the eccentricity).
    pub radial_force: f64,
    /// Tangential film force on the journal, N (positive 90 deg ahead of the
    /// eccentricity in the sense of rotation).
    pub tangential_force: f64,
    /// Load capacity `sqrt(W_r^2 + W_t^2)`, N.
    pub load: f64,
    /// Attitude angle, rad.
    pub attitude_angle: f64,
    /// Friction torque resisting the journal rotation, N m (magnitude).
    pub friction_torque: f64,
    /// Peak film pressure, Pa (gauge, above the ambient at the bearing ends).
    pub max_pressure: f64,
}

/// Solves the non-dimensional problem for eccentricity ratio `eps` in [0, 1)
/// and slenderness `l_over_d = L / (2 R)`.
pub fn solve_nondim(
    eps: f64,
    l_over_d: f64,
    opts: &FdOptions,
) -> Result<NondimSolution, ReynoldsError> {
    if opts.n_theta < 8 || opts.n_z < 2 {
        return Err(ReynoldsError::Grid {
            n_theta: opts.n_theta,
            n_z: opts.n_z,
        });
    }
    if !(eps.is_finite() && (0.0..1.0).contains(&eps)) {
        return Err(ReynoldsError::Eccentricity { eps });
    }
    if !(l_over_d.is_finite() && l_over_d > 0.0) {
        return Err(ReynoldsError::Parameter {
            name: "l_over_d",
            value: l_over_d,
        });
    }
    let grid = Grid::new(eps, l_over_d, opts.n_theta, opts.n_z);
    let mut p = grid.direct();
    let mut iterations = 0;
    match opts.cavitation {
        Cavitation::FullSommerfeld => {}
        Cavitation::HalfSommerfeld => p.iter_mut().for_each(|v| *v = v.max(0.0)),
        Cavitation::Reynolds => {
            let ok = opts.relaxation > 0.0 && opts.relaxation < 2.0 && opts.tolerance > 0.0;
            if !ok {
                return Err(ReynoldsError::Relaxation {
                    relaxation: opts.relaxation,
                    tolerance: opts.tolerance,
                });
            }
            p.iter_mut().for_each(|v| *v = v.max(0.0));
            iterations = grid.sor(
                &mut p,
                true,
                opts.relaxation,
                opts.tolerance,
                opts.max_iterations,
            )?;
        }
    }
    Ok(grid.integrate(p, iterations))
}

/// Solves the dimensional problem. `radius`, `length`, `clearance` in m,
/// `eps = e / c` in [0, 1), `omega` journal speed in rad/s (either sign: the
/// results are magnitudes in the line-of-centres frame, which turns with the
/// sense of rotation), `mu` in Pa s.
pub fn solve(
    radius: f64,
    length: f64,
    clearance: f64,
    eps: f64,
    omega: f64,
    mu: f64,
    opts: &FdOptions,
) -> Result<FdBearingResult, ReynoldsError> {
    for (name, value) in [
        ("radius", radius),
        ("length", length),
        ("clearance", clearance),
        ("mu", mu),
    ] {
        if !(value.is_finite() && value > 0.0) {
            return Err(ReynoldsError::Parameter { name, value });
        }
    }
    if !omega.is_finite() {
        return Err(ReynoldsError::Parameter {
            name: "omega",
            value: omega,
        });
    }
    let s = solve_nondim(eps, length / (2.0 * radius), opts)?;
    let w = omega.abs();
    let force_scale = mu * w * radius.powi(3) * length / (clearance * clearance);
    let torque_scale = mu * w * radius.powi(3) * length / clearance;
    let p_scale = mu * w * radius * radius / (clearance * clearance);
    Ok(FdBearingResult {
        eps,
        radial_force: force_scale * s.radial,
        tangential_force: force_scale * s.tangential,
        load: force_scale * s.load(),
        attitude_angle: s.attitude(),
        friction_torque: torque_scale * s.friction(),
        max_pressure: p_scale * s.max_pressure(),
    })
}

/// Discretised problem: coefficients of the 5-point scheme.
struct Grid {
    n: usize,
    m: usize,
    eps: f64,
    dtheta: f64,
    /// `H^3` at face `i + 1/2` (index i) .
    h3_east: Vec<f64>,
    /// `H^3` at nodes.
    h3: Vec<f64>,
    /// `beta = (R/L)^2 dtheta^2 / dZ^2`.
    beta: f64,
    /// Source `6 dtheta (H_{i+1/2} - H_{i-1/2})` (equation multiplied by dtheta^2).
    rhs: Vec<f64>,
}

impl Grid {
    fn new(eps: f64, l_over_d: f64, n: usize, m: usize) -> Self {
        let dtheta = 2.0 * PI / n as f64;
        let dz = 1.0 / m as f64;
        let film = |t: f64| 1.0 + eps * t.cos();
        let h3_east: Vec<f64> = (0..n)
            .map(|i| film((i as f64 + 0.5) * dtheta).powi(3))
            .collect();
        let h3: Vec<f64> = (0..n).map(|i| film(i as f64 * dtheta).powi(3)).collect();
        let rhs = (0..n)
            .map(|i| {
                let t = i as f64 * dtheta;
                6.0 * dtheta * (film(t + 0.5 * dtheta) - film(t - 0.5 * dtheta))
            })
            .collect();
        let r_over_l = 0.5 / l_over_d;
        Self {
            n,
            m,
            eps,
            dtheta,
            h3_east,
            h3,
            beta: r_over_l * r_over_l * dtheta * dtheta / (dz * dz),
            rhs,
        }
    }

    #[inline]
    fn west(&self, i: usize) -> f64 {
        self.h3_east[(i + self.n - 1) % self.n]
    }

    /// Direct solution of the linear (full-Sommerfeld) discrete problem by a
    /// discrete sine transform in Z and cyclic tridiagonal solves in theta.
    fn direct(&self) -> Vec<f64> {
        let (n, m) = (self.n, self.m);
        let stride = m + 1;
        let mut p = vec![0.0; n * stride];
        // sine table sin(k pi j / m), k, j in 1..m
        let sin_kj = |k: usize, j: usize| (PI * (k * j) as f64 / m as f64).sin();
        let mut lo = vec![0.0; n];
        let mut di = vec![0.0; n];
        let mut up = vec![0.0; n];
        let mut r = vec![0.0; n];
        for k in 1..m {
            // coefficient of the constant axial profile 1 on mode k
            let s_k: f64 = (1..m).map(|j| sin_kj(k, j)).sum::<f64>() * 2.0 / m as f64;
            if s_k.abs() < 1e-14 {
                continue; // even modes vanish by symmetry
            }
            let sigma = 2.0 - 2.0 * (PI * k as f64 / m as f64).cos();
            for i in 0..n {
                let (ae, aw) = (self.h3_east[i], self.west(i));
                lo[i] = aw;
                up[i] = ae;
                di[i] = -(ae + aw + self.beta * sigma * self.h3[i]);
                r[i] = self.rhs[i] * s_k;
            }
            let q = solve_cyclic_tridiagonal(&lo, &di, &up, &r);
            for (i, qi) in q.iter().enumerate() {
                for j in 1..m {
                    p[i * stride + j] += qi * sin_kj(k, j);
                }
            }
        }
        p
    }

    /// (Projected) SOR sweeps on `p` until the largest update is below
    /// `tol` times the largest pressure. Returns the number of sweeps.
    fn sor(
        &self,
        p: &mut [f64],
        project: bool,
        relax: f64,
        tol: f64,
        max_iter: usize,
    ) -> Result<usize, ReynoldsError> {
        let (n, m) = (self.n, self.m);
        let stride = m + 1;
        let mut update = f64::INFINITY;
        for it in 1..=max_iter {
            let mut max_du = 0.0_f64;
            let mut max_p = 0.0_f64;
            for i in 0..n {
                let ie = (i + 1) % n;
                let iw = (i + n - 1) % n;
                let (ae, aw) = (self.h3_east[i], self.west(i));
                let az = self.beta * self.h3[i];
                let diag = ae + aw + 2.0 * az;
                for j in 1..m {
                    let idx = i * stride + j;
                    let gs = (ae * p[ie * stride + j]
                        + aw * p[iw * stride + j]
                        + az * (p[idx + 1] + p[idx - 1])
                        - self.rhs[i])
                        / diag;
                    let mut new = p[idx] + relax * (gs - p[idx]);
                    if project && new < 0.0 {
                        new = 0.0;
                    }
                    max_du = max_du.max((new - p[idx]).abs());
                    max_p = max_p.max(new.abs());
                    p[idx] = new;
                }
            }
            update = if max_p > 0.0 { max_du / max_p } else { 0.0 };
            if update < tol {
                return Ok(it);
            }
        }
        Err(ReynoldsError::NotConverged {
            iterations: max_iter,
            update,
        })
    }

    /// Loads and friction from the pressure field (periodic rectangle rule in
    /// theta, trapezoidal rule in Z; the end values are zero).
    fn integrate(&self, p: Vec<f64>, iterations: usize) -> NondimSolution {
        let (n, m) = (self.n, self.m);
        let stride = m + 1;
        let dz = 1.0 / m as f64;
        let area = self.dtheta * dz;
        let (mut wr, mut wt, mut poiseuille, mut couette) = (0.0, 0.0, 0.0, 0.0);
        for i in 0..n {
            let t = i as f64 * self.dtheta;
            let (s, c) = t.sin_cos();
            let h = 1.0 + self.eps * c;
            let ie = (i + 1) % n;
            let iw = (i + n - 1) % n;
            couette += self.dtheta / h;
            for j in 1..m {
                let pij = p[i * stride + j];
                wr -= pij * c * area;
                wt += pij * s * area;
                let dpdt = (p[ie * stride + j] - p[iw * stride + j]) / (2.0 * self.dtheta);
                poiseuille += 0.5 * h * dpdt * area;
            }
        }
        NondimSolution {
            radial: wr,
            tangential: wt,
            friction_couette: couette,
            friction_poiseuille: poiseuille,
            n_theta: n,
            n_z: m,
            pressure: p,
            iterations,
        }
    }
}

/// Solves the cyclic tridiagonal system
/// `lo[i] x[i-1] + d[i] x[i] + up[i] x[i+1] = r[i]` (indices mod n, n >= 3)
/// by the Thomas algorithm with a Sherman-Morrison correction. The matrix must
/// be diagonally dominant (it is: the axial mode term adds to the diagonal).
fn solve_cyclic_tridiagonal(lo: &[f64], d: &[f64], up: &[f64], r: &[f64]) -> Vec<f64> {
    let n = d.len();
    let alpha = up[n - 1]; // row n-1, column 0
    let beta = lo[0]; // row 0, column n-1
    let gamma = -d[0];
    let mut bb = d.to_vec();
    bb[0] = d[0] - gamma;
    bb[n - 1] = d[n - 1] - alpha * beta / gamma;
    let x = thomas(lo, &bb, up, r);
    let mut u = vec![0.0; n];
    u[0] = gamma;
    u[n - 1] = alpha;
    let z = thomas(lo, &bb, up, &u);
    let fact = (x[0] + beta * x[n - 1] / gamma) / (1.0 + z[0] + beta * z[n - 1] / gamma);
    x.iter().zip(&z).map(|(xi, zi)| xi - fact * zi).collect()
}

/// Plain tridiagonal solve (`lo[0]` and `up[n-1]` ignored).
fn thomas(lo: &[f64], d: &[f64], up: &[f64], r: &[f64]) -> Vec<f64> {
    let n = d.len();
    let mut c = vec![0.0; n];
    let mut x = vec![0.0; n];
    let mut den = d[0];
    c[0] = up[0] / den;
    x[0] = r[0] / den;
    for i in 1..n {
        den = d[i] - lo[i] * c[i - 1];
        c[i] = up[i] / den;
        x[i] = (r[i] - lo[i] * x[i - 1]) / den;
    }
    for i in (0..n - 1).rev() {
        x[i] -= c[i] * x[i + 1];
    }
    x
}

/// Closed-form half-Sommerfeld loads of the infinitely long bearing (Sommerfeld
/// 1904), non-dimensional `w = W c^2 / (mu omega R^3 L)`:
/// `w_r = 12 eps^2 / ((2 + eps^2)(1 - eps^2))`,
/// `w_t = 6 pi eps / ((2 + eps^2) sqrt(1 - eps^2))`. Returns `(w_r, w_t)`.
pub fn long_bearing_nondim(eps: f64) -> (f64, f64) {
    let e2 = eps * eps;
    let a = 2.0 + e2;
    (
        12.0 * e2 / (a * (1.0 - e2)),
        6.0 * PI * eps / (a * (1.0 - e2).sqrt()),
    )
}

/// Closed-form half-Sommerfeld loads of the infinitely short bearing (Ocvirk
/// 1952), same scaling: `w_r = (L/R)^2 eps^2 / (1 - eps^2)^2`,
/// `w_t = (L/R)^2 pi eps / (4 (1 - eps^2)^1.5)`. Returns `(w_r, w_t)`.
pub fn short_bearing_nondim(eps: f64, l_over_d: f64) -> (f64, f64) {
    let l_r2 = 4.0 * l_over_d * l_over_d;
    let q = 1.0 - eps * eps;
    (
        l_r2 * eps * eps / (q * q),
        l_r2 * PI * eps / (4.0 * q * q.sqrt()),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    #[test]
    fn grid_convergence_60x20_vs_120x40() {
        for &(eps, ld) in &[(0.3, 0.75), (0.6, 1.0), (0.8, 0.75)] {
            let a = solve_nondim(eps, ld, &FdOptions::half_sommerfeld(60, 20)).unwrap();
            let b = solve_nondim(eps, ld, &FdOptions::half_sommerfeld(120, 40)).unwrap();
            let c = solve_nondim(eps, ld, &FdOptions::half_sommerfeld(240, 80)).unwrap();
            let (e1, e2) = (rel(a.load(), b.load()), rel(b.load(), c.load()));
            println!("eps {eps} L/D {ld}: 60x20 vs 120x40 {e1:.2e}, 120x40 vs 240x80 {e2:.2e}");
            assert!(e1 < 0.015, "eps {eps}: {e1}");
            assert!(e2 < 0.5 * e1 + 1e-6, "not converging: {e1} {e2}");
            assert!((a.attitude() - b.attitude()).abs() < 0.01);
        }
    }

    #[test]
    fn long_bearing_limit() {
        // ends reduce the load by O(D/L): the gap must shrink as L/D grows
        for &eps in &[0.2, 0.5, 0.8] {
            let (lr, lt) = long_bearing_nondim(eps);
            let wl = lr.hypot(lt);
            let mut prev = f64::INFINITY;
            for &ld in &[4.0, 10.0, 30.0] {
                let s = solve_nondim(eps, ld, &FdOptions::half_sommerfeld(240, 120)).unwrap();
                let e = rel(s.load(), wl);
                println!(
                    "long: eps {eps} L/D {ld}: FD {:.4} closed {wl:.4} err {e:.4}, phi {:.2} vs {:.2} deg",
                    s.load(),
                    s.attitude().to_degrees(),
                    lt.atan2(lr).to_degrees()
                );
                assert!(s.load() < wl * 1.002 && e < prev);
                prev = e;
            }
            assert!(prev < 0.05, "eps {eps}: {prev}");
        }
    }

    #[test]
    fn short_bearing_limit() {
        for &eps in &[0.2, 0.5, 0.8] {
            let mut prev = f64::INFINITY;
            for &ld in &[0.25, 0.1, 0.03] {
                let (sr, st) = short_bearing_nondim(eps, ld);
                let ws = sr.hypot(st);
                let s = solve_nondim(eps, ld, &FdOptions::half_sommerfeld(480, 40)).unwrap();
                let e = rel(s.load(), ws);
                println!(
                    "short: eps {eps} L/D {ld}: FD/closed {:.4}, phi {:.2} vs {:.2} deg",
                    s.load() / ws,
                    s.attitude().to_degrees(),
                    st.atan2(sr).to_degrees()
                );
                assert!(s.load() < ws * 1.002 && e < prev);
                prev = e;
            }
            assert!(prev < 0.03, "eps {eps}: {prev}");
        }
    }

    #[test]
    fn full_sommerfeld_is_antisymmetric_and_matches_sor() {
        let opts = FdOptions {
            cavitation: Cavitation::FullSommerfeld,
            ..FdOptions::half_sommerfeld(48, 12)
        };
        let s = solve_nondim(0.5, 1.0, &opts).unwrap();
        // no radial load, all tangential
        assert!(s.radial.abs() < 1e-10 * s.tangential.abs());
        // the direct solution is a fixed point of the (unprojected) SOR sweep
        let g = Grid::new(0.5, 1.0, 48, 12);
        let mut p = vec![0.0; s.pressure.len()];
        g.sor(&mut p, false, 1.8, 1e-12, 100_000).unwrap();
        let err = p
            .iter()
            .zip(&s.pressure)
            .fold(0.0_f64, |a, (x, y)| a.max((x - y).abs()));
        assert!(err < 1e-8 * s.max_pressure(), "{err}");
    }

    #[test]
    fn reynolds_condition_nonnegative_and_near_half_sommerfeld() {
        for &eps in &[0.3, 0.7] {
            let h = solve_nondim(eps, 0.75, &FdOptions::half_sommerfeld(72, 24)).unwrap();
            let r = solve_nondim(eps, 0.75, &FdOptions::reynolds(72, 24)).unwrap();
            assert!(r.pressure.iter().all(|&p| p >= 0.0));
            assert!(r.iterations > 0);
            println!(
                "Reynolds vs half-Sommerfeld, eps {eps}: load {:.4} / {:.4}, phi {:.2} / {:.2} deg, sweeps {}",
                r.load(),
                h.load(),
                r.attitude().to_degrees(),
                h.attitude().to_degrees(),
                r.iterations
            );
            // Swift-Stieber gives a smaller attitude angle, similar load
            assert!(r.attitude() < h.attitude());
            assert!(rel(r.load(), h.load()) < 0.25);
        }
    }

    #[test]
    fn reynolds_condition_matches_raimondi_boyd_l_over_d_1() {
        // Raimondi & Boyd (1958), L/D = 1, as tabulated in Shigley's Mechanical
        // Engineering Design: eps, Sommerfeld number S = (R/c)^2 mu N / P,
        // friction variable (R/c) f. With P = W / (L D) and N = omega / 2 pi,
        // w = 1 / (pi S) and (R/c) f = T c / (W c) -> friction() / load().
        let table = [
            (0.1, 1.33, 26.4),
            (0.2, 0.631, 12.8),
            (0.4, 0.264, 5.79),
            (0.6, 0.121, 3.2),
            (0.8, 0.0446, 1.70),
            (0.9, 0.0188, 1.05),
        ];
        for (eps, s, rf) in table {
            let r = solve_nondim(eps, 1.0, &FdOptions::reynolds(240, 60)).unwrap();
            let w = 1.0 / (PI * s);
            println!(
                "eps {eps}: load {:.4} vs R&B {w:.4}; (R/c)f {:.3} vs {rf}",
                r.load(),
                r.friction() / r.load()
            );
            assert!(rel(r.load(), w) < 0.03, "eps {eps}");
            assert!(rel(r.friction() / r.load(), rf) < 0.03, "eps {eps}");
        }
    }

    #[test]
    fn friction_poiseuille_identity_and_petroff() {
        let eps = 0.6;
        let s = solve_nondim(eps, 0.75, &FdOptions::half_sommerfeld(240, 60)).unwrap();
        // Poiseuille part = eps * w_t / 2 (integration by parts)
        assert!(rel(s.friction_poiseuille, 0.5 * eps * s.tangential) < 0.01);
        // Couette part, full film
        let couette = 2.0 * PI / (1.0 - eps * eps).sqrt();
        assert!(rel(s.friction_couette, couette) < 1e-9);
        // Petroff at small eps, dimensional
        let (r, l, c, w, mu) = (8e-3, 12e-3, 12e-6, 200.0, 0.02);
        let d = solve(r, l, c, 0.01, w, mu, &FdOptions::default()).unwrap();
        let petroff = 2.0 * PI * mu * w * r.powi(3) * l / c;
        assert!(rel(d.friction_torque, petroff) < 1e-3);
        let dn = solve(r, l, c, 0.01, -w, mu, &FdOptions::default()).unwrap();
        assert_eq!(d, dn);
    }

    #[test]
    fn rejects_bad_input() {
        let o = FdOptions::default();
        assert!(solve_nondim(1.0, 1.0, &o).is_err());
        assert!(solve_nondim(f64::NAN, 1.0, &o).is_err());
        assert!(solve_nondim(0.5, 0.0, &o).is_err());
        assert!(solve_nondim(0.5, 1.0, &FdOptions::half_sommerfeld(4, 1)).is_err());
        assert!(solve(1.0, 1.0, -1.0, 0.5, 1.0, 1.0, &o).is_err());
        let bad = FdOptions {
            relaxation: 2.5,
            ..FdOptions::reynolds(16, 4)
        };
        assert!(solve_nondim(0.5, 1.0, &bad).is_err());
        let few = FdOptions {
            max_iterations: 2,
            ..FdOptions::reynolds(64, 16)
        };
        assert!(matches!(
            solve_nondim(0.7, 1.0, &few),
            Err(ReynoldsError::NotConverged { .. })
        ));
    }
}
