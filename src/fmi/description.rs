//! modelDescription.xml, generated from the variable table.

use fmi2_model_description as md;

use super::dependencies::model_structure;
use super::variables::{BaseType, Binding, GroundField, Variable, VariableTable, UNITS};
use super::Category;
use crate::integrator::Method;
use crate::model::Model;

/// Who made the FMU and when: the attributes that vary from build to build.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Provenance {
    /// The GUID.
    pub guid: String,
    /// `generationTool`: tool, version and git commit.
    pub generation_tool: String,
    /// `generationDateAndTime`, an `xs:dateTime` in UTC.
    pub generation_date_and_time: String,
}

impl Provenance {
    /// This program, now (or at `SOURCE_DATE_EPOCH`, for reproducible builds).
    pub fn current(guid: String) -> Self {
        let seconds = std::env::var("SOURCE_DATE_EPOCH")
            .ok()
            .and_then(|s| s.trim().parse::<i64>().ok())
            .unwrap_or_else(|| {
                std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map_or(0, |d| d.as_secs() as i64)
            });
        Self {
            guid,
            generation_tool: generation_tool(env!("TENSEGRITY_GIT_COMMIT")),
            generation_date_and_time: iso8601_utc(seconds),
        }
    }
}

/// `generationTool` for a commit: `tensegrity-fmu <version> (git <commit>)`.
pub fn generation_tool(commit: &str) -> String {
    format!(
        "tensegrity-fmu {} (git {commit})",
        env!("CARGO_PKG_VERSION")
    )
}

/// Last second `xs:dateTime` and humantime can write with four year digits (9999-12-31).
const LAST_FOUR_DIGIT_SECOND: i64 = 253_402_300_799;

/// `YYYY-MM-DDThh:mm:ssZ` for seconds since 1970-01-01 UTC (clamped to 1970..=9999).
pub fn iso8601_utc(seconds: i64) -> String {
    let seconds = seconds.clamp(0, LAST_FOUR_DIGIT_SECOND) as u64;
    let at = std::time::UNIX_EPOCH + std::time::Duration::from_secs(seconds);
    humantime::format_rfc3339_seconds(at).to_string()
}

/// The author named in modelDescription.xml.
pub const AUTHOR: &str = "the tensegrity-fmu developers";

/// The communication step of `<DefaultExperiment>`: 10 ms, or ten internal steps if
/// that is longer, so that a default run reports at a useful rate.
pub fn default_communication_step(model: &Model) -> f64 {
    (10.0 * model.solver.step_size).max(0.01)
}

/// Declared `min`/`max` of a parameter, where its value has a bound.
fn bounds(v: &Variable) -> (Option<f64>, Option<f64>) {
    match v.binding {
        Binding::Method => (Some(1.0), Some(Method::ALL.len() as f64)),
        Binding::MaxSteps => (Some(1.0), Some(f64::from(i32::MAX))),
        Binding::Ground(GroundField::Height) => (None, None),
        Binding::Mass(_)
        | Binding::StepSize
        | Binding::PointMass(_)
        | Binding::Ground(_)
        | Binding::Radius(_)
        | Binding::Terrain(..)
        | Binding::Collision(_) => (Some(0.0), None),
        _ => (None, None),
    }
}

/// Longest model identifier: C compilers guarantee 63 significant characters.
pub const MAX_MODEL_IDENTIFIER: usize = 63;

/// Name of the shared library inside `binaries/linux64/` (without `.so`): the scene name
/// as a C identifier (other characters become `_`), at most [`MAX_MODEL_IDENTIFIER`] long.
pub fn model_identifier(model: &Model) -> String {
    let mut id: String = model
        .scene
        .name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if id.starts_with(|c: char| c.is_ascii_digit()) || id.is_empty() {
        id.insert_str(0, "t_");
    }
    id.truncate(MAX_MODEL_IDENTIFIER);
    id
}

fn scalar_variable(v: &Variable) -> md::ScalarVariable {
    let (min, max) = bounds(v);
    md::ScalarVariable {
        name: v.name.clone(),
        value_reference: v.value_reference,
        description: Some(v.description.clone()),
        causality: v.causality,
        variability: v.variability,
        initial: v.initial,
        kind: match v.base_type {
            BaseType::Real => md::VariableKind::Real {
                declared_type: None,
                unit: v.unit.map(str::to_string),
                start: v.start,
                min,
                max,
            },
            BaseType::Boolean => md::VariableKind::Boolean {
                start: v.start.map(|s| s != 0.0),
            },
            BaseType::Integer => md::VariableKind::Integer {
                declared_type: None,
                start: v.start.map(|s| s as i32),
                min: min.map(|m| m as i32),
                max: max.map(|m| m as i32),
            },
        },
    }
}

/// The model description of an FMU for `model`, with variables from `table`.
pub fn model_description(
    model: &Model,
    table: &VariableTable,
    provenance: &Provenance,
) -> md::ModelDescription {
    // ModelStructure indices are 1-based positions in ModelVariables.
    let (outputs, initial_unknowns) = model_structure(model, table);
    let step = default_communication_step(model);
    md::ModelDescription {
        model_name: model.scene.name.clone(),
        guid: provenance.guid.clone(),
        description: model.scene.description.clone(),
        author: Some(AUTHOR.to_string()),
        version: Some(env!("CARGO_PKG_VERSION").to_string()),
        copyright: Some(format!("Copyright (c) {AUTHOR}")),
        license: Some(env!("CARGO_PKG_LICENSE").to_string()),
        generation_tool: Some(provenance.generation_tool.clone()),
        generation_date_and_time: Some(provenance.generation_date_and_time.clone()),
        co_simulation: md::CoSimulation {
            model_identifier: model_identifier(model),
            can_handle_variable_communication_step_size: true,
            can_get_and_set_fmu_state: true,
            can_serialize_fmu_state: true,
            can_not_use_memory_management_functions: true,
            can_be_instantiated_only_once_per_process: false,
            provides_directional_derivative: false,
            can_interpolate_inputs: false,
            max_output_derivative_order: 0,
        },
        // Only the units some variable uses: an absent effect leaves no trace.
        unit_definitions: UNITS
            .iter()
            .filter(|(name, _)| table.variables.iter().any(|v| v.unit == Some(*name)))
            .map(|(name, [kg, m, s, rad])| md::Unit {
                name: name.to_string(),
                base_unit: md::BaseUnit {
                    kg: *kg,
                    m: *m,
                    s: *s,
                    rad: *rad,
                    ..md::BaseUnit::default()
                },
            })
            .collect(),
        // solver.method is an Integer: importers such as libcosim ignore Enumerations.
        type_definitions: Vec::new(),
        log_categories: Category::ALL
            .iter()
            .map(|c| md::LogCategory {
                name: c.name().to_string(),
                description: Some(c.description().to_string()),
            })
            .collect(),
        default_experiment: Some(md::DefaultExperiment {
            start_time: Some(0.0),
            stop_time: Some(if step > 0.1 { 10.0 * step } else { 1.0 }),
            tolerance: None,
            step_size: Some(step),
        }),
        model_variables: table.variables.iter().map(scalar_variable).collect(),
        model_structure: md::ModelStructure {
            outputs,
            derivatives: Vec::new(),
            initial_unknowns,
        },
    }
}
