//! The mean-value map of one pump sample ([`PumpMap`]), generated from the
//! LP model: the periodic solutions of the very pump (design, measured
//! clearances, micromotion switch) over a grid of speed × pressure rise ×
//! oil temperature, interpolated between the nodes. It is what the FMU's
//! `map` fidelity steps on (`fmi2::pump`), thousands of times faster than
//! the pocket-level model.
//!
//! * **Nodes.** At every node the LP model is started with
//!   [`CoSimulation::start`] (periodic steady state, the design's service
//!   laws on the measured clearances, as `gearpump simulate` and the LP
//!   fidelity do) at the grid's suction pressure; one further mesh period
//!   gives the node's values: mean delivered flow `q_out`, mean suction
//!   flow `q_in`, mean shaft torque, the lowest pocket pressure, and the
//!   first [`HARMONICS`] mesh harmonics of the delivered flow and of the
//!   torque (cosine and sine coefficients against the mesh angle, each
//!   angular step's value taken at its mid angle: an exact discrete Fourier
//!   transform over the mesh period's steps), plus whether the LP results
//!   there leave the model's sense ([`Flag`]) or overload a bearing.
//!   The nodes are computed on the cores (scoped threads, as the section
//!   tables).
//! * **Interpolation.** Tensor-product local cubic Lagrange interpolation on
//!   each axis (the four nearest nodes; three or two on an axis with fewer
//!   nodes), so non-uniform node spacings are allowed; 64 nodes per value.
//!   Within one cell of the grid (between neighbouring nodes on each axis)
//!   the nodes taken are the same, so the interpolant there is one
//!   polynomial of degree three in each of the cell's local coordinates:
//!   its 64 coefficients per value are worked out when the map is made, and
//!   a point inside the grid costs the cell's search (first where the last
//!   point lay) and nested Horner schemes over the values side by side in
//!   SIMD lanes (AVX2 when the processor has it). The same interpolant as
//!   the nodes' Lagrange weights, to rounding (a unit test compares them).
//!   Outside the grid: speed is extrapolated linearly from the two nodes at
//!   that end (flow and torque are close to linear in speed), the pressure
//!   rise and the temperature are held at the grid's edge; either way
//!   [`MapValues::outside`] says so.
//! * **Standard grid** ([`MapGrid::standard`]): chosen by measuring the
//!   interpolation error against LP runs between the nodes (docs/fmu.md).
//! * **Key.** A map is stored with a key ([`PumpMap::key_for`]): a hash of
//!   the design, the measured clearances, the micromotion switch, the grid
//!   and [`MAP_FORMAT`]; a stored map whose key differs is refused
//!   ([`PumpMap::from_bytes`]).

use super::cosim::CoSimulation;
use super::{Inputs, Options, Pump, SampleClearances};
use crate::hash::{Fingerprint, Fnv1a};
use crate::limits::Flag;
use crate::units::{bar_to_pa, celsius_to_kelvin, rpm_to_rad_s, ATMOSPHERE_PA};
use std::sync::Arc;
use thiserror::Error;

/// Mesh harmonics of the delivered flow and of the torque kept per node.
pub const HARMONICS: usize = 3;

/// Version of the map's content and layout (part of the key).
pub const MAP_FORMAT: u64 = 1;

/// Values per node: q_out, q_in, torque, p_pocket_min, flagged, then the
/// flow's and the torque's harmonics (cos, sin) each.
pub const VALUES: usize = 5 + 4 * HARMONICS;

const Q_OUT: usize = 0;
const Q_IN: usize = 1;
const TORQUE: usize = 2;
const P_MIN: usize = 3;
const FLAGGED: usize = 4;
const Q_HARM: usize = 5;
const T_HARM: usize = 5 + 2 * HARMONICS;
/// The harmonics' values per node (the flow's, then the torque's).
const HARMONIC_VALUES: usize = 4 * HARMONICS;

/// Why a map could not be built or read.
#[derive(Debug, Error)]
pub enum MapError {
    #[error("LP model at {rpm:.0} rpm, {bar:.1} bar, {degc:.1} degC: {source}")]
    Node {
        rpm: f64,
        bar: f64,
        degc: f64,
        source: super::cosim::CoSimError,
    },
    #[error("grid: {0}")]
    Grid(String),
    #[error("stored map: {0}")]
    Stored(String),
}

/// The grid's axes (SI, each strictly increasing, at least two nodes) and
/// the suction pressure its nodes are computed at.
#[derive(Debug, Clone, PartialEq)]
pub struct MapGrid {
    /// Driving speed, rad/s.
    pub speed: Vec<f64>,
    /// Pressure rise p_out - p_in, Pa.
    pub dp: Vec<f64>,
    /// Oil temperature, K.
    pub temp: Vec<f64>,
    /// Suction pressure, Pa (absolute).
    pub p_in: f64,
}

impl MapGrid {
    /// The standard grid (its choice and measured error: docs/fmu.md):
    /// 500 to 4000 rpm in 9 nodes spaced evenly in the logarithm of speed,
    /// 2 to 250 bar in 11 nodes, 20 to 100 degC in 9 nodes, at atmospheric
    /// suction pressure.
    pub fn standard() -> MapGrid {
        MapGrid::spanning((1000.0, 4000.0, 6, true), (2.0, 200.0, 9), (20.0, 80.0, 7))
    }

    /// A grid from `(first, last, nodes, logarithmic)` in rpm, `(first,
    /// last, nodes)` in bar (pressure rise) and in degC, evenly spaced
    /// (speed evenly in its logarithm when `logarithmic`), at atmospheric
    /// suction pressure.
    pub fn spanning(
        speed_rpm: (f64, f64, usize, bool),
        dp_bar: (f64, f64, usize),
        temp_c: (f64, f64, usize),
    ) -> MapGrid {
        let even = |a: f64, b: f64, n: usize| -> Vec<f64> {
            (0..n)
                .map(|i| a + (b - a) * i as f64 / (n.max(2) - 1) as f64)
                .collect()
        };
        let (a, b, n, log) = speed_rpm;
        let speed = if log {
            even(a.ln(), b.ln(), n).into_iter().map(f64::exp).collect()
        } else {
            even(a, b, n)
        };
        MapGrid {
            speed: speed.into_iter().map(rpm_to_rad_s).collect(),
            dp: even(dp_bar.0, dp_bar.1, dp_bar.2)
                .into_iter()
                .map(bar_to_pa)
                .collect(),
            temp: even(temp_c.0, temp_c.1, temp_c.2)
                .into_iter()
                .map(celsius_to_kelvin)
                .collect(),
            p_in: ATMOSPHERE_PA,
        }
    }

    /// `n` points spread over the grid's range and off its nodes (the
    /// Halton sequence in bases 2, 3 and 5 over the box, speed in its
    /// logarithm): (speed rad/s, dp Pa, temperature K).
    pub fn check_points(&self, n: usize) -> Vec<(f64, f64, f64)> {
        let halton = |mut i: usize, base: usize| {
            let (mut f, mut r) = (1.0, 0.0);
            while i > 0 {
                f /= base as f64;
                r += f * (i % base) as f64;
                i /= base;
            }
            r
        };
        let span = |axis: &[f64], u: f64| axis[0] + u * (axis[axis.len() - 1] - axis[0]);
        let (s0, s1) = (self.speed[0], self.speed[self.speed.len() - 1]);
        (1..=n)
            .map(|i| {
                let u = halton(i, 2);
                (
                    s0 * (s1 / s0).powf(u),
                    span(&self.dp, halton(i, 3)),
                    span(&self.temp, halton(i, 5)),
                )
            })
            .collect()
    }

    /// Nodes in all.
    pub fn len(&self) -> usize {
        self.speed.len() * self.dp.len() * self.temp.len()
    }

    /// Whether the grid has no node.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn check(&self) -> Result<(), MapError> {
        for (name, axis) in [
            ("speed", &self.speed),
            ("dp", &self.dp),
            ("temp", &self.temp),
        ] {
            if axis.len() < 2
                || !axis.iter().all(|x| x.is_finite())
                || axis.windows(2).any(|w| w[1] <= w[0])
            {
                return Err(MapError::Grid(format!(
                    "the {name} axis needs two or more finite, strictly increasing nodes"
                )));
            }
        }
        if !(self.p_in.is_finite() && self.p_in > 0.0) {
            return Err(MapError::Grid(format!("suction pressure {}", self.p_in)));
        }
        Ok(())
    }

    /// (speed, dp, temp) of node `n` (temperature fastest, then dp).
    fn node(&self, n: usize) -> (f64, f64, f64) {
        let nt = self.temp.len();
        let nd = self.dp.len();
        (
            self.speed[n / (nd * nt)],
            self.dp[(n / nt) % nd],
            self.temp[n % nt],
        )
    }
}

/// The map's values at one point.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MapValues {
    /// Mean delivered flow, m^3/s (at delivery-line density).
    pub q_out: f64,
    /// Mean suction flow, m^3/s (at suction-line density).
    pub q_in: f64,
    /// Mean shaft torque, N m.
    pub torque: f64,
    /// Lowest pocket pressure over a mesh period, Pa.
    pub p_pocket_min: f64,
    /// Cosine and sine coefficients of the delivered flow's mesh harmonics
    /// `k = 1..=HARMONICS` against the mesh angle `z θ`, m^3/s.
    pub q_harmonics: [[f64; 2]; HARMONICS],
    /// The same for the shaft torque, N m.
    pub torque_harmonics: [[f64; 2]; HARMONICS],
    /// The point lies outside the grid (speed extrapolated, pressure rise or
    /// temperature held at the edge).
    pub outside: bool,
    /// A node the point is interpolated from had LP results out of sense
    /// (eta_v or eta_hm, [`Flag`]) or an overloaded bearing.
    pub flagged: bool,
}

/// The map of one pump sample (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct PumpMap {
    grid: MapGrid,
    key: Fingerprint,
    /// `VALUES` per node, nodes in [`MapGrid::node`] order.
    values: Vec<f64>,
    /// The same for interpolation, the temperature axis padded to four
    /// nodes (copies of the last, which get weight 0): the four means
    /// (`q_out`, `q_in`, torque, lowest pocket pressure) of each node side
    /// by side, so that one node is one multiply-add of four lanes ...
    means: Vec<[f64; 4]>,
    /// ... and the flow's and the torque's harmonics of each node.
    harmonics: Vec<[f64; HARMONIC_VALUES]>,
    /// Windows of four nodes (or fewer) per axis, and for each window of
    /// the grid whether one of its nodes is flagged.
    windows: [usize; 3],
    flagged_window: Vec<bool>,
    /// [`inverse_denominators`] of the three axes.
    inverse: [Vec<[f64; 4]>; 3],
    /// Per cell of the grid (cells in the nodes' order, `ns - 1` by `nd -
    /// 1` by `nt - 1`), the interpolant there as a polynomial of degree
    /// three in each of the cell's local coordinates (module docs,
    /// "Interpolation"): its 64 coefficients of the four means ...
    cell_means: Vec<[[f64; 4]; 64]>,
    /// ... and of the harmonics ...
    cell_harmonics: Vec<[[f64; HARMONIC_VALUES]; 64]>,
    /// ... whether a node it is interpolated from is flagged, and the
    /// reciprocal widths of the cells along each axis.
    cell_flagged: Vec<bool>,
    inverse_width: [Vec<f64>; 3],
}

impl PumpMap {
    fn new(grid: MapGrid, key: Fingerprint, values: Vec<f64>) -> PumpMap {
        let lens = [grid.speed.len(), grid.dp.len(), grid.temp.len()];
        // the temperature axis padded to four nodes (copies of the last,
        // which get weight 0)
        let ntp = lens[2].max(4);
        let padded = lens[0] * lens[1] * ntp;
        let (mut means, mut harmonics) = (Vec::with_capacity(padded), Vec::with_capacity(padded));
        for line in values.chunks_exact(VALUES * lens[2]) {
            for k in 0..ntp {
                let node = &line[k.min(lens[2] - 1) * VALUES..][..VALUES];
                means.push([node[Q_OUT], node[Q_IN], node[TORQUE], node[P_MIN]]);
                let mut h = [0.0; HARMONIC_VALUES];
                h.copy_from_slice(&node[Q_HARM..]);
                harmonics.push(h);
            }
        }
        let windows = lens.map(|n| n - n.min(4) + 1);
        let mut flagged_window = Vec::with_capacity(windows.iter().product());
        for a in 0..windows[0] {
            for b in 0..windows[1] {
                for c in 0..windows[2] {
                    let mut any = false;
                    for i in a..a + lens[0].min(4) {
                        for j in b..b + lens[1].min(4) {
                            for k in c..c + lens[2].min(4) {
                                let node = (i * lens[1] + j) * lens[2] + k;
                                any |= values[node * VALUES + FLAGGED] != 0.0;
                            }
                        }
                    }
                    flagged_window.push(any);
                }
            }
        }
        let axes = [&grid.speed, &grid.dp, &grid.temp];
        let cells = lens.map(|n| n - 1);
        let total = cells.iter().product();
        let mut cell_means = Vec::with_capacity(total);
        let mut cell_harmonics = Vec::with_capacity(total);
        let mut cell_flagged = Vec::with_capacity(total);
        for i in 0..cells[0] {
            let (fi, li) = cell_basis(axes[0], i);
            for j in 0..cells[1] {
                let (fj, lj) = cell_basis(axes[1], j);
                for k in 0..cells[2] {
                    let (fk, lk) = cell_basis(axes[2], k);
                    let node = |a: usize, b: usize, c: usize| {
                        let n = ((fi + a) * lens[1] + fj + b) * lens[2] + fk + c;
                        &values[n * VALUES..][..VALUES]
                    };
                    let c = cell_coefficients(&li, &lj, &lk, lens.map(|n| n.min(4)), node);
                    let (mut m, mut h) = ([[0.0; 4]; 64], [[0.0; HARMONIC_VALUES]; 64]);
                    for (t, coef) in c.iter().enumerate() {
                        m[t] = [coef[Q_OUT], coef[Q_IN], coef[TORQUE], coef[P_MIN]];
                        h[t].copy_from_slice(&coef[Q_HARM..]);
                    }
                    cell_means.push(m);
                    cell_harmonics.push(h);
                    cell_flagged.push(flagged_window[(fi * windows[1] + fj) * windows[2] + fk]);
                }
            }
        }
        let inverse_width = axes.map(|a| {
            a.windows(2)
                .map(|w| 1.0 / (w[1] - w[0]))
                .collect::<Vec<_>>()
        });
        PumpMap {
            means,
            harmonics,
            windows,
            flagged_window,
            inverse: [
                inverse_denominators(&grid.speed),
                inverse_denominators(&grid.dp),
                inverse_denominators(&grid.temp),
            ],
            cell_means,
            cell_harmonics,
            cell_flagged,
            inverse_width,
            grid,
            key,
            values,
        }
    }
}

/// The window of Lagrange nodes [`weights_with`] takes for the points of
/// cell `k` of `axis` (between nodes `k` and `k + 1`): its first node, and
/// each node's Lagrange basis polynomial as the coefficients of the powers
/// of the cell's local coordinate `u = (x - x_k) / (x_{k+1} - x_k)`
/// (rows past the window's nodes are 0).
fn cell_basis(axis: &[f64], k: usize) -> (usize, [[f64; 4]; 4]) {
    let n = axis.len();
    let m = n.min(4);
    let first = (k + 1).saturating_sub(m / 2).min(n - m);
    let (x0, h) = (axis[k], axis[k + 1] - axis[k]);
    let mut basis = [[0.0; 4]; 4];
    for (a, poly) in basis.iter_mut().enumerate().take(m) {
        let xa = axis[first + a];
        *poly = [1.0, 0.0, 0.0, 0.0];
        for b in (0..m).filter(|&b| b != a) {
            // times (x - x_b) / (x_a - x_b) = c0 + c1 u
            let xb = axis[first + b];
            let (c0, c1) = ((x0 - xb) / (xa - xb), h / (xa - xb));
            for p in (0..4).rev() {
                poly[p] = c0 * poly[p] + if p > 0 { c1 * poly[p - 1] } else { 0.0 };
            }
        }
    }
    (first, basis)
}

/// The coefficients `C[(p 4 + q) 4 + r]` of `u^p v^q w^r` of the tensor
/// product of the three axes' cell bases over the window's node values
/// (`node(a, b, c)`, `m` nodes per axis), one axis at a time.
fn cell_coefficients<'a>(
    lx: &[[f64; 4]; 4],
    ly: &[[f64; 4]; 4],
    lz: &[[f64; 4]; 4],
    m: [usize; 3],
    node: impl Fn(usize, usize, usize) -> &'a [f64],
) -> Vec<[f64; VALUES]> {
    // a += l f, lane by lane
    let add = |acc: &mut [f64; VALUES], l: f64, f: &[f64]| {
        for (x, fv) in acc.iter_mut().zip(f) {
            *x += l * fv;
        }
    };
    // over the temperature's nodes: s1[(a 4 + b) 4 + r]
    let mut s1 = vec![[0.0; VALUES]; 64];
    for a in 0..m[0] {
        for b in 0..m[1] {
            for (c, lc) in lz.iter().enumerate().take(m[2]) {
                let f = node(a, b, c);
                for (r, &l) in lc.iter().enumerate() {
                    add(&mut s1[(a * 4 + b) * 4 + r], l, f);
                }
            }
        }
    }
    // over the pressure's: s2[(a 4 + q) 4 + r]
    let mut s2 = vec![[0.0; VALUES]; 64];
    for a in 0..m[0] {
        for (b, lb) in ly.iter().enumerate().take(m[1]) {
            for (q, &l) in lb.iter().enumerate() {
                for r in 0..4 {
                    let f = s1[(a * 4 + b) * 4 + r];
                    add(&mut s2[(a * 4 + q) * 4 + r], l, &f);
                }
            }
        }
    }
    // over the speed's
    let mut c = vec![[0.0; VALUES]; 64];
    for (a, la) in lx.iter().enumerate().take(m[0]) {
        for (p, &l) in la.iter().enumerate() {
            for qr in 0..16 {
                let f = s2[a * 16 + qr];
                add(&mut c[p * 16 + qr], l, &f);
            }
        }
    }
    c
}

/// The cell of `axis` holding `x` (the interval [`weights_with`] takes:
/// the last node at or below `x`, the last cell at the last node), tried
/// first at `hint`; `None` outside the axis.
#[inline(always)]
fn locate(axis: &[f64], x: f64, hint: usize) -> Option<usize> {
    let n = axis.len();
    if hint < n.saturating_sub(1) {
        let (a, b) = (axis[hint], axis[hint + 1]);
        if a <= x && (x < b || (x == b && hint + 2 == n)) {
            return Some(hint);
        }
    }
    (axis[0]..=axis[n - 1])
        .contains(&x)
        .then(|| axis.partition_point(|&a| a <= x).clamp(1, n - 1) - 1)
}

/// The (cos, sin) pairs of the harmonics from `at` in `harm`.
fn pairs(harm: &[f64; HARMONIC_VALUES], at: usize) -> [[f64; 2]; HARMONICS] {
    let mut h = [[0.0; 2]; HARMONICS];
    for (k, hk) in h.iter_mut().enumerate() {
        *hk = [harm[at + 2 * k], harm[at + 2 * k + 1]];
    }
    h
}

/// The interpolant of one cell at its local coordinates `(u, v, w)` from
/// its coefficients ([`cell_coefficients`]), by nested Horner schemes:
/// sixteen cubics in `w`, four in `v`, one in `u`, each over `N` lanes.
/// Compiled for AVX2 with fused multiply-adds as [`contract`] is.
#[multiversion::multiversion(targets("x86_64+avx2+fma", "x86_64+avx"))]
fn horner<const N: usize>(c: &[[f64; N]; 64], u: f64, v: f64, w: f64) -> [f64; N] {
    let fused = multiversion::target::target_cfg_f!(target_feature = "fma");
    let madd = |a: f64, b: f64, c: f64| if fused { a.mul_add(b, c) } else { a * b + c };
    let mut acc = [0.0; N];
    for p in (0..4).rev() {
        let mut s = [0.0; N];
        for q in (0..4).rev() {
            let t = &c[(p * 4 + q) * 4..][..4];
            for l in 0..N {
                let y = madd(madd(madd(t[3][l], w, t[2][l]), w, t[1][l]), w, t[0][l]);
                s[l] = madd(s[l], v, y);
            }
        }
        for l in 0..N {
            acc[l] = madd(acc[l], u, s[l]);
        }
    }
    acc
}

/// Local Lagrange weights on `axis` at `x`: the first node and up to four
/// weights; `x` is clamped to the axis unless `extrapolate` (then the two
/// end nodes give a straight line).
#[cfg(test)]
fn weights(axis: &[f64], x: f64, extrapolate: bool) -> (usize, [f64; 4], usize, bool) {
    weights_with(axis, None, x, extrapolate)
}

/// The inverse Lagrange denominators `1 / Π_{b≠a} (x_a - x_b)` of every
/// window of four (or fewer) nodes on `axis`, by its first node.
fn inverse_denominators(axis: &[f64]) -> Vec<[f64; 4]> {
    let n = axis.len();
    let m = n.min(4);
    (0..=n - m)
        .map(|first| {
            let mut inv = [0.0; 4];
            for (a, d) in inv.iter_mut().enumerate().take(m) {
                let mut p = 1.0;
                for b in (0..m).filter(|&b| b != a) {
                    p *= axis[first + a] - axis[first + b];
                }
                *d = 1.0 / p;
            }
            inv
        })
        .collect()
}

/// [`weights`], with the window's denominators from `inverse` when given.
#[inline(always)]
fn weights_with(
    axis: &[f64],
    inverse: Option<&[[f64; 4]]>,
    x: f64,
    extrapolate: bool,
) -> (usize, [f64; 4], usize, bool) {
    let n = axis.len();
    let (lo, hi) = (axis[0], axis[n - 1]);
    let outside = !(lo..=hi).contains(&x);
    if outside && extrapolate {
        let (i, j) = if x < lo { (0, 1) } else { (n - 2, n - 1) };
        let t = (x - axis[i]) / (axis[j] - axis[i]);
        return (i, [1.0 - t, t, 0.0, 0.0], 2, true);
    }
    let x = x.clamp(lo, hi);
    let m = n.min(4);
    // the interval holding x, then the m nodes around it
    let k = axis.partition_point(|&a| a <= x).clamp(1, n - 1) - 1;
    let first = (k + 1).saturating_sub(m / 2).min(n - m);
    let mut w = [0.0; 4];
    if let Some(inv) = inverse {
        let d = [x - axis[first], x - axis[first + 1], 0.0, 0.0];
        let d = if m == 4 {
            [d[0], d[1], x - axis[first + 2], x - axis[first + 3]]
        } else if m == 3 {
            [d[0], d[1], x - axis[first + 2], 1.0]
        } else {
            [d[0], d[1], 1.0, 1.0]
        };
        // Π_{b≠a} (x - x_b), each without its own factor
        let (p01, p23) = (d[0] * d[1], d[2] * d[3]);
        let prods = [d[1] * p23, d[0] * p23, p01 * d[3], p01 * d[2]];
        for a in 0..m {
            w[a] = prods[a] * inv[first][a];
        }
        return (first, w, m, outside);
    }
    for (a, wa) in w.iter_mut().enumerate().take(m) {
        let xa = axis[first + a];
        let mut p = 1.0;
        for b in 0..m {
            if b != a {
                let xb = axis[first + b];
                p *= (x - xb) / (xa - xb);
            }
        }
        *wa = p;
    }
    (first, w, m, outside)
}

/// The interpolation's sum: per row of four temperatures (`rows`, the
/// index of its first node in `nodes`), the temperature weights `wk` first,
/// then the row's weight; every node's `N` values side by side, so that
/// each node is one multiply-add over `N` lanes. Compiled also for AVX2
/// with fused multiply-adds (and for AVX), the version chosen at run time
/// by what the processor has: the sums are the same in the same order, the
/// fused multiply-adds rounding once instead of twice (so results differ
/// between processors with and without them by rounding in the last bits).
#[multiversion::multiversion(targets("x86_64+avx2+fma", "x86_64+avx"))]
fn contract<const N: usize>(
    nodes: &[[f64; N]],
    rows: &[usize; 16],
    row_w: &[f64; 16],
    wk: &[f64; 4],
) -> [f64; N] {
    // a fused multiply-add only where the processor has one (in software
    // it would be slow)
    let fused = multiversion::target::target_cfg_f!(target_feature = "fma");
    let madd = |a: f64, b: f64, c: f64| if fused { a.mul_add(b, c) } else { a * b + c };
    let mut acc = [0.0; N];
    for (&row, &w) in rows.iter().zip(row_w) {
        let Some(&[n0, n1, n2, n3]) = nodes.get(row..row + 4) else {
            continue;
        };
        for v in 0..N {
            let t = madd(wk[1], n1[v], wk[0] * n0[v]) + madd(wk[3], n3[v], wk[2] * n2[v]);
            acc[v] = madd(w, t, acc[v]);
        }
    }
    acc
}

/// The node's values from an LP run (see the module docs).
fn node_values(
    pump: &Arc<Pump>,
    sample: SampleClearances,
    options: Options,
    inputs: Inputs,
) -> Result<[f64; VALUES], super::cosim::CoSimError> {
    let (cs, out) = CoSimulation::start(
        Arc::clone(pump),
        inputs,
        sample,
        options,
        true,
        inputs.omega,
        true,
    )?;
    let state = cs.state();
    let spp = pump.steps_per_period();
    let dtheta = pump.tables.dtheta;
    let z = pump.tables.z[0] as f64;
    let mut v = [0.0; VALUES];
    v[Q_OUT] = out.q_out;
    v[Q_IN] = out.q_in;
    v[TORQUE] = out.torque;
    v[P_MIN] = out.p_pocket_min;
    let sim = cs.simulation();
    let flagged = Flag::of(out.eta_v, out.eta_hm).iter().any(Option::is_some)
        || sim.bearing_overload()
        || !(out.q_out.is_finite() && out.torque.is_finite());
    v[FLAGGED] = if flagged { 1.0 } else { 0.0 };
    // the window's steps end at steps_done - spp + 1 ..= steps_done; the
    // mesh angle of step j's middle
    let first = state.committed.steps_done + 1 - state.window.len() as u64;
    let n = state.window.len() as f64;
    for (j, s) in state.window.iter().enumerate() {
        let phase = (((first + j as u64) % spp as u64) as f64 - 0.5) * dtheta * z;
        let q = s.volume * inputs.omega / dtheta;
        let t = s.work / dtheta;
        for k in 0..HARMONICS {
            let (sin, cos) = ((k + 1) as f64 * phase).sin_cos();
            v[Q_HARM + 2 * k] += 2.0 / n * q * cos;
            v[Q_HARM + 2 * k + 1] += 2.0 / n * q * sin;
            v[T_HARM + 2 * k] += 2.0 / n * t * cos;
            v[T_HARM + 2 * k + 1] += 2.0 / n * t * sin;
        }
    }
    Ok(v)
}

impl PumpMap {
    /// The key of the map of `pump` with `sample`, `options` on `grid`.
    pub fn key_for(
        pump: &Pump,
        sample: &SampleClearances,
        options: Options,
        grid: &MapGrid,
    ) -> Fingerprint {
        let mut h = Fnv1a::new();
        h.write_u64(MAP_FORMAT);
        h.write_str(&format!("{:?}", pump.design));
        for x in sample
            .tip
            .iter()
            .chain(&sample.bearing)
            .chain(std::iter::once(&sample.lateral))
        {
            h.write_f64(*x);
        }
        h.write_u64(u64::from(options.micromotion));
        for axis in [&grid.speed, &grid.dp, &grid.temp] {
            h.write_u64(axis.len() as u64);
            axis.iter().for_each(|&x| h.write_f64(x));
        }
        h.write_f64(grid.p_in);
        h.finish()
    }

    /// Computes the map: the LP model's periodic solution at every node, on
    /// up to `threads` threads.
    pub fn build(
        pump: &Arc<Pump>,
        sample: SampleClearances,
        options: Options,
        grid: &MapGrid,
        threads: usize,
    ) -> Result<PumpMap, MapError> {
        grid.check()?;
        let nodes = crate::geometry::tables::parallel_map_on(threads, grid.len(), |n| {
            let (omega, dp, temp_k) = grid.node(n);
            let inputs = Inputs {
                omega,
                p_suction: grid.p_in,
                p_delivery: grid.p_in + dp,
                temp_k,
                measured_torque: None,
            };
            node_values(pump, sample, options, inputs).map_err(|source| MapError::Node {
                rpm: crate::units::rad_s_to_rpm(omega),
                bar: crate::units::pa_to_bar(dp),
                degc: crate::units::kelvin_to_celsius(temp_k),
                source,
            })
        });
        let mut values = Vec::with_capacity(grid.len() * VALUES);
        for node in nodes {
            values.extend_from_slice(&node?);
        }
        Ok(PumpMap::new(
            grid.clone(),
            PumpMap::key_for(pump, &sample, options, grid),
            values,
        ))
    }

    /// The LP model's values at one point (what a node holds), the
    /// reference the map is checked against.
    pub fn lp_point(
        pump: &Arc<Pump>,
        sample: SampleClearances,
        options: Options,
        omega: f64,
        dp: f64,
        temp_k: f64,
        p_in: f64,
    ) -> Result<MapValues, super::cosim::CoSimError> {
        let v = node_values(
            pump,
            sample,
            options,
            Inputs {
                omega,
                p_suction: p_in,
                p_delivery: p_in + dp,
                temp_k,
                measured_torque: None,
            },
        )?;
        let harmonics = |at: usize| {
            let mut h = [[0.0; 2]; HARMONICS];
            for (k, hk) in h.iter_mut().enumerate() {
                *hk = [v[at + 2 * k], v[at + 2 * k + 1]];
            }
            h
        };
        Ok(MapValues {
            q_out: v[Q_OUT],
            q_in: v[Q_IN],
            torque: v[TORQUE],
            p_pocket_min: v[P_MIN],
            q_harmonics: harmonics(Q_HARM),
            torque_harmonics: harmonics(T_HARM),
            outside: false,
            flagged: v[FLAGGED] != 0.0,
        })
    }

    /// The grid.
    pub fn grid(&self) -> &MapGrid {
        &self.grid
    }

    /// The key the map was built for.
    pub fn key(&self) -> Fingerprint {
        self.key
    }

    /// The values at speed `omega` (rad/s), pressure rise `dp` (Pa) and oil
    /// temperature `temp_k` (K) (see the module docs).
    pub fn eval(&self, omega: f64, dp: f64, temp_k: f64) -> MapValues {
        self.eval_with(omega, dp, temp_k, true)
    }

    /// [`eval`](Self::eval), the harmonics left at 0 unless `harmonics`
    /// (a quarter of the work without them).
    pub fn eval_with(&self, omega: f64, dp: f64, temp_k: f64, harmonics: bool) -> MapValues {
        let mut out = MapValues::default();
        self.eval_into(omega, dp, temp_k, harmonics, &mut [usize::MAX; 3], &mut out);
        out
    }

    /// [`eval_with`](Self::eval_with) into `out`; `cell` is where the
    /// search for the point's cell starts (a caller stepping through
    /// nearby points keeps the last point's there; any value is accepted)
    /// and is left at the point's cell.
    pub fn eval_into(
        &self,
        omega: f64,
        dp: f64,
        temp_k: f64,
        harmonics: bool,
        cell: &mut [usize; 3],
        out: &mut MapValues,
    ) {
        let g = &self.grid;
        let (Some(i), Some(j), Some(k)) = (
            locate(&g.speed, omega, cell[0]),
            locate(&g.dp, dp, cell[1]),
            locate(&g.temp, temp_k, cell[2]),
        ) else {
            // outside the grid: speed extrapolated, the rest held
            *out = self.eval_lagrange(omega, dp, temp_k, harmonics);
            return;
        };
        *cell = [i, j, k];
        let w = &self.inverse_width;
        let (u, v, t) = (
            (omega - g.speed[i]) * w[0][i],
            (dp - g.dp[j]) * w[1][j],
            (temp_k - g.temp[k]) * w[2][k],
        );
        let at = (i * (g.dp.len() - 1) + j) * (g.temp.len() - 1) + k;
        let mean = horner(&self.cell_means[at], u, v, t);
        let harm = if harmonics {
            horner(&self.cell_harmonics[at], u, v, t)
        } else {
            [0.0; HARMONIC_VALUES]
        };
        (out.q_out, out.q_in, out.torque, out.p_pocket_min) = (mean[0], mean[1], mean[2], mean[3]);
        out.q_harmonics = pairs(&harm, 0);
        out.torque_harmonics = pairs(&harm, T_HARM - Q_HARM);
        out.outside = false;
        out.flagged = self.cell_flagged[at];
    }

    /// [`eval_with`](Self::eval_with) by the Lagrange weights of the nodes
    /// around the point (outside the grid, and the reference of the cells'
    /// polynomials in the tests).
    fn eval_lagrange(&self, omega: f64, dp: f64, temp_k: f64, harmonics: bool) -> MapValues {
        let g = &self.grid;
        let (ns, nd, nt) = (g.speed.len(), g.dp.len(), g.temp.len());
        let (fi, wi, _, oi) = weights_with(&g.speed, Some(&self.inverse[0]), omega, true);
        let (fj, wj, _, oj) = weights_with(&g.dp, Some(&self.inverse[1]), dp, false);
        let (fk, wk, _, ok) = weights_with(&g.temp, Some(&self.inverse[2]), temp_k, false);
        let ntp = nt.max(4);
        // the 16 (speed, dp) rows of four temperatures each (weights 0 past
        // an axis's end)
        let at_i = [0, 1, 2, 3].map(|a| (fi + a).min(ns - 1) * nd * ntp);
        let at_j = [0, 1, 2, 3].map(|b| (fj + b).min(nd - 1) * ntp + fk);
        let (mut rows, mut row_w) = ([0usize; 16], [0.0f64; 16]);
        for a in 0..4 {
            for b in 0..4 {
                rows[4 * a + b] = at_i[a] + at_j[b];
                row_w[4 * a + b] = wi[a] * wj[b];
            }
        }
        let mean = contract(&self.means, &rows, &row_w, &wk);
        let harm = if harmonics {
            contract(&self.harmonics, &rows, &row_w, &wk)
        } else {
            [0.0; HARMONIC_VALUES]
        };
        let window = |first: usize, n: usize| first.min(n.saturating_sub(4));
        let flagged = self.flagged_window[(window(fi, ns) * self.windows[1] + window(fj, nd))
            * self.windows[2]
            + window(fk, nt)];
        MapValues {
            q_out: mean[0],
            q_in: mean[1],
            torque: mean[2],
            p_pocket_min: mean[3],
            q_harmonics: pairs(&harm, 0),
            torque_harmonics: pairs(&harm, T_HARM - Q_HARM),
            outside: oi || oj || ok,
            flagged,
        }
    }

    /// The map as bytes (CBOR), with its key.
    pub fn to_bytes(&self) -> Vec<u8> {
        let stored = Stored {
            format: MAP_FORMAT,
            key: self.key.0,
            speed: self.grid.speed.clone(),
            dp: self.grid.dp.clone(),
            temp: self.grid.temp.clone(),
            p_in: self.grid.p_in,
            values: self.values.clone(),
        };
        let mut bytes = Vec::new();
        ciborium::into_writer(&stored, &mut bytes).expect("writing to a Vec does not fail");
        bytes
    }

    /// A stored map, refused unless its key is `key` and its content fits
    /// its grid.
    pub fn from_bytes(bytes: &[u8], key: Fingerprint) -> Result<PumpMap, MapError> {
        let s: Stored = ciborium::from_reader(bytes)
            .map_err(|e| MapError::Stored(format!("not a pump map ({e})")))?;
        if s.format != MAP_FORMAT {
            return Err(MapError::Stored(format!(
                "format {}, this build reads {MAP_FORMAT}",
                s.format
            )));
        }
        if s.key != key.0 {
            return Err(MapError::Stored(format!(
                "a map of another pump, sample or grid (key {} against {key})",
                Fingerprint(s.key)
            )));
        }
        let grid = MapGrid {
            speed: s.speed,
            dp: s.dp,
            temp: s.temp,
            p_in: s.p_in,
        };
        grid.check()?;
        if s.values.len() != grid.len() * VALUES || !s.values.iter().all(|x| x.is_finite()) {
            return Err(MapError::Stored(format!(
                "{} values for {} nodes",
                s.values.len(),
                grid.len()
            )));
        }
        Ok(PumpMap::new(grid, key, s.values))
    }
}

#[derive(serde::Serialize, serde::Deserialize)]
struct Stored {
    format: u64,
    key: u64,
    speed: Vec<f64>,
    dp: Vec<f64>,
    temp: Vec<f64>,
    p_in: f64,
    values: Vec<f64>,
}

/// The mesh ripple of `harmonics` averaged over the driving angle from
/// `theta0` to `theta1` (rad; `z` teeth on the driving gear), and its value
/// at `theta1`. Over a zero-length interval the average is the value.
pub fn ripple(harmonics: &[[f64; 2]; HARMONICS], z: f64, theta0: f64, theta1: f64) -> (f64, f64) {
    let [r] = ripple_between(
        [harmonics],
        z * (theta1 - theta0),
        (z * theta0).sin_cos(),
        (z * theta1).sin_cos(),
    );
    r
}

/// [`ripple`] of several sets of harmonics at once (the flow's and the
/// torque's) from the mesh angle's span `z (theta1 - theta0)` and the
/// (sin, cos) of `z theta0` and `z theta1`: the higher harmonics by angle
/// addition, one reciprocal of the span for all (one `sin_cos` per step
/// when the caller keeps the last one, none when it rotates it).
pub fn ripple_between<const N: usize>(
    sets: [&[[f64; 2]; HARMONICS]; N],
    span: f64,
    e0: (f64, f64),
    e1: (f64, f64),
) -> [(f64, f64); N] {
    let mut out = [(0.0, 0.0); N];
    let (mut s0, mut c0) = e0;
    let (mut s1, mut c1) = e1;
    let per_span = 1.0 / span;
    for k in 0..HARMONICS {
        let m = (k + 1) as f64;
        // mean of c cos(m φ) + s sin(m φ) over the interval (its value
        // when the interval is too short to divide by)
        let spread = span.abs() * m > 1e-9;
        let per = per_span / m;
        for (set, (mean, end)) in sets.iter().zip(out.iter_mut()) {
            let [c, s] = set[k];
            let value = c * c1 + s * s1;
            *end += value;
            *mean += if spread {
                (c * (s1 - s0) - s * (c1 - c0)) * per
            } else {
                value
            };
        }
        // to harmonic k + 2: (cos, sin)(m φ + φ)
        (s0, c0) = (s0 * e0.1 + c0 * e0.0, c0 * e0.1 - s0 * e0.0);
        (s1, c1) = (s1 * e1.1 + c1 * e1.0, c1 * e1.1 - s1 * e1.0);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// The local cubic reproduces cubics exactly on a non-uniform axis and
    /// straight lines outside when extrapolating.
    #[test]
    fn weights_reproduce_cubics_and_lines() {
        let axis = [1.0, 1.5, 2.5, 3.0, 4.5, 6.0];
        let f = |x: f64| 2.0 - x + 0.5 * x * x - 0.1 * x * x * x;
        for x in [1.0, 1.2, 2.0, 2.9, 3.7, 5.9, 6.0] {
            let (i, w, m, out) = weights(&axis, x, false);
            assert!(!out);
            let y: f64 = (0..m).map(|a| w[a] * f(axis[i + a])).sum();
            assert!((y - f(x)).abs() < 1e-12, "{x}: {y} against {}", f(x));
        }
        // the precomputed denominators give the same weights, on axes of
        // 2, 3 and more nodes
        for ax in [&axis[..], &axis[..3], &axis[..2]] {
            let inv = inverse_denominators(ax);
            for x in [1.0, 1.2, 1.4, 1.5, 2.0, 2.9, 3.7, 5.9, 6.0] {
                let (i, w, m, _) = weights(ax, x, false);
                let (j, v, n, _) = weights_with(ax, Some(&inv), x, false);
                assert_eq!((i, m), (j, n));
                for a in 0..m {
                    assert!((w[a] - v[a]).abs() < 1e-12, "{x}: {w:?} {v:?}");
                }
            }
        }
        let g = |x: f64| 3.0 * x - 1.0;
        for x in [0.2, 7.5] {
            let (i, w, m, out) = weights(&axis, x, true);
            assert!(out);
            let y: f64 = (0..m).map(|a| w[a] * g(axis[i + a])).sum();
            assert!((y - g(x)).abs() < 1e-12);
        }
    }

    /// A map whose node values are polynomials of degree three in each
    /// axis (tensor products, on non-uniform axes) returns them exactly
    /// between its nodes, every value and harmonic in its place; outside,
    /// speed follows the straight line of the two end nodes and the other
    /// axes are held at the edge.
    #[test]
    fn eval_reproduces_tricubic_polynomials() {
        let grid = MapGrid {
            speed: vec![50.0, 80.0, 130.0, 200.0, 300.0, 420.0],
            dp: vec![0.0, 1.0e6, 2.5e6, 4.0e6, 7.0e6, 1.0e7, 1.5e7],
            temp: vec![293.0, 303.0, 318.0, 333.0, 353.0],
            p_in: 1.0e5,
        };
        // value v at (w, d, t): a different tricubic for each v
        let f = |v: usize, w: f64, d: f64, t: f64| {
            let (x, y, z) = (w / 100.0, d / 1.0e6, (t - 300.0) / 20.0);
            let c = v as f64 + 1.0;
            (1.0 + c * x - 0.3 * x * x * x / c)
                * (2.0 - 0.1 * c * y + 0.01 * y * y * y)
                * (0.5 + z - 0.2 * c * z * z + 0.05 * z * z * z)
        };
        let mut values = Vec::new();
        for n in 0..grid.len() {
            let (w, d, t) = grid.node(n);
            for v in 0..VALUES {
                // the flag stays 0 (it is not interpolated)
                values.push(if v == FLAGGED { 0.0 } else { f(v, w, d, t) });
            }
        }
        let map = PumpMap::new(grid.clone(), Fingerprint(0), values);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-11 * (1.0 + b.abs());
        for (w, d, t) in [
            (50.0, 0.0, 293.0),
            (61.0, 0.3e6, 296.5),
            (123.4, 5.5e6, 340.0),
            (299.0, 1.2e7, 352.0),
            (420.0, 1.5e7, 353.0),
        ] {
            let m = map.eval(w, d, t);
            assert!(!m.outside && !m.flagged);
            let want = |v| f(v, w, d, t);
            assert!(close(m.q_out, want(Q_OUT)), "q_out at {w} {d} {t}");
            assert!(close(m.q_in, want(Q_IN)));
            assert!(close(m.torque, want(TORQUE)));
            assert!(close(m.p_pocket_min, want(P_MIN)));
            for k in 0..HARMONICS {
                for p in 0..2 {
                    assert!(close(m.q_harmonics[k][p], want(Q_HARM + 2 * k + p)));
                    assert!(close(m.torque_harmonics[k][p], want(T_HARM + 2 * k + p)));
                }
            }
            // without the harmonics, the same means
            let n = map.eval_with(w, d, t, false);
            assert_eq!((n.q_out, n.torque), (m.q_out, m.torque));
            assert_eq!(n.q_harmonics, [[0.0; 2]; HARMONICS]);
        }
        // outside: speed on the line through the two end nodes, the rest held
        // at the edge they are beyond
        let (s, n) = (&grid.speed, grid.speed.len());
        let (d_lo, d_hi) = (grid.dp[0], grid.dp[grid.dp.len() - 1]);
        let (t_lo, t_hi) = (grid.temp[0], grid.temp[grid.temp.len() - 1]);
        for (w, d, t, dh, th) in [
            (1.2 * s[n - 1], 1.3 * d_hi, t_hi + 7.0, d_hi, t_hi),
            (0.4 * s[0], d_lo - 1.0e5, t_lo - 13.0, d_lo, t_lo),
        ] {
            let m = map.eval(w, d, t);
            assert!(m.outside);
            let (a, b) = if w > s[n - 1] {
                (s[n - 2], s[n - 1])
            } else {
                (s[0], s[1])
            };
            let line = f(TORQUE, a, dh, th)
                + (w - a) / (b - a) * (f(TORQUE, b, dh, th) - f(TORQUE, a, dh, th));
            assert!(close(m.torque, line), "{w}: {} against {line}", m.torque);
        }
    }

    /// The cells' polynomials give what the Lagrange weights of the nodes
    /// around the point give (values that are no polynomial, non-uniform
    /// axes, axes of two and three nodes, a flagged node), on the nodes,
    /// on the cells' edges and between.
    #[test]
    fn cell_polynomials_are_the_lagrange_interpolant() {
        let axes = [
            vec![50.0, 80.0, 130.0, 200.0, 300.0, 420.0],
            vec![0.0, 1.0e6, 2.5e6, 4.0e6, 7.0e6, 1.0e7, 1.5e7],
            vec![293.0, 303.0, 318.0],
            vec![293.0, 318.0],
        ];
        for temp in [&axes[2], &axes[3], &axes[0]] {
            let grid = MapGrid {
                speed: axes[0].clone(),
                dp: axes[1].clone(),
                temp: temp.clone(),
                p_in: 1.0e5,
            };
            let mut values = Vec::new();
            for n in 0..grid.len() {
                let (w, d, t) = grid.node(n);
                for v in 0..VALUES {
                    let c = v as f64 + 1.0;
                    values.push(if v == FLAGGED {
                        f64::from(n == 17)
                    } else {
                        (c * w / 300.0).sin() * (-d / 1.0e7).exp() + (t / 300.0).ln() * c
                    });
                }
            }
            let map = PumpMap::new(grid.clone(), Fingerprint(0), values);
            let along = |a: &[f64], s: f64| {
                let n = a.len();
                let x = s * (n - 1) as f64;
                let i = (x.floor() as usize).min(n - 2);
                a[i] + (x - i as f64) * (a[i + 1] - a[i])
            };
            let (mut flagged, mut last) = (0, [0; 3]);
            for n in 0..=600 {
                // a lattice through nodes, edges and interiors
                let s = |b: usize| ((n * b) % 601) as f64 / 600.0;
                let (w, d, t) = (
                    along(&grid.speed, s(7)),
                    along(&grid.dp, s(13)),
                    along(&grid.temp, s(29)),
                );
                for harm in [true, false] {
                    // from no hint, from the last point's cell (a jump), and
                    // from a neighbouring cell
                    let a = map.eval_with(w, d, t, harm);
                    for hint in [&mut last, &mut [1, 2, 1]] {
                        let mut b = MapValues::default();
                        map.eval_into(w, d, t, harm, hint, &mut b);
                        assert_eq!(a, b, "at {w} {d} {t} from the cell {hint:?}");
                    }
                    let b = map.eval_lagrange(w, d, t, harm);
                    let close = |x: f64, y: f64| (x - y).abs() <= 1e-12 * (1.0 + y.abs());
                    let (xs, ys) = (
                        [a.q_out, a.q_in, a.torque, a.p_pocket_min],
                        [b.q_out, b.q_in, b.torque, b.p_pocket_min],
                    );
                    for (x, y) in xs.iter().zip(&ys) {
                        assert!(close(*x, *y), "at {w} {d} {t}: {x} against {y}");
                    }
                    for k in 0..HARMONICS {
                        for p in 0..2 {
                            assert!(close(a.q_harmonics[k][p], b.q_harmonics[k][p]));
                            assert!(close(a.torque_harmonics[k][p], b.torque_harmonics[k][p]));
                        }
                    }
                    assert_eq!((a.outside, a.flagged), (b.outside, b.flagged));
                    flagged += usize::from(a.flagged);
                }
            }
            assert!(flagged > 0, "the flagged node is reached");
        }
    }

    /// The ripple's mean over whole mesh periods is zero, and over a short
    /// interval it tends to the value.
    #[test]
    fn ripple_means() {
        let h = [[1.0, 0.5], [0.2, -0.3], [0.05, 0.01]];
        let z = 14.0;
        let period = 2.0 * PI / z;
        let (mean, _) = ripple(&h, z, 0.3, 0.3 + 3.0 * period);
        assert!(mean.abs() < 1e-12, "{mean}");
        let (mean, end) = ripple(&h, z, 0.3, 0.3 + 1e-7);
        assert!((mean - end).abs() < 1e-4, "{mean} {end}");
        // against the sum of the harmonics written out, by quadrature
        let f = |t: f64| {
            h.iter()
                .enumerate()
                .map(|(k, [c, s])| {
                    let m = (k + 1) as f64 * z;
                    c * (m * t).cos() + s * (m * t).sin()
                })
                .sum::<f64>()
        };
        let (a, b) = (0.1, 0.1 + 0.37 * period);
        let n = 20_000;
        let quad = (0..n)
            .map(|i| f(a + (i as f64 + 0.5) * (b - a) / n as f64))
            .sum::<f64>()
            / n as f64;
        let (mean, end) = ripple(&h, z, a, b);
        assert!((mean - quad).abs() < 1e-8, "{mean} {quad}");
        assert!((end - f(b)).abs() < 1e-12, "{end} {}", f(b));
    }
}
