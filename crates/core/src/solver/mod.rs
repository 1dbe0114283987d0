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
use std::sync::Arc;
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
    /// LU factorisations of the Jacobian.
    pub factorisations: usize,
    /// The last scaled correction, max_i |dx_i| / scale_i.
    pub last_correction: f64,
    /// The bound on the scaled error left after it (below the tolerance):
    /// `c / (1 - c)` times the correction for a contraction `c`, the
    /// correction itself while `c` is unknown (see [`JacobianUpdate::Chord`]).
    pub error_bound: f64,
    /// Whether the last residual was evaluated at the solution returned
    /// (a verified correction of kept factors, see
    /// [`NewtonWorkspace::load_factors`]): the problem's buffers then hold
    /// its storage and fluxes there.
    pub residual_at_solution: bool,
    /// Whether the solution returned is the starting point itself: the
    /// first correction of kept factors was round-off
    /// ([`ROUND_OFF_FLOOR`]) and was not applied.
    pub at_start: bool,
}

/// When the Newton iteration refreshes the Jacobian.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum JacobianUpdate {
    /// A fresh Jacobian and LU factorisation at every iteration (plain Newton).
    Every,
    /// Modified (chord) Newton: keep the factorisation of the workspace, from
    /// an earlier iteration or an earlier solve of a nearby problem, while
    /// each correction is at most `max_contraction` times the previous one.
    /// A slower contraction takes the correction (without the convergence
    /// test) and refreshes the Jacobian for the next iteration; a correction
    /// that does not shrink (or is not finite) is discarded and the Jacobian
    /// refreshed at the current iterate. With a contraction `c` the error
    /// left after the last correction is at most `c / (1 - c)` times that
    /// correction: the convergence test takes the correction itself as the
    /// bound (`c = 0.5`, the most `max_contraction` may be) until the kept
    /// factorisation has shown its contraction, then the largest ratio of
    /// successive corrections seen with it (at least
    /// [`MIN_CONTRACTION_ESTIMATE`]), also in later solves that reuse it.
    Chord { max_contraction: f64 },
}

/// The smallest contraction the convergence test of a chord iteration
/// assumes, however fast the corrections have shrunk: the ratio of two
/// successive corrections is one sample, and where the residual bends
/// sharply (orifices near their regularisation, an upwind switch) the next
/// ones shrink more slowly. In the pump's first step after a 1000 Pa jump of
/// the delivery pressure two corrections shrank 30-fold while the error
/// left was 5x the tolerance (the outlet chamber 17 Pa off at a 3 Pa
/// tolerance): 0.02 accepted it, 0.1 still left 4.5 Pa, 0.2 meets the
/// tolerance. It costs nothing where the first, fresh correction already
/// meets the tolerance (every step at the periodic state).
pub const MIN_CONTRACTION_ESTIMATE: f64 = 0.2;

/// Below this fraction of the tolerance a correction of foreign factors
/// ([`NewtonWorkspace::load_factors`]) is taken as round-off: the iterate
/// it was computed at is accepted as it is (the first iterate, where the
/// prediction already is the solution), or, for the verifying correction,
/// whatever the ratio of the two corrections (at the pump's periodic state
/// the periodic prediction's first correction is 1e-13 to 1e-8 of the
/// delivery pressure, and the ratio of two round-off corrections is noise,
/// 0.2-1.2). The error left is the correction times the inverse of
/// `J_kept^-1 J`, which stays below the tolerance unless the kept factors
/// are off by more than a factor 1000 (the pump's are dropped when the
/// speed, which sets the storage term, changes by more than a factor 2).
/// 1e-2 saved 2 % of the pump's instructions, but left the instantaneous
/// flows 1e-5 apart between runs of different histories (the flow ripple
/// of periodic runs marched to different lengths: test
/// `model::tests::the_relaxed_start_reaches_the_same_periodic_state_for_less_work`).
pub const ROUND_OFF_FLOOR: f64 = 1e-3;

/// Settings of the Newton iteration.
#[derive(Debug, Clone, Copy)]
pub struct NewtonOptions {
    /// Converged when max_i |dx_i| / scale_i < tol.
    pub tol: f64,
    pub max_iter: usize,
    /// Largest allowed |dx_i| / scale_i in one iteration (damping).
    pub max_step: f64,
    /// Damp each correction further until the natural monotonicity test
    /// holds (see [`newton_with`]); for the hard steps a plain Newton
    /// iteration cycles on (a pocket whose pressure falls into the gas
    /// release band, where the storage curve flattens).
    pub monotone: bool,
}

impl NewtonOptions {
    /// The options of a hard step's retry: the natural monotonicity test,
    /// corrections limited to `max_step`, `times` the iterations.
    pub fn careful(self, max_step: f64, times: usize) -> NewtonOptions {
        NewtonOptions {
            max_step,
            monotone: true,
            max_iter: times * self.max_iter,
            ..self
        }
    }
}

/// The strong damping of a hard step's last retries (largest correction
/// and iteration factor for [`NewtonOptions::careful`]).
pub const STRONG_DAMPING: (f64, usize) = (0.05, 20);

/// Halvings of the damping factor the monotonicity test may ask for in one
/// iteration (down to 2^-12 of the correction).
const MAX_HALVINGS: usize = 12;

/// A nonlinear system: residual and Jacobian at x.
pub trait NewtonProblem {
    fn dim(&self) -> usize;
    /// Fills `r = F(x)` and `j = dF/dx`.
    fn eval(&mut self, x: &DVector<f64>, r: &mut DVector<f64>, j: &mut DMatrix<f64>);
    /// As [`eval`](NewtonProblem::eval) into the workspace's Jacobian, which
    /// `known` describes (what its previous evaluation left outside its
    /// sparsity pattern, see [`JacobianZeros`]): a problem may then skip
    /// clearing the whole matrix. It must leave `known` true to what `j`
    /// holds. The default forgets it and calls `eval`.
    fn eval_reusing(
        &mut self,
        x: &DVector<f64>,
        r: &mut DVector<f64>,
        j: &mut DMatrix<f64>,
        known: &mut JacobianZeros,
    ) {
        known.forget();
        self.eval(x, r, j);
    }
    /// Fills `r = F(x)` only (chord iterations). The default evaluates the
    /// Jacobian too, into a scratch matrix.
    fn residual(&mut self, x: &DVector<f64>, r: &mut DVector<f64>) {
        let n = self.dim();
        let mut j = DMatrix::zeros(n, n);
        self.eval(x, r, &mut j);
    }
    /// Scale of each unknown for the convergence test.
    fn scale(&self, i: usize) -> f64;
    /// The scale of every unknown, when it is one positive number: the
    /// convergence test then divides the largest correction by it once
    /// (the same value as the largest quotient: division by a positive
    /// number is monotone, to the bit) instead of every correction.
    fn uniform_scale(&self) -> Option<f64> {
        None
    }
    /// An elimination order for the LU factorisation (a permutation of the
    /// unknowns, sparse ones first), when the problem knows one; otherwise
    /// [`Lu`] orders by the Jacobian's nonzeros at each factorisation.
    fn ordering(&self) -> Option<&[usize]> {
        None
    }
    /// The Jacobian's sparsity, when the problem knows it (at most 64
    /// unknowns): for each unknown i, the bit set of the unknowns j whose
    /// entry (i, j) may be nonzero, the diagonal included. Every entry off
    /// it must be zero; [`Lu`] then reads only the entries in it.
    fn pattern(&self) -> Option<&[u64]> {
        None
    }
}

/// LU factorisation `P (Q A Q^T) = L U` for small, sparse, nearly
/// diagonally dominant matrices held dense: a symmetric ordering `Q` given by
/// the problem ([`NewtonProblem::ordering`]) or else by ascending number of
/// off-diagonal nonzeros (nodes coupled to everything last), threshold
/// partial pivoting (the diagonal is kept while it is at least a tenth of the
/// largest candidate), elimination that skips structural zeros, and the
/// factors kept as sparse lists for the substitutions (120-160 nonzeros
/// each in L and U for the pump's 27 nodes with one axial zone, against 729
/// dense entries).
/// Multipliers are formed with the reciprocal of the pivot. Storage is
/// reused between factorisations (no allocation once sized).
///
/// Up to 64 unknowns the factorisation first runs row by row without
/// interchanges (the earlier rows of U subtracted from each row of the
/// reordered matrix with a nonzero multiplier, in ascending order): every
/// entry sees the same operations in the same order as in the elimination
/// above, so the factors are the same to the bit, at a fraction of the
/// cost, as long as no
/// interchange is due (every multiplier within 1/threshold). When one is
/// due it stops and the elimination with interchanges runs instead. Each
/// row's possible nonzeros are a bit set (its own, then those of the rows of
/// U it receives), so the elimination visits them without scanning the
/// zeros; each finished row goes into compact row lists (L, U, diagonal)
/// that the later rows' eliminations and the substitutions follow. With
/// the problem's sparsity pattern ([`NewtonProblem::pattern`]) only the
/// entries in it are read from the dense matrix.
#[derive(Debug, Clone, Default)]
pub struct Lu {
    n: usize,
    /// Factors of the reordered matrix, row-major: unit L below the diagonal, U on and above.
    a: Vec<f64>,
    /// `order[i]`: original index of reordered unknown i.
    order: Vec<usize>,
    /// Row interchanges: at elimination step k, row k was swapped with `piv[k]`.
    piv: Vec<usize>,
    cols: Vec<usize>,
    deg: Vec<usize>,
    y: Vec<f64>,
    /// The nonzeros of L (below the diagonal; by column, or by row when
    /// `l_by_rows`) and U (above it, by row), for the substitutions: line
    /// i's entries are `[ptr[i], ptr[i + 1])`.
    l_by_rows: bool,
    rows: Vec<usize>,
    l_ptr: Vec<usize>,
    l: Vec<(usize, f64)>,
    u_ptr: Vec<usize>,
    u: Vec<(usize, f64)>,
    diag: Vec<f64>,
    /// Whether the last factorisation is the one without interchanges: its
    /// factors are in `by_rows`.
    in_place: bool,
    by_rows: RowFactors,
    /// `pos[i]`: position of original unknown i in the order.
    pos: Vec<usize>,
    /// The nonzero columns of each reordered row as a bit set (n <= 64).
    row_mask: Vec<u64>,
    /// The elimination structures of the sparsity patterns met so far
    /// (see [`Symbolic`]), and which one the last factorisation used
    /// (`Some` when its factors are in `by_rows` on that structure).
    symbolic: Vec<Symbolic>,
    structured: Option<usize>,
    last_symbolic: Option<usize>,
    /// Which structure is replaced next when the cache is full.
    symbolic_next: usize,
    /// One eliminated row, dense (the structured factorisation's scratch).
    w: Vec<f64>,
    /// Factors taken back by [`load_structured`](Self::load_structured):
    /// their values of L and U are read where they are (shared, not
    /// copied) until the next factorisation.
    kept: Option<Arc<SavedFactors>>,
}

/// The numeric factors of one structured factorisation, kept apart from
/// the [`Lu`] that made them ([`Lu::save_structured`]) to be taken back
/// later ([`Lu::load_structured`]): the sparsity pattern and elimination
/// order that define their structure, and the values of L, U and U's
/// reciprocal diagonal on it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SavedFactors {
    pattern: Vec<u64>,
    order: Vec<usize>,
    l_val: Vec<f64>,
    u_val: Vec<f64>,
    inv_diag: Vec<f64>,
}

impl SavedFactors {
    /// The pattern, the order and the values of L, U and 1 / diag(U).
    #[allow(clippy::type_complexity)]
    pub fn parts(&self) -> (&[u64], &[usize], &[f64], &[f64], &[f64]) {
        (
            &self.pattern,
            &self.order,
            &self.l_val,
            &self.u_val,
            &self.inv_diag,
        )
    }

    /// Factors from their [`parts`](Self::parts) (e.g. read back from a
    /// saved state), checked as far as they can be without the structure:
    /// the order a permutation of the `n <= 64` unknowns, the pattern one
    /// row per unknown with its diagonal, every value finite, U's
    /// reciprocal diagonal nonzero. Whether L and U fit the structure is
    /// checked when they are loaded.
    pub fn from_parts(
        pattern: Vec<u64>,
        order: Vec<usize>,
        l_val: Vec<f64>,
        u_val: Vec<f64>,
        inv_diag: Vec<f64>,
    ) -> Result<SavedFactors, String> {
        let n = order.len();
        if n == 0 || n > 64 {
            return Err(format!("{n} unknowns (1 to 64)"));
        }
        if pattern.len() != n || inv_diag.len() != n {
            return Err(format!(
                "{} pattern rows and {} diagonal values for {n} unknowns",
                pattern.len(),
                inv_diag.len()
            ));
        }
        let mut seen = 0u64;
        for &o in &order {
            if o >= n || seen >> o & 1 == 1 {
                return Err("the elimination order is not a permutation".into());
            }
            seen |= 1 << o;
        }
        if pattern
            .iter()
            .enumerate()
            .any(|(i, &row)| row >> i & 1 == 0)
        {
            return Err("a pattern row without its diagonal".into());
        }
        if !l_val
            .iter()
            .chain(&u_val)
            .chain(&inv_diag)
            .all(|v| v.is_finite())
            || inv_diag.contains(&0.0)
        {
            return Err("a non-finite factor or a zero pivot".into());
        }
        Ok(SavedFactors {
            pattern,
            order,
            l_val,
            u_val,
            inv_diag,
        })
    }
}

/// Structures kept by [`Lu`] (a pump's mesh period has 13 distinct
/// patterns at the bundled design).
const SYMBOLIC_CACHE: usize = 32;

/// The elimination structure of one sparsity pattern and elimination order
/// (the symbolic factorisation): for each reordered row, the entries read
/// from the column-major matrix, and the columns of L and of U that the
/// elimination without interchanges may fill (the pattern's own and the
/// fill-in, ascending). The factorisation without interchanges visits the
/// same columns in the same order whatever the values, so a pattern met
/// again needs only the arithmetic: the structures are cached by pattern
/// (the pump's network meets the same few patterns every mesh period).
#[derive(Debug, Clone, Default)]
struct Symbolic {
    /// The key: the pattern (original indices), the order, and their hash.
    pattern: Vec<u64>,
    order: Vec<usize>,
    hash: u64,
    /// Row i reads `a_col[t]` (reordered column) from `s[a_src[t]]` for t
    /// in `[a_ptr[i], a_ptr[i + 1])`.
    a_ptr: Vec<u32>,
    a_col: Vec<u32>,
    a_src: Vec<u32>,
    /// L and U by rows, as in [`RowFactors`].
    l_ptr: Vec<u32>,
    l_idx: Vec<u32>,
    u_ptr: Vec<u32>,
    u_idx: Vec<u32>,
}

/// FNV-1a of a pattern and an order (the cache's look-up key).
fn pattern_hash(pattern: &[u64], order: &[usize]) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for v in pattern
        .iter()
        .copied()
        .chain(order.iter().map(|&o| o as u64))
    {
        h = (h ^ v).wrapping_mul(0x0100_0000_01b3);
    }
    h
}

impl Symbolic {
    /// The structure of `pattern` (one bit set per original row, the
    /// diagonal included; bits beyond `n` ignored) under `order`.
    fn new(pattern: &[u64], order: &[usize], hash: u64) -> Symbolic {
        let n = order.len();
        let full = if n == 64 { u64::MAX } else { (1u64 << n) - 1 };
        let mut pos = vec![0usize; n];
        for (p, &o) in order.iter().enumerate() {
            pos[o] = p;
        }
        let mut sym = Symbolic {
            pattern: pattern.to_vec(),
            order: order.to_vec(),
            hash,
            ..Symbolic::default()
        };
        sym.a_ptr.push(0);
        sym.l_ptr.push(0);
        sym.u_ptr.push(0);
        let mut u_masks: Vec<u64> = Vec::with_capacity(n);
        for (i, &oi) in order.iter().enumerate() {
            let mut row = 0u64;
            let start = sym.a_col.len();
            for oj in Bits(pattern[oi] & full) {
                let c = pos[oj];
                row |= 1 << c;
                sym.a_col.push(c as u32);
                sym.a_src.push((oj * n + oi) as u32);
            }
            // ascending columns, as the elimination reads them
            let mut entries: Vec<(u32, u32)> = sym.a_col[start..]
                .iter()
                .copied()
                .zip(sym.a_src[start..].iter().copied())
                .collect();
            entries.sort_unstable();
            for (t, (c, src)) in entries.into_iter().enumerate() {
                sym.a_col[start + t] = c;
                sym.a_src[start + t] = src;
            }
            sym.a_ptr.push(sym.a_col.len() as u32);
            let below = (1u64 << i) - 1;
            let diag = 1u64 << i;
            let (mut lower, mut upper) = (row & below, row & !below & !diag);
            let mut todo = lower;
            while todo != 0 {
                let k = todo.trailing_zeros() as usize;
                todo &= todo - 1;
                let fill = u_masks[k];
                todo |= fill & below;
                lower |= fill & below;
                upper |= fill & !below & !diag;
            }
            sym.l_idx.extend(Bits(lower).map(|j| j as u32));
            sym.u_idx.extend(Bits(upper).map(|j| j as u32));
            sym.l_ptr.push(sym.l_idx.len() as u32);
            sym.u_ptr.push(sym.u_idx.len() as u32);
            u_masks.push(upper);
        }
        sym
    }
}

/// The factors of the factorisation without interchanges by rows: the
/// nonzeros of each row of L (left of the diagonal) and of U (right of it),
/// and the reciprocals of U's diagonal; row i's entries are
/// `[ptr[i], ptr[i + 1])`, in ascending columns.
#[derive(Debug, Clone, Default)]
struct RowFactors {
    l_ptr: Vec<u32>,
    l_idx: Vec<u32>,
    l_val: Vec<f64>,
    u_ptr: Vec<u32>,
    u_idx: Vec<u32>,
    u_val: Vec<f64>,
    /// 1 / U's diagonal: the multipliers and the back substitution multiply
    /// by it (a division's latency on every step of their dependency
    /// chains).
    inv_diag: Vec<f64>,
    /// The columns of row i's U nonzeros as a bit set (n <= 64).
    u_mask: Vec<u64>,
}

impl RowFactors {
    /// Empties the factors of an `n x n` matrix (storage kept).
    fn clear(&mut self, n: usize) {
        for v in [&mut self.l_ptr, &mut self.u_ptr] {
            v.clear();
            v.push(0);
        }
        for v in [&mut self.l_idx, &mut self.u_idx] {
            v.resize(n * n, 0);
        }
        for v in [&mut self.l_val, &mut self.u_val] {
            v.resize(n * n, 0.0);
        }
        self.inv_diag.clear();
        self.u_mask.clear();
    }

    /// Appends row i of the factors from the eliminated dense row `w`,
    /// whose entries off the bit sets `lower` (columns below i) and `upper`
    /// (above i) are zero.
    fn push_row(&mut self, i: usize, w: &[f64], lower: u64, upper: u64) {
        let at = *self.l_ptr.last().unwrap_or(&0) as usize;
        let (nl, _) = append_nonzeros(w, lower, &mut self.l_idx, &mut self.l_val, at);
        self.inv_diag.push(1.0 / w[i]);
        let at = *self.u_ptr.last().unwrap_or(&0) as usize;
        let (nu, mask) = append_nonzeros(w, upper, &mut self.u_idx, &mut self.u_val, at);
        self.l_ptr.push(nl as u32);
        self.u_ptr.push(nu as u32);
        self.u_mask.push(mask);
    }
}

/// Writes the nonzeros of `w` at the columns in the bit set `cols`
/// (ascending) to `idx` and `val` from position `at`; the position after
/// them and their columns as a bit set.
fn append_nonzeros(
    w: &[f64],
    cols: u64,
    idx: &mut [u32],
    val: &mut [f64],
    mut at: usize,
) -> (usize, u64) {
    let mut mask = 0;
    for j in Bits(cols) {
        let v = w[j];
        if v != 0.0 {
            idx[at] = j as u32;
            val[at] = v;
            at += 1;
            mask |= 1 << j;
        }
    }
    (at, mask)
}

/// The members of a bit set, ascending.
struct Bits(u64);

impl Iterator for Bits {
    type Item = usize;
    #[inline]
    fn next(&mut self) -> Option<usize> {
        if self.0 == 0 {
            return None;
        }
        let k = self.0.trailing_zeros() as usize;
        self.0 &= self.0 - 1;
        Some(k)
    }
}

/// Threshold of the partial pivoting (see [`Lu`]).
const PIVOT_THRESHOLD: f64 = 0.1;

impl Lu {
    /// Factorises the square matrix `m`; false when it is singular (a zero
    /// pivot column) or not finite.
    pub fn factor(&mut self, m: &DMatrix<f64>) -> bool {
        self.factor_ordered(m, None)
    }

    /// [`factor`](Self::factor) with a given elimination order (a
    /// permutation of `0..n`; ignored when it is not one of the right length).
    pub fn factor_ordered(&mut self, m: &DMatrix<f64>, order: Option<&[usize]>) -> bool {
        self.factor_structured(m, order, None)
    }

    /// [`factor_ordered`](Self::factor_ordered) of a matrix whose entries
    /// off `pattern` are zero (see [`NewtonProblem::pattern`]; ignored
    /// unless it has one bit set per row): only the entries in it are read.
    pub fn factor_structured(
        &mut self,
        m: &DMatrix<f64>,
        order: Option<&[usize]>,
        pattern: Option<&[u64]>,
    ) -> bool {
        let n = m.nrows();
        self.n = n;
        self.a.resize(n * n, 0.0);
        self.piv.resize(n, 0);
        self.y.resize(n, 0.0);
        // column-major storage: m[(i, j)] = s[j * n + i]
        let s = m.as_slice();
        match order.filter(|o| o.len() == n) {
            Some(o) => {
                self.order.clear();
                self.order.extend_from_slice(o);
            }
            None => {
                self.deg.clear();
                self.deg.resize(n, 0);
                for (j, col) in s.chunks_exact(n).enumerate() {
                    for (i, &v) in col.iter().enumerate() {
                        if v != 0.0 && i != j {
                            self.deg[i] += 1;
                            self.deg[j] += 1;
                        }
                    }
                }
                self.order.clear();
                self.order.extend(0..n);
                let deg = &self.deg;
                self.order.sort_unstable_by_key(|&i| (deg[i], i));
            }
        }
        self.structured = None;
        self.kept = None;
        if n <= 64 {
            let done = match pattern.filter(|p| p.len() == n) {
                Some(p) => self.factor_symbolic(s, p),
                None => self.factor_without_interchanges(s, None),
            };
            if done {
                return true;
            }
        }
        self.structured = None;
        self.factor_with_interchanges(s)
    }

    /// The elimination with threshold partial pivoting of the reordered
    /// column-major matrix `s` (`self.n`, `self.order` set).
    fn factor_with_interchanges(&mut self, s: &[f64]) -> bool {
        let n = self.n;
        self.in_place = false;
        for (row, &oi) in self.a.chunks_exact_mut(n).zip(&self.order) {
            for (v, &oj) in row.iter_mut().zip(&self.order) {
                *v = s[oj * n + oi];
            }
        }
        let a = &mut self.a;
        let (lp, l) = (&mut self.l_ptr, &mut self.l);
        let (up, u) = (&mut self.u_ptr, &mut self.u);
        lp.clear();
        l.clear();
        up.clear();
        u.clear();
        self.diag.clear();
        let mut swapped = false;
        for k in 0..n {
            // the rows below k with an entry in column k, and the largest
            self.rows.clear();
            let mut amax = a[k * n + k].abs();
            let mut imax = k;
            for i in k + 1..n {
                let v = a[i * n + k];
                if v != 0.0 {
                    self.rows.push(i);
                    if v.abs() > amax {
                        imax = i;
                        amax = v.abs();
                    }
                }
            }
            if !(amax > 0.0 && amax.is_finite()) {
                return false;
            }
            let p = if a[k * n + k].abs() >= PIVOT_THRESHOLD * amax {
                k
            } else {
                imax
            };
            self.piv[k] = p;
            if p != k {
                swapped = true;
                for j in 0..n {
                    a.swap(k * n + j, p * n + j);
                }
                self.rows.clear();
                self.rows
                    .extend((k + 1..n).filter(|&i| a[i * n + k] != 0.0));
            }
            let (top, bottom) = a.split_at_mut((k + 1) * n);
            let row_k = &top[k * n..];
            let d = row_k[k];
            self.diag.push(d);
            // the multipliers by the reciprocal pivot, as in
            // `factor_without_interchanges` (the same bits)
            let inv = 1.0 / d;
            // row k of U is final
            up.push(u.len());
            self.cols.clear();
            for (j, &v) in row_k.iter().enumerate().skip(k + 1) {
                if v != 0.0 {
                    self.cols.push(j);
                    u.push((j, v));
                }
            }
            // column k of L
            lp.push(l.len());
            for &i in &self.rows {
                let row_i = &mut bottom[(i - k - 1) * n..(i - k) * n];
                let m = row_i[k] * inv;
                row_i[k] = m;
                l.push((i, m));
                for &j in &self.cols {
                    row_i[j] -= m * row_k[j];
                }
            }
        }
        lp.push(l.len());
        up.push(u.len());
        self.l_by_rows = swapped;
        if swapped {
            // the interchanges moved multipliers between rows: L by rows
            // from the factors
            lp.clear();
            l.clear();
            for (i, row) in a.chunks_exact(n).enumerate() {
                lp.push(l.len());
                l.extend(
                    row[..i]
                        .iter()
                        .enumerate()
                        .filter(|(_, v)| **v != 0.0)
                        .map(|(j, v)| (j, *v)),
                );
            }
            lp.push(l.len());
        }
        true
    }

    /// The row-by-row factorisation without interchanges of the reordered
    /// column-major matrix `s` (`n = self.n <= 64`, `self.order` set); false
    /// (factors undefined) when an interchange is due or a pivot is zero or
    /// not finite.
    fn factor_without_interchanges(&mut self, s: &[f64], pattern: Option<&[u64]>) -> bool {
        let n = self.n;
        let limit = 1.0 / PIVOT_THRESHOLD;
        self.pos.resize(n, 0);
        for (p, &o) in self.order.iter().enumerate() {
            self.pos[o] = p;
        }
        // the reordered matrix, row-major, and the nonzero columns of each
        // row as a bit set: from the entries in the pattern when there is
        // one, else from every entry (all written: no branch on the zeros)
        let (a, order, pos) = (&mut self.a[..n * n], &self.order[..n], &self.pos[..n]);
        // the unknowns' bits (a pattern's bits beyond them are ignored)
        let full = if n == 64 { u64::MAX } else { (1u64 << n) - 1 };
        let rows = &mut self.row_mask;
        rows.clear();
        for (row, &oi) in a.chunks_exact_mut(n).zip(order) {
            let mut mask = 0u64;
            match pattern {
                Some(p) => {
                    row.fill(0.0);
                    for oj in Bits(p[oi] & full) {
                        let (c, v) = (pos[oj], s[oj * n + oi]);
                        row[c] = v;
                        mask |= u64::from(v != 0.0) << c;
                    }
                }
                None => {
                    for (c, (v, &oj)) in row.iter_mut().zip(order).enumerate() {
                        *v = s[oj * n + oi];
                        mask |= u64::from(*v != 0.0) << c;
                    }
                }
            }
            rows.push(mask);
        }
        let f = &mut self.by_rows;
        f.clear(n);
        for (i, &row) in rows.iter().enumerate() {
            let w = &mut a[i * n..(i + 1) * n];
            let below = (1u64 << i) - 1;
            // the columns left of the diagonal that may be nonzero, visited
            // in ascending order as the dense loop over k < i would (the
            // entries off the set are zero and would be skipped); each
            // elimination adds the columns of row k of U
            let (mut lower, mut upper) = (row & below, row & !below & !(1u64 << i));
            let mut todo = lower;
            while todo != 0 {
                let k = todo.trailing_zeros() as usize;
                todo &= todo - 1;
                let wk = w[k];
                if wk == 0.0 {
                    continue;
                }
                let m = wk * f.inv_diag[k];
                w[k] = m;
                if m == 0.0 {
                    continue;
                }
                if m.is_nan() || m.abs() > limit {
                    return false;
                }
                // the nonzeros of row k of U
                let (lo, hi) = (f.u_ptr[k] as usize, f.u_ptr[k + 1] as usize);
                for (&j, &u) in f.u_idx[lo..hi].iter().zip(&f.u_val[lo..hi]) {
                    w[j as usize] -= m * u;
                }
                let fill = f.u_mask[k];
                todo |= fill & below;
                lower |= fill & below;
                upper |= fill & !below & !(1u64 << i);
            }
            let d = w[i];
            if d == 0.0 || !d.is_finite() {
                return false;
            }
            f.push_row(i, w, lower, upper);
        }
        self.in_place = true;
        true
    }

    /// The structure of `pattern` under the current order, from the cache
    /// or made now; its index in `self.symbolic`.
    fn symbolic_for(&mut self, pattern: &[u64]) -> usize {
        // the last one first (consecutive steps mostly share their pattern)
        if let Some(k) = self.last_symbolic {
            let sym = &self.symbolic[k];
            if sym.pattern == pattern && sym.order == self.order {
                return k;
            }
        }
        let hash = pattern_hash(pattern, &self.order);
        let same =
            |sym: &Symbolic| sym.hash == hash && sym.pattern == pattern && sym.order == self.order;
        if let Some(k) = self.symbolic.iter().position(same) {
            return k;
        }
        let sym = Symbolic::new(pattern, &self.order, hash);
        if self.symbolic.len() < SYMBOLIC_CACHE {
            self.symbolic.push(sym);
            self.symbolic.len() - 1
        } else {
            let k = self.symbolic_next;
            self.symbolic_next = (k + 1) % SYMBOLIC_CACHE;
            self.symbolic[k] = sym;
            k
        }
    }

    /// The values of the last structured factorisation into `into` (see
    /// [`SavedFactors`]); false (and `into` unchanged) when the last one
    /// was not structured.
    pub fn save_structured(&self, into: &mut SavedFactors) -> bool {
        let Some(k) = self.structured else {
            return false;
        };
        let sym = &self.symbolic[k];
        let (l_val, u_val) = self.structured_values();
        into.pattern.clone_from(&sym.pattern);
        into.order.clone_from(&sym.order);
        into.l_val.clear();
        into.l_val.extend_from_slice(l_val);
        into.u_val.clear();
        into.u_val.extend_from_slice(u_val);
        into.inv_diag.clear();
        into.inv_diag
            .extend_from_slice(&self.by_rows.inv_diag[..self.n]);
        true
    }

    /// The values of L and U of the structured factorisation: those taken
    /// back by [`load_structured`](Self::load_structured), or the last
    /// factorisation's.
    fn structured_values(&self) -> (&[f64], &[f64]) {
        match &self.kept {
            Some(saved) => (&saved.l_val, &saved.u_val),
            None => (&self.by_rows.l_val, &self.by_rows.u_val),
        }
    }

    /// Takes saved factors back as the current factorisation (their
    /// structure rebuilt from their pattern and order when it is not
    /// cached); false, and no factorisation kept, when they do not fit
    /// that structure.
    pub fn load_structured(&mut self, saved: &Arc<SavedFactors>) -> bool {
        let n = saved.order.len();
        self.structured = None;
        self.kept = None;
        self.in_place = false;
        if n == 0 || n > 64 || saved.pattern.len() != n || saved.inv_diag.len() != n {
            return false;
        }
        self.n = n;
        self.order.clone_from(&saved.order);
        let k = self.symbolic_for(&saved.pattern);
        let sym = &self.symbolic[k];
        if sym.l_idx.len() != saved.l_val.len() || sym.u_idx.len() != saved.u_val.len() {
            return false;
        }
        self.y.resize(n, 0.0);
        let f = &mut self.by_rows;
        f.inv_diag.resize(64, 0.0);
        f.inv_diag[..n].copy_from_slice(&saved.inv_diag);
        self.kept = Some(Arc::clone(saved));
        self.structured = Some(k);
        self.last_symbolic = Some(k);
        true
    }

    /// The factorisation without interchanges of the column-major matrix
    /// `s` on the cached structure of `pattern` (`n = self.n <= 64`,
    /// `self.order` set): the same arithmetic in the same order as
    /// [`factor_without_interchanges`](Self::factor_without_interchanges)
    /// (the same factors, to the bit), the bit sets, the tests of the
    /// zeros and the lists' assembly done once per pattern. The factors
    /// keep the structure's entries that happen to be zero. False when an
    /// interchange is due or a pivot is zero or not finite.
    fn factor_symbolic(&mut self, s: &[f64], pattern: &[u64]) -> bool {
        let n = self.n;
        let limit = 1.0 / PIVOT_THRESHOLD;
        let k_sym = self.symbolic_for(pattern);
        self.last_symbolic = Some(k_sym);
        let sym = &self.symbolic[k_sym];
        let f = &mut self.by_rows;
        f.l_val.resize(sym.l_idx.len(), 0.0);
        f.u_val.resize(sym.u_idx.len(), 0.0);
        f.inv_diag.resize(64, 0.0);
        self.w.resize(64, 0.0);
        // the columns are below 64: indexing the 64-entry arrays with
        // `j & 63` needs no bounds test in the inner loops
        let w: &mut [f64; 64] = (&mut self.w[..64]).try_into().expect("64 entries");
        let inv_diag: &mut [f64; 64] = (&mut f.inv_diag[..64]).try_into().expect("64 entries");
        let (l_val, u_val) = (&mut f.l_val[..], &mut f.u_val[..]);
        let (l_ptr, l_idx) = (&sym.l_ptr[..], &sym.l_idx[..]);
        let (u_ptr, u_idx) = (&sym.u_ptr[..], &sym.u_idx[..]);
        let (a_ptr, a_col, a_src) = (&sym.a_ptr[..], &sym.a_col[..], &sym.a_src[..]);
        for i in 0..n {
            let (l_lo, l_hi) = (l_ptr[i] as usize, l_ptr[i + 1] as usize);
            let (u_lo, u_hi) = (u_ptr[i] as usize, u_ptr[i + 1] as usize);
            let (a_lo, a_hi) = (a_ptr[i] as usize, a_ptr[i + 1] as usize);
            let (row_l, row_u) = (&l_idx[l_lo..l_hi], &u_idx[u_lo..u_hi]);
            // the row's structure cleared, then the matrix's entries
            for &j in row_l.iter().chain(row_u) {
                w[(j & 63) as usize] = 0.0;
            }
            w[i & 63] = 0.0;
            for (&c, &src) in a_col[a_lo..a_hi].iter().zip(&a_src[a_lo..a_hi]) {
                w[(c & 63) as usize] = s[src as usize];
            }
            for &k in row_l {
                let k = (k & 63) as usize;
                let wk = w[k];
                if wk == 0.0 {
                    continue;
                }
                let m = wk * inv_diag[k];
                w[k] = m;
                if m == 0.0 {
                    continue;
                }
                if m.is_nan() || m.abs() > limit {
                    return false;
                }
                let (lo, hi) = (u_ptr[k] as usize, u_ptr[k + 1] as usize);
                for (&j, &u) in u_idx[lo..hi].iter().zip(&u_val[lo..hi]) {
                    w[(j & 63) as usize] -= m * u;
                }
            }
            let d = w[i & 63];
            if d == 0.0 || !d.is_finite() {
                return false;
            }
            inv_diag[i & 63] = 1.0 / d;
            for (v, &j) in l_val[l_lo..l_hi].iter_mut().zip(row_l) {
                *v = w[(j & 63) as usize];
            }
            for (v, &j) in u_val[u_lo..u_hi].iter_mut().zip(row_u) {
                *v = w[(j & 63) as usize];
            }
        }
        self.in_place = false;
        self.kept = None;
        self.structured = Some(k_sym);
        true
    }

    /// The factors of the last factorisation without interchanges as one
    /// dense row-major matrix (unit L below the diagonal, U above it, and
    /// the reciprocals of U's diagonal on it), for the tests.
    #[cfg(test)]
    fn dense_factors(&self) -> Vec<f64> {
        let Some(k) = self.structured else {
            let mut a = self.a.clone();
            for i in 0..self.n {
                a[i * self.n + i] = 1.0 / a[i * self.n + i];
            }
            return a;
        };
        let (n, f, sym) = (self.n, &self.by_rows, &self.symbolic[k]);
        let (l_val, u_val) = self.structured_values();
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            let (lo, hi) = (sym.l_ptr[i] as usize, sym.l_ptr[i + 1] as usize);
            for (&j, &v) in sym.l_idx[lo..hi].iter().zip(&l_val[lo..hi]) {
                a[i * n + j as usize] = v;
            }
            a[i * n + i] = f.inv_diag[i];
            let (lo, hi) = (sym.u_ptr[i] as usize, sym.u_ptr[i + 1] as usize);
            for (&j, &v) in sym.u_idx[lo..hi].iter().zip(&u_val[lo..hi]) {
                a[i * n + j as usize] = v;
            }
        }
        a
    }

    /// Solves `A dx = r` with the last factorisation.
    pub fn solve(&mut self, r: &DVector<f64>, dx: &mut DVector<f64>) {
        let n = self.n;
        let r = r.as_slice();
        if let Some(k) = self.structured {
            // n <= 64: the substitutions index a 64-entry array with `j &
            // 63`, which needs no bounds test in the inner loops (the same
            // arithmetic in the same order)
            let (f, sym) = (&self.by_rows, &self.symbolic[k]);
            let (l_vals, u_vals) = self.structured_values();
            let mut w = [0.0f64; 64];
            for (wi, &oi) in w[..n].iter_mut().zip(&self.order) {
                *wi = r[oi];
            }
            let inv_diag: &[f64; 64] = f.inv_diag[..64].try_into().expect("64 entries");
            let (l_ptr, l_idx, l_val) = (&sym.l_ptr[..=n], &sym.l_idx[..], l_vals);
            let (u_ptr, u_idx, u_val) = (&sym.u_ptr[..=n], &sym.u_idx[..], u_vals);
            for i in 0..n {
                let (lo, hi) = (l_ptr[i] as usize, l_ptr[i + 1] as usize);
                let mut s = w[i & 63];
                for (&k, &l) in l_idx[lo..hi].iter().zip(&l_val[lo..hi]) {
                    s -= l * w[(k & 63) as usize];
                }
                w[i & 63] = s;
            }
            for i in (0..n).rev() {
                let (lo, hi) = (u_ptr[i] as usize, u_ptr[i + 1] as usize);
                let mut s = w[i & 63];
                // the row's columns from the last: the nearest, solved
                // just before, enters last, so that the products with the
                // ones solved long before are summed while it is computed
                for (&j, &u) in u_idx[lo..hi].iter().zip(&u_val[lo..hi]).rev() {
                    s -= u * w[(j & 63) as usize];
                }
                w[i & 63] = s * inv_diag[i & 63];
            }
            let dx = dx.as_mut_slice();
            for (wi, &oi) in w[..n].iter().zip(&self.order) {
                dx[oi] = *wi;
            }
            return;
        }
        let y = &mut self.y;
        for (yi, &oi) in y.iter_mut().zip(&self.order) {
            *yi = r[oi];
        }
        if self.in_place {
            let f = &self.by_rows;
            for i in 0..n {
                let (lo, hi) = (f.l_ptr[i] as usize, f.l_ptr[i + 1] as usize);
                let mut s = y[i];
                for (&k, &l) in f.l_idx[lo..hi].iter().zip(&f.l_val[lo..hi]) {
                    s -= l * y[k as usize];
                }
                y[i] = s;
            }
            for i in (0..n).rev() {
                let (lo, hi) = (f.u_ptr[i] as usize, f.u_ptr[i + 1] as usize);
                let mut s = y[i];
                // from the last column, as the structured substitution
                for (&j, &u) in f.u_idx[lo..hi].iter().zip(&f.u_val[lo..hi]).rev() {
                    s -= u * y[j as usize];
                }
                y[i] = s * f.inv_diag[i];
            }
            for (yi, &oi) in y.iter().zip(&self.order) {
                dx[oi] = *yi;
            }
            return;
        }
        for k in 0..n {
            y.swap(k, self.piv[k]);
        }
        if self.l_by_rows {
            for (i, w) in self.l_ptr.windows(2).enumerate() {
                let mut s = y[i];
                for &(j, v) in &self.l[w[0]..w[1]] {
                    s -= v * y[j];
                }
                y[i] = s;
            }
        } else {
            for (k, w) in self.l_ptr.windows(2).enumerate() {
                let yk = y[k];
                for &(i, v) in &self.l[w[0]..w[1]] {
                    y[i] -= v * yk;
                }
            }
        }
        for (i, w) in self.u_ptr.windows(2).enumerate().rev() {
            let mut s = y[i];
            for &(j, v) in &self.u[w[0]..w[1]] {
                s -= v * y[j];
            }
            y[i] = s / self.diag[i];
        }
        for (yi, &oi) in y.iter().zip(&self.order) {
            dx[oi] = *yi;
        }
    }
}

/// What a workspace's Jacobian holds outside a sparsity pattern: when
/// known, every entry off `pattern` is exactly -0.0 (what
/// [`ImplicitEuler`]'s evaluation leaves there: zeros, negated). Its next
/// evaluation then clears only the entries of the old and the new pattern
/// instead of the whole matrix (issue 18 point 5: clearing and negating
/// the dense 50 x 50 matrix at each Jacobian was 6 % of a co-simulation
/// step's instructions); the matrix it builds is the same to the bit.
#[derive(Debug, Clone, Default)]
pub struct JacobianZeros {
    pattern: Vec<u64>,
    known: bool,
}

impl JacobianZeros {
    /// Nothing is known about the matrix.
    pub fn forget(&mut self) {
        self.known = false;
    }
    /// The pattern off which every entry is -0.0, when known.
    pub fn pattern(&self) -> Option<&[u64]> {
        self.known.then_some(&self.pattern[..])
    }
    /// Every entry off `pattern` is now -0.0.
    pub fn set(&mut self, pattern: &[u64]) {
        self.pattern.clear();
        self.pattern.extend_from_slice(pattern);
        self.known = true;
    }
}

/// Buffers of the Newton iteration and the Jacobian factorisation it may
/// reuse ([`JacobianUpdate::Chord`]).
#[derive(Debug, Clone)]
pub struct NewtonWorkspace {
    r: DVector<f64>,
    dx: DVector<f64>,
    /// Trial point, its residual and simplified correction (monotonicity test).
    x_trial: DVector<f64>,
    r_trial: DVector<f64>,
    dx_trial: DVector<f64>,
    j: DMatrix<f64>,
    /// What `j` holds off its last sparsity pattern.
    j_zeros: JacobianZeros,
    lu: Lu,
    /// Whether `lu` holds a factorisation that may be reused.
    valid: bool,
    /// The largest ratio of successive corrections seen with it (chord).
    contraction: Option<f64>,
    /// Whether `lu` holds factors taken from elsewhere
    /// ([`load_factors`](Self::load_factors)) that have not yet shown
    /// their contraction on this problem.
    foreign: bool,
}

impl NewtonWorkspace {
    pub fn new(n: usize) -> Self {
        NewtonWorkspace {
            r: DVector::zeros(n),
            dx: DVector::zeros(n),
            x_trial: DVector::zeros(n),
            r_trial: DVector::zeros(n),
            dx_trial: DVector::zeros(n),
            j: DMatrix::zeros(n, n),
            j_zeros: JacobianZeros::default(),
            lu: Lu::default(),
            valid: false,
            contraction: None,
            foreign: false,
        }
    }

    /// Number of unknowns the buffers are sized for.
    pub fn dim(&self) -> usize {
        self.r.len()
    }

    /// The current factorisation's values into `into`, when it is a
    /// reusable structured one (false otherwise, `into` unchanged).
    pub fn save_factors(&self, into: &mut SavedFactors) -> bool {
        self.valid && self.lu.save_structured(into)
    }

    /// Takes saved factors as the factorisation to reuse (chord); false
    /// when they cannot be (their structure is not cached).
    pub fn load_factors(&mut self, saved: &Arc<SavedFactors>) -> bool {
        self.valid = saved.order.len() == self.r.len() && self.lu.load_structured(saved);
        self.contraction = None;
        self.foreign = self.valid;
        self.valid
    }

    /// Forgets the factorisation: the next iteration evaluates a fresh Jacobian.
    pub fn invalidate(&mut self) {
        self.valid = false;
        self.contraction = None;
    }
}

/// Solves F(x) = 0 from the initial guess in `x` (plain Newton).
pub fn newton<P: NewtonProblem>(
    p: &mut P,
    x: &mut DVector<f64>,
    opt: &NewtonOptions,
) -> Result<NewtonReport, SolverError> {
    let mut ws = NewtonWorkspace::new(p.dim());
    newton_with(p, x, opt, JacobianUpdate::Every, &mut ws)
}

/// The largest `|d_i| / scale(i)`, as `f64::max` takes it (a NaN
/// correction leaves the running maximum, which starts at 0, as it was; the
/// caller's residual test has refused non-finite residuals before), with
/// one division when the scale is uniform.
#[inline]
fn scaled_max<P: NewtonProblem>(p: &P, d: &[f64]) -> f64 {
    let max = |m: f64, v: f64| if v > m { v } else { m };
    match p.uniform_scale() {
        Some(s) => d.iter().fold(0.0, |m, v| max(m, v.abs())) / s,
        None => d
            .iter()
            .enumerate()
            .fold(0.0, |m, (i, v)| max(m, v.abs() / p.scale(i))),
    }
}

/// Solves F(x) = 0 from the initial guess in `x` with the buffers (and,
/// for [`JacobianUpdate::Chord`], the factorisation) of `ws`. Iterations that
/// discard a stale correction count towards `opt.max_iter`.
pub fn newton_with<P: NewtonProblem>(
    p: &mut P,
    x: &mut DVector<f64>,
    opt: &NewtonOptions,
    update: JacobianUpdate,
    ws: &mut NewtonWorkspace,
) -> Result<NewtonReport, SolverError> {
    let n = p.dim();
    if ws.r.len() != n {
        *ws = NewtonWorkspace::new(n);
    }
    let max_contraction = match update {
        JacobianUpdate::Every => {
            ws.invalidate();
            f64::NAN
        }
        JacobianUpdate::Chord { max_contraction } => max_contraction,
    };
    let mut last = f64::INFINITY;
    let mut factorisations = 0;
    // a correction of foreign factors that met the tolerance, to be
    // verified by the next one before it is accepted
    let mut verifying = false;
    for it in 1..=opt.max_iter {
        let fresh = !ws.valid;
        if fresh {
            p.eval_reusing(x, &mut ws.r, &mut ws.j, &mut ws.j_zeros);
        } else {
            p.residual(x, &mut ws.r);
        }
        if ws.r.as_slice().iter().any(|v| !v.is_finite()) {
            return Err(SolverError::NonFinite { iteration: it });
        }
        if fresh {
            factorisations += 1;
            if !ws.lu.factor_structured(&ws.j, p.ordering(), p.pattern()) {
                return Err(SolverError::Singular { iteration: it });
            }
            ws.valid = matches!(update, JacobianUpdate::Chord { .. });
            ws.contraction = None;
            ws.foreign = false;
        }
        ws.lu.solve(&ws.r, &mut ws.dx);
        let worst = scaled_max(p, ws.dx.as_slice());
        if !fresh && ws.foreign && ws.contraction.is_none() && worst < ROUND_OFF_FLOOR * opt.tol {
            // the kept factors' correction at the iterate is round-off: the
            // iterate is the solution (its error at most the correction
            // over ROUND_OFF_FLOOR), and the residual was evaluated there
            return Ok(NewtonReport {
                termination: Termination::Converged,
                iterations: it,
                factorisations,
                last_correction: worst,
                error_bound: worst / ROUND_OFF_FLOOR,
                residual_at_solution: true,
                at_start: it == 1,
            });
        }
        if verifying {
            verifying = false;
            // the correction the kept factors give at the accepted point:
            // their contraction, and the error left there, at most
            // `worst / (1 - c)`
            let c = if last > 0.0 {
                worst / last
            } else if worst == 0.0 {
                0.0
            } else {
                f64::INFINITY
            };
            let settled = worst < ROUND_OFF_FLOOR * opt.tol;
            if settled || c <= max_contraction && worst / (1.0 - c) < opt.tol {
                ws.foreign = false;
                ws.contraction = Some(ws.contraction.map_or(c, |k| k.max(c)));
                return Ok(NewtonReport {
                    termination: Termination::Converged,
                    iterations: it,
                    factorisations,
                    last_correction: last,
                    error_bound: worst / (1.0 - c),
                    residual_at_solution: true,
                    at_start: false,
                });
            }
        }
        let mut slow = false;
        let contracting =
            worst <= max_contraction * last || (last.is_infinite() && worst.is_finite());
        if !fresh && !contracting {
            let shrinking = worst < last;
            if !shrinking {
                // the kept factorisation does not converge (or the correction
                // is not finite): discard the correction and refresh at x
                ws.valid = false;
                continue;
            }
            // converging, but slowly: take the correction, refresh next
            ws.valid = false;
            slow = true;
        }
        if !worst.is_finite() {
            return Err(SolverError::NonFinite { iteration: it });
        }
        let mut damp = if worst > opt.max_step {
            opt.max_step / worst
        } else {
            1.0
        };
        if opt.monotone {
            damp = monotone_damping(p, x, ws, worst, damp);
        }
        for (xi, d) in x.as_mut_slice().iter_mut().zip(ws.dx.as_slice()) {
            *xi -= damp * d;
        }
        if slow {
            // no convergence test on a slow contraction: the error left may
            // exceed the correction
            last = worst;
            continue;
        }
        if ws.valid && !fresh && last.is_finite() {
            let ratio = worst / last;
            ws.contraction = Some(ws.contraction.map_or(ratio, |c| c.max(ratio)));
        }
        last = worst;
        let error_bound = match ws.contraction {
            Some(c) if ws.valid => {
                let c = c.max(MIN_CONTRACTION_ESTIMATE);
                worst * c / (1.0 - c)
            }
            _ => worst,
        };
        if error_bound < opt.tol {
            if ws.valid && ws.foreign && ws.contraction.is_none() {
                // foreign factors have not shown their contraction here:
                // one more correction decides
                verifying = true;
                continue;
            }
            return Ok(NewtonReport {
                termination: Termination::Converged,
                iterations: it,
                factorisations,
                last_correction: worst,
                error_bound,
                residual_at_solution: false,
                at_start: false,
            });
        }
    }
    Err(SolverError::NoConvergence {
        iterations: opt.max_iter,
        last_correction: last,
    })
}

/// The natural monotonicity test (Deuflhard, *Newton Methods for Nonlinear
/// Problems*, 2004, Sec. 3.3): a damped correction `lambda dx` is taken when
/// the simplified correction at the trial point, solved with the same
/// factorisation, has shrunk, `|J^-1 F(x - lambda dx)| <= (1 - lambda / 4)
/// |dx|` (scaled max norms); otherwise `lambda` is halved. The test is
/// affine invariant: it needs no scaling of the residuals. Starting from
/// `damp` (the `max_step` limit); after [`MAX_HALVINGS`] halvings the
/// smallest step is taken.
fn monotone_damping<P: NewtonProblem>(
    p: &mut P,
    x: &DVector<f64>,
    ws: &mut NewtonWorkspace,
    worst: f64,
    damp: f64,
) -> f64 {
    let n = x.len();
    let mut lambda = damp;
    for _ in 0..MAX_HALVINGS {
        for i in 0..n {
            ws.x_trial[i] = x[i] - lambda * ws.dx[i];
        }
        p.residual(&ws.x_trial, &mut ws.r_trial);
        if ws.r_trial.iter().all(|v| v.is_finite()) {
            ws.lu.solve(&ws.r_trial, &mut ws.dx_trial);
            let w = scaled_max(p, ws.dx_trial.as_slice());
            if w <= (1.0 - 0.25 * lambda) * worst {
                return lambda;
            }
        }
        lambda *= 0.5;
    }
    lambda
}

/// A conservative system d m(x)/dt = f(x) with diagonal storage.
pub trait ConservativeSystem {
    fn dim(&self) -> usize;
    /// Storage m_i(x_i) and dm_i/dx_i of every state.
    fn storage(&self, x: &DVector<f64>, m: &mut DVector<f64>, dm: &mut DVector<f64>);
    /// Net inflow f(x) and its Jacobian (added to `jac`, which the caller zeroes).
    fn fluxes(&mut self, x: &DVector<f64>, f: &mut DVector<f64>, jac: &mut DMatrix<f64>);
    /// Storage, its derivative and the net inflow at x in one pass, the flux
    /// Jacobian added to `jac` when given (zeroed by the caller). Systems
    /// override it to share work between the two; the default calls
    /// [`storage`](Self::storage) and [`fluxes`](Self::fluxes).
    fn evaluate(
        &mut self,
        x: &DVector<f64>,
        m: &mut DVector<f64>,
        dm: &mut DVector<f64>,
        f: &mut DVector<f64>,
        jac: Option<&mut DMatrix<f64>>,
    ) {
        self.storage(x, m, dm);
        match jac {
            Some(j) => self.fluxes(x, f, j),
            None => {
                let n = self.dim();
                self.fluxes(x, f, &mut DMatrix::zeros(n, n))
            }
        }
    }
    fn scale(&self, i: usize) -> f64;
    /// See [`NewtonProblem::uniform_scale`].
    fn uniform_scale(&self) -> Option<f64> {
        None
    }
    /// An elimination order suited to the Jacobian's sparsity (see
    /// [`NewtonProblem::ordering`]).
    fn ordering(&self) -> Option<&[usize]> {
        None
    }
    /// The flux Jacobian's sparsity, diagonal included (see
    /// [`NewtonProblem::pattern`]).
    fn pattern(&self) -> Option<&[u64]> {
        None
    }
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

/// The storage and flux buffers of an [`ImplicitEuler`] step, to reuse
/// from one step to the next ([`ImplicitEuler::with_buffers`]); they hold
/// no state.
#[derive(Debug, Clone, Default)]
pub struct EulerBuffers {
    m: DVector<f64>,
    dm: DVector<f64>,
    f: DVector<f64>,
}

impl EulerBuffers {
    /// The storage derivatives and the fluxes of the last evaluation.
    pub fn derivatives_and_fluxes(&self) -> (&DVector<f64>, &DVector<f64>) {
        (&self.dm, &self.f)
    }

    /// The storage of the last evaluation.
    pub fn storage(&self) -> &DVector<f64> {
        &self.m
    }
}

impl<'a, S: ConservativeSystem> ImplicitEuler<'a, S> {
    pub fn new(system: &'a mut S, m_old: &'a DVector<f64>, dt: f64) -> Self {
        Self::with_buffers(system, m_old, dt, EulerBuffers::default())
    }

    /// [`new`](Self::new) in the buffers of an earlier step.
    pub fn with_buffers(
        system: &'a mut S,
        m_old: &'a DVector<f64>,
        dt: f64,
        buffers: EulerBuffers,
    ) -> Self {
        let n = system.dim();
        let EulerBuffers {
            mut m,
            mut dm,
            mut f,
        } = buffers;
        for v in [&mut m, &mut dm, &mut f] {
            if v.len() != n {
                *v = DVector::zeros(n);
            }
        }
        Self {
            system,
            m_old,
            dt,
            m,
            dm,
            f,
        }
    }

    /// The buffers, for the next step's [`with_buffers`](Self::with_buffers).
    pub fn into_buffers(self) -> EulerBuffers {
        EulerBuffers {
            m: self.m,
            dm: self.dm,
            f: self.f,
        }
    }

    fn residual_from_parts(&self, r: &mut DVector<f64>) {
        let (m, m_old, f) = (self.m.as_slice(), self.m_old.as_slice(), self.f.as_slice());
        for (((ri, &mi), &m0), &fi) in r.as_mut_slice().iter_mut().zip(m).zip(m_old).zip(f) {
            *ri = (mi - m0) / self.dt - fi;
        }
    }
}

impl<S: ConservativeSystem> NewtonProblem for ImplicitEuler<'_, S> {
    fn dim(&self) -> usize {
        self.system.dim()
    }
    fn eval(&mut self, x: &DVector<f64>, r: &mut DVector<f64>, j: &mut DMatrix<f64>) {
        self.eval_reusing(x, r, j, &mut JacobianZeros::default());
    }
    /// The flux Jacobian is added into cleared entries, then negated: with
    /// a pattern (which holds every entry the system writes, the diagonal
    /// included) and `known` describing `j`, only the entries of the new
    /// pattern are cleared and negated and those of the old one outside it
    /// set to -0.0, which gives the matrix the whole-matrix clear and
    /// negation give, bit for bit (every entry off the pattern -0.0).
    fn eval_reusing(
        &mut self,
        x: &DVector<f64>,
        r: &mut DVector<f64>,
        j: &mut DMatrix<f64>,
        known: &mut JacobianZeros,
    ) {
        let n = r.len();
        let full = if n >= 64 { u64::MAX } else { (1u64 << n) - 1 };
        // (a pattern without its whole diagonal is not relied on: the
        // storage term adds to the diagonal)
        let pattern = self.system.pattern().filter(|p| {
            p.len() == n && n <= 64 && p.iter().enumerate().all(|(i, &row)| row >> i & 1 == 1)
        });
        // column-major: j[(i, c)] = s[c * n + i]
        let sparse = match (pattern, known.pattern()) {
            (Some(p), Some(old)) if old.len() == n => {
                let s = j.as_mut_slice();
                for i in 0..n {
                    for c in Bits(old[i] & !p[i] & full) {
                        s[c * n + i] = -0.0;
                    }
                    for c in Bits(p[i] & full) {
                        s[c * n + i] = 0.0;
                    }
                }
                true
            }
            _ => {
                j.as_mut_slice().fill(0.0);
                false
            }
        };
        // the new pattern, not relied on until the matrix is complete
        let has_pattern = pattern.is_some();
        if let Some(p) = pattern {
            known.set(p);
        }
        known.forget();
        self.system
            .evaluate(x, &mut self.m, &mut self.dm, &mut self.f, Some(j));
        // r = (m - m_old)/dt - f ; J = diag(dm)/dt - df/dx
        self.residual_from_parts(r);
        if sparse {
            let s = j.as_mut_slice();
            for (i, &row) in known.pattern.iter().enumerate() {
                for c in Bits(row & full) {
                    s[c * n + i] = -s[c * n + i];
                }
            }
        } else {
            for v in j.as_mut_slice() {
                *v = -*v;
            }
        }
        for i in 0..r.len() {
            j[(i, i)] += self.dm[i] / self.dt;
        }
        known.known = has_pattern;
    }
    fn ordering(&self) -> Option<&[usize]> {
        self.system.ordering()
    }
    fn pattern(&self) -> Option<&[u64]> {
        // the storage term adds to the diagonal only, which the flux
        // pattern includes
        self.system.pattern()
    }
    fn residual(&mut self, x: &DVector<f64>, r: &mut DVector<f64>) {
        self.system
            .evaluate(x, &mut self.m, &mut self.dm, &mut self.f, None);
        self.residual_from_parts(r);
    }
    fn scale(&self, i: usize) -> f64 {
        self.system.scale(i)
    }
    fn uniform_scale(&self) -> Option<f64> {
        self.system.uniform_scale()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn factorisation_without_interchanges_gives_the_same_factors() {
        // diagonally dominant with structural zeros: no interchange is due
        let n = 27;
        let m = DMatrix::from_fn(n, n, |i, j| {
            let v = ((i * 31 + j * 17) % 13) as f64 / 13.0 - 0.5;
            if i == j {
                10.0 + v
            } else if (i + 3 * j) % 7 == 0 || i.abs_diff(j) == 1 || j >= n - 4 || i >= n - 4 {
                v
            } else {
                0.0
            }
        });
        let order: Vec<usize> = (4..n).chain(0..4).collect();
        let mut fast = Lu::default();
        assert!(fast.factor_ordered(&m, Some(&order)));
        assert!(fast.in_place);
        let mut general = Lu {
            n,
            a: vec![0.0; n * n],
            piv: vec![0; n],
            y: vec![0.0; n],
            order: order.clone(),
            ..Lu::default()
        };
        assert!(general.factor_with_interchanges(m.as_slice()));
        assert!(!general.l_by_rows, "no interchange");
        assert_eq!(fast.a, general.a, "the same factors to the bit");
        // reading only the entries of a pattern that holds the nonzeros
        // (and a few zeros) gives them too
        let pattern: Vec<u64> = (0..n)
            .map(|i| {
                (0..n)
                    .filter(|&j| m[(i, j)] != 0.0 || (i * j) % 11 == 1)
                    .fold(0u64, |b, j| b | 1 << j)
            })
            .collect();
        let mut structured = Lu::default();
        assert!(structured.factor_structured(&m, Some(&order), Some(&pattern)));
        assert!(structured.structured.is_some());
        assert_eq!(
            structured.dense_factors(),
            general.dense_factors(),
            "the same factors from the pattern"
        );
        // bits beyond the unknowns are ignored
        let wide: Vec<u64> = pattern.iter().map(|b| b | 1 << 40).collect();
        let mut widened = Lu::default();
        assert!(widened.factor_structured(&m, Some(&order), Some(&wide)));
        assert_eq!(
            widened.dense_factors(),
            general.dense_factors(),
            "the same factors from a wide pattern"
        );
        // the cached structure, with other values and a pattern met before
        let m2 = m.map(|v| {
            if v != 0.0 {
                1.5 * v + 0.01 * v.signum()
            } else {
                0.0
            }
        });
        let mut general2 = general.clone();
        assert!(general2.factor_with_interchanges(m2.as_slice()));
        let (d1, d2) = (general.dense_factors(), general2.dense_factors());
        for (mat, expect) in [(&m2, &d2), (&m, &d1), (&m2, &d2)] {
            assert!(structured.factor_structured(mat, Some(&order), Some(&pattern)));
            assert_eq!(structured.symbolic.len(), 1, "one structure, reused");
            assert_eq!(&structured.dense_factors(), expect, "reused structure");
        }
        // and the substitutions give the row factorisation's solution
        let mut fast2 = Lu::default();
        assert!(fast2.factor_ordered(&m2, Some(&order)));
        let r2 = DVector::from_fn(n, |i, _| (i as f64).cos());
        let (mut y1, mut y2) = (DVector::zeros(n), DVector::zeros(n));
        structured.solve(&r2, &mut y1);
        fast2.solve(&r2, &mut y2);
        assert_eq!(y1, y2, "the same solution to the bit");
        let r = DVector::from_fn(n, |i, _| (i as f64).sin());
        let (mut x1, mut x2) = (DVector::zeros(n), DVector::zeros(n));
        fast.solve(&r, &mut x1);
        general.solve(&r, &mut x2);
        assert!((&x1 - &x2).norm() < 1e-14 * x2.norm());
    }

    #[test]
    fn lu_solves_sparse_and_pivoting_systems() {
        // a deterministic pseudo-random sparse matrix, diagonally dominant
        // (no interchange) and with small diagonals (interchanges)
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for (case, diag) in [10.0, 1e-3, 0.0].into_iter().enumerate() {
            let n = 17;
            let m = DMatrix::from_fn(n, n, |i, j| {
                let v = rnd();
                if i == j {
                    diag * (1.0 + v.abs())
                } else if (i + 2 * j) % 5 == 0 || i + 1 == j || j + 1 == i {
                    v
                } else {
                    0.0
                }
            });
            let r = DVector::from_fn(n, |_, _| rnd());
            let exact = m.clone().lu().solve(&r).unwrap();
            let mut lu = Lu::default();
            let mut dx = DVector::zeros(n);
            for order in [None, Some((0..n).rev().collect::<Vec<_>>())] {
                assert!(lu.factor_ordered(&m, order.as_deref()), "case {case}");
                lu.solve(&r, &mut dx);
                assert!((&dx - &exact).norm() < 1e-9 * exact.norm(), "case {case}");
            }
        }
        let mut lu = Lu::default();
        assert!(!lu.factor(&DMatrix::zeros(3, 3)));
    }

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

    /// The convergence test's largest scaled correction with a uniform
    /// scale (one division of the largest magnitude) is the largest of the
    /// per-unknown quotients that it replaced, `max |d_i| / s` with
    /// `f64::max`, to the bit: over corrections of every sign and a wide
    /// range of magnitudes, scales that round differently, and a NaN
    /// among the corrections (which both leave aside).
    #[test]
    fn a_uniform_scale_gives_the_per_unknown_largest_quotient_to_the_bit() {
        struct Scaled(Option<f64>, f64);
        impl NewtonProblem for Scaled {
            fn dim(&self) -> usize {
                0
            }
            fn eval(&mut self, _: &DVector<f64>, _: &mut DVector<f64>, _: &mut DMatrix<f64>) {}
            fn scale(&self, _: usize) -> f64 {
                self.1
            }
            fn uniform_scale(&self) -> Option<f64> {
                self.0
            }
        }
        // a deterministic spread of magnitudes from 1e-12 to 1e4, both signs
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let u = (state >> 11) as f64 / (1u64 << 53) as f64;
            let sign = if state & 1 == 0 { 1.0 } else { -1.0 };
            sign * 10f64.powf(-12.0 + 16.0 * u)
        };
        for s in [1.0e5, 3.1e6, 7.0, 1.0 / 3.0] {
            for trial in 0..200 {
                let mut d: Vec<f64> = (0..37).map(|_| next()).collect();
                if trial % 10 == 0 {
                    d[trial % 37] = f64::NAN;
                }
                let want = d.iter().fold(0.0_f64, |m, v| m.max(v.abs() / s));
                let got = scaled_max(&Scaled(Some(s), s), &d);
                let per_unknown = scaled_max(&Scaled(None, s), &d);
                assert!(want > 0.0);
                assert_eq!(got.to_bits(), want.to_bits(), "scale {s}, trial {trial}");
                assert_eq!(
                    per_unknown.to_bits(),
                    want.to_bits(),
                    "scale {s}, trial {trial}"
                );
            }
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
            monotone: false,
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
    fn chord_newton_meets_its_tolerance_also_when_reusing_the_factorisation() {
        // two cubic equations, solved for a target and then for a nearby one
        // with the kept factorisation: the error left is within the tolerance
        struct Cubic {
            target: [f64; 2],
        }
        impl NewtonProblem for Cubic {
            fn dim(&self) -> usize {
                2
            }
            fn eval(&mut self, x: &DVector<f64>, r: &mut DVector<f64>, j: &mut DMatrix<f64>) {
                self.residual(x, r);
                j[(0, 0)] = 3.0 * x[0] * x[0] + 1.0;
                j[(0, 1)] = 0.1;
                j[(1, 0)] = 0.0;
                j[(1, 1)] = 0.3 * x[1] * x[1] + 1.0;
            }
            fn residual(&mut self, x: &DVector<f64>, r: &mut DVector<f64>) {
                r[0] = x[0].powi(3) + x[0] + 0.1 * x[1] - self.target[0];
                r[1] = x[1] + 0.1 * x[1].powi(3) - self.target[1];
            }
            fn scale(&self, _: usize) -> f64 {
                1.0
            }
        }
        let root = |t: [f64; 2]| {
            let mut x = DVector::from_vec(vec![1.0, 1.0]);
            let exact = NewtonOptions {
                tol: 1e-15,
                max_iter: 100,
                max_step: 10.0,
                monotone: false,
            };
            newton(&mut Cubic { target: t }, &mut x, &exact).unwrap();
            x
        };
        let opt = NewtonOptions {
            tol: 1e-6,
            max_iter: 50,
            max_step: 10.0,
            monotone: false,
        };
        let mut ws = NewtonWorkspace::new(2);
        let mut x = DVector::from_vec(vec![1.2, 0.8]);
        for target in [[2.0, 1.5], [2.01, 1.49], [2.02, 1.5]] {
            let chord = JacobianUpdate::Chord {
                max_contraction: 0.25,
            };
            let rep = newton_with(&mut Cubic { target }, &mut x, &opt, chord, &mut ws).unwrap();
            let err = (&x - root(target)).amax();
            assert!(err < opt.tol, "{target:?}: error {err:e} ({rep:?})");
            assert!(rep.error_bound < opt.tol && rep.error_bound <= rep.last_correction);
        }
    }

    /// Factors saved from a structured factorisation and loaded into
    /// another `Lu` (whose structure is rebuilt from their pattern and
    /// order) solve to the bit as the original, and both as nalgebra's
    /// dense LU; parts that cannot be factors are refused, and factors that
    /// do not fit their structure are not loaded.
    #[test]
    fn kept_factors_solve_as_their_factorisation_and_bad_ones_are_refused() {
        let n = 27;
        let m = DMatrix::from_fn(n, n, |i, j| {
            let v = ((i * 29 + j * 13) % 11) as f64 / 11.0 - 0.5;
            if i == j {
                8.0 + v
            } else if i.abs_diff(j) == 1 || j >= n - 4 || i >= n - 4 || (i * j) % 9 == 2 {
                v
            } else {
                0.0
            }
        });
        let pattern: Vec<u64> = (0..n)
            .map(|i| {
                (0..n)
                    .filter(|&j| m[(i, j)] != 0.0)
                    .fold(0u64, |b, j| b | 1 << j)
            })
            .collect();
        let order: Vec<usize> = (4..n).chain(0..4).collect();
        let mut lu = Lu::default();
        assert!(lu.factor_structured(&m, Some(&order), Some(&pattern)));
        let r = DVector::from_fn(n, |i, _| (i as f64 * 0.37).sin());
        let (mut dx, mut dx_loaded) = (DVector::zeros(n), DVector::zeros(n));
        lu.solve(&r, &mut dx);
        let mut saved = SavedFactors::default();
        assert!(lu.save_structured(&mut saved));
        let mut other = Lu::default();
        assert!(other.load_structured(&Arc::new(saved.clone())));
        other.solve(&r, &mut dx_loaded);
        assert_eq!(dx.as_slice(), dx_loaded.as_slice(), "to the bit");
        let exact = m.clone().lu().solve(&r).unwrap();
        assert!((&dx - &exact).amax() < 1e-13 * exact.amax());
        // parts read back from bytes are checked
        let (p, o, l, u, d) = saved.parts();
        let (p, o, l, u, d) = (p.to_vec(), o.to_vec(), l.to_vec(), u.to_vec(), d.to_vec());
        let rebuilt =
            SavedFactors::from_parts(p.clone(), o.clone(), l.clone(), u.clone(), d.clone());
        assert_eq!(rebuilt.as_ref(), Ok(&saved));
        let mut swapped = o.clone();
        swapped[0] = swapped[1];
        let mut no_diagonal = p.clone();
        no_diagonal[3] &= !(1 << 3);
        let mut nan = l.clone();
        nan[0] = f64::NAN;
        let mut zero = d.clone();
        zero[5] = 0.0;
        for (what, bad) in [
            (
                "order",
                SavedFactors::from_parts(p.clone(), swapped, l.clone(), u.clone(), d.clone()),
            ),
            (
                "diagonal",
                SavedFactors::from_parts(no_diagonal, o.clone(), l.clone(), u.clone(), d.clone()),
            ),
            (
                "finite",
                SavedFactors::from_parts(p.clone(), o.clone(), nan, u.clone(), d.clone()),
            ),
            (
                "pivot",
                SavedFactors::from_parts(p.clone(), o.clone(), l.clone(), u.clone(), zero),
            ),
            (
                "size",
                SavedFactors::from_parts(vec![], vec![], vec![], vec![], vec![]),
            ),
        ] {
            assert!(bad.is_err(), "{what}");
        }
        // L one value short: well-formed parts that do not fit the structure
        let short = SavedFactors::from_parts(p, o, l[1..].to_vec(), u, d).unwrap();
        assert!(!other.load_structured(&Arc::new(short)));
        assert!(other.structured.is_none());
    }

    /// Factors taken from elsewhere (`NewtonWorkspace::load_factors`) are
    /// not trusted with their first correction: a second, at the accepted
    /// point, must confirm it. Good factors (the Jacobian's at the root)
    /// converge with no factorisation and the residual evaluated at the
    /// solution; factors of a Jacobian 20 times too stiff give a first
    /// correction 20 times too small, which the old rule (the correction
    /// itself as the error bound) accepted 19 times the tolerance away from
    /// the root; now the error is within the tolerance. The root is the
    /// one plain Newton finds to 1e-15.
    #[test]
    fn foreign_factors_are_verified_before_their_first_correction_is_accepted() {
        struct Stiff {
            target: [f64; 2],
            jscale: f64,
        }
        impl NewtonProblem for Stiff {
            fn dim(&self) -> usize {
                2
            }
            fn eval(&mut self, x: &DVector<f64>, r: &mut DVector<f64>, j: &mut DMatrix<f64>) {
                self.residual(x, r);
                j[(0, 0)] = self.jscale * (3.0 * x[0] * x[0] + 1.0);
                j[(0, 1)] = self.jscale * 0.1;
                j[(1, 0)] = 0.0;
                j[(1, 1)] = self.jscale * (0.3 * x[1] * x[1] + 1.0);
            }
            fn residual(&mut self, x: &DVector<f64>, r: &mut DVector<f64>) {
                r[0] = x[0].powi(3) + x[0] + 0.1 * x[1] - self.target[0];
                r[1] = x[1] + 0.1 * x[1].powi(3) - self.target[1];
            }
            fn scale(&self, _: usize) -> f64 {
                1.0
            }
            fn pattern(&self) -> Option<&[u64]> {
                Some(&[0b11, 0b10])
            }
        }
        let target = [2.0, 1.5];
        let mut root = DVector::from_vec(vec![1.0, 1.0]);
        let exact = NewtonOptions {
            tol: 1e-15,
            max_iter: 100,
            max_step: 10.0,
            monotone: false,
        };
        newton(
            &mut Stiff {
                target,
                jscale: 1.0,
            },
            &mut root,
            &exact,
        )
        .unwrap();
        let chord = JacobianUpdate::Chord {
            max_contraction: 0.25,
        };
        let opt = NewtonOptions {
            tol: 1e-4,
            max_iter: 50,
            ..exact
        };
        let factors_of = |jscale: f64| {
            let mut ws = NewtonWorkspace::new(2);
            let mut x = root.clone();
            newton_with(&mut Stiff { target, jscale }, &mut x, &opt, chord, &mut ws).unwrap();
            let mut f = SavedFactors::default();
            assert!(ws.save_factors(&mut f));
            f
        };
        // the true problem from `start`, the chord iteration from `factors`
        let solve = |factors: &SavedFactors, start: DVector<f64>| {
            let mut ws = NewtonWorkspace::new(2);
            assert!(ws.load_factors(&Arc::new(factors.clone())));
            let mut x = start;
            let mut problem = Stiff {
                target,
                jscale: 1.0,
            };
            let rep = newton_with(&mut problem, &mut x, &opt, chord, &mut ws).unwrap();
            (x, rep)
        };
        let (good, stiff) = (factors_of(1.0), factors_of(20.0));
        // good factors, the first correction below the tolerance
        let (x, rep) = solve(&good, &root + DVector::from_vec(vec![1e-5, -1e-5]));
        assert_eq!(
            (rep.factorisations, rep.residual_at_solution),
            (0, true),
            "{rep:?}"
        );
        assert!((&x - &root).amax() < opt.tol, "{rep:?}");
        // at the root itself the first correction is round-off: the iterate
        // is taken as it is, after one evaluation
        let (x, rep) = solve(&good, root.clone());
        assert_eq!(
            (rep.iterations, rep.residual_at_solution),
            (1, true),
            "{rep:?}"
        );
        assert_eq!(x, root);
        // factors of a Jacobian 20 times too stiff: the first correction is
        // 5e-5, below the tolerance, with the error 9.5e-4 after it
        let (x, rep) = solve(&stiff, &root + DVector::from_vec(vec![1e-3, -1e-3]));
        let err = (&x - &root).amax();
        assert!(err < opt.tol, "error {err:e} ({rep:?})");
        assert!(rep.iterations > 2 || rep.factorisations > 0, "{rep:?}");
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
                monotone: false,
            },
        );
        assert!(matches!(
            e,
            Err(SolverError::NoConvergence { .. }) | Err(SolverError::NonFinite { .. })
        ));
    }

    /// arctan: Newton's iteration from |x0| above the root of
    /// `2 x = (1 + x^2) atan(x)` (1.3917) moves away from the root x = 0 by
    /// steps of alternating sign (exactly there it would cycle between +x0
    /// and -x0, the failure met by the pocket pressures); with the
    /// monotonicity test it converges.
    #[test]
    fn the_monotonicity_test_converges_where_newton_diverges() {
        struct Atan;
        impl NewtonProblem for Atan {
            fn dim(&self) -> usize {
                1
            }
            fn eval(&mut self, x: &DVector<f64>, r: &mut DVector<f64>, j: &mut DMatrix<f64>) {
                r[0] = x[0].atan();
                j[(0, 0)] = 1.0 / (1.0 + x[0] * x[0]);
            }
            fn scale(&self, _: usize) -> f64 {
                1.0
            }
        }
        let opts = |monotone| NewtonOptions {
            tol: 1e-12,
            max_iter: 60,
            max_step: 1e9,
            monotone,
        };
        for x0 in [1.5, -3.0, 10.0] {
            let mut x = DVector::from_vec(vec![x0]);
            assert!(newton(&mut Atan, &mut x, &opts(false)).is_err());
            let mut x = DVector::from_vec(vec![x0]);
            let rep = newton(&mut Atan, &mut x, &opts(true)).expect("damped Newton converges");
            assert!(x[0].abs() < 1e-12, "x = {}", x[0]);
            assert!(rep.iterations < 30);
        }
    }
}
