//! Effects (issue 6): a scene without an effect has none of its FMU variables, units or
//! documentation lines; with it they appear with units and descriptions. Checked on the
//! generated modelDescription.xml, read back with quick-xml into this file's own types.
//! Also: the support reactions obey Newton's law for the whole structure.

use nalgebra::Vector3;
use serde::Deserialize;
use tensegrity_fmu::fmi::documentation::index_html;
use tensegrity_fmu::fmi::package::golden_model_description;
use tensegrity_fmu::fmi::variables::VariableTable;
use tensegrity_fmu::scene::{
    builtin, BarSpec, CableControl, CableSpec, GroundSpec, LoadSpec, PointMassSpec, Scene,
};
use tensegrity_fmu::{Model, Simulation};

#[derive(Deserialize)]
struct Md {
    #[serde(rename = "UnitDefinitions")]
    units: Option<Units>,
    #[serde(rename = "ModelVariables")]
    variables: Vars,
}

#[derive(Deserialize)]
struct Units {
    #[serde(rename = "Unit", default)]
    unit: Vec<Named>,
}

#[derive(Deserialize)]
struct Named {
    #[serde(rename = "@name")]
    name: String,
}

#[derive(Deserialize)]
struct Vars {
    #[serde(rename = "ScalarVariable", default)]
    var: Vec<Var>,
}

#[derive(Deserialize)]
struct Var {
    #[serde(rename = "@name")]
    name: String,
    #[serde(rename = "@description")]
    description: Option<String>,
    #[serde(rename = "@causality")]
    causality: String,
    #[serde(rename = "Real")]
    real: Option<Real>,
}

#[derive(Deserialize)]
struct Real {
    #[serde(rename = "@unit")]
    unit: Option<String>,
}

struct Described {
    md: Md,
    doc: String,
}

fn describe(scene: &Scene) -> Described {
    let xml = golden_model_description(scene).expect("modelDescription.xml");
    let md: Md = quick_xml::de::from_str(&xml).expect("parse modelDescription.xml");
    let sim = Simulation::new(Model::new(scene).expect("valid scene"));
    let doc = index_html(
        &sim,
        &VariableTable::new(&sim),
        &format!("{}.fmu", scene.name),
    );
    Described { md, doc }
}

impl Described {
    fn var(&self, name: &str) -> Option<&Var> {
        self.md.variables.var.iter().find(|v| v.name == name)
    }

    fn has_unit(&self, unit: &str) -> bool {
        self.md
            .units
            .as_ref()
            .is_some_and(|u| u.unit.iter().any(|n| n.name == unit))
    }

    fn any_var(&self, pattern: &str) -> bool {
        self.md
            .variables
            .var
            .iter()
            .any(|v| v.name.contains(pattern))
    }
}

/// Free-floating 6-bar icosahedron with elastic cables (rest lengths written out): no
/// optional effect at all.
fn base() -> Scene {
    let shipped = builtin("icosahedron").unwrap();
    let mut scene = Model::new(&shipped).unwrap().explicit_scene();
    scene.fixed.clear();
    scene.force_inputs.clear();
    scene.name = "base".into();
    scene.description = None;
    scene
}

/// One effect: how a scene declares it, the variables `(name, causality, unit)` it
/// brings, name fragments no other scene may show, units only it uses, its
/// documentation phrase.
struct Effect {
    name: &'static str,
    declare: fn(&mut Scene),
    variables: &'static [(&'static str, &'static str, Option<&'static str>)],
    fragments: &'static [&'static str],
    units: &'static [&'static str],
    doc: &'static str,
}

const EFFECTS: &[Effect] = &[
    Effect {
        name: "gravity",
        declare: |s| s.gravity = Some([0.0, 0.0, -9.81]),
        variables: &[
            ("gravity.x", "parameter", Some("m/s2")),
            ("gravity.z", "parameter", Some("m/s2")),
        ],
        fragments: &["gravity."],
        units: &["m/s2"],
        doc: "gravity [0, 0, -9.81]",
    },
    Effect {
        name: "cable damping",
        declare: |s| s.cables[2].damping = Some(0.5),
        variables: &[("cable[3].damping", "parameter", Some("N.s/m"))],
        fragments: &[".damping"],
        units: &["N.s/m"],
        doc: "1 cable with damping",
    },
    Effect {
        name: "force-density control",
        declare: |s| {
            s.cables[0] = CableSpec {
                nodes: s.cables[0].nodes,
                control: Some(CableControl::ForceDensity),
                force_density: Some(20.0),
                ..CableSpec::default()
            }
        },
        variables: &[("cable[1].force_density", "input", Some("N/m"))],
        fragments: &[".force_density"],
        units: &[],
        doc: "1 force-density controlled cable (",
    },
    Effect {
        name: "rest-length control",
        declare: |s| {
            s.cables[0].control = Some(CableControl::RestLength);
            s.cables[0].rest_length = Some(0.5);
        },
        variables: &[("cable[1].rest_length", "input", Some("m"))],
        fragments: &[],
        units: &[],
        doc: "1 rest-length controlled cable (",
    },
    Effect {
        name: "force inputs",
        declare: |s| s.force_inputs = vec![4],
        variables: &[
            ("node[4].fx", "input", Some("N")),
            ("node[4].fz", "input", Some("N")),
        ],
        fragments: &[".fx", ".fy", ".fz"],
        units: &[],
        doc: "force inputs on node 4",
    },
    Effect {
        name: "scripted loads",
        declare: |s| {
            s.loads = vec![LoadSpec::Sinusoidal {
                node: 2,
                amplitude: [1.0, 0.0, 0.0],
                frequency: 2.0,
                phase: 0.5,
            }]
        },
        variables: &[
            ("load[1].fx", "parameter", Some("N")),
            ("load[1].frequency", "parameter", Some("Hz")),
            ("load[1].phase", "parameter", Some("rad")),
        ],
        fragments: &["load["],
        units: &["Hz", "rad"],
        doc: "1 scripted load (",
    },
    Effect {
        name: "pins",
        declare: |s| s.fixed = vec![1, 5, 9],
        variables: &[
            ("node[1].reaction_x", "output", Some("N")),
            ("node[9].reaction_z", "output", Some("N")),
        ],
        fragments: &["reaction"],
        units: &[],
        doc: "pinned nodes: 1, 5, 9",
    },
    Effect {
        name: "ground contact",
        declare: |s| {
            s.ground = Some(GroundSpec {
                height: -1.0,
                normal: [0.0, 0.0, 1.0],
                stiffness: 1e4,
                damping: 50.0,
                friction: 0.5,
                slip_velocity: 0.01,
            })
        },
        variables: &[
            ("ground.height", "parameter", Some("m")),
            ("ground.stiffness", "parameter", Some("N/m")),
            ("ground.damping", "parameter", Some("N.s/m")),
            ("ground.friction", "parameter", None),
            ("ground.slip_velocity", "parameter", Some("m/s")),
            ("node[1].contact_force", "output", Some("N")),
            ("ground.force_z", "output", Some("N")),
        ],
        fragments: &["ground.", "contact"],
        units: &[],
        doc: "ground plane",
    },
    Effect {
        name: "point masses",
        declare: |s| {
            s.point_masses = vec![PointMassSpec {
                node: 3,
                mass: 0.25,
            }]
        },
        variables: &[("point_mass[1].mass", "parameter", Some("kg"))],
        fragments: &["point_mass"],
        units: &[],
        doc: "1 point mass (",
    },
];

#[test]
fn the_base_scene_shows_no_optional_effect() {
    let base = describe(&base());
    for effect in EFFECTS {
        for (name, causality, _) in effect.variables {
            let present = base.var(name).is_some_and(|v| v.causality == *causality);
            assert!(!present, "{}: {name} without the effect", effect.name);
        }
        for fragment in effect.fragments {
            assert!(
                !base.any_var(fragment),
                "{}: a variable containing {fragment:?} without the effect",
                effect.name
            );
        }
        for unit in effect.units {
            assert!(
                !base.has_unit(unit),
                "{}: unit {unit} declared",
                effect.name
            );
        }
        assert!(
            !base.doc.contains(effect.doc),
            "{}: documentation mentions {:?}",
            effect.name,
            effect.doc
        );
    }
    // The base shows what it has: elastic cables' parameters and no reeled input.
    let rest = base
        .var("cable[1].rest_length")
        .expect("elastic rest length");
    assert_eq!(rest.causality, "parameter");
}

#[test]
fn each_effect_brings_its_variables_with_units_and_documentation() {
    for effect in EFFECTS {
        let mut scene = base();
        (effect.declare)(&mut scene);
        let d = describe(&scene);
        for (name, causality, unit) in effect.variables {
            let v = d
                .var(name)
                .unwrap_or_else(|| panic!("{}: {name} missing", effect.name));
            assert_eq!(v.causality, *causality, "{}: {name}", effect.name);
            let real = v.real.as_ref().expect("a Real variable");
            assert_eq!(
                real.unit.as_deref(),
                *unit,
                "{}: unit of {name}",
                effect.name
            );
            if let Some(u) = unit {
                assert!(d.has_unit(u), "{}: unit {u} not declared", effect.name);
            }
            let text = v.description.as_deref().unwrap_or("");
            assert!(text.len() > 10, "{}: {name} undocumented", effect.name);
            assert!(
                d.doc.contains(&format!("<code>{name}</code>")),
                "{name} not in the HTML"
            );
        }
        assert!(
            d.doc.contains(effect.doc),
            "{}: no documentation line",
            effect.name
        );
    }
}

/// Σ support reactions + Σ applied external forces = Σ m_e a_e (Newton for the whole
/// structure; internal cable, bar and joint forces cancel).
fn newton_residual(scene: &Scene, node_force: Vector3<f64>) -> (f64, f64) {
    let model = Model::new(scene).unwrap();
    let mut sim = Simulation::new(model);
    for f in sim.inputs.node_force.iter_mut() {
        *f = node_force;
    }
    sim.refresh();
    let model = sim.model();
    let ws = sim.workspace();
    let reactions: Vector3<f64> = (0..model.supports.len())
        .map(|k| sim.support_reaction(k))
        .sum();
    let g = model.gravity.unwrap_or_else(Vector3::zeros);
    let mut external = reactions + node_force * model.force_inputs.len() as f64;
    let mut inertial = Vector3::zeros();
    for (i, bar) in model.bars.iter().enumerate() {
        external += g * bar.mass;
        let (a, b) = (ws.end_acc[2 * i], ws.end_acc[2 * i + 1]);
        inertial += (a + b) * (bar.mass / 2.0);
    }
    let scale = reactions.norm().max(inertial.norm());
    ((external - inertial).norm(), scale)
}

#[test]
fn support_reactions_balance_the_structure() {
    // Class-2 tower pinned at three nodes, gravity and loads: moving pinned joints.
    let mut tower = builtin("prism2-elastic").unwrap();
    tower.gravity = Some([0.3, 0.0, -9.81]);
    let (r, scale) = newton_residual(&tower, Vector3::new(2.0, -1.0, 4.0));
    println!("tower: |Σ R + Σ F − Σ m a| = {r:.2e} N of {scale:.2e} N");
    assert!(scale > 10.0, "the reactions are substantial");
    assert!(r < 1e-10 * scale, "residual {r:e}");

    // A bar pinned at both ends (static), and one held by a cable to a bar-less anchor.
    let anchored = Scene {
        name: "anchored".into(),
        nodes: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
        ],
        fixed: vec![1, 3, 4, 5],
        bars: vec![
            BarSpec {
                nodes: [1, 2],
                mass: 1.0,
                radius: 0.0,
            },
            BarSpec {
                nodes: [4, 5],
                mass: 2.0,
                radius: 0.0,
            },
        ],
        cables: vec![
            CableSpec {
                nodes: [2, 3],
                stiffness: Some(300.0),
                rest_length: Some(1.2),
                ..CableSpec::default()
            },
            CableSpec {
                nodes: [2, 5],
                stiffness: Some(100.0),
                rest_length: Some(0.8),
                ..CableSpec::default()
            },
        ],
        gravity: Some([0.0, 0.0, -9.81]),
        force_inputs: vec![2],
        ..base()
    };
    let (r, scale) = newton_residual(&anchored, Vector3::new(0.0, 3.0, 0.0));
    println!("anchored: |Σ R + Σ F − Σ m a| = {r:.2e} N of {scale:.2e} N");
    assert!(scale > 10.0);
    assert!(r < 1e-10 * scale, "residual {r:e}");
}
