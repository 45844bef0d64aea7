//! Private serde structs that mirror the XML layout exactly.
//!
//! `@name` fields become attributes, other fields child elements, in field order.

mod variables;

use serde::{Serialize, Serializer};

use crate::{BaseUnit, ModelDescription, SeError, SimpleTypeKind, Unknown};
use variables::ModelVariables;

/// Serializes `md` to a pretty-printed document with an XML declaration.
pub(crate) fn to_xml(md: &ModelDescription) -> Result<String, SeError> {
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let mut ser = quick_xml::se::Serializer::new(&mut out);
    ser.indent(' ', 2);
    Root::from(md).serialize(ser)?;
    out.push('\n');
    Ok(out)
}

/// An `xs:double` that round-trips exactly; NaN and infinities are errors.
#[derive(Clone, Copy)]
struct Real(f64);

impl Serialize for Real {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let x = self.0;
        if !x.is_finite() {
            return Err(serde::ser::Error::custom(format!(
                "non-finite real value {x} cannot be written"
            )));
        }
        // `{}` never uses an exponent, so switch to `{:e}` for very small/large values.
        let text = if x == 0.0 || (1e-4..1e15).contains(&x.abs()) {
            format!("{x}")
        } else {
            format!("{x:e}")
        };
        s.serialize_str(&text)
    }
}

fn real(x: Option<f64>) -> Option<Real> {
    x.map(Real)
}

fn nonzero(x: i32) -> Option<i32> {
    (x != 0).then_some(x)
}

/// `Some(wrapper)` only when `items` is non-empty.
fn non_empty<T, W>(items: Vec<T>, wrap: impl FnOnce(Vec<T>) -> W) -> Option<W> {
    (!items.is_empty()).then(|| wrap(items))
}

#[derive(Serialize)]
#[serde(rename = "fmiModelDescription")]
struct Root<'a> {
    #[serde(rename = "@fmiVersion")]
    fmi_version: &'static str,
    #[serde(rename = "@modelName")]
    model_name: &'a str,
    #[serde(rename = "@guid")]
    guid: &'a str,
    #[serde(rename = "@description", skip_serializing_if = "Option::is_none")]
    description: Option<&'a str>,
    #[serde(rename = "@author", skip_serializing_if = "Option::is_none")]
    author: Option<&'a str>,
    #[serde(rename = "@version", skip_serializing_if = "Option::is_none")]
    version: Option<&'a str>,
    #[serde(rename = "@copyright", skip_serializing_if = "Option::is_none")]
    copyright: Option<&'a str>,
    #[serde(rename = "@license", skip_serializing_if = "Option::is_none")]
    license: Option<&'a str>,
    #[serde(rename = "@generationTool", skip_serializing_if = "Option::is_none")]
    generation_tool: Option<&'a str>,
    #[serde(
        rename = "@generationDateAndTime",
        skip_serializing_if = "Option::is_none"
    )]
    generation_date_and_time: Option<&'a str>,
    #[serde(rename = "@variableNamingConvention")]
    variable_naming_convention: &'static str,
    #[serde(rename = "@numberOfEventIndicators")]
    number_of_event_indicators: u32,
    #[serde(rename = "CoSimulation")]
    co_simulation: CoSimulation<'a>,
    #[serde(rename = "UnitDefinitions", skip_serializing_if = "Option::is_none")]
    unit_definitions: Option<UnitDefinitions<'a>>,
    #[serde(rename = "TypeDefinitions", skip_serializing_if = "Option::is_none")]
    type_definitions: Option<TypeDefinitions<'a>>,
    #[serde(rename = "LogCategories", skip_serializing_if = "Option::is_none")]
    log_categories: Option<LogCategories<'a>>,
    #[serde(rename = "DefaultExperiment", skip_serializing_if = "Option::is_none")]
    default_experiment: Option<DefaultExperiment>,
    #[serde(rename = "ModelVariables")]
    model_variables: ModelVariables<'a>,
    #[serde(rename = "ModelStructure")]
    model_structure: ModelStructure,
}

impl<'a> From<&'a ModelDescription> for Root<'a> {
    fn from(md: &'a ModelDescription) -> Self {
        let cs = &md.co_simulation;
        let ms = &md.model_structure;
        let exp = md.default_experiment.as_ref();
        Root {
            fmi_version: "2.0",
            model_name: &md.model_name,
            guid: &md.guid,
            description: md.description.as_deref(),
            author: md.author.as_deref(),
            version: md.version.as_deref(),
            copyright: md.copyright.as_deref(),
            license: md.license.as_deref(),
            generation_tool: md.generation_tool.as_deref(),
            generation_date_and_time: md.generation_date_and_time.as_deref(),
            variable_naming_convention: "structured",
            number_of_event_indicators: 0,
            co_simulation: CoSimulation {
                model_identifier: &cs.model_identifier,
                can_handle_variable_communication_step_size: cs
                    .can_handle_variable_communication_step_size,
                can_interpolate_inputs: cs.can_interpolate_inputs,
                max_output_derivative_order: cs.max_output_derivative_order,
                can_be_instantiated_only_once_per_process: cs
                    .can_be_instantiated_only_once_per_process,
                can_not_use_memory_management_functions: cs.can_not_use_memory_management_functions,
                can_get_and_set_fmu_state: cs.can_get_and_set_fmu_state,
                can_serialize_fmu_state: cs.can_serialize_fmu_state,
                provides_directional_derivative: cs.provides_directional_derivative,
            },
            unit_definitions: non_empty(
                md.unit_definitions
                    .iter()
                    .map(|u| Unit {
                        name: &u.name,
                        base_unit: (&u.base_unit).into(),
                    })
                    .collect(),
                |units| UnitDefinitions { units },
            ),
            type_definitions: non_empty(
                md.type_definitions
                    .iter()
                    .map(|t| SimpleType {
                        name: &t.name,
                        description: t.description.as_deref(),
                        kind: match &t.kind {
                            SimpleTypeKind::Enumeration { items } => TypeKind::Enumeration {
                                items: items
                                    .iter()
                                    .map(|i| Item {
                                        name: &i.name,
                                        value: i.value,
                                        description: i.description.as_deref(),
                                    })
                                    .collect(),
                            },
                        },
                    })
                    .collect(),
                |types| TypeDefinitions { types },
            ),
            log_categories: non_empty(
                md.log_categories
                    .iter()
                    .map(|c| Category {
                        name: &c.name,
                        description: c.description.as_deref(),
                    })
                    .collect(),
                |categories| LogCategories { categories },
            ),
            default_experiment: exp.map(|e| DefaultExperiment {
                start_time: real(e.start_time),
                stop_time: real(e.stop_time),
                tolerance: real(e.tolerance),
                step_size: real(e.step_size),
            }),
            model_variables: ModelVariables::new(&md.model_variables),
            model_structure: ModelStructure {
                outputs: unknowns(&ms.outputs),
                derivatives: unknowns(&ms.derivatives),
                initial_unknowns: unknowns(&ms.initial_unknowns),
            },
        }
    }
}

#[derive(Serialize)]
struct CoSimulation<'a> {
    #[serde(rename = "@modelIdentifier")]
    model_identifier: &'a str,
    #[serde(rename = "@canHandleVariableCommunicationStepSize")]
    can_handle_variable_communication_step_size: bool,
    #[serde(rename = "@canInterpolateInputs")]
    can_interpolate_inputs: bool,
    #[serde(rename = "@maxOutputDerivativeOrder")]
    max_output_derivative_order: u32,
    #[serde(rename = "@canBeInstantiatedOnlyOncePerProcess")]
    can_be_instantiated_only_once_per_process: bool,
    #[serde(rename = "@canNotUseMemoryManagementFunctions")]
    can_not_use_memory_management_functions: bool,
    #[serde(rename = "@canGetAndSetFMUstate")]
    can_get_and_set_fmu_state: bool,
    #[serde(rename = "@canSerializeFMUstate")]
    can_serialize_fmu_state: bool,
    #[serde(rename = "@providesDirectionalDerivative")]
    provides_directional_derivative: bool,
}

#[derive(Serialize)]
struct UnitDefinitions<'a> {
    #[serde(rename = "Unit")]
    units: Vec<Unit<'a>>,
}

#[derive(Serialize)]
struct Unit<'a> {
    #[serde(rename = "@name")]
    name: &'a str,
    #[serde(rename = "BaseUnit")]
    base_unit: WireBaseUnit,
}

#[derive(Serialize)]
struct WireBaseUnit {
    #[serde(rename = "@kg", skip_serializing_if = "Option::is_none")]
    kg: Option<i32>,
    #[serde(rename = "@m", skip_serializing_if = "Option::is_none")]
    m: Option<i32>,
    #[serde(rename = "@s", skip_serializing_if = "Option::is_none")]
    s: Option<i32>,
    #[serde(rename = "@A", skip_serializing_if = "Option::is_none")]
    a: Option<i32>,
    #[serde(rename = "@K", skip_serializing_if = "Option::is_none")]
    k: Option<i32>,
    #[serde(rename = "@mol", skip_serializing_if = "Option::is_none")]
    mol: Option<i32>,
    #[serde(rename = "@cd", skip_serializing_if = "Option::is_none")]
    cd: Option<i32>,
    #[serde(rename = "@rad", skip_serializing_if = "Option::is_none")]
    rad: Option<i32>,
    #[serde(rename = "@factor", skip_serializing_if = "Option::is_none")]
    factor: Option<Real>,
    #[serde(rename = "@offset", skip_serializing_if = "Option::is_none")]
    offset: Option<Real>,
}

impl From<&BaseUnit> for WireBaseUnit {
    fn from(b: &BaseUnit) -> Self {
        WireBaseUnit {
            kg: nonzero(b.kg),
            m: nonzero(b.m),
            s: nonzero(b.s),
            a: nonzero(b.a),
            k: nonzero(b.k),
            mol: nonzero(b.mol),
            cd: nonzero(b.cd),
            rad: nonzero(b.rad),
            // NaN is kept so that serialization reports it.
            factor: (b.factor != 1.0).then_some(Real(b.factor)),
            offset: (b.offset != 0.0).then_some(Real(b.offset)),
        }
    }
}

#[derive(Serialize)]
struct TypeDefinitions<'a> {
    #[serde(rename = "SimpleType")]
    types: Vec<SimpleType<'a>>,
}

#[derive(Serialize)]
struct SimpleType<'a> {
    #[serde(rename = "@name")]
    name: &'a str,
    #[serde(rename = "@description", skip_serializing_if = "Option::is_none")]
    description: Option<&'a str>,
    #[serde(rename = "$value")]
    kind: TypeKind<'a>,
}

#[derive(Serialize)]
enum TypeKind<'a> {
    Enumeration {
        #[serde(rename = "Item")]
        items: Vec<Item<'a>>,
    },
}

#[derive(Serialize)]
struct Item<'a> {
    #[serde(rename = "@name")]
    name: &'a str,
    #[serde(rename = "@value")]
    value: i32,
    #[serde(rename = "@description", skip_serializing_if = "Option::is_none")]
    description: Option<&'a str>,
}

#[derive(Serialize)]
struct LogCategories<'a> {
    #[serde(rename = "Category")]
    categories: Vec<Category<'a>>,
}

#[derive(Serialize)]
struct Category<'a> {
    #[serde(rename = "@name")]
    name: &'a str,
    #[serde(rename = "@description", skip_serializing_if = "Option::is_none")]
    description: Option<&'a str>,
}

#[derive(Serialize)]
struct DefaultExperiment {
    #[serde(rename = "@startTime", skip_serializing_if = "Option::is_none")]
    start_time: Option<Real>,
    #[serde(rename = "@stopTime", skip_serializing_if = "Option::is_none")]
    stop_time: Option<Real>,
    #[serde(rename = "@tolerance", skip_serializing_if = "Option::is_none")]
    tolerance: Option<Real>,
    #[serde(rename = "@stepSize", skip_serializing_if = "Option::is_none")]
    step_size: Option<Real>,
}

#[derive(Serialize)]
struct ModelStructure {
    #[serde(rename = "Outputs", skip_serializing_if = "Option::is_none")]
    outputs: Option<Unknowns>,
    #[serde(rename = "Derivatives", skip_serializing_if = "Option::is_none")]
    derivatives: Option<Unknowns>,
    #[serde(rename = "InitialUnknowns", skip_serializing_if = "Option::is_none")]
    initial_unknowns: Option<Unknowns>,
}

#[derive(Serialize)]
struct Unknowns {
    #[serde(rename = "Unknown")]
    unknowns: Vec<WireUnknown>,
}

#[derive(Serialize)]
struct WireUnknown {
    #[serde(rename = "@index")]
    index: u32,
    #[serde(rename = "@dependencies", skip_serializing_if = "Option::is_none")]
    dependencies: Option<String>,
    #[serde(rename = "@dependenciesKind", skip_serializing_if = "Option::is_none")]
    dependencies_kind: Option<String>,
}

fn unknowns(list: &[Unknown]) -> Option<Unknowns> {
    let unknowns = list
        .iter()
        .map(|u| WireUnknown {
            index: u.index,
            dependencies: u
                .dependencies
                .as_ref()
                .map(|d| d.iter().map(u32::to_string).collect::<Vec<_>>().join(" ")),
            dependencies_kind: u
                .dependencies_kind
                .as_ref()
                .map(|d| d.iter().map(|k| k.as_str()).collect::<Vec<_>>().join(" ")),
        })
        .collect();
    non_empty(unknowns, |unknowns| Unknowns { unknowns })
}
