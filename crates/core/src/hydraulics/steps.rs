//! Per-step look-up tables over one mesh period: the section tables summed
//! over the helical slices at each angular step, with every pocket, port,
//! groove, meshing passage and sealing tooth tip of the pump.
//!
//! Pocket numbering: at driving angle `theta_loc` in `[0, pitch1)` of the
//! current mesh period, driving-gear pocket `k` is its tooth space centred at
//! local angle `theta_loc + (k + 1/2) pitch1`; driven-gear pocket `i` its
//! space centred at `theta_loc z1/z2 - lag + (i + 1) pitch2`. After a mesh
//! period every space has moved one pitch on: the solver relabels `k -> k+1`
//! (and `i -> i+1`), so one period of tables serves the whole revolution.
//!
//! ## Axial zones
//! A helical tooth space is cut along the face width into
//! `numerics.axial_nodes` zones, each a pressure node of its own: zone `j`
//! holds the slices `s` with `s * zones / slices == j` (zone 0 at the face
//! of the first plate). A tooth space's cell in zone `j` has the index
//! `j * pockets + i` (`i` the pocket number above; the whole zone-0 block
//! first), so the relabelling acts on each zone's block alike. Each zone
//! has its own volume, port openings, meshing-zone passages, tip gaps and
//! loads (its slices'); the relief grooves and lateral gaps act on the end
//! zones only (the plates are at the faces); consecutive zones of a tooth
//! space are joined by the channel along the space ([`Step::axial`]).
//!
//! Why: where the overlap ratio exceeds the transverse contact ratio minus
//! one, the channel between two contact lines opens to the delivery at one
//! face and to the suction at the other, and a fluid slice one section
//! displaces while another grows must travel along the space. One node per
//! space passes that flow with no resistance and relieves the trapped
//! volume on its net volume change only.
//!
//! ## The axial channel
//! Laminar flow along a straight duct of section `A` and wetted perimeter
//! `P`: `Q = 2 A D_h^2 / (C mu) dp/dz`, `D_h = 4 A / P`, with the
//! Poiseuille number `C = f Re` of the section ([`AXIAL_POISEUILLE`]). The
//! resistance from the centre of zone `j` to the centre of zone `j + 1` is
//! the sum over the slices on the way of `dz C mu / (2 A_s D_h,s^2)` (each
//! slice's section at its own phase, so a section that the mating tooth
//! nearly closes throttles the channel); the step table holds its inverse
//! times `mu`.

use crate::design::{AxialFlow, Design, MeshPassage, Relief};
use crate::geometry::pair::Pair;
use crate::geometry::tables::{wrap_pi, SectionTables};
use std::f64::consts::PI;

/// Shortest sealing land of a tip partly past a port edge, as a fraction of
/// the whole land. A tip whose land is only partly under the bore seals
/// over the covered part: the gap keeps the slice's full width and its
/// length shrinks with the cover. Below about one clearance height of land
/// (5 % of the 0.4-0.7 mm lands of the seed pump: 20-35 um) the laminar gap
/// law no longer holds (the entrance dominates) and the pocket is opening to
/// the port anyway, so the length is held there.
pub const MIN_LAND_FRACTION: f64 = 0.05;

/// Where within an angular step the tables take the geometry that the
/// step's pressures act through (openings, meshing passages, tip gaps,
/// pressure loads and the contact point), as a fraction of the step back
/// from its end: one half, the middle.
///
/// The step's flows and loads act over the whole step with the pressures
/// solved at its end (backward Euler), so the geometry they act through is
/// that of the step as a whole; taken at the step's end instead, every
/// opening opened half a step early and every pressure's torque was paired
/// with the volume change of half a step later, an error of first order
/// in the step: with 0.5 deg steps eta_hm came out 0.05-0.27 points low at
/// 1000 rpm and 0.24-1.35 points low at 4000 rpm, eta_v 0.04-0.08 points
/// low, against the same model marched at 1/8 of the step. At the middle
/// the error left is within 0.09 points of eta_hm and 0.031 of eta_v over
/// 1000-4000 rpm, 10-100 bar, 30 and 60 degC (docs/model.md section 7,
/// test `tests/step_convergence.rs`). The volumes stay at the step's end:
/// the mass balance's storage term is the mass at the end of the step.
pub const STEP_MIDPOINT: f64 = 0.5;

/// Poiseuille number `f Re` (Darcy friction factor times the Reynolds
/// number on the hydraulic diameter) of the axial channel along a tooth
/// space. A tooth space's section (flanks, root and tip circle) is a compact
/// shape: 56.9 for a square, 53.3 for an equilateral triangle, 64 for a
/// circle; the thin sliver a mating tooth leaves near a contact tends to the
/// slit's 96. 64 is taken; 96 throughout changes eta_v by +1.8e-6 at 1000
/// rpm / 30 bar / 60 degC (the channel conducts far more than the relief
/// paths either way).
pub const AXIAL_POISEUILLE: f64 = 64.0;

/// A section below this area (m^2) closes the axial channel (a
/// tenth of a square micrometre: nothing passes).
const AXIAL_CLOSED_AREA: f64 = 1.0e-13;

/// A tooth tip in one slice.
#[derive(Debug, Clone, Copy)]
pub struct TipSlice {
    /// Sealed land area per unit land length: slice width x fraction of the
    /// tip land under the bore, m (the land's pressure loads).
    pub width: f64,
    /// Slice width, m.
    pub dz: f64,
    /// Unit vector from the gear centre to the tip (global frame).
    pub dir: [f64; 2],
    /// Local angle of the tip (wrapped to (-pi, pi]), rad.
    pub psi: f64,
}

/// The width-weighted moments of a tooth tip's sealing slices' directions
/// `d`: `sum w`, `sum w d`, `sum w d d` and `sum w d d d` (the symmetric
/// components). With the gap height `h = c - e . d` of each slice at the
/// centre offset `e`, `sum w h` and `sum w h^3` are polynomials in `e` with
/// these coefficients, so a tip gap costs the same whatever the number of
/// slices, as long as no slice's gap closes (`h >= 0`, which `|e| <= c`
/// guarantees: `d` is a unit vector).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TipMoments {
    w: f64,
    d: [f64; 2],
    /// xx, xy, yy.
    dd: [f64; 3],
    /// xxx, xxy, xyy, yyy.
    ddd: [f64; 4],
}

impl TipSlice {
    /// The slice's gap weights `(w, w / f)`: the width of the gap (the whole
    /// slice while any of its land is under the bore) and that width over the
    /// covered fraction `f` of the land (held at [`MIN_LAND_FRACTION`]), so
    /// that the Couette flow is `w h U / 2` and the Poiseuille conductance
    /// `(w / f) h^3 / (12 mu L)` with `L` the whole land.
    pub fn gap_weights(&self) -> (f64, f64) {
        if self.width <= 0.0 {
            return (0.0, 0.0);
        }
        let f = (self.width / self.dz).clamp(MIN_LAND_FRACTION, 1.0);
        (self.dz, self.dz / f)
    }
}

impl TipMoments {
    /// The moments of the slices with a sealed width, each weighted by
    /// `weight` (e.g. a component of [`TipSlice::gap_weights`]).
    pub fn of(slices: &[TipSlice], weight: impl Fn(&TipSlice) -> f64) -> Self {
        let mut m = TipMoments::default();
        for ts in slices.iter().filter(|ts| ts.width > 0.0) {
            let (w, [x, y]) = (weight(ts), ts.dir);
            m.w += w;
            m.d = [m.d[0] + w * x, m.d[1] + w * y];
            m.dd = [
                m.dd[0] + w * x * x,
                m.dd[1] + w * x * y,
                m.dd[2] + w * y * y,
            ];
            m.ddd = [
                m.ddd[0] + w * x * x * x,
                m.ddd[1] + w * x * x * y,
                m.ddd[2] + w * x * y * y,
                m.ddd[3] + w * y * y * y,
            ];
        }
        m
    }

    /// `(sum w h, sum w h^3)` with `h = c - e . d`, exact (to round-off)
    /// while no slice's gap closes (see the type's docs).
    pub fn sums(&self, c: f64, e: [f64; 2]) -> (f64, f64) {
        self.sums_at(&TipPowers::new(c, e))
    }

    /// [`sums`](Self::sums) with the products of the clearance and the
    /// offset that every tip of a gear shares worked out once
    /// ([`TipPowers`]): the same products in the same order, so the same
    /// bits.
    #[inline]
    pub fn sums_at(&self, q: &TipPowers) -> (f64, f64) {
        // sum w (e.d)^k for k = 1, 2, 3
        let a1 = q.x * self.d[0] + q.y * self.d[1];
        let a2 = q.xx * self.dd[0] + q.xy2 * self.dd[1] + q.yy * self.dd[2];
        let a3 =
            q.xxx * self.ddd[0] + q.xxy3 * self.ddd[1] + q.xyy3 * self.ddd[2] + q.yyy * self.ddd[3];
        let wh = q.c * self.w - a1;
        let wh3 = q.ccc * self.w - q.cc3 * a1 + q.c3 * a2 - a3;
        (wh, wh3)
    }
}

/// The products of a clearance `c` and a centre offset `e = (x, y)` that
/// [`TipMoments::sums_at`] needs, each formed left to right as
/// [`TipMoments::sums`] formed it per tip (`3 x x y` is `((3 x) x) y`).
#[derive(Debug, Clone, Copy)]
pub struct TipPowers {
    c: f64,
    x: f64,
    y: f64,
    xx: f64,
    xy2: f64,
    yy: f64,
    xxx: f64,
    xxy3: f64,
    xyy3: f64,
    yyy: f64,
    ccc: f64,
    cc3: f64,
    c3: f64,
}

impl TipPowers {
    /// The centre offset these are the powers of, m.
    pub fn offset(&self) -> [f64; 2] {
        [self.x, self.y]
    }

    /// Whether the offset lies within the clearance (`|e| <= c`), where no
    /// slice's gap can close and [`TipMoments::sums_at`] is exact.
    pub fn within_clearance(&self) -> bool {
        self.xx + self.yy <= self.c * self.c
    }

    pub fn new(c: f64, [x, y]: [f64; 2]) -> Self {
        TipPowers {
            c,
            x,
            y,
            xx: x * x,
            xy2: 2.0 * x * y,
            yy: y * y,
            xxx: x * x * x,
            xxy3: 3.0 * x * x * y,
            xyy3: 3.0 * x * y * y,
            yyy: y * y * y,
            ccc: c * c * c,
            cc3: 3.0 * c * c,
            c3: 3.0 * c,
        }
    }
}

/// One angular step of the tables. Per-pocket arrays are indexed by cell,
/// `zone * pockets + pocket` (module docs).
///
/// Step `i` is the step that ends at driving angle `i dtheta`. The volumes
/// are those at its end (the backward-Euler mass balance stores
/// `rho(p) V` at the end of the step); everything the pressures act
/// through over the step (openings, passages, tip gaps, pressure loads) is
/// taken at its middle, `(i - 1/2) dtheta` ([`STEP_MIDPOINT`]).
#[derive(Debug, Clone, Default)]
pub struct Step {
    /// Volume of every cell (driving gear first in each zone) at the end of
    /// the step, m^3.
    pub volume: Vec<f64>,
    /// Orifice Cd*A from each pocket to the inlet and the outlet chamber
    /// (ports through the bore opening plus relief grooves), m^2.
    pub cda_in: Vec<f64>,
    pub cda_out: Vec<f64>,
    /// Orifice Cd*A from each pocket to the inlet and the outlet chamber
    /// through the relief grooves (both plates), m^2; apart from the bore
    /// openings so that the loss budget can tell them apart.
    pub groove_in: Vec<f64>,
    pub groove_out: Vec<f64>,
    /// Meshing-zone passages (cell of gear 1, cell of gear 2, in the same
    /// zone; Cd*A in m^2).
    pub mesh: Vec<(usize, usize, f64)>,
    /// The axial channels: (cell of zone j, the same space's cell of zone
    /// j + 1, conductance times viscosity in m^3); empty with one zone.
    pub axial: Vec<(usize, usize, f64)>,
    /// Tips: for tooth t of gear k in zone j (between pockets t-1 and t of
    /// that gear), at index `j * z[k] + t`, the sealing slices.
    pub tips: [Vec<Vec<TipSlice>>; 2],
    /// The moments of each tip's slices ([`TipMoments`]) with the
    /// Poiseuille weights and with the Couette weights of
    /// [`TipSlice::gap_weights`], as `tips`.
    pub tip_moments: [Vec<TipMoments>; 2],
    pub tip_drag_moments: [Vec<TipMoments>; 2],
    /// Loads per unit pressure of each pocket: [F1x, F1y, T1, F2x, F2y, T2]
    /// (N/Pa and N m/Pa; torques counter-clockwise positive).
    pub loads: Vec<[f64; 6]>,
}

#[derive(Debug, Clone)]
pub struct StepTables {
    pub steps: Vec<Step>,
    /// Angular step, rad (pitch1 / steps.len()).
    pub dtheta: f64,
    pub z: [usize; 2],
    /// Axial zones of every tooth space (module docs).
    pub zones: usize,
}

/// Length of the overlap of [a0, a1] with [b0, b1].
fn overlap(a0: f64, a1: f64, b0: f64, b1: f64) -> f64 {
    (a1.min(b1) - a0.max(b0)).max(0.0)
}

/// Overlap of an angular interval centred at c (half-width h) with [lo, hi],
/// all in local angles; handles wrap-around.
fn ang_overlap(c: f64, h: f64, lo: f64, hi: f64) -> f64 {
    let c = wrap_pi(c);
    let mut s = 0.0;
    for shift in [-2.0 * PI, 0.0, 2.0 * PI] {
        s += overlap(c - h + shift, c + h + shift, lo, hi);
    }
    s
}

impl StepTables {
    /// Tooth spaces of both gears (the cells of one zone).
    pub fn pockets(&self) -> usize {
        self.z[0] + self.z[1]
    }

    /// Cells: every tooth space in every axial zone.
    pub fn cells(&self) -> usize {
        self.zones * self.pockets()
    }

    pub fn build(d: &Design, pair: &Pair, sec: &SectionTables) -> StepTables {
        let z = [pair.gears[0].z, pair.gears[1].z];
        let p1 = pair.gears[0].pitch_angle();
        let n = (p1 / d.numerics.angle_step).round().max(4.0) as usize;
        let dtheta = p1 / n as f64;
        let ns = d.numerics.slices;
        let na = d.numerics.axial_nodes.clamp(1, ns);
        let zone_of = |s: usize| s * na / ns;
        let dz = pair.b / ns as f64;
        let np = z[0] + z[1];
        let nc = na * np;
        let casing = &d.casing;
        let groove_section = casing.groove_width * casing.groove_depth;
        // each zone's extent along the face (in slices) and the stretch of
        // every slice on the way from zone j's centre to zone j + 1's
        let zone_span: Vec<(f64, f64)> = (0..na)
            .map(|j| {
                let first = (0..ns).find(|&s| zone_of(s) == j).expect("na <= ns");
                let last = (0..ns).rfind(|&s| zone_of(s) == j).expect("na <= ns");
                (first as f64, (last + 1) as f64)
            })
            .collect();
        let paths: Vec<Vec<(usize, f64)>> = (0..na.saturating_sub(1))
            .map(|j| {
                let from = 0.5 * (zone_span[j].0 + zone_span[j].1);
                let to = 0.5 * (zone_span[j + 1].0 + zone_span[j + 1].1);
                (0..ns)
                    .map(|s| (s, overlap(s as f64, s as f64 + 1.0, from, to) * dz))
                    .filter(|&(_, l)| l > 0.0)
                    .collect()
            })
            .collect();
        let mut steps = Vec::with_capacity(n);
        for istep in 0..n {
            // the step's end (volumes) and the angle its flows and loads act
            // at (STEP_MIDPOINT)
            let th_end = istep as f64 * dtheta;
            let th = th_end - STEP_MIDPOINT * dtheta;
            let mut st = Step {
                volume: vec![0.0; nc],
                cda_in: vec![0.0; nc],
                cda_out: vec![0.0; nc],
                groove_in: vec![0.0; nc],
                groove_out: vec![0.0; nc],
                mesh: Vec::new(),
                axial: Vec::new(),
                tips: [vec![Vec::new(); na * z[0]], vec![Vec::new(); na * z[1]]],
                tip_moments: [Vec::new(), Vec::new()],
                tip_drag_moments: [Vec::new(), Vec::new()],
                loads: vec![[0.0; 6]; nc],
            };
            // the axial resistance (times 1/mu) of every space's slices
            let channels = na > 1 && d.casing.axial_flow == AxialFlow::Laminar;
            let mut slice_resistance = vec![0.0f64; if channels { ns * np } else { 0 }];
            for s in 0..ns {
                let ths = th + pair.slice_phase(s, ns);
                let zone = zone_of(s);
                let cell0 = zone * np;
                for k in 0..2 {
                    let g = &pair.gears[k];
                    let spec = &d.gears[k];
                    let pa = g.pitch_angle();
                    let half_tip = g.half_angle(g.ra);
                    let half_open = 0.5 * pa - half_tip;
                    let cusp = pair.cusp_angle(k);
                    for m in 0..z[k] {
                        let idx = cell0 + if k == 0 { m } else { z[0] + m };
                        let phi = pair.space_centre(k, m, ths);
                        let smp = sec.sample(k, phi);
                        let at_end = pair.space_centre(k, m, th_end + pair.slice_phase(s, ns));
                        st.volume[idx] += sec.sample(k, at_end).area * dz;
                        if channels {
                            slice_resistance[s * np + idx - cell0] = if smp.area > AXIAL_CLOSED_AREA
                            {
                                let dh = 4.0 * smp.area / smp.perimeter;
                                AXIAL_POISEUILLE / (2.0 * smp.area * dh * dh)
                            } else {
                                f64::INFINITY
                            };
                        }
                        for c in 0..3 {
                            st.loads[idx][c] += if c < 2 {
                                smp.force[0][c]
                            } else {
                                smp.torque[0]
                            } * dz;
                            st.loads[idx][3 + c] += if c < 2 {
                                smp.force[1][c]
                            } else {
                                smp.torque[1]
                            } * dz;
                        }
                        // bore openings to the chambers
                        let open_in =
                            ang_overlap(phi, half_open, cusp, spec.suction_edge) * g.ra * dz;
                        let open_out =
                            ang_overlap(phi, half_open, spec.delivery_edge, -cusp) * g.ra * dz;
                        st.cda_in[idx] += casing.port_cd * open_in;
                        st.cda_out[idx] += casing.port_cd * open_out;
                        // tooth m (trailing side of space m) sealing in the bore
                        let tip = pair.body_offset(k, ths) + m as f64 * pa;
                        let sealed = ang_overlap(
                            tip,
                            half_tip,
                            spec.suction_edge,
                            2.0 * PI + spec.delivery_edge,
                        );
                        let frac = (sealed / (2.0 * half_tip)).min(1.0);
                        let x = pair.local_to_global(k, 1.0, tip);
                        let c = pair.centre(k);
                        st.tips[k][zone * z[k] + m].push(TipSlice {
                            width: frac * dz,
                            dz,
                            dir: [x[0] - c[0], x[1] - c[1]],
                            psi: wrap_pi(tip),
                        });
                    }
                }
                // meshing-zone passages at this slice: interpolate the interface table
                let ni = sec.interfaces.len();
                let u = ths / sec.dtheta_if;
                let base = u.floor();
                let f = u - base;
                for (w, off) in [(1.0 - f, 0i64), (f, 1)] {
                    if w <= 0.0 {
                        continue;
                    }
                    let j = base as i64 + off; // table index in units of dtheta_if
                    let period = j.div_euclid(ni as i64); // whole pitches
                    let jj = j.rem_euclid(ni as i64) as usize;
                    for itf in &sec.interfaces[jj] {
                        let a =
                            cell0 + (itf.space[0] as i64 - period).rem_euclid(z[0] as i64) as usize;
                        let b = cell0
                            + z[0]
                            + (itf.space[1] as i64 - period).rem_euclid(z[1] as i64) as usize;
                        let opening = match casing.mesh_passage {
                            MeshPassage::Gap => itf.gap,
                            MeshPassage::Boundary => itf.length,
                        };
                        let cda = w * casing.mesh_cd * opening * dz;
                        match st.mesh.iter_mut().find(|e| e.0 == a && e.1 == b) {
                            Some(e) => e.2 += cda,
                            None => st.mesh.push((a, b, cda)),
                        }
                    }
                }
            }
            // the axial channels between consecutive zones of every space
            for (j, path) in paths.iter().enumerate().filter(|_| channels) {
                for i in 0..np {
                    let r: f64 = path
                        .iter()
                        .map(|&(s, l)| l * slice_resistance[s * np + i])
                        .sum();
                    if r.is_finite() && r > 0.0 {
                        st.axial.push((j * np + i, (j + 1) * np + i, 1.0 / r));
                    }
                }
            }
            let moments = |tips: &[Vec<TipSlice>], drag: bool| -> Vec<TipMoments> {
                tips.iter()
                    .map(|s| {
                        TipMoments::of(s, |ts| {
                            let (w, wp) = ts.gap_weights();
                            if drag {
                                w
                            } else {
                                wp
                            }
                        })
                    })
                    .collect()
            };
            st.tip_moments = [0, 1].map(|k| moments(&st.tips[k], false));
            st.tip_drag_moments = [0, 1].map(|k| moments(&st.tips[k], true));
            // Relief grooves: one on each plate, opening to the end zone at
            // that plate, each plate's overlap in series with its groove's
            // own section (as `hydraulics::grooves`). For helical gears each
            // plate's grooves are offset along the line of action by the
            // helix (+-b tan(beta_b)/2, the usual practice), so that both
            // faces of a pocket open and close together; this equals
            // evaluating both plates' overlaps on the mid-face section.
            if d.casing.relief == Relief::Grooves && groove_section > 0.0 {
                let eff = |a: f64| {
                    casing.groove_cd
                        / (1.0 / (a * a) + 1.0 / (groove_section * groove_section)).sqrt()
                };
                for k in 0..2 {
                    for m in 0..z[k] {
                        let idx = if k == 0 { m } else { z[0] + m };
                        let smp = sec.sample(k, pair.space_centre(k, m, th));
                        for end in [0, (na - 1) * np] {
                            if smp.groove[0] > 0.0 {
                                st.groove_out[end + idx] += eff(smp.groove[0]);
                            }
                            if smp.groove[1] > 0.0 {
                                st.groove_in[end + idx] += eff(smp.groove[1]);
                            }
                        }
                    }
                }
            }
            steps.push(st);
        }
        if d.casing.relief == Relief::Ideal {
            ideal_relief(&mut steps, z, na, casing.port_cd * casing.port_area);
        }
        StepTables {
            steps,
            dtheta,
            z,
            zones: na,
        }
    }
}

/// Ideal relief: at each step, pockets joined by meshing-zone passages form a
/// fluid region; a meshing region whose volume shrinks is joined to the
/// outlet, one whose volume grows to the inlet, through `cda`, unless it
/// already opens to the other chamber (relieving it would join the two
/// chambers through the region: it is left to its own openings). A tooth
/// space's zones joined by the axial channel belong to one region (relieving
/// its zones to different chambers would join the chambers through the
/// channel); with `casing.axial_flow = "none"` each zone is relieved on its
/// own, as the kinematic closed form relieves every section of the face.
///
/// A region that already opens to the chamber it is relieved to is relieved
/// all the same: its opening may be a closing passage between pockets (with
/// helical teeth the contact that cuts a trapped pocket off from the
/// delivery closes slice by slice over several steps, a passage of a few
/// tenths of a mm^2 at the end), through which a shrinking pocket would
/// otherwise be squeezed well above the delivery pressure, not relieved; and
/// when that passage then fell below `tiny` the pocket, still far above the
/// delivery pressure, met the wide relief orifice, where Newton's iteration
/// on the square-root orifice law overshoots to the mirror image of its
/// error (`dp -> -dp`, contracting by `1 - 2 dp_t^2 / dp^2` only) and does
/// not converge.
fn ideal_relief(steps: &mut [Step], z: [usize; 2], zones: usize, cda: f64) {
    let n = steps.len();
    let pockets = z[0] + z[1];
    let np = zones * pockets;
    // volume of cell i at step j, with the relabelling across the period end
    let volume_at = |steps: &[Step], j: i64, i: usize| -> f64 {
        let shift = j.div_euclid(n as i64);
        let jj = j.rem_euclid(n as i64) as usize;
        // label i at step j + shift*n is label (i - shift) one period earlier...
        let (zone, p) = (i / pockets, i % pockets);
        let (first, zk) = if p < z[0] { (0, z[0]) } else { (z[0], z[1]) };
        let local = (p - first) as i64;
        let src = zone * pockets + first + (local + shift).rem_euclid(zk as i64) as usize;
        steps[jj].volume[src]
    };
    let mut extra: Vec<(Vec<f64>, Vec<f64>)> = Vec::with_capacity(n);
    for j in 0..n {
        let st = &steps[j];
        let mut parent: Vec<usize> = (0..np).collect();
        fn find(p: &mut [usize], x: usize) -> usize {
            let mut r = x;
            while p[r] != r {
                r = p[r];
            }
            r
        }
        // passages and openings below a thousandth of the relief area (per
        // axial zone) carry nothing of note (a closing contact): they neither
        // join nor port a region
        let tiny = 1e-3 * cda / zones as f64;
        let mut meshing = vec![false; np];
        for &(a, b, c) in &st.mesh {
            meshing[a] = true;
            meshing[b] = true;
            if c > tiny {
                let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                parent[ra] = rb;
            }
        }
        // a tooth space's zones joined by its channel are one region
        for &(a, b, _) in &st.axial {
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            parent[ra] = rb;
        }
        let mut dv = vec![0.0; np];
        // whether the region opens to the inlet, to the outlet
        let mut opens = vec![[false; 2]; np];
        for i in 0..np {
            let r = find(&mut parent, i);
            dv[r] += volume_at(steps, j as i64 + 1, i) - volume_at(steps, j as i64 - 1, i);
            opens[r][0] |= st.cda_in[i] > tiny;
            opens[r][1] |= st.cda_out[i] > tiny;
        }
        let (mut add_in, mut add_out) = (vec![0.0; np], vec![0.0; np]);
        for i in 0..np {
            let r = find(&mut parent, i);
            // only pockets of the meshing zone, whose volume changes: a
            // pocket sealed in the bore keeps its volume, but the sum over
            // helical slices of table samples leaves it a change of about
            // 1e-9 of itself over two steps (seen up to 2.6e-9 with 1 to 16
            // slices), on which a threshold at 1e-9 relieved it, to the
            // inlet and the outlet in turn; a trapped pocket's changes by
            // 1e-3 to 1e-2 of its volume over two steps
            let vol = steps[j].volume[i].max(1e-30);
            if !(meshing[i] || dv[r].abs() > 1e-6 * vol) {
                continue;
            }
            let [to_inlet, to_outlet] = opens[r];
            if dv[r] < 0.0 {
                if !to_inlet {
                    add_out[i] = cda;
                }
            } else if !to_outlet {
                add_in[i] = cda;
            }
        }
        extra.push((add_in, add_out));
    }
    for (st, (ai, ao)) in steps.iter_mut().zip(extra) {
        for i in 0..np {
            st.cda_in[i] += ai[i];
            st.cda_out[i] += ao[i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Pump;

    fn seed_with(sets: &[&str]) -> Pump {
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        Pump::new(crate::design::from_toml_str(crate::design::SEED_PUMP_TOML, &sets).unwrap())
    }

    /// The zones split the tooth spaces without changing them: summed over
    /// the zones, every cell quantity equals the one-zone tables' (volumes,
    /// loads, port openings, meshing passages, sealing tip widths; the
    /// grooves sit on the end zones, both plates' on the single zone).
    #[test]
    fn axial_zones_sum_to_the_whole_tooth_space() {
        let one = seed_with(&["numerics.axial_nodes=1"]);
        let four = seed_with(&["numerics.axial_nodes=4"]);
        let (t1, t4) = (&one.tables, &four.tables);
        assert_eq!((t1.zones, t4.zones), (1, 4));
        let np = t1.pockets();
        let close = |a: f64, b: f64, what: &str| {
            assert!(
                (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1e-30),
                "{what}: {a} vs {b}"
            )
        };
        for (j, (s1, s4)) in t1.steps.iter().zip(&t4.steps).enumerate() {
            for i in 0..np {
                let sum = |v: &[f64]| (0..4).map(|z| v[z * np + i]).sum::<f64>();
                close(s1.volume[i], sum(&s4.volume), "volume");
                close(s1.cda_in[i], sum(&s4.cda_in), "cda_in");
                close(s1.cda_out[i], sum(&s4.cda_out), "cda_out");
                close(s1.groove_in[i], sum(&s4.groove_in), "groove_in");
                close(s1.groove_out[i], sum(&s4.groove_out), "groove_out");
                for inner in [np + i, 2 * np + i] {
                    assert_eq!(
                        s4.groove_in[inner] + s4.groove_out[inner],
                        0.0,
                        "inner zone groove"
                    );
                }
                for c in 0..6 {
                    // sums of terms of both signs: to the scale of the terms
                    let l4: f64 = (0..4).map(|z| s4.loads[z * np + i][c]).sum();
                    let scale: f64 = (0..4).map(|z| s4.loads[z * np + i][c].abs()).sum();
                    assert!((s1.loads[i][c] - l4).abs() <= 1e-12 * scale, "loads");
                }
            }
            let mesh = |t: &[(usize, usize, f64)]| {
                let mut m = vec![0.0; np * np];
                for &(a, b, c) in t {
                    m[(a % np) * np + b % np] += c;
                }
                m
            };
            for (a, b) in mesh(&s1.mesh).iter().zip(mesh(&s4.mesh)) {
                close(*a, b, "mesh");
            }
            for k in 0..2 {
                let z = t1.z[k];
                for t in 0..z {
                    let w = |tips: &[Vec<TipSlice>], zones: usize| -> f64 {
                        (0..zones)
                            .flat_map(|zn| tips[zn * z + t].iter())
                            .map(|ts| ts.width)
                            .sum()
                    };
                    close(w(&s1.tips[k], 1), w(&s4.tips[k], 4), "tip width");
                }
            }
            assert!(s1.axial.is_empty(), "step {j}: one zone has no channel");
            assert_eq!(
                s4.axial.len(),
                3 * np,
                "step {j}: every space, every zone boundary"
            );
        }
    }

    /// A tooth space far from the mesh is a straight duct of the free
    /// section: its channel between the centres of two zones of a two-zone
    /// pump (half the face width apart) conducts `2 A D_h^2 / (C mu L)` with
    /// `D_h = 4 A / P`, `L = b / 2` (Hagen-Poiseuille on the hydraulic
    /// diameter), here times mu. And `"none"` leaves no channel.
    #[test]
    fn a_free_tooth_space_channel_is_a_poiseuille_duct() {
        let p = seed_with(&["numerics.axial_nodes=2"]);
        let np = p.tables.pockets();
        let b = p.design.face_width;
        let mut checked = 0;
        for k in 0..2 {
            let free = p.sections.free[k];
            let dh = 4.0 * free.area / free.perimeter;
            let hand = 2.0 * free.area * dh * dh / (AXIAL_POISEUILLE * 0.5 * b);
            // far from the mesh: the pocket's tables are the free section
            for &(a, _, g) in &p.tables.steps[0].axial {
                let i = a % np;
                let (first, m) = if i < p.tables.z[0] {
                    (0, i)
                } else {
                    (p.tables.z[0], i - p.tables.z[0])
                };
                if (k == 0) != (first == 0) {
                    continue;
                }
                let phi = p.pair.space_centre(k, m, 0.0);
                if crate::geometry::tables::wrap_pi(phi).abs() > 2.5 {
                    assert!(
                        (g - hand).abs() < 1e-9 * hand,
                        "gear {k} space {m}: {g} vs {hand}"
                    );
                    checked += 1;
                }
            }
        }
        assert!(checked >= 4, "{checked} free spaces checked");
        let none = seed_with(&["numerics.axial_nodes=2", "casing.axial_flow=none"]);
        assert!(none.tables.steps.iter().all(|s| s.axial.is_empty()));
    }

    #[test]
    fn tip_moments_give_the_slice_sums() {
        let pump = crate::model::Pump::new(Design::seed());
        let c = pump.design.clearance.tip[0];
        let mut tips = 0;
        for st in pump.tables.steps.iter().step_by(5) {
            for k in 0..2 {
                for slices in &st.tips[k] {
                    let m = &TipMoments::of(slices, |ts| ts.width);
                    // offsets up to the clearance, in several directions
                    for (r, a) in [(0.0, 0.0), (0.3, 1.0), (0.7, 2.5), (1.0, 4.0), (0.95, 5.5)] {
                        let e = [r * c * f64::cos(a), r * c * f64::sin(a)];
                        let (mut wh, mut wh3) = (0.0, 0.0);
                        for ts in slices.iter().filter(|ts| ts.width > 0.0) {
                            let h = c - (e[0] * ts.dir[0] + e[1] * ts.dir[1]);
                            wh += ts.width * h;
                            wh3 += ts.width * h * h * h;
                        }
                        let (mh, mh3) = m.sums(c, e);
                        assert!((mh - wh).abs() <= 1e-12 * (c * m.w), "{mh} vs {wh}");
                        assert!(
                            (mh3 - wh3).abs() <= 1e-12 * (8.0 * c * c * c * m.w),
                            "{mh3} vs {wh3}"
                        );
                        tips += usize::from(wh > 0.0);
                    }
                }
            }
        }
        assert!(tips > 100, "{tips} sealing tips checked");
    }
}
