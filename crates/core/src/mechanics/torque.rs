//! Shaft torque and hydro-mechanical efficiency (docs/model.md section 6, beyond
//! the seed, which takes the measured torque).
//!
//! `T_shaft = T_hydraulic + T_tip + T_lateral + T_bearings + T_mesh + T_churn`,
//! the driven gear's losses referred to the shaft through the speed ratio
//! z1/z2 (power balance), and `eta_hm = Vm dp / (2 pi T_shaft)`.
//!
//! * `T_hydraulic`: from the pocket pressures on both gears (power balance of
//!   the pressure torques, `geometry::tables` loads).
//! * Tip shear: Couette stress `mu U / h` over the sealing tip lands (tip speed
//!   U), each slice of each land at its local clearance `h = c - e . d` from
//!   the gear centre offset `e` (held at 5 % of `c` where the tip would touch
//!   the bore: mixed friction there, which this viscous law does not model);
//!   the concentric estimate uses the mean sealed land over a period at `c`.
//!   The lands also bear the pressure-driven part of the wall stress,
//!   `(h / 2) dp/dx`, whose power is the drag flow times the pressure rise
//!   it is carried up: the model adds it per step from the network's
//!   pressures (`Network::drag_power`, in `Simulation::step`), not here. The
//!   same term of the lateral faces sums to zero round each gear's closed
//!   ring of teeth (the drag carried up the sealing arc comes back down
//!   across the tooth in the mesh).
//! * Lateral shear on both faces: `integral mu omega r / h r dA` over the disc
//!   from the journal to the root circle plus the involute teeth
//!   (`z integral 2 psi(r) r^3 dr` from root to tip, `psi` the half tooth
//!   angle), `h` = lateral clearance. (Counting the teeth as half the annulus
//!   from root to tip, as an earlier version did, overstated this shear by
//!   17.6 %: the teeth fill less than half of it where `r^3` weighs most.)
//! * Journal bearings: the finite-length bearing model's friction torque at
//!   the actual eccentricity ratio (two bearings per gear).
//! * Mesh friction: Coulomb friction `mu_m Fm` on the flanks sliding at
//!   `(omega1 + omega2) |l|` (`l`: contact distance from the pitch point, the
//!   mean over the helical slices), i.e. `mu_m Fm (1 + z1/z2) |l|` on the shaft.
//!   `mu_m = 0.06`: oil-bathed steel gears in mixed lubrication (design file).
//! * Thrust plate: pressed onto the gear faces by the delivery pressure over
//!   the unbalanced fraction `a` of the face area; Coulomb friction
//!   `mu_p a dp pi ra^2` at the mean radius `2 ra / 3` of a uniformly loaded
//!   disc, per gear (mixed lubrication, design file).
//! * Churning of the submerged gears: `C rho omega^2 ra^4 b` per gear, a disc
//!   drag law with a dimensionless coefficient `C = 0.004` (design file),
//!   the order of the moment coefficients of enclosed rotating discs.

use super::bearing::JournalBearing;
use crate::design::Design;
use crate::geometry::pair::Pair;
use crate::hydraulics::steps::StepTables;
use crate::operating::SampleClearances;
use std::f64::consts::PI;

/// The parts of the loss model fixed by the design.
#[derive(Debug, Clone, Copy, Default)]
pub struct LossModel {
    /// Sealed tip-land area of each gear (mean over a period), m^2, and tip radius, m.
    sealed_land: [f64; 2],
    ra: [f64; 2],
    /// Lateral integral `integral r^3 dr dtheta` over one face: the disc
    /// from the journal to the root circle, `pi (rf^4 - rj^4) / 2`, and the
    /// teeth ([`teeth_r3_integral`]), m^4.
    lateral: [f64; 2],
    /// Each gear's journal bearing at the design's clearance (the sample's
    /// replaces it in [`losses`](Self::losses)).
    bearings: [JournalBearing; 2],
    mesh_friction: f64,
    churning: f64,
    plate: f64,
    face_width: f64,
    ratio: f64,
}

/// Losses at one instant, N m on the driving shaft.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Losses {
    pub tip: f64,
    pub lateral: f64,
    pub bearings: f64,
    pub mesh: f64,
    pub churning: f64,
    pub plate: f64,
}

impl Losses {
    /// Adds `w` times `other` (a mean over steps).
    pub fn add_scaled(&mut self, other: &Losses, w: f64) {
        self.tip += w * other.tip;
        self.lateral += w * other.lateral;
        self.bearings += w * other.bearings;
        self.mesh += w * other.mesh;
        self.churning += w * other.churning;
        self.plate += w * other.plate;
    }

    pub fn total(&self) -> f64 {
        self.tip + self.lateral + self.bearings + self.mesh + self.churning + self.plate
    }
}

/// The teeth's part of a face's `integral r^3 dr dtheta`:
/// `z integral 2 psi(r) r^3 dr` from the root to the tip circle, `psi(r)`
/// the half tooth angle at radius `r` (the flank radial below the base
/// circle); once per pump.
fn teeth_r3_integral(g: &crate::geometry::gear::Gear) -> f64 {
    g.z as f64 * g.root_to_tip_integral(|r| 2.0 * g.half_angle(r) * r.powi(3))
}

impl LossModel {
    pub fn new(d: &Design, pair: &Pair, tables: &StepTables) -> LossModel {
        let st = &tables.steps;
        let mut sealed_land = [0.0; 2];
        let mut ra = [0.0; 2];
        let mut lateral = [0.0; 2];
        let mut bearings = [JournalBearing::default(); 2];
        for k in 0..2 {
            let g = &pair.gears[k];
            let sealed = st
                .iter()
                .map(|s| s.tips[k].iter().flatten().map(|t| t.width).sum::<f64>())
                .sum::<f64>()
                / st.len() as f64;
            sealed_land[k] = sealed * g.tip_land();
            ra[k] = g.ra;
            let rj = 0.5 * d.gears[k].bearing_diameter;
            bearings[k] = JournalBearing::unchecked(rj, d.bearing_length, d.clearance.bearing[k]);
            lateral[k] = PI * (g.rf.powi(4) - rj.powi(4)) / 2.0 + teeth_r3_integral(g);
        }
        LossModel {
            sealed_land,
            ra,
            lateral,
            bearings,
            mesh_friction: d.losses.mesh_friction,
            churning: d.losses.churning,
            plate: d.losses.plate_unbalance * d.losses.plate_friction,
            face_width: d.face_width,
            ratio: pair.ratio(),
        }
    }

    /// Losses with the gears at eccentricity ratios `eps` (bearings), a mesh
    /// force `fm` (N) at mean contact offset `l_abs` (m), delivery gauge
    /// pressure `dp` (Pa). `tip_land_over_h`: each gear's sealed tip-land
    /// area over its local clearance, summed over its sealing slices (m; see
    /// [`tip_land_over_h`]); None for the concentric mean. `gap_factor`:
    /// the multiplier on the viscosity of the tip and lateral films (the
    /// `pressure_viscosity` extension's Barus factor, 1 for the oil's own):
    /// the viscosity that sets their leakage sets their shear. The
    /// bearings' films keep `mu`: their pressure is their own
    /// hydrodynamic one, not the ports'.
    #[allow(clippy::too_many_arguments)] // the physical inputs of the loss model, each a plain number
    pub fn losses(
        &self,
        dp: f64,
        omega: f64,
        mu: f64,
        gap_factor: f64,
        rho: f64,
        sample: &SampleClearances,
        eps: [f64; 2],
        fm: f64,
        l_abs: f64,
        tip_land_over_h: Option<[f64; 2]>,
    ) -> Losses {
        let mut out = Losses::default();
        let mu_gap = mu * gap_factor;
        for (k, &eps_k) in eps.iter().enumerate() {
            let w = if k == 0 { omega } else { omega * self.ratio };
            let refer = if k == 0 { 1.0 } else { self.ratio };
            let u = w * self.ra[k];
            let area_over_h = match tip_land_over_h {
                Some(a) => a[k],
                None => self.sealed_land[k] / sample.tip[k],
            };
            out.tip += refer * mu_gap * u * area_over_h * self.ra[k];
            out.lateral += refer * 2.0 * mu_gap * w / sample.lateral * self.lateral[k];
            let b = self.bearings[k].with_clearance(sample.bearing[k]);
            out.bearings += refer * 2.0 * b.friction_torque(eps_k.min(0.99), w, mu).abs();
            out.churning +=
                refer * self.churning * rho * w * w * self.ra[k].powi(4) * self.face_width;
            out.plate +=
                refer * self.plate * dp.max(0.0) * PI * self.ra[k].powi(2) * 2.0 * self.ra[k] / 3.0;
        }
        out.mesh = self.mesh_friction * fm * (1.0 + self.ratio) * l_abs;
        out
    }
}

/// Each gear's sealed tip-land area over its local clearance at centre
/// offsets `offset` (m): the sum over the step's sealing tip slices of
/// `width L / h`, `h = c - e . d` held at 5 % of `c`. The reference form
/// over the step's tables; the model steps with [`TipLands::over_h`],
/// which gives the same bits.
pub fn tip_land_over_h(
    step: &crate::hydraulics::steps::Step,
    tip_land: [f64; 2],
    clearance: [f64; 2],
    offset: &[[f64; 2]; 2],
) -> [f64; 2] {
    [0, 1].map(|k| {
        let (c, e) = (clearance[k], offset[k]);
        step.tips[k]
            .iter()
            .flatten()
            .filter(|ts| ts.width > 0.0)
            .map(|ts| {
                let h = (c - (e[0] * ts.dir[0] + e[1] * ts.dir[1])).max(0.05 * c);
                ts.width * tip_land[k] / h
            })
            .sum()
    })
}

/// The sealing tip slices of every step of a mesh period (those with a
/// sealed width), gear by gear in one contiguous array each, in the order
/// of [`tip_land_over_h`]'s walk over `Step::tips` (tooth by tooth, slice
/// by slice), each slice as its sealed land area `width L` and the
/// components of its direction.
///
/// Why: the mechanical losses of every angular step sum `width L / h` over
/// these slices; walked through the nested per-tooth vectors of the tables
/// with the empty slices filtered out, that walk cost about 6.6 k
/// instructions per step (12 % of a co-simulation step at 1000 rpm). Built
/// once with the pump; the step tables (and their files) are unchanged.
#[derive(Debug, Clone, Default)]
pub struct TipLands {
    gears: [GearTipLands; 2],
}

/// The block of slices whose quotients [`TipLands::over_h`] computes side
/// by side.
const LANES: usize = 8;

/// One gear's part of [`TipLands`]: step `s` holds the slices
/// `start[s]..start[s + 1]` of the three arrays.
#[derive(Debug, Clone, Default)]
struct GearTipLands {
    start: Vec<usize>,
    /// `width * tip_land`, m^2 (the same product as [`tip_land_over_h`]'s).
    area: Vec<f64>,
    dir_x: Vec<f64>,
    dir_y: Vec<f64>,
}

impl TipLands {
    /// The sealing slices of `tables`' steps, with the gears' tip land
    /// lengths `tip_land` (m).
    pub fn new(tables: &StepTables, tip_land: [f64; 2]) -> TipLands {
        TipLands {
            gears: [0, 1].map(|k| {
                let mut g = GearTipLands {
                    start: vec![0],
                    ..GearTipLands::default()
                };
                for st in &tables.steps {
                    for ts in st.tips[k].iter().flatten().filter(|ts| ts.width > 0.0) {
                        g.area.push(ts.width * tip_land[k]);
                        g.dir_x.push(ts.dir[0]);
                        g.dir_y.push(ts.dir[1]);
                    }
                    g.start.push(g.area.len());
                }
                g
            }),
        }
    }

    /// [`tip_land_over_h`] of step `step` at tip clearances `clearance`
    /// and centre offsets `offset`: the same terms, summed in [`LANES`]
    /// partial sums (slice `i` into sum `i % LANES`, the sums then added in
    /// pairs, the remainder last), so equal to round-off (a few units in
    /// the last place). Summed in the slices' order, as the reference form
    /// does, the sum was one chain of about 200 dependent additions per
    /// gear, which set the time of the whole function.
    pub fn over_h(&self, step: usize, clearance: [f64; 2], offset: &[[f64; 2]; 2]) -> [f64; 2] {
        [0, 1].map(|k| {
            let g = &self.gears[k];
            let r = g.start[step]..g.start[step + 1];
            let (area, dx, dy) = (&g.area[r.clone()], &g.dir_x[r.clone()], &g.dir_y[r]);
            let (c, [ex, ey]) = (clearance[k], offset[k]);
            let floor = 0.05 * c;
            // the quotients of a block are independent, and so are the
            // block's partial sums: the compiler computes both side by side
            // in vector registers. `h.max(floor)` as a comparison: the same
            // value for every h (a NaN gives the floor either way; the
            // floor is positive, so no signed zero), one vector instruction
            // instead of the NaN-handling sequence of `f64::max`
            let quotient = |a: f64, x: f64, y: f64| {
                let h = c - (ex * x + ey * y);
                a / if h > floor { h } else { floor }
            };
            let mut sums = [0.0; LANES];
            let (a8, x8, y8) = (
                area.chunks_exact(LANES),
                dx.chunks_exact(LANES),
                dy.chunks_exact(LANES),
            );
            let (a_rest, x_rest, y_rest) = (a8.remainder(), x8.remainder(), y8.remainder());
            for ((a, x), y) in a8.zip(x8).zip(y8) {
                for j in 0..LANES {
                    sums[j] += quotient(a[j], x[j], y[j]);
                }
            }
            let mut width = LANES;
            while width > 1 {
                width /= 2;
                for j in 0..width {
                    sums[j] += sums[j + width];
                }
            }
            let mut sum = sums[0];
            for ((&a, &x), &y) in a_rest.iter().zip(x_rest).zip(y_rest) {
                sum += quotient(a, x, y);
            }
            sum
        })
    }
}

#[cfg(test)]
mod teeth_tests {
    use super::*;

    /// The flat sealing slices give the walk over the step tables, to
    /// round-off (the partial sums add in another order), at every step of
    /// the bundled pump, the gears centred and off-centre (one offset past
    /// the 5 % floor of the clearance).
    #[test]
    fn the_flat_tip_lands_are_the_tables_walk_to_round_off() {
        let pump = crate::model::Pump::new(Design::seed());
        let (tip_land, c) = (pump.geo.tip_land, pump.design.clearance.tip);
        let lands = TipLands::new(&pump.tables, tip_land);
        let offsets = [
            [[0.0; 2]; 2],
            [[0.3 * c[0], -0.5 * c[0]], [-0.2 * c[1], 0.4 * c[1]]],
            [[0.0, 0.99 * c[0]], [-0.99 * c[1], 0.0]],
        ];
        for (s, step) in pump.tables.steps.iter().enumerate() {
            for e in &offsets {
                let want = tip_land_over_h(step, tip_land, c, e);
                let got = lands.over_h(s, c, e);
                for k in 0..2 {
                    // positive terms: any order of summation is within a
                    // few ulps per term of the sum
                    let rel = (got[k] - want[k]).abs() / want[k];
                    assert!(
                        rel < 1e-13,
                        "step {s}, gear {k}: {} against {}",
                        got[k],
                        want[k]
                    );
                }
                assert!(want.iter().all(|&a| a > 0.0), "step {s}: a sealing land");
            }
        }
    }

    /// The Barus factor of the films acts as their viscosity: the tip and
    /// lateral shear with `gap_factor` f at viscosity mu are the shear at
    /// viscosity f mu (Couette, `tau = mu U / h`), the bearings' friction
    /// is the one at mu, and the other losses do not see it; concentric
    /// and off-centre, with and without a mesh force.
    #[test]
    fn the_films_barus_factor_is_their_viscosity_and_not_the_bearings() {
        let pump = crate::model::Pump::new(Design::seed());
        let d = &pump.design;
        let sample = crate::model::SampleClearances::nominal(d);
        let (mu, rho, f) = (0.0157, 840.0, 1.37);
        for (eps, fm, lands) in [
            ([0.0; 2], 0.0, None),
            ([0.6, 0.7], 250.0, Some([2.1e-3, 1.7e-3])),
        ] {
            let with = |m: f64, g: f64| {
                pump.loss_model
                    .losses(30.0e5, 104.7, m, g, rho, &sample, eps, fm, 1.2e-3, lands)
            };
            let (barus, thicker, plain) = (with(mu, f), with(f * mu, 1.0), with(mu, 1.0));
            assert_eq!(barus.tip, thicker.tip);
            assert_eq!(barus.lateral, thicker.lateral);
            assert!(barus.tip > plain.tip && barus.lateral > plain.lateral);
            assert_eq!(barus.bearings, plain.bearings);
            assert!(barus.bearings != thicker.bearings);
            for (a, b) in [
                (barus.churning, plain.churning),
                (barus.plate, plain.plate),
                (barus.mesh, plain.mesh),
            ] {
                assert_eq!(a, b);
            }
        }
    }

    /// The quadrature against a midpoint sum on 200,000 strips, for both
    /// gears of the bundled pump (the hand calculation of the whole shear
    /// is `tests/references.rs`).
    #[test]
    fn the_teeth_integral_matches_a_fine_midpoint_sum() {
        let pair = Design::seed().pair();
        for g in &pair.gears {
            let m = 200_000;
            let dr = (g.ra - g.rf) / m as f64;
            let fine: f64 = (0..m)
                .map(|i| {
                    let r = g.rf + (i as f64 + 0.5) * dr;
                    2.0 * g.half_angle(r) * r.powi(3) * dr
                })
                .sum::<f64>()
                * g.z as f64;
            let quad = teeth_r3_integral(g);
            println!(
                "z {}: quadrature {quad:.6e}, midpoint {fine:.6e}, rel {:.1e}",
                g.z,
                quad / fine - 1.0
            );
            assert!((quad / fine - 1.0).abs() < 1e-8);
            // and less than half the annulus from root to tip (the earlier count)
            assert!(quad < 0.5 * PI * (g.ra.powi(4) - g.rf.powi(4)) / 2.0);
        }
    }
}
