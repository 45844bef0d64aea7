//! `<ModelVariables>` and its `<ScalarVariable>`s.

use serde::Serialize;

use super::{real, Real};
use crate::{Causality, Initial, ScalarVariable, Variability, VariableKind};

#[derive(Serialize)]
pub(super) struct ModelVariables<'a> {
    #[serde(rename = "ScalarVariable")]
    variables: Vec<Variable<'a>>,
}

#[derive(Serialize)]
struct Variable<'a> {
    #[serde(rename = "@name")]
    name: &'a str,
    #[serde(rename = "@valueReference")]
    value_reference: u32,
    #[serde(rename = "@description", skip_serializing_if = "Option::is_none")]
    description: Option<&'a str>,
    #[serde(rename = "@causality")]
    causality: &'static str,
    #[serde(rename = "@variability")]
    variability: &'static str,
    #[serde(rename = "@initial", skip_serializing_if = "Option::is_none")]
    initial: Option<&'static str>,
    #[serde(rename = "$value")]
    kind: Kind<'a>,
}

impl<'a> ModelVariables<'a> {
    pub(super) fn new(vars: &'a [ScalarVariable]) -> Self {
        ModelVariables {
            variables: vars.iter().map(Into::into).collect(),
        }
    }
}

impl<'a> From<&'a ScalarVariable> for Variable<'a> {
    fn from(v: &'a ScalarVariable) -> Self {
        Variable {
            name: &v.name,
            value_reference: v.value_reference,
            description: v.description.as_deref(),
            causality: match v.causality {
                Causality::Parameter => "parameter",
                Causality::CalculatedParameter => "calculatedParameter",
                Causality::Input => "input",
                Causality::Output => "output",
                Causality::Local => "local",
                Causality::Independent => "independent",
            },
            variability: match v.variability {
                Variability::Constant => "constant",
                Variability::Fixed => "fixed",
                Variability::Tunable => "tunable",
                Variability::Discrete => "discrete",
                Variability::Continuous => "continuous",
            },
            initial: v.initial.map(|i| match i {
                Initial::Exact => "exact",
                Initial::Approx => "approx",
                Initial::Calculated => "calculated",
            }),
            kind: (&v.kind).into(),
        }
    }
}

/// Each variant is written as a child element named after it.
#[derive(Serialize)]
enum Kind<'a> {
    Real {
        #[serde(rename = "@declaredType", skip_serializing_if = "Option::is_none")]
        declared_type: Option<&'a str>,
        #[serde(rename = "@unit", skip_serializing_if = "Option::is_none")]
        unit: Option<&'a str>,
        #[serde(rename = "@start", skip_serializing_if = "Option::is_none")]
        start: Option<Real>,
        #[serde(rename = "@min", skip_serializing_if = "Option::is_none")]
        min: Option<Real>,
        #[serde(rename = "@max", skip_serializing_if = "Option::is_none")]
        max: Option<Real>,
    },
    Integer {
        #[serde(rename = "@declaredType", skip_serializing_if = "Option::is_none")]
        declared_type: Option<&'a str>,
        #[serde(rename = "@start", skip_serializing_if = "Option::is_none")]
        start: Option<i32>,
        #[serde(rename = "@min", skip_serializing_if = "Option::is_none")]
        min: Option<i32>,
        #[serde(rename = "@max", skip_serializing_if = "Option::is_none")]
        max: Option<i32>,
    },
    Boolean {
        #[serde(rename = "@start", skip_serializing_if = "Option::is_none")]
        start: Option<bool>,
    },
    Enumeration {
        #[serde(rename = "@declaredType")]
        declared_type: &'a str,
        #[serde(rename = "@start", skip_serializing_if = "Option::is_none")]
        start: Option<i32>,
    },
    String {
        #[serde(rename = "@start", skip_serializing_if = "Option::is_none")]
        start: Option<&'a str>,
    },
}

impl<'a> From<&'a VariableKind> for Kind<'a> {
    fn from(k: &'a VariableKind) -> Self {
        match k {
            VariableKind::Real {
                declared_type,
                unit,
                start,
                min,
                max,
            } => Kind::Real {
                declared_type: declared_type.as_deref(),
                unit: unit.as_deref(),
                start: real(*start),
                min: real(*min),
                max: real(*max),
            },
            VariableKind::Integer {
                declared_type,
                start,
                min,
                max,
            } => Kind::Integer {
                declared_type: declared_type.as_deref(),
                start: *start,
                min: *min,
                max: *max,
            },
            VariableKind::Boolean { start } => Kind::Boolean { start: *start },
            VariableKind::Enumeration {
                declared_type,
                start,
            } => Kind::Enumeration {
                declared_type,
                start: *start,
            },
            VariableKind::String { start } => Kind::String {
                start: start.as_deref(),
            },
        }
    }
}
