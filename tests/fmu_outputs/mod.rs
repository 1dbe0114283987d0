//! Every Real output of GearPump and `out_of_range`, as bits, for the
//! tests that compare two models' outputs to the bit (`fmi_pump`,
//! `fmi_pump_map`).

use gearpump::fmi2::pump::{vr, GearPumpFmu};
use gearpump::fmi2::CoSimModel;

/// Every Real output and `out_of_range` (as bits: "equal" is to the bit).
pub fn outputs(m: &GearPumpFmu) -> Vec<u64> {
    let mut v: Vec<u64> = vr::REAL_OUTPUTS
        .iter()
        .map(|&r| m.get_real(r).expect("an output").to_bits())
        .collect();
    v.push(u64::from(
        m.get_boolean(vr::OUT_OF_RANGE).expect("an output"),
    ));
    v
}
