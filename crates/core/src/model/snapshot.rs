//! The model's state as plain data: [`SimSnapshot`] holds everything
//! [`Simulation::step`] reads from one step to the next (the node pressures
//! `x`, the stored masses `m_old` and their derivatives `dm` at the current
//! step, the step index in the mesh period, the step count, the gear centre
//! offsets the next step's micromotion iteration starts from and the ones
//! handed on a step earlier, the pressures of the step before, the changes
//! over every step of the last mesh period ([`crate::predictor`]) and its
//! torques that the mesh force follows ([`super::net_torque`]), the
//! micromotion diagnostics, the pressure Jacobian's factors each step of
//! the mesh period last refreshed, which the same step of the next period
//! starts from, and the inputs the state was computed with).
//! Everything else in a [`Simulation`] follows from the pump, the inputs,
//! the sample clearances and the options, or is scratch. Restoring is
//! exact: a restored simulation steps to the same bits as the original.
//! The FMU keeps its state this way (`fmi2::sim_state` writes it as bytes).

use super::{Inputs, ModelError, NetTorque, Options, Pump, SampleClearances, Scratch, Simulation};
use crate::predictor::PeriodHistory;
use crate::solver::SavedFactors;
use nalgebra::DVector;
use std::sync::Arc;

/// The state of a [`Simulation`] between two steps (see the module docs).
#[derive(Debug, PartialEq)]
pub struct SimSnapshot {
    /// Inputs the state was computed with.
    pub inputs: Inputs,
    /// Pressure of every state node, Pa (after a change of the port
    /// pressures and before the next step, that step's starting point:
    /// `Simulation::set_inputs`).
    pub x: Vec<f64>,
    /// Stored mass of every node at the current step, kg.
    pub m_old: Vec<f64>,
    /// d(stored mass)/dp of every node, kg/Pa.
    pub dm: Vec<f64>,
    /// Step index within the mesh period.
    pub istep: usize,
    /// Completed angular steps since the simulation started.
    pub steps_done: u64,
    /// Gear centre offsets from the bore centres, m: where the next step's
    /// micromotion iteration starts.
    pub offset: [[f64; 2]; 2],
    /// The offsets handed on by the step before (None at the start and after
    /// a change of inputs), m.
    pub previous_offset: Option<[[f64; 2]; 2]>,
    /// The pressures of the step before (None at the start and after a
    /// change of inputs), Pa: the Newton predictor extrapolates from them.
    pub previous_x: Option<Vec<f64>>,
    /// Steps whose micromotion iteration hit its limit (diagnostic).
    pub unconverged_steps: u64,
    /// Whether a bearing load exceeded the film's capacity (diagnostic).
    pub overload: bool,
    /// The changes over every step of the last mesh period.
    pub history: PeriodHistory,
    /// The last mesh period's torques the mesh force follows.
    pub net_torque: NetTorque,
    /// The pressure Jacobian's factors by step of the mesh period (empty,
    /// or one entry per step; shared, not copied, between snapshots).
    pub factors: Vec<Option<Arc<SavedFactors>>>,
}

impl Clone for SimSnapshot {
    fn clone(&self) -> Self {
        SimSnapshot {
            inputs: self.inputs,
            x: self.x.clone(),
            m_old: self.m_old.clone(),
            dm: self.dm.clone(),
            istep: self.istep,
            steps_done: self.steps_done,
            offset: self.offset,
            previous_offset: self.previous_offset,
            previous_x: self.previous_x.clone(),
            unconverged_steps: self.unconverged_steps,
            overload: self.overload,
            history: self.history.clone(),
            net_torque: self.net_torque.clone(),
            factors: self.factors.clone(),
        }
    }

    /// Field by field, reusing this snapshot's storage.
    fn clone_from(&mut self, source: &Self) {
        self.inputs = source.inputs;
        self.x.clone_from(&source.x);
        self.m_old.clone_from(&source.m_old);
        self.dm.clone_from(&source.dm);
        self.istep = source.istep;
        self.steps_done = source.steps_done;
        self.offset = source.offset;
        self.previous_offset = source.previous_offset;
        self.previous_x.clone_from(&source.previous_x);
        self.unconverged_steps = source.unconverged_steps;
        self.overload = source.overload;
        self.history.clone_from(&source.history);
        self.net_torque.clone_from(&source.net_torque);
        share_factors(&mut self.factors, &source.factors);
    }
}

/// `dst` shares the factors of `src`, reusing its storage and replacing
/// only the entries that differ (most are the same from one snapshot to
/// the next).
fn share_factors(dst: &mut Vec<Option<Arc<SavedFactors>>>, src: &[Option<Arc<SavedFactors>>]) {
    if dst.len() != src.len() {
        dst.clear();
        dst.extend_from_slice(src);
        return;
    }
    for (d, s) in dst.iter_mut().zip(src) {
        let same = match (&*d, s) {
            (Some(a), Some(b)) => Arc::ptr_eq(a, b),
            (None, None) => true,
            _ => false,
        };
        if !same {
            d.clone_from(s);
        }
    }
}

impl Simulation {
    /// The state (see the module docs).
    pub fn snapshot(&self) -> SimSnapshot {
        SimSnapshot {
            inputs: self.inputs,
            x: self.x.as_slice().to_vec(),
            m_old: self.m_old.as_slice().to_vec(),
            dm: self.dm.as_slice().to_vec(),
            istep: self.istep,
            steps_done: self.steps_done,
            offset: self.gaps.offset,
            previous_offset: self.previous_offset,
            previous_x: self.previous_x.as_ref().map(|v| v.as_slice().to_vec()),
            unconverged_steps: self.unconverged_steps,
            overload: self.overload,
            history: self.history.clone(),
            net_torque: self.net_torque.clone(),
            factors: self.factors.clone(),
        }
    }

    /// [`snapshot`](Self::snapshot) into `snap`, reusing its buffers.
    pub fn snapshot_into(&self, snap: &mut SimSnapshot) {
        snap.inputs = self.inputs;
        snap.x.clear();
        snap.x.extend_from_slice(self.x.as_slice());
        snap.m_old.clear();
        snap.m_old.extend_from_slice(self.m_old.as_slice());
        snap.dm.clear();
        snap.dm.extend_from_slice(self.dm.as_slice());
        snap.istep = self.istep;
        snap.steps_done = self.steps_done;
        snap.offset = self.gaps.offset;
        snap.previous_offset = self.previous_offset;
        match (&mut snap.previous_x, &self.previous_x) {
            (Some(mine), Some(theirs)) => {
                mine.clear();
                mine.extend_from_slice(theirs.as_slice());
            }
            (mine, theirs) => *mine = theirs.as_ref().map(|v| v.as_slice().to_vec()),
        }
        snap.unconverged_steps = self.unconverged_steps;
        snap.overload = self.overload;
        snap.history.clone_from(&self.history);
        snap.net_torque.clone_from(&self.net_torque);
        share_factors(&mut snap.factors, &self.factors);
    }

    /// Puts the simulation in the state `snap`, taken from a simulation of
    /// the same pump (the sample clearances and options stay this
    /// simulation's). A state that does not fit the pump (node count, step
    /// index, period history) or whose inputs are refused is refused, the
    /// simulation left as it was.
    pub fn restore(&mut self, snap: &SimSnapshot) -> Result<(), ModelError> {
        let n = self.x.len();
        let bad = |what: String| Err(ModelError::State(what));
        if [snap.x.len(), snap.m_old.len(), snap.dm.len()] != [n; 3] {
            return bad(format!(
                "{} / {} / {} node values, the pump has {n} nodes",
                snap.x.len(),
                snap.m_old.len(),
                snap.dm.len()
            ));
        }
        if snap.previous_x.as_ref().is_some_and(|v| v.len() != n) {
            return bad(format!("previous node pressures: the pump has {n} nodes"));
        }
        let steps = self.pump.steps_per_period();
        if snap.istep >= steps {
            return bad(format!("step index {} out of range", snap.istep));
        }
        if (snap.history.steps(), snap.history.nodes()) != (steps, n) {
            return bad(format!(
                "a period history of {} steps of {} nodes, the pump has {steps} steps of {n} nodes",
                snap.history.steps(),
                snap.history.nodes()
            ));
        }
        if snap.net_torque.steps() != steps {
            return bad(format!(
                "a torque window of {} steps, the pump has {steps} steps",
                snap.net_torque.steps()
            ));
        }
        if !snap.factors.is_empty() && snap.factors.len() != steps {
            return bad(format!(
                "Jacobian factors of {} steps, the pump has {steps} steps",
                snap.factors.len()
            ));
        }
        if snap.inputs != self.inputs {
            self.apply_inputs(snap.inputs)?;
        }
        self.x.copy_from_slice(&snap.x);
        self.m_old.copy_from_slice(&snap.m_old);
        self.dm.copy_from_slice(&snap.dm);
        self.istep = snap.istep;
        self.steps_done = snap.steps_done;
        self.gaps.offset = snap.offset;
        self.previous_offset = snap.previous_offset;
        match (&mut self.previous_x, &snap.previous_x) {
            (Some(mine), Some(theirs)) => mine.copy_from_slice(theirs),
            (mine, theirs) => *mine = theirs.as_ref().map(|v| DVector::from_column_slice(v)),
        }
        self.unconverged_steps = snap.unconverged_steps;
        self.overload = snap.overload;
        self.history.restore_from(&snap.history);
        self.net_torque.clone_from(&snap.net_torque);
        share_factors(&mut self.factors, &snap.factors);
        self.net_torque.follow(&self.inputs);
        self.net_shaft_torque =
            self.net_torque
                .value(self.pump.displacement, &self.inputs, self.concentric_losses);
        Ok(())
    }

    /// A simulation of `pump` in the state `snap` (with `sample` and
    /// `options`, which are not part of the state), reusing the buffers of
    /// an earlier simulation of the pump (`Scratch::default()` for none).
    pub fn resume(
        pump: Arc<Pump>,
        snap: &SimSnapshot,
        sample: SampleClearances,
        options: Options,
        scratch: Scratch,
    ) -> Result<Simulation, ModelError> {
        let mut sim = Simulation::without_storage(pump, snap.inputs, sample, options)?;
        sim.use_scratch(scratch);
        sim.forget_period_history();
        sim.restore(snap)?;
        Ok(sim)
    }
}
