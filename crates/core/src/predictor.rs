//! Starting points of an angular step's iterations from the last mesh period.
//!
//! The pump repeats itself every mesh period: the look-up tables span one
//! base pitch and the pockets are relabelled at its end, so that node `i`
//! at step index `s` plays the same part in every period. At steady inputs
//! each step therefore repeats the step with the same index a period
//! earlier, and the events that make a step hard to predict from the two
//! before it (a pocket opening to a port or sealing, a tooth pair entering
//! or leaving contact, the jump of the mesh force's line of action) fall on
//! the same step index in every period.
//!
//! [`PeriodHistory`] keeps, for every step index of the last period, how
//! much every node pressure changed over that step and how much the
//! equilibrium position of the gear centres changed. The periodic
//! prediction of a step is the state it starts from plus the change the
//! same step made a period earlier: exact in the periodic steady state, and
//! still close while the inputs drift slowly. The other prediction is the
//! linear extrapolation from the two previous steps (`model`), which knows
//! nothing of the events but follows a fast change of the inputs. Each
//! quantity (pressures, centre offsets) takes, at every step, the
//! prediction that has missed the accepted solutions of the recent steps
//! by less: both are computed at every step, and their misses summed with
//! weights that fall by [`MEMORY`] per step, so that the large miss of
//! the linear prediction at an event outweighs its slight advantages
//! between events for a few steps. Ties go to the periodic prediction.
//!
//! A prediction is only the iterations' starting point: the accepted
//! solution meets the same Newton and micromotion tolerances wherever it
//! starts. The history is part of the simulation's state (an FMU state
//! carries it) so that a resumed run steps to the same bits.

use crate::vec2::norm;
use std::collections::VecDeque;
use std::sync::Arc;

/// Gear centre offsets from the bore centres (driving, driven gear; x, y), m.
pub type Offsets = [[f64; 2]; 2];

/// One quantity over a step: the value the step started from, its linear
/// prediction, its periodic prediction (None while the step's index had
/// not been recorded) and the accepted value at the step's end.
#[derive(Debug, Clone, Copy)]
pub struct StepValues<'a, T: ?Sized> {
    pub start: &'a T,
    pub linear: &'a T,
    pub periodic: Option<&'a T>,
    pub accepted: &'a T,
}

/// The weight of a step's miss in the sums that choose between the
/// predictions falls by this factor per step (a memory of about four
/// steps).
pub const MEMORY: f64 = 0.75;

/// The changes over every step of the last mesh period (see the module
/// docs).
///
/// Each step index's changes are one [`Entry`] shared by `Arc`: a copy of
/// the history (a simulation's snapshot, taken at every co-simulation
/// call) shares the entries instead of copying them, and a step that
/// records into an entry a copy still holds writes a fresh one (copy on
/// write), taken from the entries replaced earlier once no copy holds them
/// any more, so that stepping allocates nothing at the periodic state.
#[derive(Debug)]
pub struct PeriodHistory {
    /// Nodes per step.
    n: usize,
    /// The changes over every step index.
    entries: Vec<Arc<Entry>>,
    /// The weighted sums of the misses of the pressure predictions (linear,
    /// periodic), Pa; the periodic one is taken while its sum is not the
    /// larger.
    miss_x: [f64; 2],
    /// The same for the centre offsets, m.
    miss_e: [f64; 2],
    /// Entries replaced while a copy of the history may still hold them,
    /// oldest first, reused once none does (storage, not content: a copy
    /// starts without any, and comparisons ignore them).
    retired: VecDeque<Arc<Entry>>,
}

/// The changes over one step index.
#[derive(Debug, PartialEq)]
struct Entry {
    /// Pressure change of every node over the step, Pa (`n` values).
    dx: Vec<f64>,
    /// Change of the equilibrium centre offsets over the step, m.
    de: Offsets,
    /// Whether the step index has been recorded since the start.
    recorded: bool,
}

/// The most replaced entries a history keeps for reuse, per step index
/// (the FMU's undo copy and its partly covered step's copy each hold up to
/// a period of entries that the live history has replaced).
const RETIRED_PER_STEP: usize = 4;

impl PartialEq for PeriodHistory {
    /// The content: the replaced entries kept for reuse do not count.
    fn eq(&self, other: &Self) -> bool {
        self.n == other.n
            && self.miss_x == other.miss_x
            && self.miss_e == other.miss_e
            && self.entries.len() == other.entries.len()
            && self
                .entries
                .iter()
                .zip(&other.entries)
                .all(|(a, b)| Arc::ptr_eq(a, b) || a == b)
    }
}

impl Clone for PeriodHistory {
    /// Shares the entries (see [`PeriodHistory`]).
    fn clone(&self) -> Self {
        PeriodHistory {
            n: self.n,
            entries: self.entries.clone(),
            miss_x: self.miss_x,
            miss_e: self.miss_e,
            retired: VecDeque::new(),
        }
    }

    /// Shares the entries, reusing this history's storage (a snapshot of
    /// the simulation copies it at every co-simulation call): only the
    /// entries that differ are replaced, and replaced ones are dropped (a
    /// copy keeps no retired entries; see [`restore_from`](Self::restore_from)
    /// for the live history).
    fn clone_from(&mut self, source: &Self) {
        self.n = source.n;
        share(&mut self.entries, &source.entries);
        self.miss_x = source.miss_x;
        self.miss_e = source.miss_e;
    }
}

/// `dst` shares the entries of `src`, reusing its storage and replacing
/// only the entries that differ.
fn share<T>(dst: &mut Vec<Arc<T>>, src: &[Arc<T>]) {
    if dst.len() != src.len() {
        dst.clear();
        dst.extend(src.iter().cloned());
        return;
    }
    for (d, s) in dst.iter_mut().zip(src) {
        if !Arc::ptr_eq(d, s) {
            *d = Arc::clone(s);
        }
    }
}

impl PeriodHistory {
    /// An empty history of `nsteps` step indices of `n` nodes.
    pub fn new(nsteps: usize, n: usize) -> Self {
        PeriodHistory {
            n,
            entries: (0..nsteps)
                .map(|_| {
                    Arc::new(Entry {
                        dx: vec![0.0; n],
                        de: [[0.0; 2]; 2],
                        recorded: false,
                    })
                })
                .collect(),
            miss_x: [0.0; 2],
            miss_e: [0.0; 2],
            retired: VecDeque::new(),
        }
    }

    /// [`clone_from`](Clone::clone_from) for the live history (a simulation
    /// restored from a snapshot): the entries replaced are kept for reuse,
    /// as a step's are.
    pub fn restore_from(&mut self, source: &Self) {
        self.n = source.n;
        self.miss_x = source.miss_x;
        self.miss_e = source.miss_e;
        if self.entries.len() != source.entries.len() {
            self.retired.clear();
            self.entries.clone_from(&source.entries);
            return;
        }
        let cap = RETIRED_PER_STEP * self.entries.len();
        for (d, s) in self.entries.iter_mut().zip(&source.entries) {
            if Arc::ptr_eq(d, s) {
                continue;
            }
            // an entry in use again is no longer for reuse (it would be
            // retired twice when next replaced)
            if let Some(i) = self.retired.iter().position(|r| Arc::ptr_eq(r, s)) {
                self.retired.remove(i);
            }
            let old = std::mem::replace(d, Arc::clone(s));
            if self.retired.len() < cap {
                self.retired.push_back(old);
            }
        }
    }

    /// Step index `s`'s entry, to be written by [`record`](Self::record):
    /// a fresh one while a copy of the history shares it, holding the
    /// entry's offset changes and recorded flag but arbitrary pressure
    /// changes (`record` overwrites them all).
    fn entry_mut(&mut self, s: usize) -> &mut Entry {
        if Arc::get_mut(&mut self.entries[s]).is_none() {
            // the oldest retired entries are the likeliest to be free
            let free = match self.retired.front() {
                Some(e) if Arc::strong_count(e) == 1 => self.retired.pop_front(),
                _ => match self.retired.iter().position(|e| Arc::strong_count(e) == 1) {
                    Some(i) => self.retired.remove(i),
                    None => None,
                },
            };
            let mut fresh = match free {
                Some(e) => e,
                None => Arc::new(Entry {
                    dx: Vec::new(),
                    de: [[0.0; 2]; 2],
                    recorded: false,
                }),
            };
            let f = Arc::get_mut(&mut fresh).expect("held by no copy");
            f.dx.resize(self.n, 0.0);
            f.de = self.entries[s].de;
            f.recorded = self.entries[s].recorded;
            let old = std::mem::replace(&mut self.entries[s], fresh);
            if self.retired.len() < RETIRED_PER_STEP * self.entries.len() {
                self.retired.push_back(old);
            }
        }
        Arc::get_mut(&mut self.entries[s]).expect("held by no copy")
    }

    /// The history from its parts (as [`parts`](Self::parts) gives them):
    /// `recorded` has one entry per step index, `dx` `n` pressure changes
    /// and `de` four offset changes per step index, `misses` the four
    /// weighted misses (pressures linear, periodic; offsets linear,
    /// periodic), all finite and the misses not negative; otherwise an
    /// error that names what does not fit.
    pub fn from_parts(
        n: usize,
        dx: Vec<f64>,
        de: &[f64],
        recorded: Vec<bool>,
        misses: [f64; 4],
    ) -> Result<Self, String> {
        let nsteps = recorded.len();
        if dx.len() != nsteps.saturating_mul(n) || de.len() != 4 * nsteps {
            return Err(format!(
                "{} pressure and {} offset changes for {nsteps} steps of {n} nodes",
                dx.len(),
                de.len()
            ));
        }
        if !dx.iter().chain(de).all(|v| v.is_finite()) {
            return Err("a non-finite change".into());
        }
        if !misses.iter().all(|m| m.is_finite() && *m >= 0.0) {
            return Err(format!("prediction misses {misses:?}"));
        }
        Ok(PeriodHistory {
            n,
            entries: (0..nsteps)
                .map(|s| {
                    let c = &de[4 * s..4 * s + 4];
                    Arc::new(Entry {
                        dx: dx[s * n..(s + 1) * n].to_vec(),
                        de: [[c[0], c[1]], [c[2], c[3]]],
                        recorded: recorded[s],
                    })
                })
                .collect(),
            miss_x: [misses[0], misses[1]],
            miss_e: [misses[2], misses[3]],
            retired: VecDeque::new(),
        })
    }

    /// The parts [`from_parts`](Self::from_parts) takes: the nodes, the
    /// pressure changes, the offset changes (four per step index), which
    /// step indices are recorded, and the weighted misses.
    pub fn parts(&self) -> (usize, Vec<f64>, Vec<f64>, Vec<bool>, [f64; 4]) {
        (
            self.n,
            self.entries
                .iter()
                .flat_map(|e| e.dx.iter().copied())
                .collect(),
            self.entries
                .iter()
                .flat_map(|e| e.de.iter().flatten().copied())
                .collect(),
            self.entries.iter().map(|e| e.recorded).collect(),
            [
                self.miss_x[0],
                self.miss_x[1],
                self.miss_e[0],
                self.miss_e[1],
            ],
        )
    }

    /// Step indices per period.
    pub fn steps(&self) -> usize {
        self.entries.len()
    }

    /// Nodes per step.
    pub fn nodes(&self) -> usize {
        self.n
    }

    /// Whether step index `s` has been recorded (a periodic prediction
    /// exists for it).
    pub fn has(&self, s: usize) -> bool {
        self.entries[s].recorded
    }

    /// Whether the pressures of the next step start from the periodic
    /// prediction (when [`has`](Self::has) it).
    pub fn prefers_periodic_pressures(&self) -> bool {
        self.miss_x[1] <= self.miss_x[0]
    }

    /// The same for the centre offsets.
    pub fn prefers_periodic_offsets(&self) -> bool {
        self.miss_e[1] <= self.miss_e[0]
    }

    /// The periodic prediction of the pressures at the end of step `s` from
    /// the pressures `start` it starts from, written to `out`; each node is
    /// held above the lower of its start pressure and `p_low` (the lower
    /// port pressure) less `p_low`: a change recorded at other inputs (a
    /// period at a higher delivery pressure) takes a start above the
    /// suction no lower than zero absolute, while pockets that the seed
    /// pump empties within a step at 4000 rpm, 30 bar, 60 degC (the driven
    /// gear's last from 1.3 bar to 0.4 bar) or fills under cavitation
    /// (the oil law lets the driving gear's fall to -4.6 kPa absolute) are
    /// predicted as they were a period earlier. Half the lower of the two,
    /// the bound before, clipped those predictions: 11 of the 51 steps of
    /// every period started 0.5-12 kPa off and took two to four Newton
    /// iterations, one of them with a fresh Jacobian. Step `s` must have
    /// been recorded.
    pub fn predict_pressures(&self, s: usize, start: &[f64], p_low: f64, out: &mut [f64]) {
        let d = &self.entries[s].dx;
        for ((o, &x0), &dx) in out.iter_mut().zip(start).zip(d) {
            *o = periodic(x0, dx, p_low);
        }
    }

    /// The periodic prediction of the equilibrium offsets at step `s` from
    /// the ones the step before handed on. Step `s` must have been recorded.
    pub fn predict_offsets(&self, s: usize, handed_on: &Offsets) -> Offsets {
        let d = &self.entries[s].de;
        [0, 1].map(|k| [0, 1].map(|a| handed_on[k][a] + d[k][a]))
    }

    /// Records step `s` from its pressures (start, predictions, accepted
    /// solution) and, with micromotion, its equilibrium offsets (the ones
    /// handed on to it, their predictions, the equilibrium of its accepted
    /// loads). Where the step had a periodic prediction, the misses of both
    /// predictions of each quantity enter its weighted sums (see the module
    /// docs).
    pub fn record(
        &mut self,
        s: usize,
        x: StepValues<'_, [f64]>,
        e: Option<StepValues<'_, Offsets>>,
    ) {
        if let Some(periodic) = x.periodic {
            let (mut linear_miss, mut periodic_miss) = (0.0_f64, 0.0_f64);
            // the largest misses by comparison: as `f64::max` here (a NaN
            // miss leaves the running maximum, which starts at 0 and is
            // never NaN, as it was), one instruction instead of its
            // NaN-handling sequence
            let max = |m: f64, d: f64| if d > m { d } else { m };
            for ((&p, &linear), &accepted) in periodic.iter().zip(x.linear).zip(x.accepted) {
                periodic_miss = max(periodic_miss, (p - accepted).abs());
                linear_miss = max(linear_miss, (linear - accepted).abs());
            }
            self.miss_x = [
                MEMORY * self.miss_x[0] + linear_miss,
                MEMORY * self.miss_x[1] + periodic_miss,
            ];
        }
        if let Some(e) = e {
            if let Some(periodic) = e.periodic {
                let miss = |p: &Offsets| {
                    (0..2)
                        .map(|k| norm(p[k][0] - e.accepted[k][0], p[k][1] - e.accepted[k][1]))
                        .fold(0.0, f64::max)
                };
                self.miss_e = [
                    MEMORY * self.miss_e[0] + miss(e.linear),
                    MEMORY * self.miss_e[1] + miss(periodic),
                ];
            }
        }
        debug_assert!(
            x.accepted.len() == self.n && x.start.len() == self.n,
            "a step of {} nodes recorded in a history of {}",
            x.accepted.len(),
            self.n
        );
        let entry = self.entry_mut(s);
        for ((d, &a), &x0) in entry.dx.iter_mut().zip(x.accepted).zip(x.start) {
            *d = a - x0;
        }
        if let Some(e) = e {
            entry.de = [0, 1].map(|k| [0, 1].map(|a| e.accepted[k][a] - e.start[k][a]));
        }
        entry.recorded = true;
    }
}

/// The periodic prediction of one pressure: `x0` plus the change `dx`,
/// held above the lower of `x0` and `p_low` less `p_low`. The lower and
/// the higher by comparison, the values `f64::min` and `f64::max` give for
/// a finite `p_low` (an input, checked finite; a zero's sign aside): a NaN
/// `x0` or `x0 + dx` gives way to the other operand either way; one
/// instruction each instead of the NaN-handling sequences.
#[inline]
fn periodic(x0: f64, dx: f64, p_low: f64) -> f64 {
    let (v, low) = (x0 + dx, if x0 < p_low { x0 } else { p_low });
    let bound = low - p_low;
    if v > bound {
        v
    } else {
        bound
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const N: usize = 2;
    const STEPS: usize = 5;

    /// A periodic signal of period STEPS with a jump at step 3 (an event),
    /// at step `k` since the start, plus a drift `a k^2` that steepens.
    fn signal(k: usize, a: f64) -> [f64; N] {
        let base = if k % STEPS >= 3 { 2.0e5 } else { 1.0e5 };
        [base + a * (k * k) as f64, 3.0e6 - base]
    }

    fn offsets(k: usize) -> Offsets {
        let v = if k % STEPS >= 3 { 2.0e-6 } else { 1.0e-6 };
        [[v, -v], [0.5 * v, v]]
    }

    /// Steps the history over `periods` periods of `signal(.., a)`, each
    /// step predicted linearly from the two before; returns, for the last
    /// period, the largest miss of the prediction the history prefers at
    /// each step and that of the periodic prediction.
    fn run(h: &mut PeriodHistory, periods: usize, a: f64) -> (f64, f64) {
        let (mut worst, mut worst_periodic) = (0.0_f64, 0.0_f64);
        for k in 1..periods * STEPS {
            let s = k % STEPS;
            let start = signal(k - 1, a);
            let before = if k >= 2 { signal(k - 2, a) } else { start };
            let linear: Vec<f64> = (0..N).map(|i| 2.0 * start[i] - before[i]).collect();
            let accepted = signal(k, a);
            let (e0, e1) = (offsets(k - 1), offsets(k));
            let e_before = if k >= 2 { offsets(k - 2) } else { e0 };
            let e_lin = [0, 1].map(|g| [0, 1].map(|a| 2.0 * e0[g][a] - e_before[g][a]));
            let mut p = [0.0; N];
            let e_per = h.has(s).then(|| h.predict_offsets(s, &e0));
            if h.has(s) {
                h.predict_pressures(s, &start, 1.0e5, &mut p);
            }
            if k >= (periods - 1) * STEPS && h.has(s) {
                let chosen = if h.prefers_periodic_pressures() {
                    p.to_vec()
                } else {
                    linear.clone()
                };
                for i in 0..N {
                    worst = worst.max((chosen[i] - accepted[i]).abs());
                    worst_periodic = worst_periodic.max((p[i] - accepted[i]).abs());
                }
            }
            h.record(
                s,
                StepValues {
                    start: &start[..],
                    linear: &linear[..],
                    periodic: e_per.is_some().then_some(&p[..]),
                    accepted: &accepted[..],
                },
                Some(StepValues {
                    start: &e0,
                    linear: &e_lin,
                    periodic: e_per.as_ref(),
                    accepted: &e1,
                }),
            );
        }
        (worst, worst_periodic)
    }

    #[test]
    fn the_periodic_bound_by_comparison_is_the_min_max_form() {
        let values = [
            -3.0e5,
            -1.0,
            -0.0,
            0.0,
            2.0e4,
            1.0e5,
            1.01325e5,
            3.1e6,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        for &x0 in &values {
            for &dx in &values {
                for p_low in [0.0, 2.0e4, 1.01325e5, 3.1e6] {
                    let want = (x0 + dx).max(x0.min(p_low) - p_low);
                    let got = periodic(x0, dx, p_low);
                    // (a zero's sign aside: `f64::min` of two zeros may
                    // give either)
                    assert!(
                        got == want || (got.is_nan() && want.is_nan()),
                        "x0 {x0}, dx {dx}, p_low {p_low}: {got} against {want}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_periodic_signal_is_predicted_exactly_after_one_period() {
        let mut h = PeriodHistory::new(STEPS, N);
        assert!((0..STEPS).all(|s| !h.has(s)));
        let (worst, _) = run(&mut h, 3, 0.0);
        assert!((0..STEPS).all(|s| h.has(s)));
        assert!(h.prefers_periodic_pressures() && h.prefers_periodic_offsets());
        assert_eq!(worst, 0.0);
        // the jump at step 3 repeats: the periodic offsets land on it
        let e = h.predict_offsets(3, &offsets(2));
        assert_eq!(e, offsets(3));
    }

    #[test]
    fn the_linear_prediction_is_kept_where_it_does_better() {
        // a drift that steepens (the inputs keep changing): the increments
        // of a period ago fall ever shorter, the linear prediction misses
        // only by the drift's curvature and at the jumps
        let mut h = PeriodHistory::new(STEPS, N);
        let (worst, worst_periodic) = run(&mut h, 6, 1.0e5);
        assert!(
            !h.prefers_periodic_pressures() && worst < 0.5 * worst_periodic,
            "the chosen predictions miss by {worst}, the periodic ones by {worst_periodic}"
        );
        // the offsets repeat exactly: the periodic prediction stays
        assert!(h.prefers_periodic_offsets());
    }

    #[test]
    fn a_stale_change_takes_a_prediction_no_lower_than_the_bound() {
        let mut h = PeriodHistory::new(1, 1);
        h.record(
            0,
            StepValues {
                start: &[3.0e6][..],
                linear: &[3.0e6][..],
                periodic: None,
                accepted: &[1.0e5][..],
            },
            None,
        );
        let mut p = [0.0];
        h.predict_pressures(0, &[2.0e5], 1.0e5, &mut p);
        assert_eq!(p[0], 0.0);
        // from a start below the suction the bound is the suction pressure
        // lower
        h.predict_pressures(0, &[-4.0e3], 1.0e5, &mut p);
        assert_eq!(p[0], -4.0e3 - 1.0e5);
    }

    /// A pocket filling under cavitation (the seed pump's last driving
    /// pocket at 4000 rpm, 30 bar, 60 degC: 1871 Pa at the step's start,
    /// -480 Pa at its end) repeats the change it made a period earlier,
    /// below zero absolute as the oil law has it: half the lower of the
    /// start and the suction, the bound before, held it at 936 Pa.
    #[test]
    fn a_cavitating_pocket_is_predicted_as_it_was_a_period_earlier() {
        let mut h = PeriodHistory::new(1, 1);
        let (start, end) = (1.8713638713889636e3, -4.799167876089336e2);
        h.record(
            0,
            StepValues {
                start: &[start][..],
                linear: &[start][..],
                periodic: None,
                accepted: &[end][..],
            },
            None,
        );
        let mut p = [0.0];
        h.predict_pressures(0, &[start], 1.0e5, &mut p);
        assert!(
            (p[0] - end).abs() <= 1e-12 * start,
            "{} against {end}",
            p[0]
        );
    }

    /// A copy shares the entries and keeps its content while the original
    /// records on; the original reuses the entries no copy holds any more
    /// (no fresh ones once the copies are renewed), and a restore brings
    /// back the copy's content.
    #[test]
    fn copies_keep_their_content_and_replaced_entries_are_reused() {
        let mut h = PeriodHistory::new(STEPS, N);
        run(&mut h, 2, 0.0);
        let mut copy = h.clone();
        let frozen = PeriodHistory::from_parts(
            h.parts().0,
            h.parts().1,
            &h.parts().2,
            h.parts().3,
            h.parts().4,
        )
        .unwrap();
        assert_eq!(copy, frozen);
        run(&mut h, 2, 1.0e5);
        assert_eq!(copy, frozen);
        assert_ne!(h, frozen);
        // every entry was replaced once while the copy held it
        assert_eq!(h.retired.len(), STEPS);
        // renewed, the copy lets the replaced entries go: the next records
        // take them instead of fresh ones
        copy.clone_from(&h);
        assert_eq!(copy, h);
        let before: Vec<*const Entry> = h.retired.iter().map(Arc::as_ptr).collect();
        run(&mut h, 1, 2.0e5);
        let reused = h
            .entries
            .iter()
            .filter(|e| before.contains(&Arc::as_ptr(e)));
        assert_eq!(reused.count(), STEPS - 1);
        // restoring the copy gives its content back
        h.restore_from(&copy);
        assert_eq!(h, copy);
        let mut fresh = PeriodHistory::new(STEPS, N);
        fresh.restore_from(&frozen);
        assert_eq!(fresh, frozen);
    }

    #[test]
    fn parts_round_trip_and_wrong_parts_are_refused() {
        let mut h = PeriodHistory::new(STEPS, N);
        run(&mut h, 2, 0.0);
        let (n, dx, de, recorded, misses) = h.parts();
        let back =
            PeriodHistory::from_parts(n, dx.to_vec(), &de, recorded.to_vec(), misses).unwrap();
        assert_eq!(back, h);
        let short = PeriodHistory::from_parts(n, dx[1..].to_vec(), &de, recorded.to_vec(), misses);
        assert!(short.unwrap_err().contains("pressure and"));
        let mut nan = dx.to_vec();
        nan[0] = f64::NAN;
        let bad = PeriodHistory::from_parts(n, nan, &de, recorded.to_vec(), misses);
        assert!(bad.unwrap_err().contains("non-finite"));
        let negative = PeriodHistory::from_parts(n, dx.to_vec(), &de, recorded.to_vec(), [-1.0; 4]);
        assert!(negative.unwrap_err().contains("misses"));
    }
}
