//! Co-simulation stepping of the LP model ([`CoSimulation`]): a live
//! [`Simulation`] advanced by a time with held inputs, as a system
//! simulation calls it (the FMU, `fmi2::pump`, is a thin adapter on it).
//!
//! * **Step in shaft angle.** The model integrates in driving-gear angle with
//!   a fixed angular step `dθ`; [`advance`](CoSimulation::advance) by `h`
//!   moves the angle by `speed · h`, in general not a whole number of steps.
//! * **Fractional steps, exact conservation.** The delivered volume is a
//!   piecewise-linear function of the angle: over an angular step it grows
//!   linearly by that step's volume `q_out · dθ/ω`. A call that ends inside
//!   an angular step computes that step (from the last whole-step state,
//!   with the current inputs) and delivers the covered fraction of its
//!   volume; the next call delivers the rest (recomputing the step first if
//!   the inputs changed, so the remainder flows at the new inputs). Hence
//!   `Q_out = ΔV / h` and `Σ Q_out · h = V_delivered` to rounding, for any
//!   sequence of step sizes; `torque` is the time-weighted mean of the
//!   angular steps' shaft torque with the same fractions.
//! * **Efficiencies over the last mesh period** of whole angular steps (the
//!   window): `eta_v = V / (D θ / 2π)`, `eta_hm = Σ D Δp dθ / 2π / Σ T dθ`;
//!   the lowest pocket pressure over the same window.
//! * **Flow shape.** `q_out_slope` is the slope of the least-squares
//!   straight line through the delivered flow over the call (the angular
//!   steps' flows, piecewise constant in time): `12/h^3 Σ q_k ∫(s - h/2) ds`
//!   over each covered piece. A unit fed by the pump (a circuit) that takes
//!   `q_out + q_out_slope (s - h/2)` over the call receives the same volume
//!   and the flow's trend within the call: at 2500 rpm a 1 ms call covers
//!   0.58 tooth periods, and the ripple's phase within it decides the
//!   pressure a stiff circuit reaches at its end.
//! * **Pressure sensitivity** ([`CoSimulation::flow_sensitivity`]): the
//!   derivative of the mean delivered flow with respect to the delivery
//!   pressure at the current state and inputs, by a central difference on
//!   the model (documented there); likewise for the other inputs.
//! * **Inlet flow** `q_in` like `q_out`: the suction volume (at suction-line
//!   density) drawn over the call divided by its duration.
//! * **Service laws.** Started or resumed with `design_laws`, the
//!   simulation follows the design's clearance growth and Barus keys
//!   ([`super::service`]): `sample` are then the measured clearances and
//!   the gaps in service follow every change of the inputs.
//! * **Standstill.** Below [`MIN_SPEED`] the gears stand still: a call keeps
//!   the state and delivers nothing (leakage at standstill is not modelled).
//! * **Transactions.** A call that fails leaves everything as it was.
//!
//! The state between calls ([`CoSimState`]) is plain data: the simulation's
//! snapshot at the last whole angular step, the covered fraction of the
//! next step, the delivered volume and the window. A partly covered step is
//! not part of it: it is recomputed from the whole-step state when needed,
//! to the same bits.

use super::{Inputs, ModelError, Options, Pump, SampleClearances, SimSnapshot, Simulation};
use std::collections::VecDeque;
use std::f64::consts::PI;
use std::sync::Arc;
use thiserror::Error;

/// Speed below which the gears are taken to stand still, rad/s.
pub const MIN_SPEED: f64 = 0.01;

/// Most angular steps one call may run (a longer call would block the
/// caller for minutes).
pub const MAX_ANGULAR_STEPS: f64 = 1.0e6;

/// Why a call failed (the state is left as it was).
#[derive(Debug, Error)]
pub enum CoSimError {
    #[error(
        "the step covers {steps:.3e} angular steps of the LP model (speed * h / {dtheta:.3e} rad), \
         more than the limit {MAX_ANGULAR_STEPS:.0e}: use shorter communication steps"
    )]
    TooLong { steps: f64, dtheta: f64 },
    #[error("{0}")]
    Model(#[from] ModelError),
    #[error("non-finite result (Q = {q_out}, torque = {torque})")]
    NonFinite { q_out: f64, torque: f64 },
    #[error("state: {0}")]
    State(String),
}

/// The input a flow sensitivity is taken with respect to
/// ([`CoSimulation::flow_sensitivity`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FlowInput {
    /// Shaft speed, rad/s.
    Speed,
    /// Suction pressure, Pa.
    Suction,
    /// Delivery pressure, Pa.
    Delivery,
    /// Oil temperature, K.
    Temperature,
}

/// One whole angular step in the efficiency window.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowStep {
    /// Delivered volume of the step, m^3.
    pub volume: f64,
    /// Shaft work of the step, T dθ, J.
    pub work: f64,
    /// Ideal work of the step, D Δp dθ / 2π, J.
    pub ideal_work: f64,
    /// Suction volume of the step (at suction-line density), m^3.
    pub inlet_volume: f64,
    /// Lowest pocket pressure at the end of the step, Pa.
    pub p_pocket_min: f64,
}

/// What a call (or the start) gives.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Outputs {
    /// Mean delivered flow over the call, m^3/s.
    pub q_out: f64,
    /// Mean suction flow over the call (at suction-line density), m^3/s.
    pub q_in: f64,
    /// Least-squares slope of the delivered flow over the call, m^3/s^2:
    /// `q_out + q_out_slope (s - h/2)`, `s` the time from the call's start,
    /// is the straight line closest (L2) to the angular steps' flow over
    /// the call; it has the call's mean, so it delivers the call's volume
    /// (module docs, "Flow shape"). 0 at the start and at standstill.
    pub q_out_slope: f64,
    /// Lowest pocket pressure over the window (at the state when the
    /// window is empty), Pa.
    pub p_pocket_min: f64,
    /// Delivered flow of the last angular step touched, m^3/s.
    pub q_out_inst: f64,
    /// Mean shaft torque over the call, N m.
    pub torque: f64,
    /// Efficiencies over the window (0 while it is empty).
    pub eta_v: f64,
    pub eta_hm: f64,
    /// Delivered volume since the start, m^3.
    pub v_delivered: f64,
    /// Driving angle since the start (whole steps plus the covered
    /// fraction), rad.
    pub theta: f64,
    /// Whole angular steps in the window (a full mesh period once the
    /// efficiencies are over one).
    pub window_steps: usize,
    /// A journal bearing was overloaded at an angular step of this call
    /// (at the start: of the mesh period that fills the window).
    pub bearing_overload: bool,
}

/// The state between calls (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct CoSimState {
    /// The simulation at the last whole angular step.
    pub committed: SimSnapshot,
    /// `steps_done` at the start (theta = 0).
    pub k0: u64,
    /// Covered fraction of the next angular step, [0, 1).
    pub frac: f64,
    /// Delivered volume since the start, m^3.
    pub v_total: f64,
    /// Outlet flow of the last whole angular step, m^3/s.
    pub last_q: f64,
    /// The last mesh period of whole angular steps, oldest first.
    pub window: Vec<WindowStep>,
}

/// An angular step computed but only partly covered so far: the live
/// simulation stands after it, `before` is the whole-step state.
#[derive(Debug, Clone)]
struct Pending {
    inputs: Inputs,
    before: SimSnapshot,
    q_out: f64,
    q_in: f64,
    torque: f64,
    overload: bool,
}

/// The co-simulation of one pump sample (see the module docs).
pub struct CoSimulation {
    sim: Simulation,
    k0: u64,
    frac: f64,
    v_total: f64,
    last_q: f64,
    window: VecDeque<WindowStep>,
    pending: Option<Pending>,
    /// The state at the start of the current call, for a failed call.
    undo: Option<SimSnapshot>,
    /// The window and the pending step at the start of the current call,
    /// for a failed call (buffers kept across calls: an FMU stepped at 1 ms
    /// calls `advance` thousands of times a second, and the copies reuse
    /// their storage).
    undo_window: VecDeque<WindowStep>,
    undo_pending: Option<Pending>,
    /// Storage of `undo_pending` while it is `None`.
    undo_kept: Option<Pending>,
    /// A snapshot buffer no longer in use (a pending step's `before` once
    /// the step is covered), reused for the next pending step.
    spare: Option<SimSnapshot>,
}

/// `dst` becomes a copy of `src`, reusing `dst`'s storage, or `kept`'s
/// (where a `dst` no longer needed is put: calls with and without a
/// pending step alternate, and a fresh copy allocated its snapshot's
/// buffers each time).
fn copy_pending(dst: &mut Option<Pending>, src: &Option<Pending>, kept: &mut Option<Pending>) {
    let Some(s) = src else {
        if let Some(d) = dst.take() {
            *kept = Some(d);
        }
        return;
    };
    if dst.is_none() {
        *dst = kept.take();
    }
    match dst {
        Some(d) => {
            d.inputs = s.inputs;
            d.q_out = s.q_out;
            d.q_in = s.q_in;
            d.torque = s.torque;
            d.overload = s.overload;
            d.before.clone_from(&s.before);
        }
        None => *dst = Some(s.clone()),
    }
}

impl std::fmt::Debug for CoSimulation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CoSimulation")
            .field("inputs", self.sim.inputs())
            .field("steps_done", &self.sim.steps_done())
            .field("frac", &self.frac)
            .field("v_total", &self.v_total)
            .finish_non_exhaustive()
    }
}

impl CoSimulation {
    /// Starts at `inputs` (a speed below [`MIN_SPEED`]: standing still, the
    /// state then made at `fallback_speed`). With `periodic` the model first
    /// marches to the periodic steady state and one more mesh period fills
    /// the window; the outputs are that period's, and theta and the
    /// delivered volume start at 0. With `design_laws` the clearances and
    /// the gap viscosity follow the design's service laws, `sample` being
    /// the measured clearances (module docs).
    pub fn start(
        pump: Arc<Pump>,
        mut inputs: Inputs,
        sample: SampleClearances,
        options: Options,
        periodic: bool,
        fallback_speed: f64,
        design_laws: bool,
    ) -> Result<(CoSimulation, Outputs), CoSimError> {
        let standstill = inputs.omega < MIN_SPEED;
        if standstill {
            inputs.omega = fallback_speed;
        }
        let in_service = if design_laws {
            pump.service_clearances(sample, &inputs)
        } else {
            sample
        };
        let mut sim = Simulation::new(Arc::clone(&pump), inputs, in_service, options)?;
        if design_laws {
            sim.follow_design_laws(sample)?;
        }
        let mut cs = CoSimulation {
            k0: 0,
            frac: 0.0,
            v_total: 0.0,
            last_q: 0.0,
            window: VecDeque::with_capacity(pump.steps_per_period()),
            pending: None,
            undo: None,
            undo_window: VecDeque::with_capacity(pump.steps_per_period()),
            undo_pending: None,
            undo_kept: None,
            spare: None,
            sim: {
                if periodic && !standstill {
                    sim.run_periodic()?;
                }
                sim
            },
        };
        let mut out = Outputs::default();
        if periodic && !standstill {
            let (mut v, mut vin, mut tw) = (0.0, 0.0, 0.0);
            let dt = pump.tables.dtheta / inputs.omega;
            for _ in 0..pump.steps_per_period() {
                let o = cs.sim.step()?;
                out.bearing_overload |= o.bearing_overload;
                v += o.q_out * dt;
                vin += o.q_in * dt;
                tw += o.torque * dt;
                cs.last_q = o.q_out;
                let p_min = cs.sim.lowest_pocket_pressure();
                cs.push_window(&inputs, o.q_out, o.q_in, o.torque, p_min);
            }
            let period = pump.steps_per_period() as f64 * dt;
            out.q_out = v / period;
            out.q_in = vin / period;
            out.torque = tw / period;
            out.q_out_inst = cs.last_q;
        }
        cs.k0 = cs.sim.steps_done();
        cs.fill_window_outputs(&mut out);
        Ok((cs, out))
    }

    /// The simulation (at the last whole step or after a partly covered one).
    pub fn simulation(&self) -> &Simulation {
        &self.sim
    }

    /// Advances by `h` seconds at `inputs` held over the call (see the
    /// module docs); on failure the state is left as it was.
    pub fn advance(&mut self, inputs: Inputs, h: f64) -> Result<Outputs, CoSimError> {
        let mut out = Outputs {
            v_delivered: self.v_total,
            ..Outputs::default()
        };
        if inputs.omega < MIN_SPEED {
            // standstill: the partly covered step's inputs no longer hold
            if let Some(p) = self.pending.take() {
                self.sim.restore(&p.before)?;
            }
            self.fill_window_outputs(&mut out);
            return Ok(out);
        }
        let dtheta = self.sim.pump().tables.dtheta;
        let mut need = self.frac + inputs.omega * h / dtheta;
        // a step that lands within 1e-9 of a step boundary ends on it
        let nearest = need.round();
        if (need - nearest).abs() < 1e-9 {
            need = nearest;
        }
        if need > MAX_ANGULAR_STEPS {
            return Err(CoSimError::TooLong {
                steps: need,
                dtheta,
            });
        }
        // the whole-step state, to go back to on failure
        let (frac0, v0, last_q0) = (self.frac, self.v_total, self.last_q);
        self.undo_window.clone_from(&self.window);
        copy_pending(&mut self.undo_pending, &self.pending, &mut self.undo_kept);
        let mut undo = self.undo.take().unwrap_or_else(|| self.sim.snapshot());
        self.sim.snapshot_into(&mut undo);
        match self.march(inputs, need, h, &mut out) {
            Ok(()) => {
                self.undo = Some(undo);
                Ok(out)
            }
            Err(e) => {
                self.sim.restore(&undo)?;
                self.undo = Some(undo);
                (self.frac, self.v_total, self.last_q) = (frac0, v0, last_q0);
                std::mem::swap(&mut self.window, &mut self.undo_window);
                std::mem::swap(&mut self.pending, &mut self.undo_pending);
                Err(e)
            }
        }
    }

    fn march(
        &mut self,
        inputs: Inputs,
        mut need: f64,
        h: f64,
        out: &mut Outputs,
    ) -> Result<(), CoSimError> {
        let dt = self.sim.pump().tables.dtheta / inputs.omega;
        let v_start = self.v_total;
        let mut torque_time = 0.0;
        let mut inlet_volume = 0.0;
        let mut q_inst = self.last_q;
        // the flow's first moment about the call's middle, ∫ q (s - h/2) ds
        let (mut elapsed, mut moment) = (0.0, 0.0);
        while need > 0.0 {
            let full = need >= 1.0;
            let (q_out, q_in, torque, overload) = match self.pending.take() {
                Some(p) if p.inputs == inputs => {
                    // the step computed by an earlier call, same inputs
                    let r = (p.q_out, p.q_in, p.torque, p.overload);
                    if full {
                        self.spare = Some(p.before);
                    } else {
                        self.pending = Some(p);
                    }
                    r
                }
                other => {
                    if let Some(p) = other {
                        // the inputs changed: recompute from the whole step
                        self.sim.restore(&p.before)?;
                        self.spare = Some(p.before);
                    }
                    if *self.sim.inputs() != inputs {
                        self.sim.set_inputs(inputs)?;
                    }
                    let before = (!full).then(|| match self.spare.take() {
                        Some(mut b) => {
                            self.sim.snapshot_into(&mut b);
                            b
                        }
                        None => self.sim.snapshot(),
                    });
                    let o = self.sim.step()?;
                    if !(o.q_out.is_finite() && o.torque.is_finite()) {
                        return Err(CoSimError::NonFinite {
                            q_out: o.q_out,
                            torque: o.torque,
                        });
                    }
                    if let Some(before) = before {
                        self.pending = Some(Pending {
                            inputs,
                            before,
                            q_out: o.q_out,
                            q_in: o.q_in,
                            torque: o.torque,
                            overload: o.bearing_overload,
                        });
                    }
                    (o.q_out, o.q_in, o.torque, o.bearing_overload)
                }
            };
            out.bearing_overload |= overload;
            let covered = need.min(1.0) - self.frac;
            let (a, b) = (elapsed - 0.5 * h, elapsed + covered * dt - 0.5 * h);
            moment += q_out * 0.5 * (b * b - a * a);
            elapsed += covered * dt;
            self.v_total += covered * q_out * dt;
            inlet_volume += covered * q_in * dt;
            torque_time += covered * torque * dt;
            q_inst = q_out;
            if full {
                need -= 1.0;
                self.frac = 0.0;
                self.last_q = q_out;
                // a whole step: the live simulation stands after it
                let p_min = self.sim.lowest_pocket_pressure();
                self.push_window(&inputs, q_out, q_in, torque, p_min);
            } else {
                self.frac = need;
                need = 0.0;
            }
        }
        out.q_out = (self.v_total - v_start) / h;
        out.q_in = inlet_volume / h;
        out.q_out_slope = 12.0 * moment / (h * h * h);
        out.q_out_inst = q_inst;
        out.torque = torque_time / h;
        out.v_delivered = self.v_total;
        self.fill_window_outputs(out);
        Ok(())
    }

    /// The derivative of the mean delivered flow with respect to one of the
    /// inputs ([`FlowInput`]), SI units per unit of the input, at the
    /// current state and `inputs`: a central difference on the model. From
    /// a copy of the whole-step state (the live simulation is not touched),
    /// the model runs one mesh period at the input `± delta` to settle (the
    /// pockets' pressure transient after a change dies out within a
    /// fraction of a mesh period) and one more over which the delivered
    /// flow is averaged; the difference of the two means over the
    /// difference of the inputs is the quasi-static sensitivity of the mean
    /// flow (for the delivery pressure: leakage and compressibility of the
    /// delivered oil), the one two periodic solutions give. `sample`,
    /// `options` and `design_laws` as given to [`start`](Self::start). A
    /// pair that would leave the input's range is moved inside it (`range`,
    /// for the pressures also `p_delivery >= p_suction - 0.9 bar`). At
    /// standstill the flow is 0 whatever the inputs: 0. Costs four mesh
    /// periods of angular steps.
    pub fn flow_sensitivity(
        &self,
        inputs: Inputs,
        input: FlowInput,
        delta: f64,
        range: (f64, f64),
        how: (SampleClearances, Options, bool),
    ) -> Result<f64, CoSimError> {
        if inputs.omega < MIN_SPEED {
            return Ok(0.0);
        }
        let (sample, options, design_laws) = how;
        let value = |i: &Inputs| match input {
            FlowInput::Speed => i.omega,
            FlowInput::Suction => i.p_suction,
            FlowInput::Delivery => i.p_delivery,
            FlowInput::Temperature => i.temp_k,
        };
        let with = |x: f64| {
            let mut i = inputs;
            match input {
                FlowInput::Speed => i.omega = x,
                FlowInput::Suction => i.p_suction = x,
                FlowInput::Delivery => i.p_delivery = x,
                FlowInput::Temperature => i.temp_k = x,
            }
            i
        };
        let (mut lo, mut hi) = range;
        match input {
            FlowInput::Delivery => lo = lo.max(inputs.p_suction - 0.9e5),
            FlowInput::Suction => hi = hi.min(inputs.p_delivery + 0.9e5),
            _ => {}
        }
        let x = value(&inputs);
        let a = (x - delta).max(lo);
        let b = (a + 2.0 * delta).min(hi);
        let a = (b - 2.0 * delta).max(lo);
        let pump = Arc::clone(self.sim.shared_pump());
        let n = pump.steps_per_period();
        let mut probe = CoSimulation::resume(pump, &self.state(), sample, options, design_laws)?;
        let base = probe.sim.snapshot();
        let mut mean = [0.0; 2];
        for (k, x) in [a, b].into_iter().enumerate() {
            probe.sim.restore(&base)?;
            probe.sim.set_inputs(with(x))?;
            for _ in 0..n {
                probe.sim.step()?;
            }
            let mut q = 0.0;
            for _ in 0..n {
                q += probe.sim.step()?.q_out;
            }
            mean[k] = q / n as f64;
        }
        Ok((mean[1] - mean[0]) / (b - a))
    }

    /// The efficiencies, theta and the window length into `out`.
    fn fill_window_outputs(&self, out: &mut Outputs) {
        let pump = self.sim.pump();
        let (mut v, mut w, mut wi) = (0.0, 0.0, 0.0);
        let mut p_min = f64::INFINITY;
        for s in &self.window {
            v += s.volume;
            w += s.work;
            wi += s.ideal_work;
            p_min = p_min.min(s.p_pocket_min);
        }
        out.p_pocket_min = if self.window.is_empty() {
            match &self.pending {
                Some(p) => p.before.x[super::FIRST_POCKET..]
                    .iter()
                    .fold(f64::INFINITY, |a, &b| a.min(b)),
                None => self.sim.lowest_pocket_pressure(),
            }
        } else {
            p_min
        };
        if !self.window.is_empty() {
            let swept =
                pump.displacement * self.window.len() as f64 * pump.tables.dtheta / (2.0 * PI);
            out.eta_v = v / swept;
            out.eta_hm = if w > 0.0 { wi / w } else { 0.0 };
        }
        out.window_steps = self.window.len();
        out.theta = ((self.whole_steps() - self.k0) as f64 + self.frac) * pump.tables.dtheta;
    }

    /// Steps done up to the last whole step.
    fn whole_steps(&self) -> u64 {
        match &self.pending {
            Some(p) => p.before.steps_done,
            None => self.sim.steps_done(),
        }
    }

    fn push_window(&mut self, inputs: &Inputs, q_out: f64, q_in: f64, torque: f64, p_min: f64) {
        let pump = self.sim.pump();
        let dtheta = pump.tables.dtheta;
        let s = WindowStep {
            volume: q_out * dtheta / inputs.omega,
            work: torque * dtheta,
            ideal_work: pump.displacement * (inputs.p_delivery - inputs.p_suction) * dtheta
                / (2.0 * PI),
            inlet_volume: q_in * dtheta / inputs.omega,
            p_pocket_min: p_min,
        };
        if self.window.len() == pump.steps_per_period() {
            self.window.pop_front();
        }
        self.window.push_back(s);
    }

    /// The state (see the module docs).
    pub fn state(&self) -> CoSimState {
        CoSimState {
            committed: match &self.pending {
                Some(p) => p.before.clone(),
                None => self.sim.snapshot(),
            },
            k0: self.k0,
            frac: self.frac,
            v_total: self.v_total,
            last_q: self.last_q,
            window: self.window.iter().copied().collect(),
        }
    }

    /// A co-simulation of `pump` in `state` (with `sample`, `options` and
    /// `design_laws` as in [`start`](Self::start), which are not part of
    /// it). A state that does not fit the pump is refused.
    pub fn resume(
        pump: Arc<Pump>,
        state: &CoSimState,
        sample: SampleClearances,
        options: Options,
        design_laws: bool,
    ) -> Result<CoSimulation, CoSimError> {
        if !((0.0..1.0).contains(&state.frac) && state.k0 <= state.committed.steps_done) {
            return Err(CoSimError::State(format!(
                "step fraction {} or start step {} out of range",
                state.frac, state.k0
            )));
        }
        if state.window.len() > pump.steps_per_period() {
            return Err(CoSimError::State(format!(
                "an efficiency window of {} steps, the mesh period has {}",
                state.window.len(),
                pump.steps_per_period()
            )));
        }
        let in_service = if design_laws {
            pump.service_clearances(sample, &state.committed.inputs)
        } else {
            sample
        };
        let mut sim = Simulation::resume(
            pump,
            &state.committed,
            in_service,
            options,
            super::Scratch::default(),
        )?;
        if design_laws {
            sim.follow_design_laws(sample)?;
        }
        Ok(CoSimulation {
            sim,
            k0: state.k0,
            frac: state.frac,
            v_total: state.v_total,
            last_q: state.last_q,
            window: state.window.iter().copied().collect(),
            pending: None,
            undo: None,
            undo_window: VecDeque::with_capacity(state.window.len()),
            undo_pending: None,
            undo_kept: None,
            spare: None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::Design;
    use crate::units::*;

    fn inputs(rpm: f64, bar: f64) -> Inputs {
        Inputs {
            omega: rpm_to_rad_s(rpm),
            p_suction: ATMOSPHERE_PA,
            p_delivery: ATMOSPHERE_PA + bar_to_pa(bar),
            temp_k: celsius_to_kelvin(60.0),
            measured_torque: None,
        }
    }

    /// Uneven calls deliver what the angular steps deliver (the sum of
    /// `Q_out h` is the delivered volume); a call that fails (too long)
    /// leaves the state as it was; the state resumes to the same bits.
    #[test]
    fn calls_conserve_volume_refuse_whole_and_resume_exactly() {
        let pump = Arc::new(Pump::new(Design::seed()));
        let sample = SampleClearances::nominal(&pump.design);
        let options = Options { micromotion: false };
        let (mut cs, _) = CoSimulation::start(
            Arc::clone(&pump),
            inputs(1000.0, 30.0),
            sample,
            options,
            true,
            1.0,
            false,
        )
        .unwrap();
        let mut volume = 0.0;
        for k in 0..60 {
            let h = [7.0e-4, 1.3e-3, 2.5e-4][k % 3];
            let i = inputs(1000.0, 25.0 + (k % 7) as f64);
            let o = cs.advance(i, h).unwrap();
            volume += o.q_out * h;
            assert!((o.v_delivered - volume).abs() <= 1e-12 * volume, "step {k}");
        }
        let before = cs.state();
        let e = cs.advance(inputs(1000.0, 30.0), 1.0e4).unwrap_err();
        assert!(matches!(e, CoSimError::TooLong { .. }), "{e}");
        assert_eq!(cs.state(), before);
        let mut again =
            CoSimulation::resume(Arc::clone(&pump), &before, sample, options, false).unwrap();
        for h in [3.0e-4, 1.1e-3] {
            let a = cs.advance(inputs(1200.0, 31.0), h).unwrap();
            let b = again.advance(inputs(1200.0, 31.0), h).unwrap();
            assert_eq!(a, b);
        }
    }
    /// The flow's slope over a call is the least-squares line through the
    /// angular steps' flow (checked against a fit to samples of the flow by
    /// the normal equations, from a separate simulation stepped alone), and
    /// the pressure sensitivity is the central difference of two periodic
    /// solutions at p_out ± 0.5 bar started afresh (the mean flow of
    /// `run_periodic`, what `gearpump simulate` reports).
    #[test]
    fn flow_slope_is_the_least_squares_line_and_the_sensitivity_the_periodic_difference() {
        let pump = Arc::new(Pump::new(Design::seed()));
        let sample = SampleClearances::nominal(&pump.design);
        let options = Options { micromotion: false };
        let at = inputs(2500.0, 13.0);
        let (mut cs, _) =
            CoSimulation::start(Arc::clone(&pump), at, sample, options, true, 1.0, false).unwrap();
        let mut alone = Simulation::new(Arc::clone(&pump), at, sample, options).unwrap();
        alone.restore(&cs.state().committed).unwrap();
        let dt = pump.tables.dtheta / at.omega;
        // calls of 1 ms (29.76 angular steps: the calls end inside steps)
        let h = 1.0e-3;
        let mut flows = Vec::new();
        let mut t_end = 0.0;
        for call in 0..6 {
            let o = cs.advance(at, h).unwrap();
            while (flows.len() as f64) * dt < t_end + h + dt {
                flows.push(alone.step().unwrap().q_out);
            }
            // samples of the piecewise-constant flow over the call
            let m = 4000;
            let (mut sxx, mut sxy, mut sy) = (0.0, 0.0, 0.0);
            for i in 0..m {
                let s = (i as f64 + 0.5) / m as f64 * h;
                let q = flows[((t_end + s) / dt) as usize];
                let x = s - 0.5 * h;
                sxx += x * x;
                sxy += x * q;
                sy += q;
            }
            let slope = sxy / sxx;
            assert!(
                (o.q_out_slope - slope).abs() < 2e-3 * slope.abs().max(1e-3),
                "call {call}: {} vs {slope}",
                o.q_out_slope
            );
            assert!(
                (o.q_out - sy / m as f64).abs() < 1e-4 * o.q_out,
                "call {call}"
            );
            t_end += h;
        }
        let g = cs
            .flow_sensitivity(
                at,
                FlowInput::Delivery,
                bar_to_pa(0.5),
                (0.0, f64::INFINITY),
                (sample, options, false),
            )
            .unwrap();
        let periodic = |bar: f64| {
            let mut s =
                Simulation::new(Arc::clone(&pump), inputs(2500.0, bar), sample, options).unwrap();
            s.run_periodic().unwrap().flow
        };
        let fd = (periodic(13.5) - periodic(12.5)) / bar_to_pa(1.0);
        println!("dQ/dp: {g:e} m3/s/Pa, periodic runs {fd:e}");
        assert!(g < 0.0 && (g / fd - 1.0).abs() < 0.005, "{g} vs {fd}");
    }
}
