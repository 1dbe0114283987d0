//! Gear geometry: involute helical gears, the gear pair, pocket look-up tables
//! (docs/model.md section 3, seed Sec. 2.3). Pure functions of a validated design;
//! `cache` keeps built tables on disk.

pub mod cache;
pub mod gear;
pub mod involute;
pub mod pair;
pub mod tables;
