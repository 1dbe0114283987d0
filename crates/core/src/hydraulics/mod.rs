//! Hydraulics: the pump's control-volume network and its per-step tables
//! (seed Sec. 2.2, docs/model.md section 4). Pure: no I/O.

pub mod grooves;
pub mod network;
pub mod steps;
