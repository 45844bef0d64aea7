//! modelDescription.xml, generated from the variable table.

use fmi2_model_description as md;

use super::variables::{BaseType, Binding, GroundField, VariableTable, METHOD_TYPE, UNITS};
use super::Category;
use crate::integrator::Method;
use crate::model::Model;

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

/// The model description of an FMU for `model`, with variables from `table`.
pub fn model_description(model: &Model, table: &VariableTable, guid: &str) -> md::ModelDescription {
    let variables: Vec<md::ScalarVariable> = table
        .variables
        .iter()
        .map(|v| md::ScalarVariable {
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
                    min: matches!(
                        v.binding,
                        Binding::Mass(_)
                            | Binding::StepSize
                            | Binding::PointMass(_)
                            | Binding::Ground(_)
                    )
                    .then_some(0.0)
                    .filter(|_| v.binding != Binding::Ground(GroundField::Height)),
                    max: None,
                },
                BaseType::Boolean => md::VariableKind::Boolean {
                    start: v.start.map(|s| s != 0.0),
                },
                BaseType::Enumeration => md::VariableKind::Enumeration {
                    declared_type: METHOD_TYPE.to_string(),
                    start: v.start.map(|s| s as i32),
                },
            },
        })
        .collect();
    // ModelStructure indices are 1-based positions in ModelVariables.
    let outputs: Vec<md::Unknown> = table
        .variables
        .iter()
        .enumerate()
        .filter(|(_, v)| matches!(v.binding, Binding::Output(_)))
        .map(|(i, _)| md::Unknown {
            index: i as u32 + 1,
            dependencies: None,
        })
        .collect();
    md::ModelDescription {
        model_name: model.scene.name.clone(),
        guid: guid.to_string(),
        description: model.scene.description.clone(),
        generation_tool: Some(format!("tensegrity-fmu {}", env!("CARGO_PKG_VERSION"))),
        generation_date_and_time: None,
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
            .map(|(name, [kg, m, s])| md::Unit {
                name: name.to_string(),
                base_unit: md::BaseUnit {
                    kg: *kg,
                    m: *m,
                    s: *s,
                    ..md::BaseUnit::default()
                },
            })
            .collect(),
        type_definitions: vec![md::SimpleType {
            name: METHOD_TYPE.to_string(),
            description: Some("integration method".to_string()),
            kind: md::SimpleTypeKind::Enumeration {
                items: Method::ALL
                    .iter()
                    .enumerate()
                    .map(|(i, m)| md::EnumerationItem {
                        name: m.name().to_string(),
                        value: i as i32 + 1,
                        description: Some(m.description().to_string()),
                    })
                    .collect(),
            },
        }],
        log_categories: Category::ALL
            .iter()
            .map(|c| md::LogCategory {
                name: c.name().to_string(),
                description: Some(c.description().to_string()),
            })
            .collect(),
        default_experiment: Some(md::DefaultExperiment {
            start_time: Some(0.0),
            stop_time: Some(1.0),
            tolerance: None,
            step_size: Some(model.solver.step_size),
        }),
        model_variables: variables,
        model_structure: md::ModelStructure {
            initial_unknowns: outputs.clone(),
            outputs,
            derivatives: Vec::new(),
        },
    }
}
