//! Every Real output of GearPump and `out_of_range`, as bits, for the
//! tests that compare two models' outputs to the bit (`fmi_pump`,
//! `fmi_pump_map`).

use gearpump::fmi2::pump::{vr, GearPumpFmu};
use gearpump::fmi2::CoSimModel;

/// Every Real output and `out_of_range` (as bits: "equal" is to the bit).
pub fn outputs(m: &GearPumpFmu) -> Vec<u64> {
    let mut v: Vec<u64> = [
        vr::Q_OUT,
        vr::Q_OUT_INST,
        vr::TORQUE,
        vr::ETA_V,
        vr::ETA_HM,
        vr::V_DELIVERED,
        vr::THETA,
        vr::Q_IN,
        vr::P_SHAFT,
        vr::P_HYD,
        vr::P_POCKET_MIN,
        vr::CAVITATION_MARGIN,
        vr::Q_OUT_SLOPE,
        vr::DQ_OUT_DP_OUT,
    ]
    .iter()
    .map(|&r| m.get_real(r).expect("an output").to_bits())
    .collect();
    v.push(u64::from(
        m.get_boolean(vr::OUT_OF_RANGE).expect("an output"),
    ));
    v
}
