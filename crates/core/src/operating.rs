//! What one run is given besides the design: the operating point
//! ([`Inputs`]) and the clearances of one pump sample
//! ([`SampleClearances`]). Below the mechanics and the model, which both
//! take them (re-exported by `model`).

use crate::design::Design;

/// Operating inputs, SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Inputs {
    /// Driving shaft speed, rad/s (> 0).
    pub omega: f64,
    /// Suction (inlet) line pressure, absolute, Pa.
    pub p_suction: f64,
    /// Delivery line pressure, absolute, Pa.
    pub p_delivery: f64,
    /// Oil temperature, K.
    pub temp_k: f64,
    /// Measured mean shaft torque, N m, when the data has it (campaigns): the
    /// mesh force then follows the paper's Eq. 8 with it; None = torque model.
    pub measured_torque: Option<f64>,
}

impl Inputs {
    /// The inputs in a rig's units: `rpm`, the delivery `bar` gauge above
    /// atmospheric suction, the oil at `temp_c` degC; no measured torque.
    /// Converted to SI here.
    pub fn rig(rpm: f64, bar: f64, temp_c: f64) -> Inputs {
        use crate::units::{bar_to_pa, celsius_to_kelvin, rpm_to_rad_s, ATMOSPHERE_PA};
        Inputs {
            omega: rpm_to_rad_s(rpm),
            p_suction: ATMOSPHERE_PA,
            p_delivery: ATMOSPHERE_PA + bar_to_pa(bar),
            temp_k: celsius_to_kelvin(temp_c),
            measured_torque: None,
        }
    }
}

/// Clearances of one pump sample, SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleClearances {
    pub tip: [f64; 2],
    pub bearing: [f64; 2],
    pub lateral: f64,
}

impl SampleClearances {
    pub fn nominal(d: &Design) -> Self {
        Self {
            tip: d.clearance.tip,
            bearing: d.clearance.bearing,
            lateral: d.clearance.lateral,
        }
    }
}
