//! The safe side of the FMI layer: what a model implements ([`CoSimModel`]),
//! its variable table ([`Variable`]), its errors ([`ModelError`]), the unit
//! table ([`UnitDefinition`]) and helpers to serialise its state
//! ([`StateWriter`], [`StateReader`]).
//!
//! A model never sees an FMI type or a pointer. The glue in
//! [`super::exports`] checks call order, null pointers, value references,
//! causality (an output cannot be set, a fixed parameter cannot be set after
//! initialisation) and NaN before it calls the model; the model checks the
//! physics ranges of the values it is given.

use std::path::Path;

/// Causality of a variable (FMI 2.0, section 2.2.7). Calculated parameters
/// and the independent variable are not used by this crate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Causality {
    /// Set by the importer before initialisation (and during the run when
    /// [`Variability::Tunable`]).
    Parameter,
    /// Set by the importer before every step.
    Input,
    /// Computed by the model, read by the importer.
    Output,
    /// Computed by the model, readable for diagnostics.
    Local,
}

impl Causality {
    /// The `causality` attribute value.
    pub fn as_str(self) -> &'static str {
        match self {
            Causality::Parameter => "parameter",
            Causality::Input => "input",
            Causality::Output => "output",
            Causality::Local => "local",
        }
    }
}

/// Variability of a variable (FMI 2.0, section 2.2.7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Variability {
    /// Fixed after initialisation.
    Fixed,
    /// Constant between events: may be changed during the run (parameters).
    Tunable,
    /// Varies continuously in time (Real only).
    Continuous,
    /// Changes only at communication points / events.
    Discrete,
}

impl Variability {
    /// The `variability` attribute value.
    pub fn as_str(self) -> &'static str {
        match self {
            Variability::Fixed => "fixed",
            Variability::Tunable => "tunable",
            Variability::Continuous => "continuous",
            Variability::Discrete => "discrete",
        }
    }
}

/// The `initial` attribute (FMI 2.0, section 2.2.7, table of combinations).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Initial {
    /// The start value is the initial value.
    Exact,
    /// The start value is a guess for an iteration.
    Approx,
    /// Computed by the model during initialisation (no start value).
    Calculated,
}

impl Initial {
    /// The `initial` attribute value.
    pub fn as_str(self) -> &'static str {
        match self {
            Initial::Exact => "exact",
            Initial::Approx => "approx",
            Initial::Calculated => "calculated",
        }
    }
}

/// Type, unit and start value of a variable.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum VariableKind {
    /// `<Real>`: `unit` must be a name in [`CoSimModel::units`] (or `None`
    /// for a dimensionless quantity without a unit); `display_unit` one of
    /// that unit's display units.
    /// `min`/`max` (SI, inclusive) are written to the XML and refused
    /// outside by the model's setter ([`Variable::check_range`]).
    Real {
        unit: Option<&'static str>,
        display_unit: Option<&'static str>,
        start: Option<f64>,
        min: Option<f64>,
        max: Option<f64>,
    },
    /// `<Boolean>`.
    Boolean { start: Option<bool> },
    /// `<Integer>`: `min`/`max` (inclusive) are written to the XML and
    /// refused outside by the model's setter ([`Variable::check_integer`]).
    Integer {
        start: Option<i32>,
        min: Option<i32>,
        max: Option<i32>,
    },
}

/// The base type of a variable, as the FMI functions name it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BaseType {
    Real,
    Integer,
    Boolean,
    String,
}

impl BaseType {
    /// The name used in messages and in the FMI function names.
    pub fn as_str(self) -> &'static str {
        match self {
            BaseType::Real => "Real",
            BaseType::Integer => "Integer",
            BaseType::Boolean => "Boolean",
            BaseType::String => "String",
        }
    }
}

/// One row of a model's variable table: the one source of truth for the
/// XML, the documentation and the glue's checks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Variable {
    /// Structured name (`variableNamingConvention="structured"`).
    pub name: &'static str,
    /// Unique per base type (this crate keeps them unique overall).
    pub value_reference: u32,
    pub description: &'static str,
    pub causality: Causality,
    pub variability: Variability,
    /// `None` leaves the attribute out (FMI default for the combination).
    pub initial: Option<Initial>,
    pub kind: VariableKind,
}

impl Variable {
    /// A Real variable without description, display unit or start value
    /// (add them with the builder methods below; usable in `const` tables).
    pub const fn real(
        name: &'static str,
        value_reference: u32,
        causality: Causality,
        variability: Variability,
        unit: &'static str,
    ) -> Self {
        Variable {
            name,
            value_reference,
            description: "",
            causality,
            variability,
            initial: None,
            kind: VariableKind::Real {
                unit: Some(unit),
                display_unit: None,
                start: None,
                min: None,
                max: None,
            },
        }
    }

    /// A Boolean variable without description or start value.
    pub const fn boolean(
        name: &'static str,
        value_reference: u32,
        causality: Causality,
        variability: Variability,
    ) -> Self {
        Variable {
            name,
            value_reference,
            description: "",
            causality,
            variability,
            initial: None,
            kind: VariableKind::Boolean { start: None },
        }
    }

    /// An Integer variable with the range `[min, max]`, without
    /// description or start value.
    pub const fn integer(
        name: &'static str,
        value_reference: u32,
        causality: Causality,
        variability: Variability,
        min: i32,
        max: i32,
    ) -> Self {
        Variable {
            name,
            value_reference,
            description: "",
            causality,
            variability,
            initial: None,
            kind: VariableKind::Integer {
                start: None,
                min: Some(min),
                max: Some(max),
            },
        }
    }

    /// With an Integer start value (ignored for other types).
    pub const fn start_int(mut self, value: i32) -> Self {
        if let VariableKind::Integer { min, max, .. } = self.kind {
            self.kind = VariableKind::Integer {
                start: Some(value),
                min,
                max,
            };
        }
        self
    }

    /// With a description.
    pub const fn describe(mut self, description: &'static str) -> Self {
        self.description = description;
        self
    }

    /// With an explicit `initial`.
    pub const fn initial(mut self, initial: Initial) -> Self {
        self.initial = Some(initial);
        self
    }

    /// With a display unit (Real only; ignored for a Boolean).
    pub const fn display(mut self, display: &'static str) -> Self {
        if let VariableKind::Real {
            unit,
            start,
            min,
            max,
            ..
        } = self.kind
        {
            self.kind = VariableKind::Real {
                unit,
                display_unit: Some(display),
                start,
                min,
                max,
            };
        }
        self
    }

    /// With a Real start value (ignored for a Boolean).
    pub const fn start(mut self, value: f64) -> Self {
        if let VariableKind::Real {
            unit,
            display_unit,
            min,
            max,
            ..
        } = self.kind
        {
            self.kind = VariableKind::Real {
                unit,
                display_unit,
                start: Some(value),
                min,
                max,
            };
        }
        self
    }

    /// With a physical range `[min, max]` (SI, inclusive; Real only): the
    /// XML's `min` and `max`, and what [`Variable::check_range`] accepts.
    pub const fn range(mut self, min: f64, max: f64) -> Self {
        if let VariableKind::Real {
            unit,
            display_unit,
            start,
            ..
        } = self.kind
        {
            self.kind = VariableKind::Real {
                unit,
                display_unit,
                start,
                min: Some(min),
                max: Some(max),
            };
        }
        self
    }

    /// With a Boolean start value (ignored for a Real).
    pub const fn start_bool(mut self, value: bool) -> Self {
        if let VariableKind::Boolean { .. } = self.kind {
            self.kind = VariableKind::Boolean { start: Some(value) };
        }
        self
    }
}

impl Variable {
    /// The base type (`Real` or `Boolean`).
    pub fn base_type(&self) -> BaseType {
        match self.kind {
            VariableKind::Real { .. } => BaseType::Real,
            VariableKind::Boolean { .. } => BaseType::Boolean,
            VariableKind::Integer { .. } => BaseType::Integer,
        }
    }

    /// The `initial` in force: the explicit one or the FMI default for the
    /// causality/variability combination.
    pub fn effective_initial(&self) -> Option<Initial> {
        if self.initial.is_some() {
            return self.initial;
        }
        match (self.causality, self.variability) {
            (Causality::Parameter, _) => Some(Initial::Exact),
            (Causality::Input, _) => None,
            (Causality::Output | Causality::Local, _) => Some(Initial::Calculated),
        }
    }

    /// `value` if it is finite and within the variable's `min`/`max` (the
    /// XML's), otherwise [`ModelError::InvalidValue`] naming the variable
    /// and the range. Booleans and Reals without a range: finite is enough.
    /// A Real variable's accepted range `[min, max]` (infinite where the
    /// table gives none; `None` for other types). Usable in `const` tables
    /// (a model's setter can look its inputs' ranges up at compile time).
    pub const fn real_range(&self) -> Option<(f64, f64)> {
        match self.kind {
            VariableKind::Real { min, max, .. } => Some((
                match min {
                    Some(x) => x,
                    None => f64::NEG_INFINITY,
                },
                match max {
                    Some(x) => x,
                    None => f64::INFINITY,
                },
            )),
            VariableKind::Boolean { .. } | VariableKind::Integer { .. } => None,
        }
    }

    pub fn check_range(&self, value: f64) -> Result<f64, ModelError> {
        let (min, max, unit) = match self.kind {
            VariableKind::Real { min, max, unit, .. } => (min, max, unit.unwrap_or("")),
            VariableKind::Boolean { .. } | VariableKind::Integer { .. } => (None, None, ""),
        };
        let lo = min.unwrap_or(f64::NEG_INFINITY);
        let hi = max.unwrap_or(f64::INFINITY);
        if value.is_finite() && value >= lo && value <= hi {
            return Ok(value);
        }
        let range = match (min, max) {
            (None, None) => "must be finite".to_string(),
            _ => format!(
                "outside its range [{}, {}] {unit} (modelDescription min/max)",
                min.map_or("-inf".to_string(), |x| format!("{x:e}")),
                max.map_or("inf".to_string(), |x| format!("{x:e}")),
            ),
        };
        Err(ModelError::invalid(self.name, value, range))
    }

    /// Whether the variable has a start value.
    pub fn has_start(&self) -> bool {
        match self.kind {
            VariableKind::Real { start, .. } => start.is_some(),
            VariableKind::Boolean { start } => start.is_some(),
            VariableKind::Integer { start, .. } => start.is_some(),
        }
    }

    /// `value` if it is within the Integer variable's `min`/`max` (the
    /// XML's), otherwise [`ModelError::InvalidValue`] naming the variable
    /// and the range.
    pub fn check_integer(&self, value: i32) -> Result<i32, ModelError> {
        let (min, max) = match self.kind {
            VariableKind::Integer { min, max, .. } => (min, max),
            _ => (None, None),
        };
        if min.is_none_or(|lo| value >= lo) && max.is_none_or(|hi| value <= hi) {
            return Ok(value);
        }
        Err(ModelError::invalid(
            self.name,
            value,
            format!(
                "outside its range [{}, {}] (modelDescription min/max)",
                min.map_or("-inf".to_string(), |x| x.to_string()),
                max.map_or("inf".to_string(), |x| x.to_string()),
            ),
        ))
    }
}

/// A `BaseUnit` with the SI exponents of a unit (FMI 2.0, section 2.2.2):
/// `value(SI) = factor * value(unit) + offset`. Units here are SI, so factor
/// 1 and offset 0 except where stated.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BaseUnit {
    pub kg: i32,
    pub m: i32,
    pub s: i32,
    pub a: i32,
    pub k: i32,
    pub mol: i32,
    pub cd: i32,
    pub rad: i32,
}

/// A `DisplayUnit`: `value(display) = factor * value(unit) + offset`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DisplayUnit {
    pub name: &'static str,
    pub factor: f64,
    pub offset: f64,
}

/// A `<Unit>` of `UnitDefinitions`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UnitDefinition {
    pub name: &'static str,
    pub base: BaseUnit,
    pub display: &'static [DisplayUnit],
}

const fn display(name: &'static str, factor: f64, offset: f64) -> DisplayUnit {
    DisplayUnit {
        name,
        factor,
        offset,
    }
}

const NONE: BaseUnit = BaseUnit {
    kg: 0,
    m: 0,
    s: 0,
    a: 0,
    k: 0,
    mol: 0,
    cd: 0,
    rad: 0,
};

/// The SI units this crate's models use, with the display units of the
/// test-rig edge (rpm, bar, degC, l/min, um). `bar` is a plain factor: it
/// shows the absolute pressure in bar (gauge pressure is a CLI/CSV
/// convention, not a unit). Only the units a model's variables use are
/// written to its modelDescription.xml.
pub const STANDARD_UNITS: &[UnitDefinition] = &[
    UnitDefinition {
        name: "rad/s",
        base: BaseUnit {
            s: -1,
            rad: 1,
            ..NONE
        },
        // 60 / (2 pi)
        display: &[display("rpm", 9.549_296_585_513_72, 0.0)],
    },
    UnitDefinition {
        name: "rad",
        base: BaseUnit { rad: 1, ..NONE },
        display: &[display("deg", 57.295_779_513_082_32, 0.0)],
    },
    UnitDefinition {
        name: "Pa",
        base: BaseUnit {
            kg: 1,
            m: -1,
            s: -2,
            ..NONE
        },
        display: &[display("bar", 1.0e-5, 0.0)],
    },
    UnitDefinition {
        name: "K",
        base: BaseUnit { k: 1, ..NONE },
        display: &[display("degC", 1.0, -273.15)],
    },
    UnitDefinition {
        name: "m3/s",
        base: BaseUnit {
            m: 3,
            s: -1,
            ..NONE
        },
        display: &[display("l/min", 60_000.0, 0.0)],
    },
    UnitDefinition {
        name: "m3",
        base: BaseUnit { m: 3, ..NONE },
        display: &[display("l", 1.0e3, 0.0), display("cm3", 1.0e6, 0.0)],
    },
    UnitDefinition {
        name: "m",
        base: BaseUnit { m: 1, ..NONE },
        display: &[display("um", 1.0e6, 0.0), display("mm", 1.0e3, 0.0)],
    },
    UnitDefinition {
        name: "m2",
        base: BaseUnit { m: 2, ..NONE },
        display: &[],
    },
    UnitDefinition {
        name: "m3/s2",
        base: BaseUnit {
            m: 3,
            s: -2,
            ..NONE
        },
        display: &[],
    },
    UnitDefinition {
        // a flow per pressure: m^3/s / Pa = m^4 s / kg
        name: "m3/(s.Pa)",
        base: BaseUnit {
            kg: -1,
            m: 4,
            s: 1,
            ..NONE
        },
        // l/min per bar: 6e4 * 1e5
        display: &[display("l/(min.bar)", 6.0e9, 0.0)],
    },
    UnitDefinition {
        name: "m2/s",
        base: BaseUnit {
            m: 2,
            s: -1,
            ..NONE
        },
        display: &[display("cSt", 1.0e6, 0.0)],
    },
    UnitDefinition {
        name: "N.m",
        base: BaseUnit {
            kg: 1,
            m: 2,
            s: -2,
            ..NONE
        },
        display: &[],
    },
    UnitDefinition {
        name: "N",
        base: BaseUnit {
            kg: 1,
            m: 1,
            s: -2,
            ..NONE
        },
        display: &[],
    },
    UnitDefinition {
        name: "W",
        base: BaseUnit {
            kg: 1,
            m: 2,
            s: -3,
            ..NONE
        },
        display: &[],
    },
    UnitDefinition {
        name: "s",
        base: BaseUnit { s: 1, ..NONE },
        display: &[],
    },
    UnitDefinition {
        name: "kg/m3",
        base: BaseUnit {
            kg: 1,
            m: -3,
            ..NONE
        },
        display: &[],
    },
    UnitDefinition {
        name: "Pa.s",
        base: BaseUnit {
            kg: 1,
            m: -1,
            s: -1,
            ..NONE
        },
        display: &[],
    },
    UnitDefinition {
        name: "1",
        base: NONE,
        display: &[display("%", 100.0, 0.0)],
    },
];

/// `DefaultExperiment` of the model description.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DefaultExperiment {
    pub start_time: f64,
    pub stop_time: f64,
    pub tolerance: Option<f64>,
    pub step_size: f64,
}

/// An error of a model, reported by the glue as `fmi2Error` with this
/// message through the importer's logger.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// A value out of the model's range.
    #[error("{name} = {value}: {reason}")]
    InvalidValue {
        name: &'static str,
        value: String,
        reason: String,
    },
    /// A value reference the model does not know (should not happen: the
    /// glue checks value references against the table first).
    #[error("unknown value reference {0}")]
    UnknownValueReference(u32),
    /// The resources folder lacks something or holds something invalid.
    #[error("resources: {0}")]
    Resource(String),
    /// A step could not be computed.
    #[error("step at t = {t} s, h = {h} s failed: {reason}")]
    StepFailed { t: f64, h: f64, reason: String },
    /// Bytes given to [`CoSimModel::restore_state`] are not a state of this
    /// model.
    #[error("invalid FMU state: {0}")]
    InvalidState(String),
    /// Anything else.
    #[error("{0}")]
    Other(String),
}

impl ModelError {
    /// Shorthand for [`ModelError::InvalidValue`].
    pub fn invalid(name: &'static str, value: impl ToString, reason: impl Into<String>) -> Self {
        ModelError::InvalidValue {
            name,
            value: value.to_string(),
            reason: reason.into(),
        }
    }
}

/// A co-simulation model as the FMI layer sees it. One type per cdylib is
/// exported with [`crate::export_fmi2!`].
///
/// Call sequence (the glue enforces it; see [`super`] for the state
/// machine): `instantiate` -> [`setup_experiment`] -> `set_*` (parameters,
/// inputs) -> `exit_initialization` -> (`set_*` inputs / tunable
/// parameters, `do_step`, `get_*`)* ; `reset` returns to just after
/// `instantiate`. `save_state` / `restore_state` may be called at any time
/// after `instantiate`.
///
/// [`setup_experiment`]: CoSimModel::setup_experiment
pub trait CoSimModel: Sized {
    /// `modelIdentifier`: a C identifier, the name of the shared library in
    /// the FMU (`binaries/linux64/<MODEL_IDENTIFIER>.so`) and of the .fmu.
    const MODEL_IDENTIFIER: &'static str;
    /// `guid`: change it whenever the variable table changes.
    const GUID: &'static str;
    /// `modelName`.
    const MODEL_NAME: &'static str;
    /// `description`.
    const DESCRIPTION: &'static str;
    /// `author`.
    const AUTHOR: &'static str = "";
    /// `version`.
    const VERSION: &'static str = env!("CARGO_PKG_VERSION");
    /// `DefaultExperiment`, if any.
    const DEFAULT_EXPERIMENT: Option<DefaultExperiment> = None;

    /// The variable table, in the order of `ModelVariables`.
    fn variables() -> &'static [Variable];

    /// The units the variables may use (only used ones are written).
    fn units() -> &'static [UnitDefinition] {
        STANDARD_UNITS
    }

    /// An HTML fragment (`<h2>` sections) added to
    /// `documentation/index.html`: what the model computes and how it
    /// behaves in co-simulation. Default: nothing.
    fn documentation() -> &'static str {
        ""
    }

    /// Files shipped under `resources/` in the FMU: `(relative path with
    /// '/', bytes)`. They are found again under `resources` at
    /// [`instantiate`](CoSimModel::instantiate).
    fn resource_files() -> Vec<(String, Vec<u8>)> {
        Vec::new()
    }

    /// The `guid` of an FMU of this binary whose resources folder is
    /// `resources`, which `fmi2Instantiate` checks the importer's against.
    /// Default: [`GUID`](CoSimModel::GUID). A model whose FMUs differ by
    /// what they ship (the gear pump's design file) derives it from those
    /// files, so that two FMUs of one binary but different contents never
    /// share a GUID (importers cache and match FMUs by it).
    fn guid_for_resources(_resources: &Path) -> String {
        Self::GUID.to_string()
    }

    /// A new model with every variable at its start value. `resources` is
    /// the FMU's resources folder (it exists); `logger` sends an
    /// informational message to the importer (shown when debug logging is on).
    fn instantiate(resources: &Path, logger: &dyn Fn(&str)) -> Result<Self, ModelError>;

    /// Called by `fmi2SetupExperiment` (tolerance and stop time if the
    /// importer defined them). Default: nothing.
    fn setup_experiment(
        &mut self,
        _start_time: f64,
        _stop_time: Option<f64>,
        _tolerance: Option<f64>,
    ) -> Result<(), ModelError> {
        Ok(())
    }

    /// Set a Real parameter or input. The glue has checked that `vr` is a
    /// settable Real variable at this point of the call sequence and that
    /// `value` is not NaN; the model checks its range and returns
    /// [`ModelError::InvalidValue`] naming the variable otherwise.
    fn set_real(&mut self, vr: u32, value: f64) -> Result<(), ModelError>;
    /// Get any Real variable (the glue has checked that `vr` is Real).
    fn get_real(&self, vr: u32) -> Result<f64, ModelError>;
    /// Set a Boolean parameter or input (as for [`set_real`](CoSimModel::set_real)).
    fn set_boolean(&mut self, _vr: u32, _value: bool) -> Result<(), ModelError> {
        Err(ModelError::Other(
            "the model has no settable Boolean variables".into(),
        ))
    }
    /// Get any Boolean variable.
    fn get_boolean(&self, vr: u32) -> Result<bool, ModelError> {
        Err(ModelError::UnknownValueReference(vr))
    }
    /// Set an Integer parameter or input (as for [`set_real`](CoSimModel::set_real)).
    fn set_integer(&mut self, _vr: u32, _value: i32) -> Result<(), ModelError> {
        Err(ModelError::Other(
            "the model has no settable Integer variables".into(),
        ))
    }
    /// Get any Integer variable.
    fn get_integer(&self, vr: u32) -> Result<i32, ModelError> {
        Err(ModelError::UnknownValueReference(vr))
    }

    /// `providesDirectionalDerivative`: `fmi2GetDirectionalDerivative`
    /// answers for the outputs [`output_dependencies`] declares, with
    /// [`partial_derivative`]. Default: no.
    ///
    /// [`output_dependencies`]: CoSimModel::output_dependencies
    /// [`partial_derivative`]: CoSimModel::partial_derivative
    const PROVIDES_DIRECTIONAL_DERIVATIVE: bool = false;

    /// The inputs (value references) the Real output `vr` depends on, for
    /// `ModelStructure/Outputs` (`dependencies`, kind `dependent`); `None`
    /// writes no `dependencies` attribute (an importer then takes the output
    /// to depend on every input). Default: `None`.
    fn output_dependencies(_vr: u32) -> Option<&'static [u32]> {
        None
    }

    /// The partial derivative of the Real output `unknown` with respect to
    /// the Real input `known` at the current state and inputs (the glue has
    /// checked that `known` is in `unknown`'s [`output_dependencies`]).
    ///
    /// [`output_dependencies`]: CoSimModel::output_dependencies
    fn partial_derivative(&mut self, unknown: u32, _known: u32) -> Result<f64, ModelError> {
        Err(ModelError::UnknownValueReference(unknown))
    }

    /// The outputs in Initialization mode: called by the glue there before
    /// an output is read (`fmi2GetReal` / `fmi2GetBoolean` /
    /// `fmi2GetInteger` naming at least one output) and before
    /// `fmi2GetDirectionalDerivative`, as often as the importer calls them.
    /// A model whose outputs are computed by `exit_initialization` computes
    /// them here for the current parameters and inputs, as
    /// `exit_initialization` would, and keeps that work for it (redoing it
    /// only when a parameter or an input has changed since). Warnings
    /// queued here ([`take_warnings`]) are sent right after. Default:
    /// nothing (the outputs read in Initialization mode are whatever the
    /// model holds).
    ///
    /// [`take_warnings`]: CoSimModel::take_warnings
    fn initial_outputs(&mut self) -> Result<(), ModelError> {
        Ok(())
    }

    /// End of initialisation: check the parameters together, compute the
    /// initial outputs (or keep the ones [`initial_outputs`] computed for
    /// the same parameters and inputs).
    ///
    /// [`initial_outputs`]: CoSimModel::initial_outputs
    fn exit_initialization(&mut self) -> Result<(), ModelError>;
    /// Advance from communication point `t` by `h > 0` (the glue has checked
    /// both).
    fn do_step(&mut self, t: f64, h: f64) -> Result<(), ModelError>;
    /// Back to the state right after `instantiate` (start values).
    fn reset(&mut self) -> Result<(), ModelError>;

    /// Warnings the model has for the user since the last call (e.g. an
    /// operating point outside its range), taken after each successful
    /// `exit_initialization` and `do_step` and sent to the importer's
    /// logger with status fmi2Warning; the call itself still returns
    /// fmi2OK. The model decides how often a condition is worth a message.
    /// Default: none.
    fn take_warnings(&mut self) -> Vec<String> {
        Vec::new()
    }

    /// The complete model state (variables, internal states) as
    /// self-contained bytes: no pointers, restorable in another process.
    fn save_state(&self) -> Vec<u8>;
    /// Restore a state made by [`save_state`](CoSimModel::save_state),
    /// possibly in another process; refuse bytes that are not one.
    fn restore_state(&mut self, bytes: &[u8]) -> Result<(), ModelError>;
}

/// Checks a model's variable table and constants against the FMI 2.0 rules
/// that importers check (unique names and value references, the allowed
/// causality/variability/initial combinations, start values where required
/// and only there, known units and display units, a C identifier as
/// modelIdentifier). Returns every problem found.
pub fn check_model<M: CoSimModel>() -> Result<(), Vec<String>> {
    let mut problems = Vec::new();
    if !is_c_identifier(M::MODEL_IDENTIFIER) {
        problems.push(format!(
            "modelIdentifier {:?} is not a C identifier",
            M::MODEL_IDENTIFIER
        ));
    }
    if M::GUID.trim().is_empty() {
        problems.push("empty GUID".into());
    }
    let vars = M::variables();
    if vars.is_empty() {
        problems.push("no variables".into());
    }
    for (i, v) in vars.iter().enumerate() {
        let at = format!("variable {:?} (vr {})", v.name, v.value_reference);
        if v.name.is_empty() || v.name.chars().any(|c| c.is_whitespace() || c.is_control()) {
            problems.push(format!("{at}: invalid name"));
        }
        for w in &vars[..i] {
            if w.name == v.name {
                problems.push(format!("{at}: duplicate name"));
            }
            if w.value_reference == v.value_reference && w.base_type() == v.base_type() {
                problems.push(format!("{at}: value reference also used by {:?}", w.name));
            }
        }
        use Causality as C;
        use Variability as V;
        match (v.causality, v.variability) {
            (C::Parameter, V::Fixed | V::Tunable) => {}
            (C::Input, V::Continuous | V::Discrete) => {}
            (C::Output | C::Local, _) => {}
            (c, var) => problems.push(format!(
                "{at}: causality {} with variability {} is not allowed",
                c.as_str(),
                var.as_str()
            )),
        }
        if let (VariableKind::Boolean { .. }, V::Continuous) = (v.kind, v.variability) {
            problems.push(format!("{at}: a Boolean cannot be continuous"));
        }
        if let (VariableKind::Integer { .. }, V::Continuous) = (v.kind, v.variability) {
            problems.push(format!("{at}: an Integer cannot be continuous"));
        }
        let allowed_initial: &[Initial] = match (v.causality, v.variability) {
            (C::Parameter, _) => &[Initial::Exact],
            (C::Input, _) => &[],
            (C::Output, _) => &[Initial::Exact, Initial::Approx, Initial::Calculated],
            (C::Local, V::Fixed | V::Tunable) => &[Initial::Approx, Initial::Calculated],
            (C::Local, _) => &[Initial::Exact, Initial::Approx, Initial::Calculated],
        };
        if let Some(init) = v.initial {
            if !allowed_initial.contains(&init) {
                problems.push(format!(
                    "{at}: initial=\"{}\" is not allowed for causality {}",
                    init.as_str(),
                    v.causality.as_str()
                ));
            }
        }
        let needs_start = v.causality == C::Input
            || matches!(
                v.effective_initial(),
                Some(Initial::Exact | Initial::Approx)
            );
        if needs_start && !v.has_start() {
            problems.push(format!("{at}: a start value is required"));
        }
        if !needs_start && v.has_start() {
            problems.push(format!(
                "{at}: a start value is not allowed with initial=\"calculated\""
            ));
        }
        if let VariableKind::Real {
            unit,
            display_unit,
            start,
            min,
            max,
        } = v.kind
        {
            if let Some(s) = start {
                if !s.is_finite() {
                    problems.push(format!("{at}: start value {s} is not finite"));
                }
            }
            for (what, x) in [("min", min), ("max", max)] {
                if x.is_some_and(|x| !x.is_finite()) {
                    problems.push(format!("{at}: {what} is not finite"));
                }
            }
            if let (Some(lo), Some(hi)) = (min, max) {
                if lo >= hi {
                    problems.push(format!("{at}: min {lo} is not below max {hi}"));
                }
            }
            // FMI 2.0 section 2.2.7: min <= start <= max
            if let Some(s) = start {
                if min.is_some_and(|lo| s < lo) || max.is_some_and(|hi| s > hi) {
                    problems.push(format!("{at}: start value {s} is outside [min, max]"));
                }
            }
            match unit.map(|u| M::units().iter().find(|d| d.name == u)) {
                Some(None) => problems.push(format!(
                    "{at}: unit {:?} is not in the unit table",
                    unit.unwrap_or_default()
                )),
                Some(Some(def)) => {
                    if let Some(du) = display_unit {
                        if !def.display.iter().any(|d| d.name == du) {
                            problems.push(format!(
                                "{at}: display unit {du:?} is not defined for unit {:?}",
                                def.name
                            ));
                        }
                    }
                }
                None => {
                    if display_unit.is_some() {
                        problems.push(format!("{at}: a display unit needs a unit"));
                    }
                }
            }
        }
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(problems)
    }
}

/// Whether `s` is a C identifier (`[A-Za-z_][A-Za-z0-9_]*`).
pub fn is_c_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// Writes a model state as self-contained little-endian bytes, starting
/// with an 8-byte tag that [`StateReader::new`] checks.
#[derive(Debug, Clone, Default)]
pub struct StateWriter {
    buf: Vec<u8>,
}

impl StateWriter {
    /// A writer whose bytes start with `tag` (identifies model and format
    /// version, e.g. `*b"TANK0001"`).
    pub fn new(tag: &[u8; 8]) -> Self {
        StateWriter { buf: tag.to_vec() }
    }
    pub fn f64(&mut self, v: f64) -> &mut Self {
        self.buf.extend_from_slice(&v.to_le_bytes());
        self
    }
    pub fn u64(&mut self, v: u64) -> &mut Self {
        self.buf.extend_from_slice(&v.to_le_bytes());
        self
    }
    pub fn bool(&mut self, v: bool) -> &mut Self {
        self.buf.push(u8::from(v));
        self
    }
    /// A length-prefixed slice of f64 (vectors of states).
    pub fn f64s(&mut self, v: &[f64]) -> &mut Self {
        self.u64(v.len() as u64);
        for x in v {
            self.f64(*x);
        }
        self
    }
    /// A length-prefixed byte string.
    pub fn bytes(&mut self, v: &[u8]) -> &mut Self {
        self.u64(v.len() as u64);
        self.buf.extend_from_slice(v);
        self
    }
    /// The bytes, followed by their checksum ([`state_checksum`]).
    pub fn finish(&mut self) -> Vec<u8> {
        let sum = state_checksum(&self.buf);
        self.buf.extend_from_slice(&sum.to_le_bytes());
        std::mem::take(&mut self.buf)
    }
}

/// The checksum a state's bytes end with: 64-bit FNV-1a of everything
/// before it. A state corrupted in storage or in transit (or bytes that
/// were never a state) is refused before any of it is read, instead of
/// resuming a simulation from values no setter would accept.
pub fn state_checksum(bytes: &[u8]) -> u64 {
    let mut h = gearpump_core::hash::Fnv1a::new();
    h.write(bytes);
    h.finish().0
}

/// Reads what a [`StateWriter`] wrote; every read checks the remaining
/// length, so truncated or foreign bytes give [`ModelError::InvalidState`].
#[derive(Debug, Clone)]
pub struct StateReader<'a> {
    buf: &'a [u8],
    pos: usize,
}

impl<'a> StateReader<'a> {
    /// Checks the tag and the checksum and starts reading after the tag.
    pub fn new(bytes: &'a [u8], tag: &[u8; 8]) -> Result<Self, ModelError> {
        if bytes.len() < 16 || &bytes[..8] != tag {
            return Err(ModelError::InvalidState(format!(
                "expected a state tagged {:?}",
                String::from_utf8_lossy(tag)
            )));
        }
        let (body, sum) = bytes.split_at(bytes.len() - 8);
        let mut stored = [0u8; 8];
        stored.copy_from_slice(sum);
        if u64::from_le_bytes(stored) != state_checksum(body) {
            return Err(ModelError::InvalidState(
                "checksum mismatch: the state bytes were changed or cut".into(),
            ));
        }
        Ok(StateReader { buf: body, pos: 8 })
    }
    fn take(&mut self, n: usize) -> Result<&'a [u8], ModelError> {
        let end = self
            .pos
            .checked_add(n)
            .filter(|&e| e <= self.buf.len())
            .ok_or_else(|| {
                ModelError::InvalidState(format!(
                    "truncated: {} bytes wanted at offset {}, {} available",
                    n,
                    self.pos,
                    self.buf.len() - self.pos
                ))
            })?;
        let s = &self.buf[self.pos..end];
        self.pos = end;
        Ok(s)
    }
    pub fn f64(&mut self) -> Result<f64, ModelError> {
        let mut b = [0u8; 8];
        b.copy_from_slice(self.take(8)?);
        Ok(f64::from_le_bytes(b))
    }
    pub fn u64(&mut self) -> Result<u64, ModelError> {
        let mut b = [0u8; 8];
        b.copy_from_slice(self.take(8)?);
        Ok(u64::from_le_bytes(b))
    }
    pub fn bool(&mut self) -> Result<bool, ModelError> {
        match self.take(1)?[0] {
            0 => Ok(false),
            1 => Ok(true),
            b => Err(ModelError::InvalidState(format!(
                "invalid Boolean byte {b}"
            ))),
        }
    }
    fn len(&mut self, item: usize) -> Result<usize, ModelError> {
        let n = self.u64()?;
        usize::try_from(n)
            .ok()
            .filter(|&n| n.saturating_mul(item) <= self.buf.len() - self.pos)
            .ok_or_else(|| ModelError::InvalidState(format!("invalid length {n}")))
    }
    pub fn f64s(&mut self) -> Result<Vec<f64>, ModelError> {
        let n = self.len(8)?;
        (0..n).map(|_| self.f64()).collect()
    }
    pub fn bytes(&mut self) -> Result<&'a [u8], ModelError> {
        let n = self.len(1)?;
        self.take(n)
    }
    /// Checks that everything was read.
    pub fn finish(self) -> Result<(), ModelError> {
        if self.pos == self.buf.len() {
            Ok(())
        } else {
            Err(ModelError::InvalidState(format!(
                "{} trailing bytes",
                self.buf.len() - self.pos
            )))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn state_writer_reader_round_trip_and_refusals() {
        let bytes = StateWriter::new(b"TEST0001")
            .f64(1.5)
            .u64(7)
            .bool(true)
            .f64s(&[1.0, -2.0])
            .bytes(b"abc")
            .finish();
        let mut r = StateReader::new(&bytes, b"TEST0001").unwrap();
        assert_eq!(r.f64().unwrap(), 1.5);
        assert_eq!(r.u64().unwrap(), 7);
        assert!(r.bool().unwrap());
        assert_eq!(r.f64s().unwrap(), vec![1.0, -2.0]);
        assert_eq!(r.bytes().unwrap(), b"abc");
        r.finish().unwrap();

        assert!(StateReader::new(&bytes, b"OTHER001").is_err());
        assert!(StateReader::new(&bytes[..4], b"TEST0001").is_err());
        // cut bytes fail the checksum
        assert!(StateReader::new(&bytes[..12], b"TEST0001").is_err());
        // so does any single changed byte (after the tag), whatever it is
        for i in 8..bytes.len() {
            for flip in [0x01u8, 0x80, 0xff] {
                let mut bad = bytes.clone();
                bad[i] ^= flip;
                assert!(
                    matches!(
                        StateReader::new(&bad, b"TEST0001"),
                        Err(ModelError::InvalidState(m)) if m.contains("checksum")
                    ),
                    "byte {i} ^ {flip:#x} accepted"
                );
            }
        }
        // a short body behind a valid checksum: reads past its end are refused
        let short = StateWriter::new(b"TEST0001").bool(true).finish();
        let mut r = StateReader::new(&short, b"TEST0001").unwrap();
        assert!(matches!(r.f64(), Err(ModelError::InvalidState(_))));
        // A huge length prefix is refused, not allocated.
        let evil = StateWriter::new(b"TEST0001").u64(u64::MAX).finish();
        let mut r = StateReader::new(&evil, b"TEST0001").unwrap();
        assert!(r.f64s().is_err());
        let r = StateReader::new(&bytes, b"TEST0001").unwrap();
        assert!(r.finish().is_err());
    }

    #[test]
    fn display_unit_factors() {
        let find = |u: &str, d: &str| {
            let def = STANDARD_UNITS.iter().find(|x| x.name == u).unwrap();
            *def.display.iter().find(|x| x.name == d).unwrap()
        };
        let rpm = find("rad/s", "rpm");
        assert!((rpm.factor * gearpump_core::units::rpm_to_rad_s(1000.0) - 1000.0).abs() < 1e-9);
        let bar = find("Pa", "bar");
        assert!((bar.factor * 3.0e6 + bar.offset - 30.0).abs() < 1e-12);
        let degc = find("K", "degC");
        assert!((degc.factor * 333.15 + degc.offset - 60.0).abs() < 1e-12);
        let lpm = find("m3/s", "l/min");
        assert!((lpm.factor * gearpump_core::units::lpm_to_m3_s(14.65) - 14.65).abs() < 1e-12);
    }

    #[test]
    fn c_identifiers() {
        assert!(is_c_identifier("GearPump"));
        assert!(is_c_identifier("_a1"));
        assert!(!is_c_identifier("1a"));
        assert!(!is_c_identifier("a-b"));
        assert!(!is_c_identifier(""));
    }
}
