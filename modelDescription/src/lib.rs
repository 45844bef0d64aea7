//! FMI 2.0 co-simulation `modelDescription.xml` as plain Rust types.
//!
//! Build a [`ModelDescription`] and call [`ModelDescription::to_xml`]. The XML is
//! written with quick-xml's serde serializer through private "wire" structs that
//! fix element order, attribute names and the omission of empty lists.
//!
//! ```
//! use fmi2_model_description::*;
//!
//! let md = ModelDescription {
//!     model_name: "Demo".into(),
//!     guid: "{0}".into(),
//!     description: None,
//!     author: None,
//!     version: None,
//!     copyright: None,
//!     license: None,
//!     generation_tool: None,
//!     generation_date_and_time: None,
//!     co_simulation: CoSimulation { model_identifier: "demo".into(), ..Default::default() },
//!     unit_definitions: vec![],
//!     type_definitions: vec![],
//!     log_categories: vec![],
//!     default_experiment: None,
//!     model_variables: vec![ScalarVariable {
//!         name: "time".into(),
//!         value_reference: 0,
//!         description: None,
//!         causality: Causality::Independent,
//!         variability: Variability::Continuous,
//!         initial: None,
//!         kind: VariableKind::Real { declared_type: None, unit: None, start: None, min: None, max: None },
//!     }],
//!     model_structure: ModelStructure::default(),
//! };
//! let xml = md.to_xml().unwrap();
//! assert!(xml.contains("<Real/>") && xml.contains("<ModelStructure/>"));
//! ```

#![warn(missing_docs)]

#[cfg(feature = "xml")]
mod wire;

/// Error returned by [`ModelDescription::to_xml`].
#[cfg(feature = "xml")]
pub use quick_xml::SeError;

/// The root `fmiModelDescription` element.
///
/// Always written with `fmiVersion="2.0"`, `variableNamingConvention="structured"`
/// and `numberOfEventIndicators="0"`.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelDescription {
    /// `modelName`.
    pub model_name: String,
    /// `guid`.
    pub guid: String,
    /// `description`.
    pub description: Option<String>,
    /// `author`.
    pub author: Option<String>,
    /// `version`: the model's version.
    pub version: Option<String>,
    /// `copyright`.
    pub copyright: Option<String>,
    /// `license`.
    pub license: Option<String>,
    /// `generationTool`.
    pub generation_tool: Option<String>,
    /// `generationDateAndTime`; must be an `xs:dateTime`.
    pub generation_date_and_time: Option<String>,
    /// `<CoSimulation>`.
    pub co_simulation: CoSimulation,
    /// `<UnitDefinitions>`; omitted when empty.
    pub unit_definitions: Vec<Unit>,
    /// `<TypeDefinitions>`; omitted when empty.
    pub type_definitions: Vec<SimpleType>,
    /// `<LogCategories>`; omitted when empty.
    pub log_categories: Vec<LogCategory>,
    /// `<DefaultExperiment>`.
    pub default_experiment: Option<DefaultExperiment>,
    /// `<ModelVariables>`; always written.
    pub model_variables: Vec<ScalarVariable>,
    /// `<ModelStructure>`; always written.
    pub model_structure: ModelStructure,
}

#[cfg(feature = "xml")]
impl ModelDescription {
    /// Writes the pretty-printed XML document, with its `<?xml ...?>` declaration.
    ///
    /// Fails if a real value is NaN or infinite.
    pub fn to_xml(&self) -> Result<String, SeError> {
        wire::to_xml(self)
    }
}

/// The `<CoSimulation>` capability flags.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct CoSimulation {
    /// `modelIdentifier`: the binary's file name without extension.
    pub model_identifier: String,
    /// `canHandleVariableCommunicationStepSize`.
    pub can_handle_variable_communication_step_size: bool,
    /// `canGetAndSetFMUstate`.
    pub can_get_and_set_fmu_state: bool,
    /// `canSerializeFMUstate`.
    pub can_serialize_fmu_state: bool,
    /// `canNotUseMemoryManagementFunctions`.
    pub can_not_use_memory_management_functions: bool,
    /// `canBeInstantiatedOnlyOncePerProcess`.
    pub can_be_instantiated_only_once_per_process: bool,
    /// `providesDirectionalDerivative`.
    pub provides_directional_derivative: bool,
    /// `canInterpolateInputs`.
    pub can_interpolate_inputs: bool,
    /// `maxOutputDerivativeOrder`.
    pub max_output_derivative_order: u32,
}

/// A `<Unit>` in `<UnitDefinitions>`.
#[derive(Debug, Clone, PartialEq)]
pub struct Unit {
    /// `name`, as used by a variable's `unit`.
    pub name: String,
    /// `<BaseUnit>`.
    pub base_unit: BaseUnit,
}

/// `<BaseUnit>`: SI exponents, `factor` and `offset`.
///
/// Only nonzero exponents are written; `factor` only when not 1, `offset` only
/// when not 0. [`Default`] is dimensionless with `factor = 1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BaseUnit {
    /// Exponent of kilogram (`kg`).
    pub kg: i32,
    /// Exponent of metre (`m`).
    pub m: i32,
    /// Exponent of second (`s`).
    pub s: i32,
    /// Exponent of ampere (`A`).
    pub a: i32,
    /// Exponent of kelvin (`K`).
    pub k: i32,
    /// Exponent of mole (`mol`).
    pub mol: i32,
    /// Exponent of candela (`cd`).
    pub cd: i32,
    /// Exponent of radian (`rad`).
    pub rad: i32,
    /// `factor` (default 1).
    pub factor: f64,
    /// `offset` (default 0).
    pub offset: f64,
}

impl Default for BaseUnit {
    fn default() -> Self {
        BaseUnit {
            kg: 0,
            m: 0,
            s: 0,
            a: 0,
            k: 0,
            mol: 0,
            cd: 0,
            rad: 0,
            factor: 1.0,
            offset: 0.0,
        }
    }
}

/// A `<SimpleType>` in `<TypeDefinitions>`.
#[derive(Debug, Clone, PartialEq)]
pub struct SimpleType {
    /// `name`, as used by a variable's `declaredType`.
    pub name: String,
    /// `description`.
    pub description: Option<String>,
    /// The type's child element.
    pub kind: SimpleTypeKind,
}

/// The child element of a `<SimpleType>`.
#[derive(Debug, Clone, PartialEq)]
pub enum SimpleTypeKind {
    /// `<Enumeration>` with its `<Item>`s.
    Enumeration {
        /// The items.
        items: Vec<EnumerationItem>,
    },
}

/// An enumeration `<Item>`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EnumerationItem {
    /// `name`.
    pub name: String,
    /// `value`.
    pub value: i32,
    /// `description`.
    pub description: Option<String>,
}

/// A `<Category>` in `<LogCategories>`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LogCategory {
    /// `name`.
    pub name: String,
    /// `description`.
    pub description: Option<String>,
}

/// `<DefaultExperiment>`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct DefaultExperiment {
    /// `startTime`.
    pub start_time: Option<f64>,
    /// `stopTime`.
    pub stop_time: Option<f64>,
    /// `tolerance`.
    pub tolerance: Option<f64>,
    /// `stepSize`.
    pub step_size: Option<f64>,
}

/// A `<ScalarVariable>`.
#[derive(Debug, Clone, PartialEq)]
pub struct ScalarVariable {
    /// `name`.
    pub name: String,
    /// `valueReference`.
    pub value_reference: u32,
    /// `description`.
    pub description: Option<String>,
    /// `causality`.
    pub causality: Causality,
    /// `variability`.
    pub variability: Variability,
    /// `initial`.
    pub initial: Option<Initial>,
    /// The type element and its attributes.
    pub kind: VariableKind,
}

/// `causality` of a variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Causality {
    /// `parameter`.
    Parameter,
    /// `calculatedParameter`.
    CalculatedParameter,
    /// `input`.
    Input,
    /// `output`.
    Output,
    /// `local`.
    Local,
    /// `independent`.
    Independent,
}

/// `variability` of a variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Variability {
    /// `constant`.
    Constant,
    /// `fixed`.
    Fixed,
    /// `tunable`.
    Tunable,
    /// `discrete`.
    Discrete,
    /// `continuous`.
    Continuous,
}

/// `initial` of a variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Initial {
    /// `exact`.
    Exact,
    /// `approx`.
    Approx,
    /// `calculated`.
    Calculated,
}

/// The type element of a `<ScalarVariable>`.
#[derive(Debug, Clone, PartialEq)]
pub enum VariableKind {
    /// `<Real>`.
    Real {
        /// `declaredType`.
        declared_type: Option<String>,
        /// `unit`.
        unit: Option<String>,
        /// `start`.
        start: Option<f64>,
        /// `min`.
        min: Option<f64>,
        /// `max`.
        max: Option<f64>,
    },
    /// `<Integer>`.
    Integer {
        /// `declaredType`.
        declared_type: Option<String>,
        /// `start`.
        start: Option<i32>,
        /// `min`.
        min: Option<i32>,
        /// `max`.
        max: Option<i32>,
    },
    /// `<Boolean>`.
    Boolean {
        /// `start`.
        start: Option<bool>,
    },
    /// `<Enumeration>`.
    Enumeration {
        /// `declaredType`: name of a [`SimpleType`].
        declared_type: String,
        /// `start`.
        start: Option<i32>,
    },
    /// `<String>`.
    String {
        /// `start`.
        start: Option<String>,
    },
}

/// `<ModelStructure>`. Empty lists are omitted.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ModelStructure {
    /// `<Outputs>`.
    pub outputs: Vec<Unknown>,
    /// `<Derivatives>`.
    pub derivatives: Vec<Unknown>,
    /// `<InitialUnknowns>`.
    pub initial_unknowns: Vec<Unknown>,
}

/// An `<Unknown>` in `<ModelStructure>`.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Unknown {
    /// `index`: 1-based index into `model_variables`.
    pub index: u32,
    /// `dependencies`: `None` omits the attribute, `Some(vec![])` writes `""`.
    pub dependencies: Option<Vec<u32>>,
    /// `dependenciesKind`, one per dependency; `None` omits the attribute (meaning
    /// "dependent" for every dependency).
    pub dependencies_kind: Option<Vec<DependencyKind>>,
}

/// How a Known enters an Unknown (`dependenciesKind`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DependencyKind {
    /// `dependent`: no particular structure, `f(v)`.
    Dependent,
    /// `constant`: a constant factor, `c·v` (Reals only).
    Constant,
    /// `fixed`: a factor fixed after initialization, `p·v` (Reals only).
    Fixed,
    /// `tunable`: a factor that changes with tunable parameters, `p·v` (Reals only).
    Tunable,
    /// `discrete`: a factor that changes at events, `d·v` (Reals only).
    Discrete,
}

impl DependencyKind {
    /// The attribute value.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Dependent => "dependent",
            Self::Constant => "constant",
            Self::Fixed => "fixed",
            Self::Tunable => "tunable",
            Self::Discrete => "discrete",
        }
    }
}
