//! # gearpump
//!
//! Lumped-parameter model of external gear pumps after Battarra & Mucchi
//! (2020): helical gears with unequal tooth numbers, pocket-by-pocket pressure
//! build-up, leakages, gear micromotions, journal bearings, mesh force; with
//! population validation, diagnosis and an FMI 2.0 co-simulation unit.
//!
//! SI units everywhere inside; conversions at the edges live in [`units`].
#![deny(unsafe_code)]

pub mod campaign;
pub mod circuit;
pub mod design;
pub mod diagnosis;
pub mod flow;
pub mod fmi2;
pub mod geometry;
pub mod hash;
pub mod hydraulics;
pub mod limits;
pub mod losses;
pub mod mechanics;
pub mod model;
pub mod oil;
pub mod plots;
pub mod predictor;
pub mod solver;
pub mod units;
pub mod vec2;
