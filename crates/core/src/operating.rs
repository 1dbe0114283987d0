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
