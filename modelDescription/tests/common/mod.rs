//! Descriptions shared by the XML tests.

use fmi2_model_description::*;

/// Text that needs XML escaping, with non-ASCII.
pub const TRICKY: &str = "a < b & \"c\" 'd' > e: ‖b‖ − l";

/// Reals that must round-trip bit-exactly.
pub const REALS: [f64; 12] = [
    1e-3,
    0.5773502691896258,
    -1.0605752387249069e-16,
    1e300,
    5e-324,
    f64::MAX,
    f64::MIN_POSITIVE,
    -0.0,
    1.0,
    100.0,
    0.1 + 0.2,
    123456789012345680.0,
];

/// A variable; `initial` is `exact` unless the combination forbids it.
pub fn var(
    name: &str,
    vr: u32,
    c: Causality,
    v: Variability,
    kind: VariableKind,
) -> ScalarVariable {
    let initial = match (c, v) {
        (Causality::Input | Causality::Independent, _) => None,
        (_, Variability::Constant) => None,
        _ => Some(Initial::Exact),
    };
    ScalarVariable {
        name: name.into(),
        value_reference: vr,
        description: None,
        causality: c,
        variability: v,
        initial,
        kind,
    }
}

/// A fixed `<Real>` parameter.
pub fn real(name: &str, vr: u32, start: Option<f64>) -> ScalarVariable {
    let kind = VariableKind::Real {
        declared_type: None,
        unit: None,
        start,
        min: None,
        max: None,
    };
    var(name, vr, Causality::Parameter, Variability::Fixed, kind)
}

/// Only the required parts; every list empty.
pub fn minimal() -> ModelDescription {
    ModelDescription {
        model_name: "Empty".into(),
        guid: "{0}".into(),
        description: None,
        author: None,
        version: None,
        copyright: None,
        license: None,
        generation_tool: None,
        generation_date_and_time: None,
        co_simulation: CoSimulation {
            model_identifier: "empty".into(),
            ..Default::default()
        },
        unit_definitions: vec![],
        type_definitions: vec![],
        log_categories: vec![],
        default_experiment: None,
        model_variables: vec![],
        model_structure: ModelStructure::default(),
    }
}

/// A full description that fmpy 0.3.32 validates without problems.
pub fn sample() -> ModelDescription {
    use Causality::*;
    use Variability::*;
    use VariableKind as K;
    let real_kind = |unit: &str, start| K::Real {
        declared_type: None,
        unit: Some(unit.into()),
        start,
        min: None,
        max: None,
    };
    let int_kind = |start, min, max| K::Integer {
        declared_type: None,
        start,
        min,
        max,
    };
    let enum_kind = |start| K::Enumeration {
        declared_type: "Solver".into(),
        start,
    };
    let mut x = var("node[1].x", 0, Output, Continuous, real_kind("m", None));
    x.description = Some(TRICKY.into());
    x.kind = K::Real {
        declared_type: None,
        unit: Some("m".into()),
        start: Some(0.5773502691896258),
        min: Some(-1.0605752387249069e-16),
        max: Some(1.0),
    };
    let mut steps = var("steps", 2, Output, Discrete, int_kind(None, Some(0), None));
    steps.initial = Some(Initial::Calculated);
    let mut mode = var("mode", 7, CalculatedParameter, Fixed, enum_kind(None));
    mode.initial = Some(Initial::Calculated);
    let mut vars = vec![
        x,
        var("force", 1, Input, Continuous, real_kind("N", Some(0.0))),
        steps,
        var(
            "iterations",
            3,
            Parameter,
            Fixed,
            int_kind(Some(-7), Some(-10), Some(10)),
        ),
        var(
            "enabled",
            4,
            Parameter,
            Tunable,
            K::Boolean { start: Some(true) },
        ),
        var(
            "slack",
            5,
            Local,
            Discrete,
            K::Boolean { start: Some(false) },
        ),
        var("solver", 6, Parameter, Fixed, enum_kind(Some(2))),
        mode,
        var(
            "scene",
            8,
            Parameter,
            Fixed,
            K::String {
                start: Some(TRICKY.into()),
            },
        ),
        var(
            "label",
            9,
            Local,
            Constant,
            K::String {
                start: Some("constant".into()),
            },
        ),
        var("time", 10, Independent, Continuous, real_kind("s", None)),
    ];
    for (i, &x) in REALS.iter().enumerate() {
        vars.push(real(&format!("rt{i}"), 100 + i as u32, Some(x)));
    }
    ModelDescription {
        model_name: "Tensegrity".into(),
        guid: "{8c4e810f-3df3-4a00-8276-176fa3c9f000}".into(),
        description: Some(TRICKY.into()),
        author: Some("A. Author".into()),
        version: Some("1.2.3".into()),
        copyright: Some("© 2026 A. Author".into()),
        license: Some("MIT OR Apache-2.0".into()),
        generation_tool: Some("fmi2-model-description".into()),
        generation_date_and_time: Some("2024-01-01T00:00:00Z".into()),
        co_simulation: CoSimulation {
            model_identifier: "tensegrity".into(),
            can_handle_variable_communication_step_size: true,
            can_get_and_set_fmu_state: true,
            can_serialize_fmu_state: true,
            can_not_use_memory_management_functions: true,
            can_be_instantiated_only_once_per_process: false,
            provides_directional_derivative: false,
            can_interpolate_inputs: false,
            max_output_derivative_order: 0,
        },
        unit_definitions: vec![
            Unit {
                name: "m".into(),
                base_unit: BaseUnit {
                    m: 1,
                    ..Default::default()
                },
            },
            Unit {
                name: "N".into(),
                base_unit: BaseUnit {
                    kg: 1,
                    m: 1,
                    s: -2,
                    ..Default::default()
                },
            },
            Unit {
                name: "degC".into(),
                base_unit: BaseUnit {
                    k: 1,
                    offset: 273.15,
                    ..Default::default()
                },
            },
            Unit {
                name: "s".into(),
                base_unit: BaseUnit {
                    s: 1,
                    ..Default::default()
                },
            },
            Unit {
                name: "deg".into(),
                base_unit: BaseUnit {
                    rad: 1,
                    factor: std::f64::consts::PI / 180.0,
                    ..Default::default()
                },
            },
        ],
        type_definitions: vec![SimpleType {
            name: "Solver".into(),
            description: Some("integration & projection".into()),
            kind: SimpleTypeKind::Enumeration {
                items: vec![
                    EnumerationItem {
                        name: "euler".into(),
                        value: 1,
                        description: Some("explicit".into()),
                    },
                    EnumerationItem {
                        name: "rk4".into(),
                        value: 2,
                        description: None,
                    },
                ],
            },
        }],
        log_categories: vec![
            LogCategory {
                name: "logStatusError".into(),
                description: Some("errors".into()),
            },
            LogCategory {
                name: "logAll".into(),
                description: None,
            },
        ],
        default_experiment: Some(DefaultExperiment {
            start_time: Some(0.0),
            stop_time: Some(10.0),
            tolerance: None,
            step_size: Some(1e-3),
        }),
        model_variables: vars,
        model_structure: ModelStructure {
            outputs: vec![
                Unknown {
                    index: 1,
                    dependencies: Some(vec![2, 11]),
                    dependencies_kind: Some(vec![
                        DependencyKind::Dependent,
                        DependencyKind::Constant,
                    ]),
                },
                Unknown {
                    index: 3,
                    dependencies: Some(vec![]),
                    dependencies_kind: None,
                },
            ],
            derivatives: vec![],
            initial_unknowns: vec![
                Unknown {
                    index: 3,
                    dependencies: None,
                    dependencies_kind: None,
                },
                Unknown {
                    index: 8,
                    dependencies: None,
                    dependencies_kind: None,
                },
            ],
        },
    }
}
