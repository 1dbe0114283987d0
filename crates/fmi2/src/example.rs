//! A first-order tank, the test model of the FMI layer (not a pump model).
//!
//! Level `h` (m) of a tank of area `A` (m2) with inflow `q_in` (m3/s) and a
//! linear outlet `q_out = k_out * h` (k_out in m2/s; 0 when `outlet_open`
//! is false):
//!
//! `A dh/dt = q_in - k_out h`
//!
//! With `q_in` held over a step of length `dt` (as a co-simulation master
//! does), the step is solved exactly:
//! `h(t+dt) = h_ss + (h(t) - h_ss) exp(-k_out dt / A)`, `h_ss = q_in / k_out`
//! (and `h + q_in dt / A` for a closed outlet), so tests can compare with the
//! closed form. `overflow` is true when `h > level_max`.

use std::path::Path;

use super::model::{
    Causality, CoSimModel, DefaultExperiment, Initial, ModelError, StateReader, StateWriter,
    Variability, Variable,
};

/// The first-order tank (see the module docs). Fields are SI.
#[derive(Debug, Clone, PartialEq)]
pub struct Tank {
    /// Inflow, m3/s (input).
    pub q_in: f64,
    /// Cross-section area, m2 (fixed parameter, > 0).
    pub area: f64,
    /// Outlet conductance, m2/s (tunable parameter, >= 0).
    pub k_out: f64,
    /// Initial level, m (fixed parameter, >= 0).
    pub level_start: f64,
    /// Overflow threshold, m (fixed parameter, > 0).
    pub level_max: f64,
    /// Outlet open (tunable parameter).
    pub outlet_open: bool,
    /// Level, m (state, output).
    pub level: f64,
}

/// Value references of [`Tank`].
pub mod vr {
    pub const Q_IN: u32 = 1;
    pub const AREA: u32 = 2;
    pub const K_OUT: u32 = 3;
    pub const LEVEL_START: u32 = 4;
    pub const LEVEL_MAX: u32 = 5;
    pub const LEVEL: u32 = 6;
    pub const Q_OUT: u32 = 7;
    pub const VOLUME: u32 = 8;
    pub const OUTLET_OPEN: u32 = 9;
    pub const OVERFLOW: u32 = 10;
}

use Causality::{Input, Output, Parameter};
use Variability::{Continuous, Discrete, Fixed, Tunable};

const VARIABLES: &[Variable] = &[
    Variable::real("q_in", vr::Q_IN, Input, Continuous, "m3/s")
        .describe("Inflow")
        .display("l/min")
        .start(1.0e-3),
    Variable::real("area", vr::AREA, Parameter, Fixed, "m2")
        .describe("Cross-section area of the tank")
        .start(0.5),
    Variable::real("k_out", vr::K_OUT, Parameter, Tunable, "m2/s")
        .describe("Outlet conductance: q_out = k_out*level")
        .start(0.01),
    Variable::real("level_start", vr::LEVEL_START, Parameter, Fixed, "m")
        .describe("Initial level")
        .display("mm")
        .start(0.0),
    Variable::real("level_max", vr::LEVEL_MAX, Parameter, Fixed, "m")
        .describe("Overflow threshold")
        .start(1.0),
    Variable::boolean("outlet_open", vr::OUTLET_OPEN, Parameter, Tunable)
        .describe("Outlet valve open")
        .start_bool(true),
    Variable::real("level", vr::LEVEL, Output, Continuous, "m")
        .describe("Level in the tank")
        .display("mm")
        .initial(Initial::Calculated),
    Variable::real("q_out", vr::Q_OUT, Output, Continuous, "m3/s")
        .describe("Outflow")
        .display("l/min"),
    Variable::real("volume", vr::VOLUME, Output, Continuous, "m3")
        .describe("Volume in the tank")
        .display("l"),
    Variable::boolean("overflow", vr::OVERFLOW, Output, Discrete).describe("Level above level_max"),
];

const STATE_TAG: &[u8; 8] = b"TANK0001";

impl Default for Tank {
    fn default() -> Self {
        Tank {
            q_in: 1.0e-3,
            area: 0.5,
            k_out: 0.01,
            level_start: 0.0,
            level_max: 1.0,
            outlet_open: true,
            level: 0.0,
        }
    }
}

impl Tank {
    fn k_eff(&self) -> f64 {
        if self.outlet_open {
            self.k_out
        } else {
            0.0
        }
    }

    /// The level after `dt` s with the current input (closed form).
    pub fn level_after(&self, level: f64, dt: f64) -> f64 {
        let k = self.k_eff();
        if k > 0.0 {
            let h_ss = self.q_in / k;
            h_ss + (level - h_ss) * (-k * dt / self.area).exp()
        } else {
            level + self.q_in * dt / self.area
        }
        .max(0.0)
    }
}

impl CoSimModel for Tank {
    const MODEL_IDENTIFIER: &'static str = "Tank";
    const GUID: &'static str = "{5f0c2d7e-3b4a-4c1e-9d2f-7a8b6c5d4e01}";
    const MODEL_NAME: &'static str = "gearpump.fmi2.example.Tank";
    const DESCRIPTION: &'static str =
        "First-order tank (test model of the gearpump FMI layer): A dh/dt = q_in - k_out h";
    const DEFAULT_EXPERIMENT: Option<DefaultExperiment> = Some(DefaultExperiment {
        start_time: 0.0,
        stop_time: 100.0,
        tolerance: None,
        step_size: 0.1,
    });

    fn variables() -> &'static [Variable] {
        VARIABLES
    }

    fn resource_files() -> Vec<(String, Vec<u8>)> {
        vec![(
            "README.txt".into(),
            b"The Tank test model needs no resources.\n".to_vec(),
        )]
    }

    fn instantiate(_resources: &Path, logger: &dyn Fn(&str)) -> Result<Self, ModelError> {
        logger("tank ready");
        Ok(Tank::default())
    }

    fn set_real(&mut self, vr: u32, value: f64) -> Result<(), ModelError> {
        let (name, target, ok, reason) = match vr {
            vr::Q_IN => (
                "q_in",
                &mut self.q_in,
                value >= 0.0 && value.is_finite(),
                "must be finite and >= 0 m3/s",
            ),
            vr::AREA => (
                "area",
                &mut self.area,
                value > 0.0 && value.is_finite(),
                "must be finite and > 0 m2",
            ),
            vr::K_OUT => (
                "k_out",
                &mut self.k_out,
                value >= 0.0 && value.is_finite(),
                "must be finite and >= 0 m2/s",
            ),
            vr::LEVEL_START => (
                "level_start",
                &mut self.level_start,
                value >= 0.0 && value.is_finite(),
                "must be finite and >= 0 m",
            ),
            vr::LEVEL_MAX => (
                "level_max",
                &mut self.level_max,
                value > 0.0 && value.is_finite(),
                "must be finite and > 0 m",
            ),
            _ => return Err(ModelError::UnknownValueReference(vr)),
        };
        if !ok {
            return Err(ModelError::invalid(name, value, reason));
        }
        *target = value;
        Ok(())
    }

    fn get_real(&self, vr: u32) -> Result<f64, ModelError> {
        Ok(match vr {
            vr::Q_IN => self.q_in,
            vr::AREA => self.area,
            vr::K_OUT => self.k_out,
            vr::LEVEL_START => self.level_start,
            vr::LEVEL_MAX => self.level_max,
            vr::LEVEL => self.level,
            vr::Q_OUT => self.k_eff() * self.level,
            vr::VOLUME => self.area * self.level,
            _ => return Err(ModelError::UnknownValueReference(vr)),
        })
    }

    fn set_boolean(&mut self, vr: u32, value: bool) -> Result<(), ModelError> {
        match vr {
            vr::OUTLET_OPEN => self.outlet_open = value,
            _ => return Err(ModelError::UnknownValueReference(vr)),
        }
        Ok(())
    }

    fn get_boolean(&self, vr: u32) -> Result<bool, ModelError> {
        match vr {
            vr::OUTLET_OPEN => Ok(self.outlet_open),
            vr::OVERFLOW => Ok(self.level > self.level_max),
            _ => Err(ModelError::UnknownValueReference(vr)),
        }
    }

    fn exit_initialization(&mut self) -> Result<(), ModelError> {
        self.level = self.level_start;
        Ok(())
    }

    fn do_step(&mut self, t: f64, h: f64) -> Result<(), ModelError> {
        let next = self.level_after(self.level, h);
        if !next.is_finite() {
            return Err(ModelError::StepFailed {
                t,
                h,
                reason: format!("level became {next}"),
            });
        }
        self.level = next;
        Ok(())
    }

    fn reset(&mut self) -> Result<(), ModelError> {
        *self = Tank::default();
        Ok(())
    }

    fn save_state(&self) -> Vec<u8> {
        StateWriter::new(STATE_TAG)
            .f64(self.q_in)
            .f64(self.area)
            .f64(self.k_out)
            .f64(self.level_start)
            .f64(self.level_max)
            .bool(self.outlet_open)
            .f64(self.level)
            .finish()
    }

    fn restore_state(&mut self, bytes: &[u8]) -> Result<(), ModelError> {
        let mut r = StateReader::new(bytes, STATE_TAG)?;
        let restored = Tank {
            q_in: r.f64()?,
            area: r.f64()?,
            k_out: r.f64()?,
            level_start: r.f64()?,
            level_max: r.f64()?,
            outlet_open: r.bool()?,
            level: r.f64()?,
        };
        r.finish()?;
        *self = restored;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::check_model;

    #[test]
    fn table_is_valid() {
        check_model::<Tank>().unwrap();
    }

    #[test]
    fn closed_form_limits() {
        let t = Tank::default();
        // Long time: steady state q_in / k_out.
        assert!((t.level_after(0.0, 1e6) - 0.1).abs() < 1e-12);
        // Small step: dh = q_in dt / A.
        assert!((t.level_after(0.0, 1e-6) - 1e-3 * 1e-6 / 0.5).abs() < 1e-15);
    }
}
