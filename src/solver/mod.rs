//! Generic implicit integration, knowing nothing of pumps (STYLE habit 8).
//!
//! * [`newton`]: damped Newton iteration on `F(x) = 0` with a dense Jacobian
//!   (nalgebra LU), returning a termination reason and iteration counts.
//! * [`ImplicitEuler`]: one backward-Euler step of a *conservative* system
//!   `d m(x)/dt = f(x)`, where each state has a storage `m_i(x_i)` (for a
//!   hydraulic control volume: the mass `rho(p) V`) and `f` sums the fluxes.
//!   The residual `(m(x) - m_old)/dt - f(x)` conserves the summed storage to
//!   round-off: what leaves one state enters another.

use nalgebra::{DMatrix, DVector};
use thiserror::Error;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum SolverError {
    #[error(
        "Newton did not converge in {iterations} iterations (last correction {last_correction:e})"
    )]
    NoConvergence {
        iterations: usize,
        last_correction: f64,
    },
    #[error("singular Jacobian at iteration {iteration}")]
    Singular { iteration: usize },
    #[error("non-finite residual at iteration {iteration}")]
    NonFinite { iteration: usize },
}

/// Why Newton stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Termination {
    /// The scaled correction fell below the tolerance.
    Converged,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewtonReport {
    pub termination: Termination,
    pub iterations: usize,
}

/// Settings of the Newton iteration.
#[derive(Debug, Clone, Copy)]
pub struct NewtonOptions {
    /// Converged when max_i |dx_i| / scale_i < tol.
    pub tol: f64,
    pub max_iter: usize,
    /// Largest allowed |dx_i| / scale_i in one iteration (damping).
    pub max_step: f64,
}

/// A nonlinear system: residual and Jacobian at x.
pub trait NewtonProblem {
    fn dim(&self) -> usize;
    /// Fills `r = F(x)` and `j = dF/dx`.
    fn eval(&mut self, x: &DVector<f64>, r: &mut DVector<f64>, j: &mut DMatrix<f64>);
    /// Scale of each unknown for the convergence test.
    fn scale(&self, i: usize) -> f64;
}

/// Solves F(x) = 0 from the initial guess in `x`.
pub fn newton<P: NewtonProblem>(
    p: &mut P,
    x: &mut DVector<f64>,
    opt: &NewtonOptions,
) -> Result<NewtonReport, SolverError> {
    let n = p.dim();
    let mut r = DVector::zeros(n);
    let mut j = DMatrix::zeros(n, n);
    let mut last = f64::INFINITY;
    for it in 1..=opt.max_iter {
        p.eval(x, &mut r, &mut j);
        if r.iter().any(|v| !v.is_finite()) {
            return Err(SolverError::NonFinite { iteration: it });
        }
        let lu = std::mem::replace(&mut j, DMatrix::zeros(0, 0)).lu();
        let dx = match lu.solve(&r) {
            Some(d) => d,
            None => return Err(SolverError::Singular { iteration: it }),
        };
        j = DMatrix::zeros(n, n);
        let mut worst: f64 = 0.0;
        for i in 0..n {
            worst = worst.max(dx[i].abs() / p.scale(i));
        }
        if !worst.is_finite() {
            return Err(SolverError::NonFinite { iteration: it });
        }
        let damp = if worst > opt.max_step {
            opt.max_step / worst
        } else {
            1.0
        };
        for i in 0..n {
            x[i] -= damp * dx[i];
        }
        last = worst;
        if worst < opt.tol {
            return Ok(NewtonReport {
                termination: Termination::Converged,
                iterations: it,
            });
        }
    }
    Err(SolverError::NoConvergence {
        iterations: opt.max_iter,
        last_correction: last,
    })
}

/// A conservative system d m(x)/dt = f(x) with diagonal storage.
pub trait ConservativeSystem {
    fn dim(&self) -> usize;
    /// Storage m_i(x_i) and dm_i/dx_i of every state.
    fn storage(&self, x: &DVector<f64>, m: &mut DVector<f64>, dm: &mut DVector<f64>);
    /// Net inflow f(x) and its Jacobian.
    fn fluxes(&mut self, x: &DVector<f64>, f: &mut DVector<f64>, jac: &mut DMatrix<f64>);
    fn scale(&self, i: usize) -> f64;
}

/// Backward-Euler step: finds x with (m(x) - m_old)/dt - f(x) = 0.
pub struct ImplicitEuler<'a, S: ConservativeSystem> {
    pub system: &'a mut S,
    pub m_old: &'a DVector<f64>,
    pub dt: f64,
    m: DVector<f64>,
    dm: DVector<f64>,
    f: DVector<f64>,
}

impl<'a, S: ConservativeSystem> ImplicitEuler<'a, S> {
    pub fn new(system: &'a mut S, m_old: &'a DVector<f64>, dt: f64) -> Self {
        let n = system.dim();
        Self {
            system,
            m_old,
            dt,
            m: DVector::zeros(n),
            dm: DVector::zeros(n),
            f: DVector::zeros(n),
        }
    }
}

impl<S: ConservativeSystem> NewtonProblem for ImplicitEuler<'_, S> {
    fn dim(&self) -> usize {
        self.system.dim()
    }
    fn eval(&mut self, x: &DVector<f64>, r: &mut DVector<f64>, j: &mut DMatrix<f64>) {
        self.system.storage(x, &mut self.m, &mut self.dm);
        j.fill(0.0);
        self.system.fluxes(x, &mut self.f, j);
        // r = (m - m_old)/dt - f ; J = diag(dm)/dt - df/dx
        for i in 0..r.len() {
            r[i] = (self.m[i] - self.m_old[i]) / self.dt - self.f[i];
        }
        j.neg_mut();
        for i in 0..r.len() {
            j[(i, i)] += self.dm[i] / self.dt;
        }
    }
    fn scale(&self, i: usize) -> f64 {
        self.system.scale(i)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two tanks joined by a linear conductance, one fed by a constant source:
    /// the summed storage grows exactly by source x dt every step.
    struct Tanks {
        c: [f64; 2],
        g: f64,
        q: f64,
    }
    impl ConservativeSystem for Tanks {
        fn dim(&self) -> usize {
            2
        }
        fn storage(&self, x: &DVector<f64>, m: &mut DVector<f64>, dm: &mut DVector<f64>) {
            for i in 0..2 {
                m[i] = self.c[i] * x[i];
                dm[i] = self.c[i];
            }
        }
        fn fluxes(&mut self, x: &DVector<f64>, f: &mut DVector<f64>, j: &mut DMatrix<f64>) {
            let q = self.g * (x[0] - x[1]);
            f[0] = self.q - q;
            f[1] = q;
            j[(0, 0)] = -self.g;
            j[(0, 1)] = self.g;
            j[(1, 0)] = self.g;
            j[(1, 1)] = -self.g;
        }
        fn scale(&self, _: usize) -> f64 {
            1.0
        }
    }

    #[test]
    fn implicit_euler_conserves_storage_and_matches_the_exact_decay() {
        let mut s = Tanks {
            c: [1.0, 1.0],
            g: 2.0,
            q: 0.0,
        };
        let mut x = DVector::from_vec(vec![1.0, 0.0]);
        let opt = NewtonOptions {
            tol: 1e-13,
            max_iter: 10,
            max_step: 1e9,
        };
        let dt = 1e-3;
        for _ in 0..1000 {
            let m_old = DVector::from_vec(vec![x[0], x[1]]);
            let mut p = ImplicitEuler::new(&mut s, &m_old, dt);
            let rep = newton(&mut p, &mut x, &opt).unwrap();
            assert!(rep.iterations <= 2); // linear problem
        }
        assert!((x[0] + x[1] - 1.0).abs() < 1e-12);
        // difference decays as exp(-2 g t) = exp(-4) at t = 1
        let exact = (-4.0f64).exp();
        assert!(((x[0] - x[1]) - exact).abs() < 2e-3 * exact.max(1.0));
        // with a source the sum grows linearly
        let mut s = Tanks {
            c: [2.0, 0.5],
            g: 1.0,
            q: 3.0,
        };
        let mut x = DVector::from_vec(vec![0.0, 0.0]);
        for _ in 0..100 {
            let m_old = DVector::from_vec(vec![2.0 * x[0], 0.5 * x[1]]);
            let mut p = ImplicitEuler::new(&mut s, &m_old, 0.01);
            newton(&mut p, &mut x, &opt).unwrap();
        }
        assert!((2.0 * x[0] + 0.5 * x[1] - 3.0).abs() < 1e-11);
    }

    #[test]
    fn newton_reports_non_convergence() {
        struct NoRoot;
        impl NewtonProblem for NoRoot {
            fn dim(&self) -> usize {
                1
            }
            fn eval(&mut self, x: &DVector<f64>, r: &mut DVector<f64>, j: &mut DMatrix<f64>) {
                r[0] = x[0] * x[0] + 1.0;
                j[(0, 0)] = 2.0 * x[0] + 1e-3;
            }
            fn scale(&self, _: usize) -> f64 {
                1.0
            }
        }
        let mut x = DVector::from_vec(vec![0.5]);
        let e = newton(
            &mut NoRoot,
            &mut x,
            &NewtonOptions {
                tol: 1e-12,
                max_iter: 20,
                max_step: 10.0,
            },
        );
        assert!(matches!(
            e,
            Err(SolverError::NoConvergence { .. }) | Err(SolverError::NonFinite { .. })
        ));
    }
}
