//! The shaft torque less friction that the mesh force takes (seed Eq. 8,
//! `crate::mechanics::mesh`), made consistent with the model's own torque.
//!
//! Eq. 8 reads the mesh force from the torque balance of both gears:
//! `Fm = (T_net - Tp1' - Tp2') / (rb1 - rb2)`, with `T_net = eta_hm T_shaft`
//! the shaft torque less the friction of both gears. The model computes
//! the pressure torques `Tp1'`, `Tp2'` itself; `T_net` has to come from
//! somewhere:
//!
//! * **Without a measured torque**, the shaft torque less friction is the
//!   model's own hydraulic torque `Tp1' + (rb1 / rb2) Tp2'` (the pressure
//!   torques' power balance, `StepOutput::torque_hydraulic`). Its mean over
//!   a mesh period put into Eq. 8 gives a mean mesh force of `Tp2' / rb2`,
//!   the driven gear's own moment balance (Eq. 5). The model used to take
//!   the ideal torque `Vm dp / (2 pi)` instead, which the hydraulic torque
//!   exceeds by the pockets' compression and trapped-volume torques (up to
//!   6 % at 4000 rpm): through the small `rb1 - rb2` that became a mean
//!   mesh force off the driven gear's balance by tens of newtons, and a
//!   mesh friction off by 0.03 N m.
//! * **With a measured torque** `T_meas`, `T_net = T_meas - T_losses`, the
//!   losses being the model's own (bearing, lateral, tip and mesh
//!   friction, churning) at the state it solved, not the quick concentric
//!   estimate without mesh friction that only starts a run.
//!
//! Both are means over the last mesh period, taken as a correction of the
//! start's estimate (the *prior*: the ideal torque without a measurement,
//! the measurement less the concentric losses without mesh friction with
//! one). The running window [`NetTorque`] holds, per step of the period, how
//! far the step's own value lay from the prior at the step's inputs: the
//! hydraulic torque less the ideal torque, or the concentric losses less
//! the step's losses. `T_net` is the prior at the current inputs plus the
//! window's mean, a step not yet stepped counting as no correction. So a
//! run starts from the prior and moves to its own torque over its first
//! mesh period without a jump (a jump of the mesh force at a period's end
//! is a new transient of the gear positions, one more period for the
//! periodic test), and a step of the delivery pressure moves `T_net` at
//! once through the prior while the window corrects only what the prior
//! misses. A run given the model's own torque as its measurement and a run
//! without one share their periodic state.

use super::Inputs;

/// The running window of the last mesh period's corrections (see the
/// module docs). Part of a simulation's state ([`super::SimSnapshot`]).
#[derive(Debug, PartialEq)]
pub struct NetTorque {
    /// One correction per step of the mesh period, by step index, N m (0
    /// for a step not stepped since the window was cleared).
    values: Vec<f64>,
    /// Whether the corrections are of losses (a measured torque) or of the
    /// hydraulic torque (none).
    measured: bool,
}

impl Clone for NetTorque {
    fn clone(&self) -> Self {
        NetTorque {
            values: self.values.clone(),
            measured: self.measured,
        }
    }

    /// Reuses this window's storage (the FMU copies its state at every
    /// communication step; the derived `clone_from` would allocate).
    fn clone_from(&mut self, source: &Self) {
        self.values.clone_from(&source.values);
        self.measured = source.measured;
    }
}

impl NetTorque {
    /// An empty window over `steps` steps for `inputs` (with or without a
    /// measured torque).
    pub fn new(steps: usize, inputs: &Inputs) -> NetTorque {
        NetTorque {
            values: vec![0.0; steps],
            measured: has_measured_torque(inputs),
        }
    }

    /// A window from its parts (a stored state), checked.
    pub fn from_parts(values: Vec<f64>, measured: bool) -> Result<Self, String> {
        if !values.iter().all(|v| v.is_finite()) {
            return Err("a non-finite torque".into());
        }
        Ok(NetTorque { values, measured })
    }

    /// The parts [`from_parts`](Self::from_parts) takes.
    pub fn parts(&self) -> (&[f64], bool) {
        (&self.values, self.measured)
    }

    /// Steps in the window.
    pub fn steps(&self) -> usize {
        self.values.len()
    }

    /// Clears the window when the inputs' kind changes (a measured torque
    /// given or taken away): its corrections would be of something else.
    pub fn follow(&mut self, inputs: &Inputs) {
        let measured = has_measured_torque(inputs);
        if measured != self.measured {
            self.values.iter_mut().for_each(|v| *v = 0.0);
            self.measured = measured;
        }
    }

    /// Records the step `istep`'s hydraulic torque and loss torque (N m)
    /// solved at `inputs` (`vm`: the displacement, m^3 per revolution;
    /// `concentric_losses`: the prior's losses at `inputs`, N m).
    pub fn record(
        &mut self,
        istep: usize,
        vm: f64,
        inputs: &Inputs,
        concentric_losses: f64,
        hydraulic: f64,
        losses: f64,
    ) {
        self.values[istep] = if self.measured {
            concentric_losses - losses
        } else {
            hydraulic - ideal_torque(vm, inputs)
        };
    }

    /// The shaft torque less friction for the mesh force at `inputs`, N m:
    /// the prior plus the window's mean correction.
    pub fn value(&self, vm: f64, inputs: &Inputs, concentric_losses: f64) -> f64 {
        let n = self.values.len().max(1) as f64;
        let correction = self.values.iter().sum::<f64>() / n;
        let prior = match inputs.measured_torque {
            Some(t) if has_measured_torque(inputs) => t - concentric_losses,
            _ => ideal_torque(vm, inputs),
        };
        prior + correction
    }
}

/// Whether the inputs carry a usable measured torque.
fn has_measured_torque(inputs: &Inputs) -> bool {
    inputs
        .measured_torque
        .is_some_and(|t| t.is_finite() && t > 0.0)
}

/// The ideal torque `Vm dp / (2 pi)` of a pump of displacement `vm`
/// (m^3 per revolution) at `inputs`, N m.
pub fn ideal_torque(vm: f64, inputs: &Inputs) -> f64 {
    vm * (inputs.p_delivery - inputs.p_suction) / (2.0 * std::f64::consts::PI)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(bar: f64, measured: Option<f64>) -> Inputs {
        Inputs {
            omega: 100.0,
            p_suction: 1.0e5,
            p_delivery: 1.0e5 + bar * 1.0e5,
            temp_k: 333.15,
            measured_torque: measured,
        }
    }

    /// The prior, the ramp over the first period and the measured case,
    /// against the definitions worked by hand (Vm = 2 pi cm^3: the ideal
    /// torque is dp * 1e-6 N m per Pa, 3 N m at 30 bar).
    #[test]
    fn the_window_corrects_the_prior_by_its_mean() {
        let vm = 2.0 * std::f64::consts::PI * 1.0e-6;
        let i = at(30.0, None);
        assert!((ideal_torque(vm, &i) - 3.0).abs() < 1e-12);
        let mut w = NetTorque::new(4, &i);
        assert!((w.value(vm, &i, 0.1) - 3.0).abs() < 1e-12);
        // one step of four with a hydraulic torque of 3.4 N m: a quarter
        // of its 0.4 N m excess
        w.record(0, vm, &i, 0.1, 3.4, 0.2);
        assert!((w.value(vm, &i, 0.1) - 3.1).abs() < 1e-12);
        for k in 1..4 {
            w.record(k, vm, &i, 0.1, 3.4, 0.2);
        }
        assert!((w.value(vm, &i, 0.1) - 3.4).abs() < 1e-12);
        // a pressure step moves the value at once through the prior
        let i40 = at(40.0, None);
        assert!((w.value(vm, &i40, 0.1) - 4.4).abs() < 1e-12);
        // a measured torque of 3.6 N m: the window is cleared; the prior is
        // the measurement less the concentric losses, then less the
        // model's own losses (0.25 N m) once a period is recorded
        let m = at(30.0, Some(3.6));
        w.follow(&m);
        assert!((w.value(vm, &m, 0.1) - 3.5).abs() < 1e-12);
        for k in 0..4 {
            w.record(k, vm, &m, 0.1, 3.4, 0.25);
        }
        assert!((w.value(vm, &m, 0.1) - 3.35).abs() < 1e-12);
        // a stored window holding a non-finite torque is refused
        assert!(NetTorque::from_parts(vec![0.0, f64::NAN], false).is_err());
    }
}
