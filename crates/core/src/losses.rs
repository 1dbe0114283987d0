//! Where the flow goes: the loss budget of a periodic steady state, as
//! shares of the kinematic flow `Vm n`.
//!
//! ## The identity
//! Let `phi = (p - p_s) / (p_d - p_s)` be the normalised pressure of every
//! node (0 at the suction line, 1 at the delivery line). Weight the mass
//! balance of every node, `dm_i/dt = sum of its inflows`, by its `phi_i` and
//! add them up: each element's mass flow `w_e` from node `a` to node `b`
//! appears twice and leaves `w_e (phi_a - phi_b)`; the delivery line, where
//! `phi = 1`, leaves the delivered mass flow. Over one mesh period of the
//! periodic state (summation by parts, the stored masses repeating) this is
//! exact:
//!
//! ```text
//!   W_out = sum_i mean(m_i dphi_i/dt) - sum_e mean(w_e (phi_a - phi_b))
//! ```
//!
//! The first term is what the pockets carry from the suction level to the
//! delivery level: for a rigid, incompressible pocket that fills at
//! `phi = 0` and empties at `phi = 1` it is its volume change times the
//! density, so it sums to `rho Vm n` less what compressibility takes (the
//! oil compressed in a pocket occupies less volume than it displaced). The
//! second term splits the leakage element by element: each flow weighted by
//! the share of the pressure rise it crosses. A leak from a pocket at 80 %
//! of the rise to one at 60 % costs 20 % of its flow; the chain of tip gaps
//! from the delivery round to the suction costs its flow once in all. A drag
//! flow carried towards the delivery counts negative (a gain).
//!
//! The budget's parts (volume flows at the delivery density over `Vm n`):
//! `tip_poiseuille` and `tip_couette` (the two terms of Eq. 10 in the tip
//! gaps); `lateral` (the lateral gaps across the teeth and inwards to the
//! hubs); `bearings` (the journal bearings and the by-pass grooves from the
//! hubs to the inlet); `mesh_zone` (meshing-zone passages between the gears'
//! pockets, the relief grooves and the channels along the helical tooth
//! spaces between their axial zones: the trapped volume); `compressibility`:
//! `1 - carried / (Vm n)` (the oil compressed in a pocket occupies less
//! volume than it displaced; it also holds the 0.02 % between the
//! closed-form displacement and the tables') plus the ports (the line ports
//! and the pockets' bore openings: chiefly the back-flow that pressurises a
//! pocket opening to the delivery at a lower pressure, a compressibility
//! effect, and the ports' throttling), reported apart as `ports` inside it.
//! The six parts add up to `1 - Q / (Vm n)` up to the periodicity of the
//! last period (the tests require 0.1 % of `Vm n`; `closure` reports the
//! difference).
//!
//! At high speed the trapped volume's pressure swings well beyond the port
//! pressures, the normalised pressure leaves [0, 1] there, and the
//! meshing-zone and compressibility parts grow with opposite signs; their
//! sum stays the meaningful figure.

use crate::hydraulics::network::FlowKind;

/// Pressure difference below which the budget is not defined (the
/// normalised pressure needs a rise), Pa.
pub const MIN_BUDGET_DP: f64 = 1.0e3;

/// The loss budget of a periodic state, as shares of `Vm n` (positive:
/// flow lost from the delivery; negative: gained).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LossBudget {
    pub tip_poiseuille: f64,
    pub tip_couette: f64,
    pub lateral: f64,
    pub bearings: f64,
    /// Meshing-zone passages and relief grooves (the trapped volume).
    pub mesh_zone: f64,
    /// Compressibility, the ports included.
    pub compressibility: f64,
    /// The ports' share, included in `compressibility`.
    pub ports: f64,
    /// The sum of the six parts.
    pub total: f64,
    /// `1 - Q / (Vm n)`, what the parts explain.
    pub deficit: f64,
    /// `deficit - total`: the periodicity error of the last period.
    pub closure: f64,
}

impl LossBudget {
    /// The six parts with their names, in the order of the reports; they
    /// add up to `total`.
    pub fn parts(&self) -> [(&'static str, f64); 6] {
        [
            ("tip_poiseuille", self.tip_poiseuille),
            ("tip_couette", self.tip_couette),
            ("lateral", self.lateral),
            ("bearings", self.bearings),
            ("mesh_zone", self.mesh_zone),
            ("compressibility", self.compressibility),
        ]
    }
}

/// The budget's running sums over one mesh period.
#[derive(Debug, Clone, Default)]
pub struct BudgetAccumulator {
    /// Pressure of the suction and of the delivery line, Pa.
    p: [f64; 2],
    /// `sum dt w_e (phi_a - phi_b)` per part, kg:
    /// [tip Poiseuille, tip Couette, lateral, bearings, mesh, ports].
    leak: [f64; 6],
    /// `sum m_i (phi_i(new) - phi_i(old))`, kg.
    carried: f64,
    /// Time covered, s.
    time: f64,
}

impl BudgetAccumulator {
    /// A budget between the suction and the delivery pressure (Pa); None
    /// when they are too close for the normalised pressure.
    pub fn new(p_suction: f64, p_delivery: f64) -> Option<Self> {
        (p_delivery - p_suction >= MIN_BUDGET_DP).then(|| BudgetAccumulator {
            p: [p_suction, p_delivery],
            ..Default::default()
        })
    }

    /// Normalised pressure.
    #[inline]
    pub fn phi(&self, p: f64) -> f64 {
        (p - self.p[0]) / (self.p[1] - self.p[0])
    }

    /// Adds one step of length `dt`: the stored masses at its start `m_old`
    /// with the pressures at its start and end (its element flows follow,
    /// [`add_flow`](Self::add_flow)).
    pub fn add_step(&mut self, dt: f64, m_old: &[f64], x_old: &[f64], x_new: &[f64]) {
        self.time += dt;
        self.carried += m_old
            .iter()
            .zip(x_old.iter().zip(x_new))
            .map(|(m, (a, b))| m * (self.phi(*b) - self.phi(*a)))
            .sum::<f64>();
    }

    /// Adds one element's flow over `dt`: its kind, its mass flows from `a`
    /// to `b` (the pressure-driven or orifice part and the drag part, kg/s)
    /// and the pressures of its ends.
    #[inline]
    pub fn add_flow(&mut self, dt: f64, kind: FlowKind, w: f64, w_drag: f64, pa: f64, pb: f64) {
        let dphi = self.phi(pa) - self.phi(pb);
        let (part, drag_part) = match kind {
            FlowKind::Tip => (0, 1),
            FlowKind::LateralTooth | FlowKind::LateralHub => (2, 2),
            FlowKind::Bearing | FlowKind::Bypass => (3, 3),
            FlowKind::Mesh | FlowKind::Groove | FlowKind::Axial => (4, 4),
            FlowKind::LinePort | FlowKind::PocketPort => (5, 5),
        };
        self.leak[part] += dt * w * dphi;
        self.leak[drag_part] += dt * w_drag * dphi;
    }

    /// The budget: `kinematic` = Vm n (m^3/s), `flow` the delivered flow
    /// (m^3/s at the delivery density `rho_d`).
    pub fn finish(&self, kinematic: f64, flow: f64, rho_d: f64) -> LossBudget {
        let share = |kg: f64| kg / self.time / rho_d / kinematic;
        let l = self.leak.map(share);
        let compressibility = 1.0 - share(self.carried) + l[5];
        let total = l[..5].iter().sum::<f64>() + compressibility;
        let deficit = 1.0 - flow / kinematic;
        LossBudget {
            tip_poiseuille: l[0],
            tip_couette: l[1],
            lateral: l[2],
            bearings: l[3],
            mesh_zone: l[4],
            compressibility,
            ports: l[5],
            total,
            deficit,
            closure: deficit - total,
        }
    }
}
