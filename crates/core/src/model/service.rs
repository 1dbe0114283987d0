//! The design's own service laws, applied per operating point: the
//! clearance growth keys of `[clearance]` (`thermal_growth_um_per_k`,
//! `pressure_growth_um_per_bar` and their sites) and the Barus coefficient
//! of `[oil]` (`pressure_viscosity_per_pa`); docs/model.md section 8. The
//! design-level keys (viscosity factors, air fraction, face width) act
//! through the design itself and need nothing here.
//!
//! `gearpump simulate --design` applies them through the campaign's effect
//! model (`gearpump_campaign::effects::EffectModel`, which opens the gaps
//! with [`open_clearances`]); a [`Simulation`] told to
//! [`follow_design_laws`](Simulation::follow_design_laws) (the FMU) applies
//! them again at every change of its inputs, so a temperature or pressure
//! ramp moves the clearances and the gap viscosity with it.

use super::{Inputs, LeakGeometry, ModelError, Pump, SampleClearances, Simulation};
use crate::design::Site;
use crate::units::celsius_to_kelvin;

/// Temperature of the metrology lab where clearances are measured, degC:
/// the thermal law is `h = h_meas + k_T (T - 20 degC)`.
pub const T_MEASURE_C: f64 = 20.0;

/// Smallest clearance a growth law may leave, m (the surface roughness
/// scale: a closed gap is metal contact, outside the model).
pub const MIN_SERVICE_CLEARANCE: f64 = 1.0e-6;

/// Opens the clearances of `site` by `dh` (m; negative closes them): the
/// tips by `dh`, the bearings by `dh R_journal / R_tip` of their gear (the
/// same differential strain), the lateral gap by `dh`; none below
/// [`MIN_SERVICE_CLEARANCE`].
pub fn open_clearances(geo: &LeakGeometry, s: &mut SampleClearances, dh: f64, site: Site) {
    let (tips, bearings, lateral) = match site {
        Site::Tips => (true, false, false),
        Site::Bearings => (false, true, false),
        Site::Lateral => (false, false, true),
        Site::Radial => (true, true, false),
        Site::All => (true, true, true),
    };
    for k in 0..2 {
        if tips {
            s.tip[k] = (s.tip[k] + dh).max(MIN_SERVICE_CLEARANCE);
        }
        if bearings {
            let scale = 0.5 * geo.bearing_diameter[k] / geo.tip_radius[k];
            s.bearing[k] = (s.bearing[k] + dh * scale).max(MIN_SERVICE_CLEARANCE);
        }
    }
    if lateral {
        s.lateral = (s.lateral + dh).max(MIN_SERVICE_CLEARANCE);
    }
}

impl Pump {
    /// The clearances in service at `inputs` of a sample measured as
    /// `measured`: the design's thermal law (oil temperature above
    /// [`T_MEASURE_C`]), then its pressure law (delivery gauge pressure),
    /// each on its site. `measured` itself when the design has neither.
    pub fn service_clearances(
        &self,
        measured: SampleClearances,
        inputs: &Inputs,
    ) -> SampleClearances {
        let g = self.design.clearance.growth;
        let mut s = measured;
        if g.thermal != 0.0 {
            let dh = g.thermal * (inputs.temp_k - celsius_to_kelvin(T_MEASURE_C));
            open_clearances(&self.geo, &mut s, dh, g.thermal_on);
        }
        if g.pressure != 0.0 {
            let dh = g.pressure * (inputs.p_delivery - inputs.p_suction);
            open_clearances(&self.geo, &mut s, dh, g.pressure_on);
        }
        s
    }

    /// The design's Barus factor on the gap viscosity at `inputs`,
    /// `exp(alpha p_gap)` at the mean gap pressure `p_gap = (p_delivery -
    /// p_suction) / 2` (not below 0); 1 when the design has no Barus key.
    pub fn service_gap_viscosity_factor(&self, inputs: &Inputs) -> f64 {
        let alpha = self.design.oil.pressure_viscosity;
        if alpha == 0.0 {
            return 1.0;
        }
        let p_gap = 0.5 * (inputs.p_delivery - inputs.p_suction).max(0.0);
        crate::oil::barus_factor(alpha, p_gap)
    }
}

impl Simulation {
    /// From now on the clearances and the gap viscosity follow the design's
    /// service laws (module docs) at the simulation's inputs, now and after
    /// every change of them ([`set_inputs`](Simulation::set_inputs),
    /// [`restore`](Simulation::restore)); `measured` are the sample's
    /// measured clearances. Replaces any earlier
    /// [`scale_gap_viscosity`](Simulation::scale_gap_viscosity). At
    /// constant inputs the simulation is the one `gearpump simulate` runs
    /// (the effect model's clearances and Barus factor), to the bit.
    pub fn follow_design_laws(&mut self, measured: SampleClearances) -> Result<(), ModelError> {
        self.measured = Some(measured);
        self.apply_inputs(self.inputs)
    }

    /// The measured clearances the design's laws start from, when the
    /// simulation follows them.
    pub fn measured_clearances(&self) -> Option<SampleClearances> {
        self.measured
    }
}
