//! The byte form of a [`SimSnapshot`] (the model's own snapshot of a
//! [`Simulation`], `model::snapshot`) for the FMU state: it holds no
//! pointers, so it restores in another process ([`write_snapshot`],
//! [`read_snapshot`]); reading checks that the state fits the pump.

use gearpump_core::model::{Inputs, NetTorque, Pump, SimSnapshot};
use gearpump_core::predictor::PeriodHistory;
use gearpump_core::solver::SavedFactors;
use std::sync::Arc;

use super::model::{ModelError, StateReader, StateWriter};

/// Appends `snap` to a state writer.
pub fn write_snapshot(snap: &SimSnapshot, w: &mut StateWriter) {
    {
        let i = &snap.inputs;
        w.f64(i.omega)
            .f64(i.p_suction)
            .f64(i.p_delivery)
            .f64(i.temp_k)
            .bool(i.measured_torque.is_some())
            .f64(i.measured_torque.unwrap_or(0.0))
            .f64s(&snap.x)
            .f64s(&snap.m_old)
            .f64s(&snap.dm)
            .u64(snap.istep as u64)
            .u64(snap.steps_done);
        for o in snap.offset.iter().flatten() {
            w.f64(*o);
        }
        w.bool(snap.previous_offset.is_some());
        for o in snap.previous_offset.unwrap_or_default().iter().flatten() {
            w.f64(*o);
        }
        w.bool(snap.previous_x.is_some())
            .f64s(snap.previous_x.as_deref().unwrap_or(&[]));
        w.u64(snap.unconverged_steps).bool(snap.overload);
        let (n, dx, de, recorded, misses) = snap.history.parts();
        let recorded: Vec<u8> = recorded.iter().map(|&r| u8::from(r)).collect();
        w.u64(n as u64)
            .f64s(&dx)
            .f64s(&de)
            .bytes(&recorded)
            .f64s(&misses);
        let (values, measured) = snap.net_torque.parts();
        w.f64s(values).bool(measured);
        write_factors(&snap.factors, w);
    }
}

/// The pressure Jacobian's factors by step: their count, then for each a
/// presence flag and its pattern (little-endian u64 rows), elimination
/// order (one byte per unknown) and values.
fn write_factors(factors: &[Option<Arc<SavedFactors>>], w: &mut StateWriter) {
    w.u64(factors.len() as u64);
    for f in factors {
        w.bool(f.is_some());
        if let Some(f) = f {
            let (pattern, order, l, u, inv_diag) = f.parts();
            let rows: Vec<u8> = pattern.iter().flat_map(|r| r.to_le_bytes()).collect();
            let order: Vec<u8> = order.iter().map(|&o| o as u8).collect();
            w.bytes(&rows).bytes(&order).f64s(l).f64s(u).f64s(inv_diag);
        }
    }
}

/// The factors as [`write_factors`] wrote them: none, or one entry per
/// step of the mesh period, each checked by [`SavedFactors::from_parts`]
/// (whether they fit their structure is checked when a step loads them).
fn read_factors(
    r: &mut StateReader<'_>,
    steps: usize,
) -> Result<Vec<Option<Arc<SavedFactors>>>, ModelError> {
    let count = r.u64()?;
    if count != 0 && count != steps as u64 {
        return Err(ModelError::InvalidState(format!(
            "Jacobian factors of {count} steps, the pump has {steps} steps"
        )));
    }
    (0..count)
        .map(|i| {
            if !r.bool()? {
                return Ok(None);
            }
            let rows = r.bytes()?;
            if rows.len() % 8 != 0 {
                return Err(ModelError::InvalidState(format!(
                    "Jacobian factors of step {i}: a pattern of {} bytes",
                    rows.len()
                )));
            }
            let pattern = rows
                .chunks_exact(8)
                .map(|c| u64::from_le_bytes(c.try_into().expect("8 bytes")))
                .collect();
            let order = r.bytes()?.iter().map(|&o| usize::from(o)).collect();
            let (l, u, inv_diag) = (r.f64s()?, r.f64s()?, r.f64s()?);
            SavedFactors::from_parts(pattern, order, l, u, inv_diag)
                .map(|f| Some(Arc::new(f)))
                .map_err(|m| ModelError::InvalidState(format!("Jacobian factors of step {i}: {m}")))
        })
        .collect()
}

/// Reads a snapshot written by [`write_snapshot`] and checks that it fits
/// `pump` (node count, step index, finite values).
pub fn read_snapshot(r: &mut StateReader<'_>, pump: &Pump) -> Result<SimSnapshot, ModelError> {
    {
        let omega = r.f64()?;
        let p_suction = r.f64()?;
        let p_delivery = r.f64()?;
        let temp_k = r.f64()?;
        let has_torque = r.bool()?;
        let torque = r.f64()?;
        let x = r.f64s()?;
        let m_old = r.f64s()?;
        let dm = r.f64s()?;
        let istep = r.u64()?;
        let steps_done = r.u64()?;
        let mut offset = [[0.0; 2]; 2];
        for o in offset.iter_mut().flatten() {
            *o = r.f64()?;
        }
        let has_previous = r.bool()?;
        let mut previous = [[0.0; 2]; 2];
        for o in previous.iter_mut().flatten() {
            *o = r.f64()?;
        }
        let previous_offset = has_previous.then_some(previous);
        let has_previous_x = r.bool()?;
        let previous_x = r.f64s()?;
        let unconverged_steps = r.u64()?;
        let overload = r.bool()?;
        let history = read_history(r)?;
        let net_torque = read_net_torque(r)?;
        let factors = read_factors(r, pump.steps_per_period())?;
        let n = gearpump_core::hydraulics::network::FIRST_POCKET + pump.tables.cells();
        let bad = |what: String| Err(ModelError::InvalidState(what));
        if has_previous_x && previous_x.len() != n || !has_previous_x && !previous_x.is_empty() {
            return bad(format!(
                "{} previous node pressures, the pump has {n} nodes",
                previous_x.len()
            ));
        }
        if (history.steps(), history.nodes()) != (pump.steps_per_period(), n) {
            return bad(format!(
                "a period history of {} steps of {} nodes, the pump has {} steps of {n} nodes",
                history.steps(),
                history.nodes(),
                pump.steps_per_period()
            ));
        }
        if net_torque.steps() != pump.steps_per_period() {
            return bad(format!(
                "a torque window of {} steps, the pump has {} steps",
                net_torque.steps(),
                pump.steps_per_period()
            ));
        }
        if [x.len(), m_old.len(), dm.len()] != [n; 3] {
            return bad(format!(
                "{} / {} / {} node values, the pump has {n} nodes",
                x.len(),
                m_old.len(),
                dm.len()
            ));
        }
        let Some(istep) = usize::try_from(istep)
            .ok()
            .filter(|&i| i < pump.steps_per_period())
        else {
            return bad(format!("step index {istep} out of range"));
        };
        let finite = [omega, p_suction, p_delivery, temp_k, torque]
            .iter()
            .chain(&x)
            .chain(&m_old)
            .chain(&dm)
            .chain(&previous_x)
            .chain(offset.iter().flatten())
            .chain(previous.iter().flatten())
            .all(|v| v.is_finite());
        if !finite {
            return bad("a non-finite value".into());
        }
        Ok(SimSnapshot {
            inputs: Inputs {
                omega,
                p_suction,
                p_delivery,
                temp_k,
                measured_torque: has_torque.then_some(torque),
            },
            x,
            m_old,
            dm,
            istep,
            steps_done,
            offset,
            previous_offset,
            previous_x: has_previous_x.then_some(previous_x),
            unconverged_steps,
            overload,
            history,
            net_torque,
            factors,
        })
    }
}

/// The mesh force's torque window as [`write_snapshot`] wrote it (its
/// length is checked against the pump by `Simulation::restore`).
fn read_net_torque(r: &mut StateReader<'_>) -> Result<NetTorque, ModelError> {
    let values = r.f64s()?;
    let measured = r.bool()?;
    NetTorque::from_parts(values, measured)
        .map_err(|m| ModelError::InvalidState(format!("torque window: {m}")))
}

/// The period history as [`write_snapshot`] wrote it.
fn read_history(r: &mut StateReader<'_>) -> Result<PeriodHistory, ModelError> {
    let n = r.u64()?;
    let dx = r.f64s()?;
    let de = r.f64s()?;
    let recorded = r
        .bytes()?
        .iter()
        .map(|&b| match b {
            0 => Ok(false),
            1 => Ok(true),
            _ => Err(ModelError::InvalidState(format!(
                "period history: invalid Boolean byte {b}"
            ))),
        })
        .collect::<Result<Vec<bool>, _>>()?;
    let misses: [f64; 4] = r.f64s()?.try_into().map_err(|m: Vec<f64>| {
        ModelError::InvalidState(format!(
            "period history: {} prediction misses, 4 expected",
            m.len()
        ))
    })?;
    let n = usize::try_from(n)
        .map_err(|_| ModelError::InvalidState(format!("period history: {n} nodes")))?;
    PeriodHistory::from_parts(n, dx, &de, recorded, misses)
        .map_err(|m| ModelError::InvalidState(format!("period history: {m}")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use gearpump_core::design::Design;
    use gearpump_core::model::{Options, SampleClearances, Scratch, Simulation};
    use gearpump_core::units::*;
    use std::sync::Arc;

    const TAG: &[u8; 8] = b"SIMTEST1";

    fn inputs() -> Inputs {
        Inputs {
            omega: rpm_to_rad_s(1000.0),
            p_suction: ATMOSPHERE_PA,
            p_delivery: ATMOSPHERE_PA + bar_to_pa(30.0),
            temp_k: celsius_to_kelvin(60.0),
            measured_torque: None,
        }
    }

    fn bytes_of(s: &SimSnapshot) -> Vec<u8> {
        let mut w = StateWriter::new(TAG);
        write_snapshot(s, &mut w);
        w.finish()
    }

    /// Steps `sim` 40 times; the pressures and delivered flows, to the bit.
    fn continue_run(sim: &mut Simulation) -> Vec<u64> {
        let mut out = Vec::new();
        for _ in 0..40 {
            let o = sim.step().unwrap();
            out.push(o.q_out.to_bits());
        }
        out.extend(sim.pressures().iter().map(|v| v.to_bits()));
        out
    }

    #[test]
    fn a_state_read_back_from_its_bytes_resumes_to_the_same_bits() {
        let pump = Arc::new(Pump::new(Design::seed()));
        let sample = SampleClearances::nominal(&pump.design);
        let options = Options { micromotion: true };
        let mut sim = Simulation::new(Arc::clone(&pump), inputs(), sample, options).unwrap();
        for _ in 0..75 {
            sim.step().unwrap();
        }
        let snap = sim.snapshot();
        assert!(snap.previous_x.is_some() && snap.previous_offset.is_some());
        let bytes = bytes_of(&snap);
        let reference = continue_run(&mut sim);
        // a snapshot resumed and run on; the message a snapshot's bytes are
        // refused with
        let run_from = |s: &SimSnapshot| {
            let mut other =
                Simulation::resume(Arc::clone(&pump), s, sample, options, Scratch::default())
                    .unwrap();
            continue_run(&mut other)
        };
        let refusal = |s: &SimSnapshot| {
            let bytes = bytes_of(s);
            let mut r = StateReader::new(&bytes, TAG).unwrap();
            match read_snapshot(&mut r, &pump) {
                Err(ModelError::InvalidState(m)) => m,
                other => panic!("accepted: {other:?}"),
            }
        };

        let mut r = StateReader::new(&bytes, TAG).unwrap();
        let read = read_snapshot(&mut r, &pump).unwrap();
        assert_eq!(read, snap);
        assert_eq!(run_from(&read), reference);

        // the history matters: without the previous pressures the linear
        // predictor starts elsewhere and the run differs in the last bits.
        // Checked on a state 30 steps in, whose next steps have no period
        // history yet (the linear prediction is the one taken there; with a
        // full period recorded the periodic one usually wins at every step)
        let mut early = Simulation::new(Arc::clone(&pump), inputs(), sample, options).unwrap();
        for _ in 0..30 {
            early.step().unwrap();
        }
        let early_snap = early.snapshot();
        let early_reference = continue_run(&mut early);
        assert_eq!(run_from(&early_snap), early_reference);
        let forgetful = SimSnapshot {
            previous_x: None,
            ..early_snap
        };
        assert_ne!(run_from(&forgetful), early_reference);
        // and so does the period history (75 steps recorded all 51 indices)
        assert!((0..pump.steps_per_period()).all(|s| snap.history.has(s)));
        let amnesic = SimSnapshot {
            history: PeriodHistory::new(pump.steps_per_period(), snap.x.len()),
            ..snap.clone()
        };
        assert_ne!(run_from(&amnesic), reference);

        // a period history that does not fit the pump is refused, naming it
        let foreign = SimSnapshot {
            history: PeriodHistory::new(3, snap.x.len()),
            ..snap.clone()
        };
        let m = refusal(&foreign);
        assert!(m.contains("period history"), "{m}");

        // the mesh force's torque window is state too: 75 steps filled it,
        // and an empty one resumes to other bits
        assert!(snap.net_torque.parts().0.iter().all(|v| *v != 0.0));
        let unwound = SimSnapshot {
            net_torque: NetTorque::new(pump.steps_per_period(), &snap.inputs),
            ..snap.clone()
        };
        assert_ne!(run_from(&unwound), reference);
        // a window that does not fit the pump is refused, naming it (a
        // non-finite one cannot be built: `NetTorque::from_parts`)
        let foreign = SimSnapshot {
            net_torque: NetTorque::from_parts(vec![0.0; 3], false).unwrap(),
            ..snap.clone()
        };
        let m = refusal(&foreign);
        assert!(m.contains("torque window of 3"), "{m}");

        // the kept Jacobian factors are state: 75 steps kept some (the
        // bytes above carried them to the same bits), and without them
        // the run refreshes its Jacobians and ends in other bits (within
        // the Newton tolerance)
        assert_eq!(snap.factors.len(), pump.steps_per_period());
        assert!(snap.factors.iter().any(|f| f.is_some()));
        let unfactored = SimSnapshot {
            factors: Vec::new(),
            ..snap.clone()
        };
        assert_ne!(run_from(&unfactored), reference);
        // factors of another period length are refused, naming them
        let foreign = SimSnapshot {
            factors: vec![None; 3],
            ..snap.clone()
        };
        let m = refusal(&foreign);
        assert!(m.contains("Jacobian factors of 3 steps"), "{m}");
        let mut fresh = Simulation::new(Arc::clone(&pump), inputs(), sample, options).unwrap();
        assert!(fresh.restore(&foreign).is_err());

        // a pressure history of the wrong length is refused, naming it
        let short = SimSnapshot {
            previous_x: Some(vec![1.0e5; 3]),
            ..snap
        };
        let m = refusal(&short);
        assert!(m.contains("previous node pressures"), "{m}");
    }
}
