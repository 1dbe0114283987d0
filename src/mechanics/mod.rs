//! Gear micromotions (seed Sec. 2.1): journal-bearing reactions of the gear
//! shafts for the quasi-static force balance of each gear.
//!
//! * [`bearing`]: fast closed-form finite-length journal bearing (force,
//!   Jacobian, friction torque, equilibrium), used at every angular step.
//! * [`reynolds`]: finite-difference solution of the Reynolds equation of the
//!   same bearing, the reference the closed form is calibrated and checked
//!   against.

pub mod bearing;
pub mod reynolds;
