//! # gearpump-core
//!
//! The bottom layer of the gearpump workspace: the lumped-parameter model of
//! external gear pumps after Battarra & Mucchi (2020) and everything it
//! stands on (units, oil, flow laws, gear geometry and pocket tables, the
//! control-volume network, mechanics, the solvers). It knows nothing of
//! campaigns, diagnosis, FMI or the command line: those crates depend on
//! this one, never the other way (Cargo refuses the import).
//!
//! SI units everywhere inside; conversions at the edges live in [`units`].
#![forbid(unsafe_code)]

pub mod design;
pub mod flow;
pub mod geometry;
pub mod hash;
pub mod hydraulics;
pub mod limits;
pub mod losses;
pub mod mechanics;
pub mod model;
pub mod oil;
pub mod operating;
pub mod predictor;
pub mod solver;
pub mod units;
pub mod vec2;
