//! What a trace records after an angular step ([`Simulation::trace`]): the
//! chambers' and every tooth space's pressure, the gear centres and every
//! tooth tip's clearance, numbered by the physical spaces and teeth round
//! each gear (the simulation's node labels move on by one every mesh
//! period), and the state of the meshing zone.

use super::{Simulation, StepOutput};
use crate::hydraulics::network::{FIRST_POCKET, INLET, OUTLET};

/// One angular step of a trace (pressures absolute, Pa; lengths m).
#[derive(Debug, Clone, PartialEq)]
pub struct TracePoint {
    /// Driving-gear angle at the end of the step (unwrapped), rad.
    pub theta: f64,
    /// Delivered flow of the step, m^3/s.
    pub q_out: f64,
    pub p_inlet: f64,
    pub p_outlet: f64,
    /// Pressure of every tooth space of each gear, by physical space (space
    /// `k` is the one that was labelled `k` at the start), at mid face
    /// width: the mean of the middle axial zone(s).
    pub space_pressure: [Vec<f64>; 2],
    /// Gear centre offsets from the bore centres over the step (global
    /// frame).
    pub offset: [[f64; 2]; 2],
    /// Tip clearance of every tooth of each gear, by physical tooth (tooth
    /// `k` trails space `k`), at the mid-face slice: `c - e . d`.
    pub tip_clearance: [Vec<f64>; 2],
    /// Highest and lowest pressure of the pockets in the meshing zone (those
    /// with a meshing-zone passage; NaN when none).
    pub meshing_pressure: [f64; 2],
    /// Cd A of the delivery and the suction relief grooves open to the
    /// trapped pockets (in the meshing zone with no bore opening), m^2.
    pub trapped_groove_cda: [f64; 2],
}

impl Simulation {
    /// The trace of the step just made, whose output is `out` (see the
    /// module docs).
    pub fn trace(&self, out: &StepOutput) -> TracePoint {
        let t = &self.pump.tables;
        let st = &t.steps[self.istep];
        let (z, zones, pockets) = (t.z, t.zones, t.pockets());
        let periods = (self.steps_done / self.pump.steps_per_period() as u64) as usize;
        let mid_zones: &[usize] = if zones % 2 == 1 {
            &[zones / 2]
        } else {
            &[zones / 2 - 1, zones / 2]
        };
        let space_pressure = [0usize, 1].map(|g| {
            let off = if g == 0 { 0 } else { z[0] };
            (0..z[g])
                .map(|space| {
                    // label k holds body space (k - periods) mod z
                    let label = (space + periods) % z[g];
                    mid_zones
                        .iter()
                        .map(|zone| self.x[FIRST_POCKET + zone * pockets + off + label])
                        .sum::<f64>()
                        / mid_zones.len() as f64
                })
                .collect()
        });
        let tip_clearance = [0usize, 1].map(|g| {
            let e = out.offset[g];
            (0..z[g])
                .map(|tooth| {
                    let label = (tooth + periods) % z[g];
                    let slices: Vec<_> = (0..zones)
                        .flat_map(|zone| st.tips[g][zone * z[g] + label].iter())
                        .collect();
                    let mid = slices[slices.len() / 2];
                    self.gaps.tip[g] - (e[0] * mid.dir[0] + e[1] * mid.dir[1])
                })
                .collect()
        });
        let meshing = |i: usize| st.mesh.iter().any(|m| m.0 == i || m.1 == i);
        let (mut hi, mut lo) = (f64::NAN, f64::NAN);
        for i in (0..t.cells()).filter(|&i| meshing(i)) {
            let p = self.x[FIRST_POCKET + i];
            hi = hi.max(p);
            lo = lo.min(p);
        }
        let trapped = |i: &usize| st.cda_in[*i] == 0.0 && st.cda_out[*i] == 0.0 && meshing(*i);
        let sum = |v: &[f64]| (0..v.len()).filter(trapped).map(|i| v[i]).sum::<f64>();
        TracePoint {
            theta: out.theta,
            q_out: out.q_out,
            p_inlet: self.x[INLET],
            p_outlet: self.x[OUTLET],
            space_pressure,
            offset: out.offset,
            tip_clearance,
            meshing_pressure: [hi, lo],
            trapped_groove_cda: [sum(&st.groove_out), sum(&st.groove_in)],
        }
    }
}
