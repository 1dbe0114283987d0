//! Pressure loads on the gears (seed Sec. 2.1: F_p, T_p of Eq. 3).
//!
//! Each pocket's pressure acts on the gear surfaces that bound it; the step
//! tables hold, per pocket, the force and torque on each gear per unit
//! pressure, integrated edge by edge over the clipped pocket polygons and
//! summed over the helical slices (`geometry::tables`). Pressures are taken
//! relative to the suction pressure (a uniform pressure over a closed gear
//! surface exerts no net load). The tooth tip lands complete the gear
//! outline: a land sealing in the bore sees the mean of its two pockets (the
//! linear pressure drop of the tip gap), a land facing a port sees that
//! chamber, a land in the meshing zone the mean of its pockets; each pushes
//! the gear radially inwards.

use crate::hydraulics::network::{FIRST_POCKET, INLET, OUTLET};
use crate::hydraulics::steps::Step;
use nalgebra::DVector;

/// Forces (N, global frame) and torques (N m, counter-clockwise positive
/// about each gear's centre) on the driving [0] and driven [1] gear.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GearLoads {
    pub force: [[f64; 2]; 2],
    pub torque: [f64; 2],
}

/// Angular limits of the tip-land regions of a gear (local angles, rad).
#[derive(Debug, Clone, Copy)]
pub struct LandRegions {
    pub cusp: f64,
    pub suction_edge: f64,
    pub delivery_edge: f64,
}

/// Pressure loads at state `x` (absolute pressures of every node), relative
/// to `p_ref` (the suction pressure).
pub fn pressure_loads(
    step: &Step,
    z: [usize; 2],
    x: &DVector<f64>,
    p_ref: f64,
    tip_land: [f64; 2],
    regions: [LandRegions; 2],
) -> GearLoads {
    let mut l = GearLoads::default();
    for (i, c) in step.loads.iter().enumerate() {
        let p = x[FIRST_POCKET + i] - p_ref;
        l.force[0][0] += p * c[0];
        l.force[0][1] += p * c[1];
        l.torque[0] += p * c[2];
        l.force[1][0] += p * c[3];
        l.force[1][1] += p * c[4];
        l.torque[1] += p * c[5];
    }
    let p_in = x[INLET] - p_ref;
    let p_out = x[OUTLET] - p_ref;
    for k in 0..2 {
        let first = FIRST_POCKET + if k == 0 { 0 } else { z[0] };
        let r = regions[k];
        for t in 0..z[k] {
            let behind = x[first + (t + z[k] - 1) % z[k]] - p_ref;
            let ahead = x[first + t] - p_ref;
            let mean = 0.5 * (behind + ahead);
            for ts in &step.tips[k][t] {
                let open = ts.dz - ts.width;
                let p_open = if ts.psi >= r.cusp && ts.psi <= r.suction_edge {
                    p_in
                } else if ts.psi >= r.delivery_edge && ts.psi <= -r.cusp {
                    p_out
                } else {
                    mean
                };
                let f = (mean * ts.width + p_open * open) * tip_land[k];
                l.force[k][0] -= f * ts.dir[0];
                l.force[k][1] -= f * ts.dir[1];
            }
        }
    }
    l
}
