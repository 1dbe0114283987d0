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
//! chamber; each pushes the gear radially inwards. A land inside the mating
//! gear's tip circle (the meshing zone) bounds one of the mesh's spaces,
//! whose clipped polygon in the tables already loads it: it adds nothing
//! here (until 2026-11-28 it added the mean of its own two pockets, a
//! second time; test `tests/references.rs::
//! a_uniform_pressure_leaves_each_gear_without_net_force`).

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
    let pockets = z[0] + z[1];
    let zones = step.tips[0].len() / z[0];
    for k in 0..2 {
        let r = regions[k];
        for zone in 0..zones {
            let first = FIRST_POCKET + zone * pockets + if k == 0 { 0 } else { z[0] };
            for t in 0..z[k] {
                let behind = x[first + (t + z[k] - 1) % z[k]] - p_ref;
                let ahead = x[first + t] - p_ref;
                let mean = 0.5 * (behind + ahead);
                for ts in &step.tips[k][zone * z[k] + t] {
                    let open = ts.dz - ts.width;
                    let p_open = if ts.psi > -r.cusp && ts.psi < r.cusp {
                        // inside the mating gear's tip circle the land
                        // bounds a space of the mesh, whose clipped
                        // polygon already loads it (until 2026-11-28 it
                        // was loaded a second time with the mean of its
                        // own spaces: docs/references.md)
                        0.0
                    } else if ts.psi >= r.cusp && ts.psi <= r.suction_edge {
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
    }
    l
}

/// The pressure loads of one step as a linear map of the node pressures:
/// [`pressure_loads`] is linear in `x - p_ref`, so its coefficients per node
/// (`[F1x, F1y, T1, F2x, F2y, T2]` per unit pressure) are collected once per
/// step and each evaluation is a short dot product. Equal to
/// [`pressure_loads`] to rounding.
#[derive(Debug, Clone, Default)]
pub struct LoadMap {
    /// Nodes with a nonzero coefficient and their coefficients.
    pub coef: Vec<(usize, [f64; 6])>,
}

impl LoadMap {
    /// The map of [`pressure_loads`] at `step` (arguments as there).
    pub fn new(step: &Step, z: [usize; 2], tip_land: [f64; 2], regions: [LandRegions; 2]) -> Self {
        let pockets = z[0] + z[1];
        let zones = step.tips[0].len() / z[0];
        let n = FIRST_POCKET + zones * pockets;
        let mut c = vec![[0.0f64; 6]; n];
        for (i, l) in step.loads.iter().enumerate() {
            for (a, b) in c[FIRST_POCKET + i].iter_mut().zip(l) {
                *a += b;
            }
        }
        for k in 0..2 {
            let r = regions[k];
            for zone in 0..zones {
                let first = FIRST_POCKET + zone * pockets + if k == 0 { 0 } else { z[0] };
                for t in 0..z[k] {
                    let behind = first + (t + z[k] - 1) % z[k];
                    let ahead = first + t;
                    for ts in &step.tips[k][zone * z[k] + t] {
                        let open = ts.dz - ts.width;
                        // f = (mean width + p_open open) tip_land, force -= f dir
                        let mut add = |node: usize, w: f64| {
                            c[node][3 * k] -= w * tip_land[k] * ts.dir[0];
                            c[node][3 * k + 1] -= w * tip_land[k] * ts.dir[1];
                        };
                        add(behind, 0.5 * ts.width);
                        add(ahead, 0.5 * ts.width);
                        if ts.psi > -r.cusp && ts.psi < r.cusp {
                            // inside the mating tip circle: loaded by the
                            // clipped polygons (see `pressure_loads`)
                        } else if ts.psi >= r.cusp && ts.psi <= r.suction_edge {
                            add(INLET, open);
                        } else if ts.psi >= r.delivery_edge && ts.psi <= -r.cusp {
                            add(OUTLET, open);
                        } else {
                            add(behind, 0.5 * open);
                            add(ahead, 0.5 * open);
                        }
                    }
                }
            }
        }
        LoadMap {
            coef: c
                .into_iter()
                .enumerate()
                .filter(|(_, v)| v.iter().any(|x| *x != 0.0))
                .collect(),
        }
    }

    /// The loads at node pressures `x`, relative to `p_ref`.
    pub fn loads(&self, x: &DVector<f64>, p_ref: f64) -> GearLoads {
        let mut s = [0.0; 6];
        for (i, c) in &self.coef {
            let p = x[*i] - p_ref;
            for (a, b) in s.iter_mut().zip(c) {
                *a += p * b;
            }
        }
        GearLoads {
            force: [[s[0], s[1]], [s[3], s[4]]],
            torque: [s[2], s[5]],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::Design;
    use crate::model::Pump;

    #[test]
    fn load_map_equals_the_direct_sum() {
        let pump = Pump::new(Design::seed());
        let z = pump.tables.z;
        let n = FIRST_POCKET + pump.tables.cells();
        let tip_land = [pump.pair.gears[0].tip_land(), pump.pair.gears[1].tip_land()];
        let regions = [0, 1].map(|k| LandRegions {
            cusp: pump.pair.cusp_angle(k),
            suction_edge: pump.design.gears[k].suction_edge,
            delivery_edge: pump.design.gears[k].delivery_edge,
        });
        for (j, st) in pump.tables.steps.iter().enumerate().step_by(5) {
            let x = DVector::from_fn(n, |i, _| {
                1.0e5 + 3.0e6 * (((i * 7 + j * 3) % 11) as f64 / 10.0)
            });
            let a = pressure_loads(st, z, &x, 1.0e5, tip_land, regions);
            let b = pump.load_maps[j].loads(&x, 1.0e5);
            for k in 0..2 {
                let scale = a.force[k][0].hypot(a.force[k][1]);
                for c in 0..2 {
                    assert!(
                        (a.force[k][c] - b.force[k][c]).abs() < 1e-12 * scale,
                        "step {j}"
                    );
                }
                assert!((a.torque[k] - b.torque[k]).abs() < 1e-12 * a.torque[k].abs().max(1e-3));
            }
        }
    }
}
