//! The operating range: inputs far outside any pump's range are refused
//! before the solver sees them, and results that leave physical sense are
//! said plainly (warnings), instead of being printed as if they were
//! ordinary numbers.
//!
//! The ranges are wide on purpose (any external gear pump, not only the
//! seed's); each bound says why it is there.

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

/// The atmosphere, bar absolute (the rig's inlet when none is given).
pub const ATMOSPHERE_BAR: f64 = crate::units::ATMOSPHERE_PA / 1.0e5;

/// The lowest absolute delivery pressure: the inlet range's near-vacuum
/// ([`INLET_BAR_ABS`]'s minimum, also GearPump.fmu's `p_out` minimum). A
/// pressure rise of -1 bar ([`PRESSURE_BAR`]'s minimum) is only possible
/// from an inlet at least this far above a vacuum.
pub const DELIVERY_MIN_BAR_ABS: f64 = INLET_BAR_ABS.min;

/// The absolute delivery pressure of an inlet at `inlet_bar_abs` and a
/// rise of `rise_bar` (bar), or a message when it falls below
/// [`DELIVERY_MIN_BAR_ABS`] (an absolute pressure cannot be negative, and
/// oil is no liquid near a vacuum). Sums that round a hair below the bound
/// pass.
pub fn delivery_bar_abs(inlet_bar_abs: f64, rise_bar: f64) -> Result<f64, String> {
    let p = inlet_bar_abs + rise_bar;
    if p.is_finite() && p >= DELIVERY_MIN_BAR_ABS * (1.0 - 1e-12) {
        Ok(p)
    } else {
        Err(format!(
            "a delivery pressure {rise_bar} bar above an inlet at {inlet_bar_abs} bar absolute is {p:.4} bar absolute, below {DELIVERY_MIN_BAR_ABS} bar absolute (an absolute pressure near a vacuum, where oil is no longer a liquid)"
        ))
    }
}

/// Measured or design clearances (tip, bearing, lateral).
pub const CLEARANCE_UM: Range = Range {
    name: "clearance",
    unit: "um",
    min: 0.1,
    max: 500.0,
    reason: "below 0.1 um a gap is below the roughness of ground surfaces; above 0.5 mm it is not a sealing gap of a gear pump",
};

/// A measured mean delivered flow (campaign CSV).
pub const FLOW_LPM: Range = Range {
    name: "measured flow",
    unit: "l/min",
    min: 0.0,
    max: 10_000.0,
    reason: "the largest external gear pumps deliver about 1,000 l/min",
};

/// A measured mean shaft torque (campaign CSV; it sets the mesh force).
pub const TORQUE_NM: Range = Range {
    name: "measured torque",
    unit: "N m",
    min: 0.0,
    max: 10_000.0,
    reason: "a 200 cm3/rev pump at 300 bar takes about 1,000 N m; the pump absorbs torque",
};

/// The clearance range for a named clearance.
pub fn clearance(name: &'static str) -> Range {
    Range {
        name,
        ..CLEARANCE_UM
    }
}

/// The ranges of the FMU's inputs and parameters in SI (GearPump.fmu's
/// variable table and so its `modelDescription.xml` `min`/`max`): the
/// ranges above converted, so the command line and the FMU refuse the same
/// things. The FMU's pressures are absolute.
pub mod si {
    use super::{CLEARANCE_UM, INLET_BAR_ABS, PRESSURE_BAR, SPEED_RPM};

    const PA_PER_BAR: f64 = 1.0e5;
    const M_PER_UM: f64 = 1.0e-6;

    /// Driving speed, rad/s: from standstill (the FMU holds its state at 0)
    /// to [`SPEED_RPM`]'s maximum.
    pub const SPEED_RAD_S: (f64, f64) = (0.0, SPEED_RPM.max * std::f64::consts::PI / 30.0);
    /// Suction pressure, Pa absolute: [`INLET_BAR_ABS`].
    pub const P_IN_PA: (f64, f64) = (
        INLET_BAR_ABS.min * PA_PER_BAR,
        INLET_BAR_ABS.max * PA_PER_BAR,
    );
    /// Delivery pressure, Pa absolute: from the lowest inlet pressure to the
    /// highest inlet plus the highest pressure rise; the rise itself,
    /// `p_out - p_in`, is held to [`DELIVERY_RISE_PA`] when the FMU steps.
    pub const P_OUT_PA: (f64, f64) = (
        INLET_BAR_ABS.min * PA_PER_BAR,
        (INLET_BAR_ABS.max + PRESSURE_BAR.max) * PA_PER_BAR,
    );
    /// `p_out - p_in`, Pa: [`PRESSURE_BAR`].
    pub const DELIVERY_RISE_PA: (f64, f64) =
        (PRESSURE_BAR.min * PA_PER_BAR, PRESSURE_BAR.max * PA_PER_BAR);
    /// Clearances, m: [`CLEARANCE_UM`].
    pub const CLEARANCE_M: (f64, f64) = (CLEARANCE_UM.min * M_PER_UM, CLEARANCE_UM.max * M_PER_UM);
}

/// The longest pump sample id, in characters. An id names files and
/// components downstream (an SSP component and its `resources/<id>.ssv`,
/// whose zip entry name may not exceed 65,535 bytes); 64 characters is far
/// beyond any rig's naming scheme (N01, PUMP-2024-0117, ...).
pub const SAMPLE_ID_MAX_CHARS: usize = 64;

/// Above this volumetric efficiency the pump delivers more than its
/// displacement by more than a compressibility transient or the meshing
/// zone's helical gain explains (the reference pump reaches 1.008).
pub const ETA_V_MAX: f64 = 1.1;

/// A result that leaves physical sense or the pump's operating range,
/// worth a warning: where the pump delivers nothing or backwards, loses
/// most of its displacement, delivers more than it displaces, or the
/// torque model gives more ideal work than shaft work.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flag {
    /// eta_v <= 0: the leakage exceeds the displacement.
    NothingOrBackwards,
    /// 0 < eta_v < 0.5.
    MostLost,
    /// eta_v > [`ETA_V_MAX`].
    MoreThanDisplacement,
    /// eta_hm > 1.
    EtaHmAboveOne,
}

impl Flag {
    /// Every flag, in [`Flag::index`] order.
    pub const ALL: [Flag; 4] = [
        Flag::NothingOrBackwards,
        Flag::MostLost,
        Flag::MoreThanDisplacement,
        Flag::EtaHmAboveOne,
    ];

    /// Position in [`Flag::ALL`] (for a table of flags already sent).
    pub fn index(self) -> usize {
        self as usize
    }

    /// The flags of a result with volumetric efficiency `eta_v` and
    /// hydro-mechanical efficiency `eta_hm` (NaN: not defined): at most one
    /// on the delivery, one on eta_hm. Allocates nothing.
    pub fn of(eta_v: f64, eta_hm: f64) -> [Option<Flag>; 2] {
        let delivery = if eta_v <= 0.0 {
            Some(Flag::NothingOrBackwards)
        } else if eta_v < 0.5 {
            Some(Flag::MostLost)
        } else if eta_v > ETA_V_MAX {
            Some(Flag::MoreThanDisplacement)
        } else {
            None
        };
        let torque = (eta_hm.is_finite() && eta_hm > 1.0).then_some(Flag::EtaHmAboveOne);
        [delivery, torque]
    }

    /// The warning's text.
    pub fn message(self, eta_v: f64, eta_hm: f64) -> String {
        match self {
            Flag::NothingOrBackwards => format!(
                "the pump delivers nothing or backwards here (eta_v = {eta_v:.3}): the leakage exceeds the displacement; this point is outside its operating range"
            ),
            Flag::MostLost => {
                format!("most of the displacement is lost here (eta_v = {eta_v:.3})")
            }
            Flag::MoreThanDisplacement => format!(
                "the pump delivers more than its displacement here (eta_v = {eta_v:.3} > {ETA_V_MAX}): a compressibility transient, or outside the model's range"
            ),
            Flag::EtaHmAboveOne => format!(
                "eta_hm = {eta_hm:.3} exceeds 1: the torque model is outside its range here"
            ),
        }
    }
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

    #[test]
    fn results_out_of_sense_are_flagged() {
        assert_eq!(Flag::of(0.95, 0.9), [None, None]);
        assert_eq!(Flag::of(-3.0, 0.9), [Some(Flag::NothingOrBackwards), None]);
        assert_eq!(Flag::of(0.3, 0.9), [Some(Flag::MostLost), None]);
        assert_eq!(Flag::of(1.2, 0.9), [Some(Flag::MoreThanDisplacement), None]);
        assert_eq!(Flag::of(0.95, 5.5), [None, Some(Flag::EtaHmAboveOne)]);
        assert_eq!(Flag::of(0.95, f64::NAN), [None, None]);
        for (k, f) in Flag::ALL.iter().enumerate() {
            assert_eq!(f.index(), k);
        }
        assert!(Flag::MoreThanDisplacement
            .message(1.2, 0.9)
            .contains("more than its displacement"));
    }

    #[test]
    fn the_si_ranges_are_the_edge_ranges_converted() {
        use crate::units::{bar_to_pa, rpm_to_rad_s, um_to_m};
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs();
        assert_eq!(si::SPEED_RAD_S.0, 0.0);
        assert!(close(si::SPEED_RAD_S.1, rpm_to_rad_s(SPEED_RPM.max)));
        assert!(close(si::P_IN_PA.0, bar_to_pa(INLET_BAR_ABS.min)));
        assert!(close(si::P_IN_PA.1, bar_to_pa(INLET_BAR_ABS.max)));
        assert!(close(si::P_OUT_PA.1, bar_to_pa(550.0)));
        assert!(close(si::DELIVERY_RISE_PA.0, bar_to_pa(PRESSURE_BAR.min)));
        assert!(close(si::CLEARANCE_M.0, um_to_m(CLEARANCE_UM.min)));
        assert!(close(si::CLEARANCE_M.1, um_to_m(CLEARANCE_UM.max)));
    }
}
