//! The control-volume network of the pump (seed Sec. 2.2, docs/model.md section 4).
//!
//! States: absolute pressures of the inlet chamber, the outlet chamber, the
//! two hubs (the annular regions round each shaft at the gear faces, fed by
//! the lateral gaps and drained through the journal bearings to the inlet
//! through the by-pass grooves of seed Sec. 3) and every pocket.
//! Pressure build-up (Eq. 9) is written in its conservative form
//! `d(rho(p) V)/dt = sum rho_up Q`, i.e. `dp/dt = B/V (sum Q - dV/dt)`.
//!
//! Flows:
//! * ports: suction line -> inlet chamber, outlet chamber -> delivery line (Eq. 11);
//! * pocket <-> chambers through the bore openings and the relief grooves (Eq. 11);
//! * meshing-zone passages between the gears' pockets (Eq. 11);
//! * tooth tip / casing gaps between consecutive pockets (Eq. 10), the local
//!   clearance `h = c - e . r_tip` from the gear centre offset `e`. The
//!   Couette (drag) term carries `w h U / 2` from the pocket behind the tooth
//!   to the pocket ahead, forward with the teeth. Why forward: the pockets
//!   are bounded by the tip circle (the tables' areas end at `ra`), so the
//!   clearance annulus between the tip circle and the bore belongs to no
//!   pocket. That annulus is fixed in the casing frame: its walls are the
//!   bore (at rest) and the tip circle (the teeth's lands moving at `U`, the
//!   spaces' fluid moving with them), so its fluid is dragged forward, a
//!   flux `w h U / 2` per unit of its width from the suction side round to
//!   the delivery side, whatever the tooth under it. Counted gap by gap,
//!   each tip gap passes that flux on from the pocket behind to the pocket
//!   ahead (each pocket between receives and gives the same). The tooth
//!   frame (fluid moving backwards relative to a tooth) would be right only
//!   if the pockets included the annulus above them, which their tables do
//!   not; it made the drag a loss of about 1.1 points of eta_v where it is a
//!   gain of about 0.7 (seed pump, 1000 rpm);
//! * lateral gaps (both faces): across each tooth between consecutive pockets
//!   (width = tooth height, length = tooth thickness at mid-height; drag
//!   forward with the teeth for the same reason as at the tips: the pockets
//!   end at the gear faces, the film between face and plate is fixed in the
//!   casing frame), and from
//!   every pocket radially inwards to the hub (annular-sector conductance
//!   `dphi h^3 / (12 mu ln(rf/R))`), Eq. 10;
//! * journal bearings (two per gear): hub -> inlet, `pi D c^3 (1 + 1.5 eps^2) / (12 mu L)`;
//! * by-pass grooves (seed Sec. 3): hub -> inlet (Eq. 11), so that the
//!   bearings are fed from suction, as in the seed's pump.

use super::steps::{Step, StepTables, TipMoments, TipPowers, TipSlice};
use crate::flow::{eccentric_annulus_factor, gap_conductance, orifice_flow};
use crate::oil::Compressibility;
pub use crate::oil::DensityLaw;
use crate::solver::ConservativeSystem;
use crate::vec2::norm;
use nalgebra::{DMatrix, DVector};

pub const INLET: usize = 0;
pub const OUTLET: usize = 1;
pub const HUB: [usize; 2] = [2, 3];
pub const FIRST_POCKET: usize = 4;

/// Node of a flow element: a state or a fixed-pressure boundary.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Node {
    State(usize),
    Suction,
    Delivery,
}

/// A flow element between two nodes: orifice (Cd*A) or laminar gap
/// (conductance G and Couette flow from a to b).
#[derive(Debug, Clone, Copy)]
pub enum Element {
    Orifice {
        a: Node,
        b: Node,
        cda: f64,
    },
    Gap {
        a: Node,
        b: Node,
        g: f64,
        couette: f64,
    },
}

/// What a flow element is, for the loss budget (`crate::losses`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FlowKind {
    /// Suction line -> inlet chamber, outlet chamber -> delivery line.
    LinePort,
    /// A pocket's opening to a chamber through the bore (the ports).
    PocketPort,
    /// A pocket's passage to a chamber through a relief groove.
    Groove,
    /// A meshing-zone passage between the gears' pockets.
    Mesh,
    /// A tooth tip / casing gap.
    Tip,
    /// A lateral gap across a tooth (both faces).
    LateralTooth,
    /// The lateral gaps from a pocket inwards to its gear's hub.
    LateralHub,
    /// A gear's journal bearings (hub -> inlet).
    Bearing,
    /// The by-pass grooves joining a hub to the inlet.
    Bypass,
    /// The channel along a helical tooth space between two axial zones.
    Axial,
}

/// Operating point of the network, SI.
#[derive(Debug, Clone, Copy)]
pub struct Conditions {
    /// Suction and delivery line pressures (absolute), Pa.
    pub p_suction: f64,
    pub p_delivery: f64,
    /// Driving speed, rad/s (> 0).
    pub omega: f64,
    /// Dynamic viscosity (Pa s) and density at atmospheric pressure (kg/m^3).
    pub mu: f64,
    pub rho: f64,
    /// Regularisation pressure of the orifice law (Eq. 11), Pa.
    pub dp_t: f64,
}

/// Fixed geometry of the leakage paths (from the design), SI.
#[derive(Debug, Clone)]
pub struct LeakGeometry {
    /// Tip land length (arc) of each gear, m.
    pub tip_land: [f64; 2],
    /// Tip radius of each gear, m.
    pub tip_radius: [f64; 2],
    /// Lateral: tooth height (ra - rf), tooth thickness at mid-height, mean radius, m.
    pub tooth_height: [f64; 2],
    pub tooth_mid_thickness: [f64; 2],
    pub mid_radius: [f64; 2],
    /// Pocket -> hub sector: angular pitch (rad) and ln(rf / R_journal).
    pub pitch: [f64; 2],
    pub ln_root_journal: [f64; 2],
    /// Bearings: diameter, length, m.
    pub bearing_diameter: [f64; 2],
    pub bearing_length: f64,
    /// Chamber volumes and hub volumes, m^3; port Cd*A, m^2.
    pub inlet_volume: f64,
    pub outlet_volume: f64,
    pub hub_volume: f64,
    pub port_cda: f64,
    /// By-pass grooves from each hub to the inlet, Cd*A, m^2 (0 = none).
    pub bypass_cda: f64,
    /// Gear speed ratio z1/z2.
    pub ratio: f64,
}

/// Clearances of one pump sample and the gear centre offsets, SI.
#[derive(Debug, Clone, Copy)]
pub struct GapState {
    pub tip: [f64; 2],
    pub bearing: [f64; 2],
    pub lateral: f64,
    /// Gear centre offsets from the bore centres (global frame), m.
    pub offset: [[f64; 2]; 2],
    /// Multiplier on the gap viscosity (pressure-viscosity extension), 1 = base.
    pub gap_viscosity_factor: f64,
}

/// An element in the flat form of the flux loop: node indices into the
/// extended node list (states, then suction `n`, then delivery `n + 1`).
#[derive(Debug, Clone, Copy)]
struct Link {
    a: usize,
    b: usize,
    /// Orifice: `Cd A sqrt(2 / rho)`; gap: conductance.
    k: f64,
    /// Gap: Couette flow a -> b (0 for orifices).
    couette: f64,
    orifice: bool,
}

/// A node's values in the flux loop: its pressure, density `rho r` and the
/// density's derivative `rho dr/dp` (`r` the density ratio, `rho` the
/// density at atmospheric pressure), and its net inflow.
///
/// One record per node (the states, then suction and delivery) rather than
/// one array per quantity: the loop reads both ends of every element and
/// writes their inflows, which costs two bounds checks per element this way
/// and five with separate arrays. The products with `rho` are formed once
/// per node: every use multiplies `rho * r` (or `rho * dr`) by something
/// else, left to right, so the product is the same whether kept or formed
/// anew, to the bit.
#[derive(Debug, Clone, Copy, Default)]
struct NodeValues {
    p: f64,
    rho_r: f64,
    rho_dr: f64,
    f: f64,
}

impl NodeValues {
    /// A node at pressure `p` before a flux pass: its density and the
    /// density's derivative from `law` and `rho`, no inflow yet.
    #[inline]
    fn at(law: &DensityLaw, rho: f64, p: f64) -> Self {
        let (r, dr) = law.ratio(p);
        NodeValues {
            p,
            rho_r: rho * r,
            rho_dr: rho * dr,
            f: 0.0,
        }
    }
}

/// Reusable buffers of [`Network`] (see [`Network::assemble_with`]).
#[derive(Debug, Clone, Default)]
pub struct NetworkBuffers {
    pub elements: Vec<Element>,
    kinds: Vec<FlowKind>,
    pub volume: Vec<f64>,
    links: Vec<Link>,
    nodes: Vec<NodeValues>,
    order: Vec<usize>,
    pattern: Vec<u64>,
    movers: Vec<Mover>,
    spinners: Vec<Spinner>,
    link_mass: Vec<f64>,
}

/// A gap whose Couette flow goes with the speed but not with the gear
/// centre offsets (the lateral gap across a tooth): its element and gear,
/// and the flow's factor before the wall speed, `nf (h / 2) s` as the
/// assembly multiplies it, so that `factor * u_mid` is its Couette flow to
/// the bit ([`Network::set_speed`]).
#[derive(Debug, Clone, Copy)]
struct Spinner {
    element: usize,
    gear: usize,
    factor: f64,
}

/// The networks of the steps of a mesh period as assembled at one set of
/// conditions (what [`Network::assemble_cached`] reuses). Every element of a
/// step depends on the step's tables, the clearances, the viscosity, the
/// density and the speed; only the gaps that follow the gear centres
/// depend on the offsets (they are moved to the offsets asked for, as
/// [`Network::set_offsets`] does: the same values as a fresh assembly, to
/// the bit), only the drag flows on the speed (an entry assembled at
/// another speed has them recomputed, [`Network::set_speed`], the same
/// bits again) and only the boundaries' densities and pressures on the
/// port pressures (set at each use). A change of anything else empties it.
/// Not part of any state: a network from it equals the one assembled anew.
/// A network holds its entry's vectors (lent, not copied) until
/// [`AssemblyCache::release`] takes them back.
#[derive(Debug, Clone, Default)]
pub struct AssemblyCache {
    key: Option<AssemblyKey>,
    /// Bumped when the key changes: an entry of another generation is stale
    /// (its storage is kept and overwritten).
    generation: u64,
    steps: Vec<CachedNetwork>,
    /// The density law of the key's oil, and the boundaries' values at the
    /// port pressures last asked for (their bits): the same at each use
    /// while neither changes, three to four transcendental calls saved per
    /// assembly.
    law: Option<DensityLaw>,
    ports: Option<([u64; 2], [NodeValues; 2])>,
}

impl AssemblyCache {
    /// The buffers of `net` for the next assembly, its step's vectors put
    /// back into the entry they came from (when that entry still expects
    /// them: same generation, still lent), which takes the entry's spare
    /// storage in exchange.
    pub fn release(&mut self, net: Network<'_>) -> NetworkBuffers {
        let slot = net.slot;
        let mut bufs = net.into_buffers();
        if let Some((istep, generation)) = slot {
            if let Some(entry) = self.steps.get_mut(istep) {
                if entry.lent && entry.generation == generation {
                    swap_assembly(&mut bufs, &mut entry.bufs);
                    entry.lent = false;
                }
            }
        }
        bufs
    }
}

/// Exchanges the vectors of a step's assembly (everything but the node
/// values and the recorded flows) between `a` and `b`.
fn swap_assembly(a: &mut NetworkBuffers, b: &mut NetworkBuffers) {
    std::mem::swap(&mut a.elements, &mut b.elements);
    std::mem::swap(&mut a.kinds, &mut b.kinds);
    std::mem::swap(&mut a.volume, &mut b.volume);
    std::mem::swap(&mut a.links, &mut b.links);
    std::mem::swap(&mut a.order, &mut b.order);
    std::mem::swap(&mut a.pattern, &mut b.pattern);
    std::mem::swap(&mut a.movers, &mut b.movers);
    std::mem::swap(&mut a.spinners, &mut b.spinners);
}

/// What a step's assembly depends on besides the step, the offsets and
/// the speed (the drag flows alone go with it: the entries follow it,
/// [`Network::set_speed`]).
#[derive(Debug, Clone, Copy, PartialEq)]
struct AssemblyKey {
    /// The addresses of the pump's tables and geometry (compared only).
    tables: usize,
    geo: usize,
    tip: [f64; 2],
    bearing: [f64; 2],
    lateral: f64,
    gap_viscosity_factor: f64,
    mu: f64,
    rho: f64,
    dp_t: f64,
    comp: [f64; 4],
}

impl AssemblyKey {
    fn new(
        tables: &StepTables,
        geo: &LeakGeometry,
        gaps: &GapState,
        cond: &Conditions,
        comp: &Compressibility,
    ) -> Self {
        AssemblyKey {
            tables: tables as *const StepTables as usize,
            geo: geo as *const LeakGeometry as usize,
            tip: gaps.tip,
            bearing: gaps.bearing,
            lateral: gaps.lateral,
            gap_viscosity_factor: gaps.gap_viscosity_factor,
            mu: cond.mu,
            rho: cond.rho,
            dp_t: cond.dp_t,
            comp: [
                comp.bulk_modulus,
                comp.gas_release_pa,
                comp.cavitation_modulus,
                comp.air_fraction,
            ],
        }
    }
}

/// One step's assembled network.
#[derive(Debug, Clone, Default)]
struct CachedNetwork {
    generation: u64,
    bufs: NetworkBuffers,
    mover_params: [MoverParams; 2],
    /// Whether the step's vectors are out in a network (see
    /// [`AssemblyCache::release`]): `bufs` then holds no assembly.
    lent: bool,
    /// The speed its drag flows were computed at (bits of rad/s): a change
    /// of speed alone updates them ([`Network::set_speed`]).
    omega: u64,
}

/// A gap element whose height follows a gear centre offset: a tooth tip gap
/// (its slices' heights `c - e . dir`) or a gear's journal bearings (their
/// eccentricity).
#[derive(Debug, Clone, Copy)]
struct Mover {
    /// Index into the elements (and the links).
    element: usize,
    gear: usize,
    /// The tip gap's index in `Step::tips[gear]` (zone * z + tooth); None
    /// for the bearings.
    tooth: Option<usize>,
    /// A tip gap's slice moments with the Poiseuille and the Couette
    /// weights (`Step::tip_moments` and `Step::tip_drag_moments` at
    /// `tooth`; zero for the bearings), copied here so that the gap update
    /// reads one list in order rather than three per-gear tables (the
    /// slices themselves only when a slice's gap can close).
    moments: TipMoments,
    drag: TipMoments,
}

/// What the offset-dependent gaps of one gear need besides the offset.
#[derive(Debug, Clone, Copy, Default)]
struct MoverParams {
    tip: f64,
    tip_land: f64,
    mu_gap: f64,
    /// Tip speed of the gear, m/s.
    u_tip: f64,
    bearing: f64,
    /// The bearings' conductance at zero eccentricity.
    bearing_g0: f64,
}

impl MoverParams {
    /// Conductance and Couette flow of a tip gap over its slices (their
    /// moments while no slice's gap can close, `|e| <= c`).
    #[inline]
    fn tip_gap<'s>(
        &self,
        slices: impl FnOnce() -> &'s [TipSlice],
        moments: &TipMoments,
        drag: &TipMoments,
        powers: &TipPowers,
    ) -> (f64, f64) {
        // the slices' Poiseuille conductances (w / f) h^3 / (12 mu L) and
        // Couette flows w h u / 2 (`TipSlice::gap_weights`), summed over the
        // slices first; `powers` are those of this gear's clearance
        // (`self.tip`) and offset
        let (wh, wh3) = if powers.within_clearance() {
            (drag.sums_at(powers).0, moments.sums_at(powers).1)
        } else {
            let e = powers.offset();
            let (mut wh, mut wh3) = (0.0, 0.0);
            for ts in slices().iter().filter(|ts| ts.width > 0.0) {
                let h = (self.tip - (e[0] * ts.dir[0] + e[1] * ts.dir[1])).max(0.0);
                let (w, wp) = ts.gap_weights();
                wh3 += wp * h * h * h;
                wh += w * h;
            }
            (wh, wh3)
        };
        (
            wh3 / (12.0 * self.mu_gap * self.tip_land),
            0.5 * wh * self.u_tip,
        )
    }

    /// Conductance of the journal bearings at offset `e`.
    #[inline]
    fn bearing_gap(&self, e: [f64; 2]) -> f64 {
        // held below 1: the network's film never closes
        let eps = (norm(e[0], e[1]) / self.bearing).min(0.99);
        self.bearing_g0 * eccentric_annulus_factor(eps)
    }
}

/// The network at one angular step, ready for the implicit solver.
pub struct Network<'a> {
    pub n: usize,
    pub volume: Vec<f64>,
    pub elements: Vec<Element>,
    /// What each element is (as `elements`).
    pub kinds: Vec<FlowKind>,
    pub cond: Conditions,
    pub comp: Compressibility,
    pub p_scale: f64,
    law: DensityLaw,
    /// The elements in the flat form of the flux loop.
    links: Vec<Link>,
    /// Pressure, density (and its derivative) and net inflow of the
    /// states and the two boundaries (suction, delivery); the states'
    /// refreshed at each flux evaluation (each node's law is evaluated
    /// once, not per element).
    nodes: Vec<NodeValues>,
    /// Elimination order of the Jacobian: the pockets (each coupled to a few
    /// neighbours) first, the chambers and hubs (coupled to many) last.
    order: Vec<usize>,
    /// The Jacobian's sparsity: for each state, the bit set of the states
    /// it shares an element with, and itself (empty beyond 64 states).
    pattern: Vec<u64>,
    /// The gaps that follow the gear centre offsets ([`set_offsets`](Self::set_offsets)).
    movers: Vec<Mover>,
    /// The gaps whose drag alone goes with the speed ([`set_speed`](Self::set_speed)).
    spinners: Vec<Spinner>,
    /// While set, each flux evaluation without a Jacobian keeps every
    /// element's mass flow a -> b in `link_mass` (the loss budget reads
    /// them: [`for_each_mass_flow`](Self::for_each_mass_flow)).
    pub record_flows: bool,
    link_mass: Vec<f64>,
    mover_params: [MoverParams; 2],
    step: &'a Step,
    /// The step index and generation of the [`AssemblyCache`] entry whose
    /// vectors this network holds (they go back at
    /// [`AssemblyCache::release`]).
    slot: Option<(usize, u64)>,
}

impl<'a> Network<'a> {
    /// The buffers, for the next [`assemble_with`](Self::assemble_with).
    pub fn into_buffers(self) -> NetworkBuffers {
        NetworkBuffers {
            elements: self.elements,
            kinds: self.kinds,
            volume: self.volume,
            links: self.links,
            nodes: self.nodes,
            order: self.order,
            pattern: self.pattern,
            movers: self.movers,
            spinners: self.spinners,
            link_mass: self.link_mass,
        }
    }

    /// Assembles the elements of step `istep`, reusing every buffer of an
    /// earlier network (`NetworkBuffers::default()` for the first).
    pub fn assemble_with(
        tables: &'a StepTables,
        istep: usize,
        geo: &LeakGeometry,
        gaps: &GapState,
        cond: Conditions,
        comp: Compressibility,
        buffers: NetworkBuffers,
    ) -> Network<'a> {
        let NetworkBuffers {
            elements,
            mut kinds,
            volume,
            mut links,
            mut nodes,
            mut order,
            mut pattern,
            mut movers,
            mut spinners,
            link_mass,
        } = buffers;
        movers.clear();
        spinners.clear();
        let st = &tables.steps[istep];
        let np = tables.cells();
        let n = FIRST_POCKET + np;
        let mut volume = volume;
        volume.clear();
        volume.extend_from_slice(&[
            geo.inlet_volume,
            geo.outlet_volume,
            geo.hub_volume,
            geo.hub_volume,
        ]);
        volume.extend_from_slice(&st.volume);
        let mut el = elements;
        el.clear();
        kinds.clear();
        push_ports_and_passages(&mut el, &mut kinds, st, geo, cond.mu);
        let mover_params = push_gear_gaps(
            &mut el,
            &mut kinds,
            &mut movers,
            &mut spinners,
            tables,
            istep,
            geo,
            gaps,
            cond,
        );
        let p_scale = cond.p_delivery.max(cond.p_suction).max(1.0e5);
        let index = |node: Node| match node {
            Node::State(i) => i,
            Node::Suction => n,
            Node::Delivery => n + 1,
        };
        let sqrt_2_rho = (2.0 / cond.rho).sqrt();
        links.clear();
        links.extend(el.iter().map(|e| match *e {
            Element::Orifice { a, b, cda } => Link {
                a: index(a),
                b: index(b),
                // as in `flow::orifice_flow` (no flow through a closed orifice)
                k: if cda > 0.0 { cda * sqrt_2_rho } else { 0.0 },
                couette: 0.0,
                orifice: true,
            },
            Element::Gap { a, b, g, couette } => Link {
                a: index(a),
                b: index(b),
                k: g,
                couette,
                orifice: false,
            },
        }));
        let law = DensityLaw::new(comp);
        set_boundaries(n, &mut nodes, boundary_values(&law, &cond));
        order.clear();
        order.extend(FIRST_POCKET..n);
        order.extend([OUTLET, HUB[0], HUB[1], INLET]);
        pattern.clear();
        if n <= 64 {
            pattern.extend((0..n).map(|i| 1u64 << i));
            for l in links.iter().filter(|l| l.a < n && l.b < n) {
                pattern[l.a] |= 1 << l.b;
                pattern[l.b] |= 1 << l.a;
            }
        }
        Network {
            n,
            volume,
            elements: el,
            kinds,
            cond,
            comp,
            p_scale,
            law,
            links,
            nodes,
            order,
            pattern,
            movers,
            spinners,
            record_flows: false,
            link_mass,
            mover_params,
            step: st,
            slot: None,
        }
    }

    /// [`assemble_with`](Self::assemble_with) through `cache`: a step
    /// already assembled at the same conditions (all but the offsets and
    /// the port pressures) is copied from it, its gear gaps moved to
    /// `gaps.offset` and its boundaries set to the port pressures, which
    /// gives the network `assemble_with` gives, to the bit; otherwise the
    /// step is assembled and kept. The copy costs a fraction of the
    /// assembly (issue 16: a tenth of a co-simulation step's instructions
    /// were the assembly).
    #[allow(clippy::too_many_arguments)] // assemble_with's, and the cache
    pub fn assemble_cached(
        tables: &'a StepTables,
        istep: usize,
        geo: &LeakGeometry,
        gaps: &GapState,
        cond: Conditions,
        comp: Compressibility,
        buffers: NetworkBuffers,
        cache: &mut AssemblyCache,
    ) -> Network<'a> {
        let key = AssemblyKey::new(tables, geo, gaps, &cond, &comp);
        if cache.key != Some(key) {
            cache.key = Some(key);
            cache.generation += 1;
            cache.law = None;
            cache.ports = None;
        }
        if cache.steps.len() != tables.steps.len() {
            cache
                .steps
                .resize_with(tables.steps.len(), CachedNetwork::default);
        }
        let generation = cache.generation;
        let entry = &mut cache.steps[istep];
        // the assembly is not copied: the network takes the entry's vectors
        // and gives them back at `AssemblyCache::release` (what it changes
        // in them, the moving gaps, `set_offsets` sets afresh at each use)
        if entry.generation != generation || entry.lent {
            let mut net = Self::assemble_with(tables, istep, geo, gaps, cond, comp, buffers);
            entry.mover_params = net.mover_params;
            entry.generation = generation;
            entry.omega = cond.omega.to_bits();
            entry.lent = true;
            net.slot = Some((istep, generation));
            return net;
        }
        let mut buffers = buffers;
        swap_assembly(&mut buffers, &mut entry.bufs);
        entry.lent = true;
        let NetworkBuffers {
            elements,
            kinds,
            volume,
            links,
            mut nodes,
            order,
            pattern,
            movers,
            spinners,
            link_mass,
        } = buffers;
        // the boundaries, as `assemble_with` sets them (the law and the
        // ports' values kept while the conditions stay)
        let n = volume.len();
        let law = *cache.law.get_or_insert_with(|| DensityLaw::new(comp));
        let ports = [cond.p_suction, cond.p_delivery].map(f64::to_bits);
        let boundaries = match cache.ports {
            Some((p, v)) if p == ports => v,
            _ => {
                let v = boundary_values(&law, &cond);
                cache.ports = Some((ports, v));
                v
            }
        };
        set_boundaries(n, &mut nodes, boundaries);
        let mut net = Network {
            n,
            volume,
            elements,
            kinds,
            cond,
            comp,
            p_scale: cond.p_delivery.max(cond.p_suction).max(1.0e5),
            law,
            links,
            nodes,
            order,
            pattern,
            movers,
            spinners,
            record_flows: false,
            link_mass,
            mover_params: entry.mover_params,
            step: &tables.steps[istep],
            slot: Some((istep, generation)),
        };
        if entry.omega != cond.omega.to_bits() {
            net.set_speed(geo);
            entry.mover_params = net.mover_params;
            entry.omega = cond.omega.to_bits();
        }
        net.set_offsets(&gaps.offset);
        net
    }

    /// Takes the drag flows to the speed of the network's conditions, as
    /// [`assemble_with`](Self::assemble_with) computes them: the tip gaps'
    /// wall speed (their flows follow at [`set_offsets`](Self::set_offsets))
    /// and the lateral gaps' Couette flows; nothing else depends on the
    /// speed.
    fn set_speed(&mut self, geo: &LeakGeometry) {
        let omega = gear_speeds(self.cond.omega, geo);
        let u_mid = [0, 1].map(|k| omega[k] * geo.mid_radius[k]);
        for (k, mp) in self.mover_params.iter_mut().enumerate() {
            mp.u_tip = omega[k] * geo.tip_radius[k];
        }
        for sp in &self.spinners {
            let cou = sp.factor * u_mid[sp.gear];
            if let Element::Gap { couette, .. } = &mut self.elements[sp.element] {
                *couette = cou;
            }
            self.links[sp.element].couette = cou;
        }
    }

    /// Moves the gear centres to `offset` (global frame, m): the tip gaps and
    /// the journal bearings take the heights and eccentricities of the new
    /// position, as [`assemble_with`](Self::assemble_with) would give them;
    /// nothing else depends on the offsets.
    pub fn set_offsets(&mut self, offset: &[[f64; 2]; 2]) {
        // the products of each gear's clearance and offset that all its
        // tips share, once per gear (they were a third of this function's
        // instructions formed per tip)
        let powers = [0, 1].map(|k| TipPowers::new(self.mover_params[k].tip, offset[k]));
        for m in &self.movers {
            let mp = &self.mover_params[m.gear];
            let e = offset[m.gear];
            let (g, cou) = match m.tooth {
                Some(t) => mp.tip_gap(
                    || &self.step.tips[m.gear][t],
                    &m.moments,
                    &m.drag,
                    &powers[m.gear],
                ),
                None => (mp.bearing_gap(e), 0.0),
            };
            if let Element::Gap { g: eg, couette, .. } = &mut self.elements[m.element] {
                *eg = g;
                *couette = cou;
            }
            let l = &mut self.links[m.element];
            l.k = g;
            l.couette = cou;
        }
    }

    /// Pressure of a node.
    #[inline]
    pub fn pressure(&self, x: &DVector<f64>, node: Node) -> f64 {
        match node {
            Node::State(i) => x[i],
            Node::Suction => self.cond.p_suction,
            Node::Delivery => self.cond.p_delivery,
        }
    }

    /// Volume flow of an element from a to b (m^3/s at the upstream state)
    /// and its derivative with respect to p_a - p_b.
    #[inline]
    pub fn element_flow(&self, e: &Element, x: &DVector<f64>) -> (f64, f64, Node, Node) {
        match *e {
            Element::Orifice { a, b, cda } => {
                let dp = self.pressure(x, a) - self.pressure(x, b);
                let (q, dq) = orifice_flow(cda, self.cond.rho, dp, self.dp_t());
                (q, dq, a, b)
            }
            Element::Gap { a, b, g, couette } => {
                let dp = self.pressure(x, a) - self.pressure(x, b);
                (g * dp + couette, g, a, b)
            }
        }
    }

    /// Calls `f(element, w, w_drag, p_a, p_b)` for every element with its
    /// mass flow from a to b as the last flux evaluation without a Jacobian
    /// recorded it ([`record_flows`](Self::record_flows) set), split into
    /// the pressure-driven (or orifice) part `w` and the drag part `w_drag`
    /// (kg/s), and the pressures of its ends (for the loss budget,
    /// `crate::losses`).
    pub fn for_each_mass_flow(&self, mut f: impl FnMut(usize, f64, f64, f64, f64)) {
        debug_assert_eq!(self.link_mass.len(), self.links.len(), "flows not recorded");
        let v = &self.nodes;
        for (i, (l, &m)) in self.links.iter().zip(&self.link_mass).enumerate() {
            // the drag part at the same upstream density as the whole
            let up = if m >= 0.0 { l.a } else { l.b };
            let w_drag = v[up].rho_r * l.couette;
            f(i, m - w_drag, w_drag, v[l.a].p, v[l.b].p);
        }
    }

    /// The power (W) that the drag flows of the tip gaps and of the lateral
    /// gaps across the teeth ([`FlowKind::Tip`], [`FlowKind::LateralTooth`],
    /// the elements with a drag flow) take up the pressure differences at
    /// the last evaluated pressures: the sums of `couette (p_b - p_a)` (the
    /// drag flow runs from a to b). In a gap whose wall moves, the wall's
    /// stress holds, besides the Couette shear `mu U / h`, the
    /// pressure-driven part `(h / 2) dp/dx`; over the gap it is `(h w / 2)
    /// dp` per unit of wall speed, and its power is exactly the drag flow
    /// `U h w / 2` times `dp`. The shaft pays it. Each sum runs over its
    /// elements in their order, found through the lists that move them (the
    /// tips' movers, the spinners), not through every element.
    pub fn drag_powers(&self) -> [f64; 2] {
        let tips = self.movers.iter().filter(|m| m.tooth.is_some());
        let (tips, teeth) = (
            tips.map(|m| m.element),
            self.spinners.iter().map(|s| s.element),
        );
        // the node list indexed as in the flux loop (`mass_flows`): no
        // bounds test per access in the usual block
        match <&[NodeValues; NODE_BLOCK]>::try_from(&self.nodes[..]) {
            Ok(block) => [
                drag_power_in::<{ NODE_BLOCK - 1 }, _>(&self.links, block, tips),
                drag_power_in::<{ NODE_BLOCK - 1 }, _>(&self.links, block, teeth),
            ],
            Err(_) => [
                drag_power_in::<{ usize::MAX }, _>(&self.links, &self.nodes[..], tips),
                drag_power_in::<{ usize::MAX }, _>(&self.links, &self.nodes[..], teeth),
            ],
        }
    }

    #[inline]
    fn dp_t(&self) -> f64 {
        self.cond.dp_t
    }

    /// The mass flows (kg/s) into the pump through its inlet line port
    /// and out through its outlet line port (elements 0 and 1) at the
    /// pressures of the last evaluation, from the node values it left:
    /// [`mass_flow`](Self::mass_flow) of those elements there, to the bit
    /// (the same orifice law, the same densities), without evaluating the
    /// oil law again.
    pub fn port_mass_flows(&self) -> [f64; 2] {
        let dp_t2 = self.cond.dp_t * self.cond.dp_t;
        [0, 1].map(|i| {
            let l = &self.links[i];
            link_mass(l, &self.nodes[l.a], &self.nodes[l.b], dp_t2)
        })
    }

    /// Whether the last evaluation was at the pressures `x` (to the bit):
    /// what [`port_mass_flows`](Self::port_mass_flows) relies on.
    pub fn evaluated_at(&self, x: &DVector<f64>) -> bool {
        x.len() == self.n
            && self.nodes[..self.n]
                .iter()
                .zip(x.as_slice())
                .all(|(v, &p)| v.p.to_bits() == p.to_bits())
    }

    /// Mass flow (kg/s) through an element from a to b at state x.
    pub fn mass_flow(&self, e: &Element, x: &DVector<f64>) -> f64 {
        let (q, _, a, b) = self.element_flow(e, x);
        let up = if q >= 0.0 { a } else { b };
        let (r, _) = self.law.ratio(self.pressure(x, up));
        self.cond.rho * r * q
    }

    /// Net inflow of every state node into `f` at the states' pressures,
    /// densities and zero inflows in `self.nodes[..n]` (as
    /// [`NodeValues::at`] gives them), with the flux Jacobian added to
    /// `jac` when given. The element laws are those of
    /// [`element_flow`](Self::element_flow) (the orifice law of
    /// `flow::orifice_flow` with its constant factor precomputed, the same
    /// bits).
    fn flux_pass(&mut self, f: &mut DVector<f64>, jac: Option<&mut DMatrix<f64>>) {
        let n = self.n;
        let v = &mut self.nodes[..];
        for b in &mut v[n..n + 2] {
            b.f = 0.0;
        }
        let dp_t2 = self.cond.dp_t * self.cond.dp_t;
        match jac {
            None => {
                self.link_mass.clear();
                if self.record_flows {
                    mass_flows::<true>(&self.links, v, dp_t2, &mut self.link_mass);
                } else {
                    mass_flows::<false>(&self.links, v, dp_t2, &mut self.link_mass);
                }
            }
            Some(jac) => {
                for l in &self.links {
                    let dp = v[l.a].p - v[l.b].p;
                    let (q, dq) = if l.orifice {
                        let s = dp * dp + dp_t2;
                        let q4 = s.sqrt().sqrt();
                        (l.k * dp / q4, l.k * (s - 0.5 * dp * dp) / (s * q4))
                    } else {
                        (l.k * dp + l.couette, l.k)
                    };
                    let up = if q >= 0.0 { l.a } else { l.b };
                    let (rho_r, rho_dr) = (v[up].rho_r, v[up].rho_dr);
                    let m = rho_r * q;
                    v[l.a].f -= m;
                    v[l.b].f += m;
                    // dm/dpa, dm/dpb
                    let mut dma = rho_r * dq;
                    let mut dmb = -dma;
                    let dup = rho_dr * q;
                    if up == l.a {
                        dma += dup;
                    } else {
                        dmb += dup;
                    }
                    if l.a < n {
                        jac[(l.a, l.a)] -= dma;
                        if l.b < n {
                            jac[(l.a, l.b)] -= dmb;
                        }
                    }
                    if l.b < n {
                        jac[(l.b, l.b)] += dmb;
                        if l.a < n {
                            jac[(l.b, l.a)] += dma;
                        }
                    }
                }
            }
        }
        for (fi, vi) in f.as_mut_slice().iter_mut().zip(&self.nodes[..n]) {
            *fi = vi.f;
        }
    }
}

/// The flux loop without a Jacobian: every element's mass flow `a -> b`
/// taken from the inflow of `a` and added to that of `b` (`nodes` as
/// [`Network::flux_pass`] has them), and pushed onto `record` when
/// `RECORD`. (The flag a constant: no test of it per element.)
///
/// Node lists of [`NODE_BLOCK`] entries (every network of up to
/// `NODE_BLOCK - 2` states, [`set_boundaries`]) are indexed through a
/// fixed-size array with the indices masked to its length, which needs no
/// bounds test per access (the indices are below it: the mask changes
/// none of them).
#[inline]
fn mass_flows<const RECORD: bool>(
    links: &[Link],
    v: &mut [NodeValues],
    dp_t2: f64,
    record: &mut Vec<f64>,
) {
    match <&mut [NodeValues; NODE_BLOCK]>::try_from(&mut *v) {
        Ok(block) => mass_flows_in::<RECORD, { NODE_BLOCK - 1 }, _>(links, block, dp_t2, record),
        Err(_) => mass_flows_in::<RECORD, { usize::MAX }, _>(links, v, dp_t2, record),
    }
}

/// [`mass_flows`] over nodes `v` indexed by `index & MASK`.
#[inline(always)]
fn mass_flows_in<const RECORD: bool, const MASK: usize, V>(
    links: &[Link],
    v: &mut V,
    dp_t2: f64,
    record: &mut Vec<f64>,
) where
    V: std::ops::IndexMut<usize, Output = NodeValues> + ?Sized,
{
    for l in links {
        let (a, b) = (l.a & MASK, l.b & MASK);
        let m = link_mass(l, &v[a], &v[b], dp_t2);
        v[a].f -= m;
        v[b].f += m;
        if RECORD {
            record.push(m);
        }
    }
}

/// The mass flow of link `l` from its node `a` to its node `b` (values
/// `va`, `vb`), kg/s: the orifice law of `flow::orifice_flow` (`dp_t2` the
/// square of its transition pressure) or the gap's conductance and drag
/// flow, at the upstream node's density.
#[inline(always)]
fn link_mass(l: &Link, va: &NodeValues, vb: &NodeValues, dp_t2: f64) -> f64 {
    let dp = va.p - vb.p;
    let q = if l.orifice {
        let s = dp * dp + dp_t2;
        l.k * dp / s.sqrt().sqrt()
    } else {
        l.k * dp + l.couette
    };
    let rho_r = if q >= 0.0 { va.rho_r } else { vb.rho_r };
    rho_r * q
}

/// The drag power of `elements` (see [`Network::drag_powers`]) over nodes
/// `v` indexed by `index & MASK`; an element without a drag flow adds
/// nothing.
#[inline(always)]
fn drag_power_in<const MASK: usize, V>(
    links: &[Link],
    v: &V,
    elements: impl Iterator<Item = usize>,
) -> f64
where
    V: std::ops::Index<usize, Output = NodeValues> + ?Sized,
{
    let mut sum = 0.0;
    for i in elements {
        let l = &links[i];
        let power = l.couette * (v[l.b & MASK].p - v[l.a & MASK].p);
        sum += if l.couette != 0.0 { power } else { 0.0 };
    }
    sum
}

/// The gears' angular speeds (driving, driven) at the driving gear's
/// `omega`, rad/s.
fn gear_speeds(omega: f64, geo: &LeakGeometry) -> [f64; 2] {
    [omega, omega * geo.ratio]
}

/// Appends an element and its kind.
fn push(el: &mut Vec<Element>, kinds: &mut Vec<FlowKind>, e: Element, kind: FlowKind) {
    el.push(e);
    kinds.push(kind);
}

/// The line ports, every cell's openings to the chambers (bore and relief
/// grooves), the meshing-zone passages and the axial channels of step `st`.
fn push_ports_and_passages(
    el: &mut Vec<Element>,
    kinds: &mut Vec<FlowKind>,
    st: &Step,
    geo: &LeakGeometry,
    mu: f64,
) {
    let np = st.volume.len();
    let pk = |i: usize| Node::State(FIRST_POCKET + i);
    push(
        el,
        kinds,
        Element::Orifice {
            a: Node::Suction,
            b: Node::State(INLET),
            cda: geo.port_cda,
        },
        FlowKind::LinePort,
    );
    push(
        el,
        kinds,
        Element::Orifice {
            a: Node::State(OUTLET),
            b: Node::Delivery,
            cda: geo.port_cda,
        },
        FlowKind::LinePort,
    );
    for i in 0..np {
        for (cda, into, kind) in [
            (st.cda_in[i], false, FlowKind::PocketPort),
            (st.cda_out[i], true, FlowKind::PocketPort),
            (st.groove_in[i], false, FlowKind::Groove),
            (st.groove_out[i], true, FlowKind::Groove),
        ] {
            if cda > 0.0 {
                // inlet -> pocket, pocket -> outlet
                let (a, b) = if into {
                    (pk(i), Node::State(OUTLET))
                } else {
                    (Node::State(INLET), pk(i))
                };
                push(el, kinds, Element::Orifice { a, b, cda }, kind);
            }
        }
    }
    for &(a, b, cda) in &st.mesh {
        push(
            el,
            kinds,
            Element::Orifice {
                a: pk(a),
                b: pk(b),
                cda,
            },
            FlowKind::Mesh,
        );
    }
    for &(a, b, g_mu) in &st.axial {
        push(
            el,
            kinds,
            Element::Gap {
                a: pk(a),
                b: pk(b),
                g: g_mu / mu,
                couette: 0.0,
            },
            FlowKind::Axial,
        );
    }
}

/// Each gear's tip gaps (per axial zone), lateral gaps across the teeth and
/// to the hub (on the end zones), journal bearings and by-pass grooves; the
/// gaps that follow the gear centres are listed in `movers`. Returns what
/// those need besides the offset.
#[allow(clippy::too_many_arguments)] // the step's tables and the run's gaps and conditions
fn push_gear_gaps(
    el: &mut Vec<Element>,
    kinds: &mut Vec<FlowKind>,
    movers: &mut Vec<Mover>,
    spinners: &mut Vec<Spinner>,
    tables: &StepTables,
    istep: usize,
    geo: &LeakGeometry,
    gaps: &GapState,
    cond: Conditions,
) -> [MoverParams; 2] {
    let st = &tables.steps[istep];
    let z = tables.z;
    let pockets = tables.pockets();
    let zones = tables.zones;
    let pk = |i: usize| Node::State(FIRST_POCKET + i);
    // the plates face the end zones: both faces on one zone's cells with
    // a single zone, one face on each end zone's otherwise
    let faces: &[(usize, f64)] = if zones == 1 {
        &[(0, 2.0)]
    } else {
        &[(0, 1.0), (zones - 1, 1.0)]
    };
    let mu_gap = cond.mu * gaps.gap_viscosity_factor;
    let mut mover_params = [MoverParams::default(); 2];
    let omega = gear_speeds(cond.omega, geo);
    for k in 0..2 {
        let omega_k = omega[k];
        let first = if k == 0 { 0 } else { z[0] };
        let e = gaps.offset[k];
        let u_mid = omega_k * geo.mid_radius[k];
        let mp = MoverParams {
            tip: gaps.tip[k],
            tip_land: geo.tip_land[k],
            mu_gap,
            u_tip: omega_k * geo.tip_radius[k],
            bearing: gaps.bearing[k],
            bearing_g0: 2.0
                * std::f64::consts::PI
                * geo.bearing_diameter[k]
                * gaps.bearing[k].powi(3)
                / (12.0 * mu_gap * geo.bearing_length),
        };
        mover_params[k] = mp;
        let powers = TipPowers::new(mp.tip, e);
        for zone in 0..zones {
            let cell0 = zone * pockets + first;
            for t in 0..z[k] {
                // tooth t separates pocket t-1 (behind) from pocket t (ahead)
                let behind = pk(cell0 + (t + z[k] - 1) % z[k]);
                let ahead = pk(cell0 + t);
                let tooth = zone * z[k] + t;
                // a tip gap with a slice on the casing is an element even
                // when closed at this offset: it may open at another
                if st.tips[k][tooth].iter().any(|ts| ts.width > 0.0) {
                    let (moments, drag) = (st.tip_moments[k][tooth], st.tip_drag_moments[k][tooth]);
                    let (g, cou) = mp.tip_gap(|| &st.tips[k][tooth], &moments, &drag, &powers);
                    movers.push(Mover {
                        element: el.len(),
                        gear: k,
                        tooth: Some(tooth),
                        moments,
                        drag,
                    });
                    // drag forward: from the pocket behind to the one ahead
                    push(
                        el,
                        kinds,
                        Element::Gap {
                            a: behind,
                            b: ahead,
                            g,
                            couette: cou,
                        },
                        FlowKind::Tip,
                    );
                }
            }
        }
        for &(zone, nf) in faces {
            let cell0 = zone * pockets + first;
            for t in 0..z[k] {
                let behind = pk(cell0 + (t + z[k] - 1) % z[k]);
                let ahead = pk(cell0 + t);
                // lateral gap across the tooth, on the faces of this zone
                let gl = nf
                    * gap_conductance(
                        geo.tooth_height[k],
                        gaps.lateral,
                        geo.tooth_mid_thickness[k],
                        mu_gap,
                    );
                // (the factor before u_mid is the one `set_speed` keeps)
                let factor = nf * 0.5 * geo.tooth_height[k] * gaps.lateral;
                let cl = factor * u_mid;
                spinners.push(Spinner {
                    element: el.len(),
                    gear: k,
                    factor,
                });
                push(
                    el,
                    kinds,
                    Element::Gap {
                        a: behind,
                        b: ahead,
                        g: gl,
                        couette: cl,
                    },
                    FlowKind::LateralTooth,
                );
            }
            // pockets -> hub through the lateral gaps of these faces
            let gh =
                nf * geo.pitch[k] * gaps.lateral.powi(3) / (12.0 * mu_gap * geo.ln_root_journal[k]);
            for m in 0..z[k] {
                push(
                    el,
                    kinds,
                    Element::Gap {
                        a: pk(cell0 + m),
                        b: Node::State(HUB[k]),
                        g: gh,
                        couette: 0.0,
                    },
                    FlowKind::LateralHub,
                );
            }
        }
        // journal bearings: hub -> inlet (two bearings, eccentric annulus)
        movers.push(Mover {
            element: el.len(),
            gear: k,
            tooth: None,
            moments: TipMoments::default(),
            drag: TipMoments::default(),
        });
        push(
            el,
            kinds,
            Element::Gap {
                a: Node::State(HUB[k]),
                b: Node::State(INLET),
                g: mp.bearing_gap(e),
                couette: 0.0,
            },
            FlowKind::Bearing,
        );
        // by-pass grooves: hub -> inlet, feeding the bearings from suction
        if geo.bypass_cda > 0.0 {
            push(
                el,
                kinds,
                Element::Orifice {
                    a: Node::State(HUB[k]),
                    b: Node::State(INLET),
                    cda: geo.bypass_cda,
                },
                FlowKind::Bypass,
            );
        }
    }
    mover_params
}

impl ConservativeSystem for Network<'_> {
    fn dim(&self) -> usize {
        self.n
    }
    fn storage(&self, x: &DVector<f64>, m: &mut DVector<f64>, dm: &mut DVector<f64>) {
        for i in 0..self.n {
            let (r, dr) = self.law.ratio(x[i]);
            m[i] = self.cond.rho * r * self.volume[i];
            dm[i] = self.cond.rho * dr * self.volume[i];
        }
    }
    fn fluxes(&mut self, x: &DVector<f64>, f: &mut DVector<f64>, jac: &mut DMatrix<f64>) {
        let rho = self.cond.rho;
        for (v, &p) in self.nodes.iter_mut().zip(x.as_slice()) {
            *v = NodeValues::at(&self.law, rho, p);
        }
        self.flux_pass(f, Some(jac));
    }
    fn evaluate(
        &mut self,
        x: &DVector<f64>,
        m: &mut DVector<f64>,
        dm: &mut DVector<f64>,
        f: &mut DVector<f64>,
        jac: Option<&mut DMatrix<f64>>,
    ) {
        let rho = self.cond.rho;
        // (on the slices: nalgebra's iterators cost more than the loop)
        let states = self.nodes.iter_mut().zip(x.as_slice()).zip(&self.volume);
        let storage = m.as_mut_slice().iter_mut().zip(dm.as_mut_slice());
        for (((v, &p), vol), (m, dm)) in states.zip(storage) {
            *v = NodeValues::at(&self.law, rho, p);
            *m = v.rho_r * vol;
            *dm = v.rho_dr * vol;
        }
        self.flux_pass(f, jac);
    }
    fn scale(&self, _i: usize) -> f64 {
        self.p_scale
    }
    fn uniform_scale(&self) -> Option<f64> {
        Some(self.p_scale)
    }
    fn ordering(&self) -> Option<&[usize]> {
        Some(&self.order)
    }
    fn pattern(&self) -> Option<&[u64]> {
        (self.pattern.len() == self.n).then_some(&self.pattern[..])
    }
}

/// The values of the two boundaries (suction, delivery) at the conditions
/// `cond`: their pressures and densities, zero inflows.
fn boundary_values(law: &DensityLaw, cond: &Conditions) -> [NodeValues; 2] {
    [cond.p_suction, cond.p_delivery].map(|p| NodeValues::at(law, cond.rho, p))
}

/// The length of the node lists of networks of up to `NODE_BLOCK - 2`
/// states (the rest unused), which [`mass_flows`] indexes without bounds
/// tests.
const NODE_BLOCK: usize = 64;

/// `n` states (zero values) and the two boundaries (`boundaries`) in
/// `nodes`, padded with unused entries to [`NODE_BLOCK`].
fn set_boundaries(n: usize, nodes: &mut Vec<NodeValues>, boundaries: [NodeValues; 2]) {
    nodes.clear();
    nodes.resize(n, NodeValues::default());
    nodes.extend(boundaries);
    if nodes.len() < NODE_BLOCK {
        // unused entries up to the block the flux loop indexes
        // (`mass_flows`)
        nodes.resize(NODE_BLOCK, NodeValues::default());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Pump;

    /// The seed pump at 30 bar, 1000 rpm, with its oil's compressibility.
    fn seed() -> (Pump, Conditions, Compressibility) {
        let pump = Pump::new(crate::design::Design::seed());
        let cond = Conditions {
            p_suction: 1.0e5,
            p_delivery: 31.0e5,
            omega: 104.7,
            mu: 0.02,
            rho: 860.0,
            dp_t: 1.0e3,
        };
        let comp = Compressibility::from_oil(&pump.design.oil);
        (pump, cond, comp)
    }

    /// The design clearances of `pump` with the gear centres at `offset`.
    fn gaps_at(pump: &Pump, offset: [[f64; 2]; 2]) -> GapState {
        let d = &pump.design;
        GapState {
            tip: d.clearance.tip,
            bearing: d.clearance.bearing,
            lateral: d.clearance.lateral,
            offset,
            gap_viscosity_factor: 1.0,
        }
    }

    #[test]
    fn moving_the_gears_equals_assembling_at_the_new_offsets() {
        let (pump, cond, comp) = seed();
        let gaps = |offset| gaps_at(&pump, offset);
        let (a, b) = (
            [[1.0e-6, 4.0e-6], [-2.0e-6, 3.0e-6]],
            [[-1.5e-6, 9.0e-6], [2.5e-6, 8.0e-6]],
        );
        for istep in [0, 7, 30] {
            let net = |o| {
                let g = gaps(o);
                let bufs = NetworkBuffers::default();
                Network::assemble_with(&pump.tables, istep, &pump.geo, &g, cond, comp, bufs)
            };
            let mut moved = net(a);
            moved.set_offsets(&b);
            let fresh = net(b);
            let key = |n: &Network| -> Vec<String> {
                n.links
                    .iter()
                    .map(|l| format!("{} {} {:e} {:e} {}", l.a, l.b, l.k, l.couette, l.orifice))
                    .chain(n.elements.iter().map(|e| format!("{e:?}")))
                    .collect()
            };
            assert_eq!(key(&moved), key(&fresh), "step {istep}");
            // the offsets matter: the network at `a` differs
            assert_ne!(key(&net(a)), key(&fresh), "step {istep}");
        }
    }

    /// `got` is `want` to the bit, and `want` has no zero (a test of
    /// nothing would pass).
    fn assert_nonzero_and_same_bits(got: [f64; 2], want: [f64; 2], what: &str) {
        assert!(want.iter().all(|&w| w != 0.0), "{what}: {want:?}");
        assert_eq!(got.map(f64::to_bits), want.map(f64::to_bits), "{what}");
    }

    /// The drag powers summed through the tips' movers and the spinners
    /// are the sums by kind over every element (Tip, LateralTooth) from the
    /// elements' own pressures and Couette flows, to the bit, off-centre
    /// and with pressures that differ from node to node; no other kind of
    /// element has a drag flow.
    #[test]
    fn the_drag_powers_are_the_sums_over_their_kinds_to_the_bit() {
        let (pump, cond, comp) = seed();
        let offset = [[1.0e-6, 4.0e-6], [-2.0e-6, 3.0e-6]];
        for istep in [0, 7, 30] {
            let g = gaps_at(&pump, offset);
            let bufs = NetworkBuffers::default();
            let mut net =
                Network::assemble_with(&pump.tables, istep, &pump.geo, &g, cond, comp, bufs);
            let x = DVector::from_fn(net.n, |i, _| {
                1.0e5 + 1.7e5 * i as f64 + 3.1e3 * (i % 5) as f64
            });
            let (mut m, mut dm, mut f) = (x.clone(), x.clone(), x.clone());
            net.evaluate(&x, &mut m, &mut dm, &mut f, None);
            let mut want = [0.0; 2];
            for (e, &kind) in net.elements.iter().zip(&net.kinds) {
                let &Element::Gap { a, b, couette, .. } = e else {
                    continue;
                };
                let slot = match kind {
                    FlowKind::Tip => 0,
                    FlowKind::LateralTooth => 1,
                    other => {
                        assert_eq!(couette, 0.0, "{other:?} has a drag flow");
                        continue;
                    }
                };
                if couette != 0.0 {
                    want[slot] += couette * (net.pressure(&x, b) - net.pressure(&x, a));
                }
            }
            assert_nonzero_and_same_bits(net.drag_powers(), want, &format!("step {istep}"));
        }
    }

    /// The line ports' mass flows from the last evaluation's node values
    /// are `mass_flow` of the port elements at those pressures, to the
    /// bit, forwards and (suction above the inlet chamber) backwards.
    #[test]
    fn the_port_flows_from_the_node_values_are_the_mass_flows_to_the_bit() {
        let (pump, cond, comp) = seed();
        let g = gaps_at(&pump, [[0.0; 2]; 2]);
        for istep in [0, 20] {
            let bufs = NetworkBuffers::default();
            let mut net =
                Network::assemble_with(&pump.tables, istep, &pump.geo, &g, cond, comp, bufs);
            for inlet in [0.6e5, 1.4e5] {
                let x = DVector::from_fn(net.n, |i, _| {
                    if i == INLET {
                        inlet
                    } else {
                        2.0e5 + 1.3e5 * i as f64
                    }
                });
                let (mut m, mut dm, mut f) = (x.clone(), x.clone(), x.clone());
                net.evaluate(&x, &mut m, &mut dm, &mut f, None);
                assert!(net.evaluated_at(&x));
                let want = [0, 1].map(|i| net.mass_flow(&net.elements[i], &x));
                let what = format!("step {istep}, inlet {inlet} Pa");
                assert_nonzero_and_same_bits(net.port_mass_flows(), want, &what);
            }
        }
    }

    /// A network copied from the assembly cache, at other offsets and port
    /// pressures than those it was assembled at, is the one assembled anew,
    /// to the bit; a change of the conditions is assembled anew.
    #[test]
    fn a_cached_network_is_the_fresh_assembly_to_the_bit() {
        let (pump, cond, comp) = seed();
        let key = |n: &Network| -> Vec<String> {
            n.links
                .iter()
                .map(|l| format!("{} {} {:e} {:e} {}", l.a, l.b, l.k, l.couette, l.orifice))
                .chain(n.elements.iter().map(|e| format!("{e:?}")))
                .chain(n.kinds.iter().map(|k| format!("{k:?}")))
                .chain(n.volume.iter().map(|v| format!("{v:e}")))
                .chain(
                    n.nodes
                        .iter()
                        .map(|v| format!("{:e} {:e} {:e}", v.p, v.rho_r, v.rho_dr)),
                )
                .chain(n.order.iter().map(|o| o.to_string()))
                .chain(n.pattern.iter().map(|p| p.to_string()))
                .chain([format!("{:e}", n.p_scale)])
                .collect()
        };
        let (a, b) = (
            [[1.0e-6, 4.0e-6], [-2.0e-6, 3.0e-6]],
            [[-1.5e-6, 9.0e-6], [2.5e-6, 8.0e-6]],
        );
        let other_ports = Conditions {
            p_delivery: 101.0e5,
            p_suction: 0.8e5,
            ..cond
        };
        let thinner = Conditions { mu: 0.01, ..cond };
        // a change of speed alone keeps the entries: their drag flows follow
        let faster = Conditions {
            omega: 1.7 * cond.omega,
            ..cond
        };
        let mut cache = AssemblyCache::default();
        let mut bufs = NetworkBuffers::default();
        for (round, (offset, c)) in [
            (a, cond),
            (b, other_ports),
            (a, faster),
            (b, cond),
            (a, thinner),
            (b, cond),
        ]
        .into_iter()
        .enumerate()
        {
            let gaps = gaps_at(&pump, offset);
            for istep in [0, 7, 30, 7] {
                let cached = Network::assemble_cached(
                    &pump.tables,
                    istep,
                    &pump.geo,
                    &gaps,
                    c,
                    comp,
                    bufs,
                    &mut cache,
                );
                let fresh = Network::assemble_with(
                    &pump.tables,
                    istep,
                    &pump.geo,
                    &gaps,
                    c,
                    comp,
                    NetworkBuffers::default(),
                );
                assert_eq!(key(&cached), key(&fresh), "round {round}, step {istep}");
                bufs = cache.release(cached);
            }
        }
        assert_eq!(
            cache.generation, 3,
            "a new generation at each change of conditions but the speed"
        );
        // the networks hold the cached vectors (lent, not copied): two of
        // one step out at once, one never given back, and given back in
        // either order, every assembly is still the fresh one
        let gaps = gaps_at(&pump, b);
        let at = |cache: &mut AssemblyCache, bufs: NetworkBuffers| {
            Network::assemble_cached(&pump.tables, 7, &pump.geo, &gaps, cond, comp, bufs, cache)
        };
        let fresh = key(&Network::assemble_with(
            &pump.tables,
            7,
            &pump.geo,
            &gaps,
            cond,
            comp,
            NetworkBuffers::default(),
        ));
        let first = at(&mut cache, bufs);
        let second = at(&mut cache, NetworkBuffers::default());
        assert_eq!(key(&first), fresh);
        assert_eq!(key(&second), fresh);
        let spare = cache.release(second);
        let dropped = at(&mut cache, spare);
        let bufs = cache.release(first);
        drop(dropped);
        for bufs in [bufs, NetworkBuffers::default()] {
            let again = at(&mut cache, bufs);
            assert_eq!(key(&again), fresh);
            cache.release(again);
        }
    }

    #[test]
    fn the_jacobian_pattern_holds_every_nonzero_and_is_symmetric() {
        use crate::solver::ConservativeSystem;
        let (pump, cond, comp) = seed();
        let gaps = gaps_at(&pump, [[1.0e-6, 4.0e-6], [-2.0e-6, 3.0e-6]]);
        let mut bufs = NetworkBuffers::default();
        let mut sparse_steps = 0;
        for istep in 0..pump.steps_per_period() {
            let mut net =
                Network::assemble_with(&pump.tables, istep, &pump.geo, &gaps, cond, comp, bufs);
            let n = net.n;
            // pressures spread between the ports so that every element flows
            let x = DVector::from_fn(n, |i, _| 1.0e5 + 3.0e6 * ((i * 7) % n) as f64 / n as f64);
            let (mut m, mut dm, mut f) = (DVector::zeros(n), DVector::zeros(n), DVector::zeros(n));
            let mut jac = DMatrix::zeros(n, n);
            net.evaluate(&x, &mut m, &mut dm, &mut f, Some(&mut jac));
            let pattern = net.pattern().expect("27 states: a pattern").to_vec();
            let mut entries = 0;
            for i in 0..n {
                assert!(pattern[i] & (1 << i) != 0, "step {istep}: diagonal {i}");
                for j in 0..n {
                    let inside = pattern[i] & (1 << j) != 0;
                    assert_eq!(
                        inside,
                        pattern[j] & (1 << i) != 0,
                        "step {istep}: symmetric"
                    );
                    if jac[(i, j)] != 0.0 {
                        assert!(inside, "step {istep}: entry ({i}, {j}) off the pattern");
                    }
                    entries += usize::from(inside);
                }
            }
            // and it is sparse: far fewer entries than the dense matrix
            if entries < n * n / 3 {
                sparse_steps += 1;
            }
            bufs = net.into_buffers();
        }
        assert_eq!(sparse_steps, pump.steps_per_period());
    }

    /// The implicit step's Jacobian evaluated into the matrix of the step
    /// before (clearing only the entries of the old and the new pattern,
    /// [`crate::solver::JacobianZeros`]) is the one evaluated into a cleared
    /// matrix, bit for bit, over a mesh period of changing patterns.
    #[test]
    fn the_jacobian_reusing_the_last_pattern_is_the_fresh_one_to_the_bit() {
        use crate::solver::{ImplicitEuler, JacobianZeros, NewtonProblem};
        let (pump, cond, comp) = seed();
        let gaps = gaps_at(&pump, [[1.0e-6, 4.0e-6], [-2.0e-6, 3.0e-6]]);
        let mut bufs = NetworkBuffers::default();
        let (mut kept, mut known) = (None::<DMatrix<f64>>, JacobianZeros::default());
        let (mut reused, mut changed, mut last) = (0, 0, Vec::new());
        for istep in 0..2 * pump.steps_per_period() {
            let k = istep % pump.steps_per_period();
            let mut net =
                Network::assemble_with(&pump.tables, k, &pump.geo, &gaps, cond, comp, bufs);
            let n = net.n;
            let x = DVector::from_fn(n, |i, _| {
                1.0e5 + 3.0e6 * ((i * 7 + k) % n) as f64 / n as f64
            });
            let m_old = DVector::from_fn(n, |i, _| 800.0 + i as f64);
            let mut r = DVector::zeros(n);
            let mut fresh = DMatrix::zeros(n, n);
            ImplicitEuler::new(&mut net, &m_old, 1e-5).eval(&x, &mut r, &mut fresh);
            let j = kept.get_or_insert_with(|| DMatrix::zeros(n, n));
            reused += usize::from(known.pattern().is_some());
            let pattern = net.pattern().unwrap().to_vec();
            changed += usize::from(!last.is_empty() && pattern != last);
            last = pattern;
            ImplicitEuler::new(&mut net, &m_old, 1e-5).eval_reusing(&x, &mut r, j, &mut known);
            let bits = |m: &DMatrix<f64>| m.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(j), bits(&fresh), "step {istep}");
            bufs = net.into_buffers();
        }
        assert_eq!(reused, 2 * pump.steps_per_period() - 1);
        assert!(changed > 0, "the pattern never changed");
        println!("{changed} pattern changes");
    }

    #[test]
    fn compressed_share_is_one_less_the_density_ratio() {
        let oil = crate::design::Design::seed().oil;
        let base = Compressibility::from_oil(&oil);
        let b = base.bulk_modulus;
        let law = DensityLaw::new(base);
        // the liquid branch (above 4.2 bar absolute), against the closed form by the library's
        // exp_m1, over steps from 1 Pa to 200 bar up and down (the series
        // and the function)
        for p0 in [5.0e5_f64, 3.0e6, 2.5e7] {
            for dp in [1.0, 1.0e3, 5.0e4, 1.0e6, 1.4e6, 1.6e6, 2.0e7] {
                for p1 in [p0 + dp, (p0 - dp).max(4.5e5)] {
                    let want = -((p0 - p1) / b).exp_m1();
                    let got = law.compressed_share(p0, p1);
                    assert!(
                        (got - want).abs() <= 4.0 * f64::EPSILON * want.abs(),
                        "{p0} -> {p1} Pa: {got:e} against {want:e}"
                    );
                }
            }
        }
        // near and below the gas release pressure, and with entrained air:
        // one less the ratio of the law's densities
        let airy = DensityLaw::new(Compressibility {
            air_fraction: 0.01,
            ..base
        });
        for law in [&law, &airy] {
            for (p0, p1) in [(5.0e3, 2.0e4), (1.0e5, 3.0e4), (3.0e5, 1.0e6)] {
                let want = 1.0 - law.ratio(p0).0 / law.ratio(p1).0;
                let got = law.compressed_share(p0, p1);
                assert!(
                    (got - want).abs() <= 1e-12 * want.abs().max(1e-12),
                    "{p0} -> {p1}"
                );
            }
        }
    }

    #[test]
    fn the_flux_loop_over_the_node_block_is_the_plain_loop_to_the_bit() {
        // a made-up network of 30 states and the two ports: orifices and
        // gaps between arbitrary nodes, pressures of either sign of
        // difference
        let n = 30;
        let links: Vec<Link> = (0..120)
            .map(|i| Link {
                a: (i * 7) % (n + 2),
                b: (i * 11 + 3) % (n + 2),
                k: 1e-9 * (1.0 + (i % 5) as f64),
                couette: if i % 3 == 0 { 1e-7 * i as f64 } else { 0.0 },
                orifice: i % 2 == 0,
            })
            .collect();
        let node = |i: usize| NodeValues {
            p: 1e5 + 3.7e4 * ((i * 13) % 17) as f64,
            rho_r: 860.0 + i as f64,
            rho_dr: 0.0,
            f: 0.0,
        };
        let mut plain: Vec<NodeValues> = (0..n + 2).map(node).collect();
        let mut block = plain.clone();
        block.resize(NODE_BLOCK, NodeValues::default());
        let (mut rec_plain, mut rec_block) = (Vec::new(), Vec::new());
        mass_flows::<true>(&links, &mut plain, 4e8, &mut rec_plain);
        mass_flows::<true>(&links, &mut block, 4e8, &mut rec_block);
        let bits = |v: &[NodeValues]| v.iter().map(|x| x.f.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&plain), bits(&block[..n + 2]));
        assert_eq!(rec_plain, rec_block);
        assert!(plain.iter().any(|v| v.f != 0.0));
        assert!(block[n + 2..].iter().all(|v| v.f == 0.0));
    }
}
