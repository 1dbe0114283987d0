//! Mechanics (seed Sec. 2.1, docs/model.md sections 5-6): pressure loads on the
//! gears, journal bearings, the mesh force from the torque balance, the
//! quasi-static balance of the gear centres, and the shaft torque.
//!
//! * [`loads`]: pressure forces and torques on both gears from the pockets.
//! * [`bearing`]: fast closed-form finite-length journal bearing (force,
//!   Jacobian, friction torque, equilibrium), used at every angular step.
//! * [`reynolds`]: finite-difference solution of the Reynolds equation of the
//!   same bearing, the reference the closed form is calibrated and checked
//!   against.
//! * [`mesh`]: mesh force, seed Eqs. 5 and 8 with derived signs.
//! * [`micromotion`]: the 4-DOF balance of Eq. 3.
//! * [`torque`]: shaft torque and hydro-mechanical efficiency.

pub mod bearing;
pub mod loads;
pub mod mesh;
pub mod micromotion;
pub mod reynolds;
pub mod torque;

pub use crate::vec2::norm;
