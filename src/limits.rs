//! The operating range: inputs far outside any pump's range are refused
//! before the solver sees them, and results that leave physical sense are
//! said plainly (warnings), instead of being printed as if they were
//! ordinary numbers.
//!
//! The ranges are wide on purpose (any external gear pump, not only the
//! seed's); each bound says why it is there.

use crate::model::Summary;

/// A physical range of one input, in the units at the edges.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range {
    pub name: &'static str,
    pub unit: &'static str,
    pub min: f64,
    pub max: f64,
    /// Why the bounds are where they are.
    pub reason: &'static str,
}

impl Range {
    /// `v` if it is finite and within the range; otherwise a message that
    /// names the quantity, the value and the range.
    pub fn check(&self, v: f64) -> Result<f64, String> {
        if v.is_finite() && v >= self.min && v <= self.max {
            Ok(v)
        } else {
            Err(format!(
                "{} = {v} {} is outside [{}, {}] {} ({})",
                self.name, self.unit, self.min, self.max, self.unit, self.reason
            ))
        }
    }
}

/// Driving speed.
pub const SPEED_RPM: Range = Range {
    name: "speed",
    unit: "rpm",
    min: 1.0,
    max: 20_000.0,
    reason: "gear pumps run from tens to a few thousand rpm; at 20,000 rpm the tips of a 40 mm gear move at 40 m/s, beyond the laminar gap and filling laws",
};

/// Delivery pressure above the inlet.
pub const PRESSURE_BAR: Range = Range {
    name: "delivery pressure",
    unit: "bar gauge",
    min: -1.0,
    max: 500.0,
    reason: "the highest-rated external gear pumps run to about 300 bar",
};

/// Inlet (suction) pressure.
pub const INLET_BAR_ABS: Range = Range {
    name: "inlet pressure",
    unit: "bar absolute",
    min: 0.05,
    max: 50.0,
    reason: "a suction line between near-vacuum and a boosted supply",
};

/// Measured or design clearances (tip, bearing, lateral).
pub const CLEARANCE_UM: Range = Range {
    name: "clearance",
    unit: "um",
    min: 0.1,
    max: 500.0,
    reason: "below 0.1 um a gap is below the roughness of ground surfaces; above 0.5 mm it is not a sealing gap of a gear pump",
};

/// The clearance range for a named clearance.
pub fn clearance(name: &'static str) -> Range {
    Range {
        name,
        ..CLEARANCE_UM
    }
}

/// How little a pump delivers, where it is worth a warning.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LowDelivery {
    /// eta_v <= 0: the leakage exceeds the displacement.
    NothingOrBackwards,
    /// 0 < eta_v < 0.5.
    MostLost,
}

impl LowDelivery {
    /// How little a pump with volumetric efficiency `eta_v` delivers, where
    /// it is worth a warning: nothing or backwards (eta_v <= 0), most of
    /// the displacement lost (eta_v < 0.5).
    pub fn of(eta_v: f64) -> Option<LowDelivery> {
        if eta_v <= 0.0 {
            Some(LowDelivery::NothingOrBackwards)
        } else if eta_v < 0.5 {
            Some(LowDelivery::MostLost)
        } else {
            None
        }
    }

    /// The warning's text at `eta_v`.
    pub fn message(self, eta_v: f64) -> String {
        match self {
            LowDelivery::NothingOrBackwards => format!(
                "the pump delivers nothing or backwards here (eta_v = {eta_v:.3}): the leakage exceeds the displacement; this point is outside its operating range"
            ),
            LowDelivery::MostLost => {
                format!("most of the displacement is lost here (eta_v = {eta_v:.3})")
            }
        }
    }
}

/// Warnings on a periodic state: where the pump delivers nothing or
/// backwards, loses most of its displacement, or the torque model leaves
/// physical sense; and the solver's own caveats (not converged, micromotion
/// iterations at their limit, a bearing overloaded).
pub fn operating_warnings(
    s: &Summary,
    unconverged_coupling_steps: u64,
    bearing_overload: bool,
) -> Vec<String> {
    let mut w = Vec::new();
    if let Some(low) = LowDelivery::of(s.eta_v) {
        w.push(low.message(s.eta_v));
    }
    if s.eta_hm.is_finite() && s.eta_hm > 1.0 {
        w.push(format!(
            "eta_hm = {:.3} exceeds 1: the torque model is outside its range here",
            s.eta_hm
        ));
    }
    if !s.converged {
        w.push("the periodic steady state was not reached".to_string());
    }
    if unconverged_coupling_steps > 0 {
        w.push(format!(
            "the micromotion iteration hit its limit at {unconverged_coupling_steps} steps"
        ));
    }
    if bearing_overload {
        w.push(
            "a journal bearing was overloaded (the load exceeded the film's capacity: metal contact)"
                .to_string(),
        );
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_refuse_what_no_pump_sees_and_name_it() {
        for v in [1e9, 1e300, 1e-9, 0.0, -5.0, f64::NAN, f64::INFINITY] {
            let e = SPEED_RPM.check(v).unwrap_err();
            assert!(e.starts_with("speed = ") && e.contains("rpm"), "{e}");
        }
        assert_eq!(SPEED_RPM.check(1000.0), Ok(1000.0));
        assert!(PRESSURE_BAR.check(1e6).is_err());
        assert!(PRESSURE_BAR.check(40.0).is_ok());
        assert!(clearance("tip clearance")
            .check(1e6)
            .unwrap_err()
            .contains("tip clearance"));
        assert!(CLEARANCE_UM.check(0.0).is_err());
        assert!(CLEARANCE_UM.check(30.0).is_ok());
        assert!(INLET_BAR_ABS.check(1.01325).is_ok());
        assert!(INLET_BAR_ABS.check(0.0).is_err());
    }
}
