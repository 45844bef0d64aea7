//! Structured scene inputs for the fuzzer: valid in shape, then edited with extreme
//! numbers, wrong types, missing and unknown keys and degenerate geometry (real scene
//! files with their bytes mutated are in `mutate`).

use proptest::collection::vec;
use proptest::option;
use proptest::prelude::*;
use proptest::sample::select;
use toml::{Table, Value};

/// A scene document as a user could hand it in.
#[derive(Debug, Clone)]
pub struct Input {
    /// JSON (else TOML).
    pub json: bool,
    /// The document.
    pub text: String,
    /// Also take the FMU instance path (instantiate … DoStep).
    pub fmu: bool,
}

/// Numbers chosen to break things: zeros, signs, the ends of the double range, NaN, ∞.
const EXTREMES: [f64; 20] = [
    0.0,
    -0.0,
    -1.0,
    -1e-12,
    1e-300,
    5e-324,
    f64::MIN_POSITIVE,
    1e-15,
    1e15,
    -1e15,
    5e14,
    1e12,
    1e100,
    1e300,
    f64::MAX,
    -f64::MAX,
    f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    1.0000000000000002,
];

/// Integers chosen to break counts and node numbers.
const EXTREME_INTEGERS: [i64; 9] = [0, -1, 1, 2, 13, 1000, 1 << 31, i64::MAX, i64::MIN];

/// An ordinary coordinate: extremes come from the edits.
fn coordinate() -> impl Strategy<Value = f64> + Clone {
    -1.0..1.0f64
}

/// An ordinary positive magnitude, between 0.1 and 10.
fn magnitude() -> impl Strategy<Value = f64> + Clone {
    0.1..10.0f64
}

fn float(x: f64) -> Value {
    Value::Float(x)
}

fn vec3(c: impl Strategy<Value = f64> + Clone) -> impl Strategy<Value = Value> {
    [c.clone(), c.clone(), c].prop_map(|v| Value::Array(v.map(float).into()))
}

/// A node on a free bar end: 2 to the last node on a bar (node 1 may be pinned).
fn free_node(n: usize) -> impl Strategy<Value = Value> {
    (2..=(n - n % 2) as i64).prop_map(Value::Integer)
}

/// Two different node numbers.
fn pair(n: usize) -> impl Strategy<Value = Value> {
    (0..n, 1..n).prop_map(move |(a, d)| {
        let b = (a + d) % n;
        Value::Array(vec![
            Value::Integer(a as i64 + 1),
            Value::Integer(b as i64 + 1),
        ])
    })
}

fn table(entries: Vec<(&str, Option<Value>)>) -> Value {
    Value::Table(
        entries
            .into_iter()
            .filter_map(|(k, v)| v.map(|v| (k.to_string(), v)))
            .collect(),
    )
}

/// A cable: elastic, force-density controlled or reeled, with or without the values a
/// `prestress` table would derive.
fn cable(n: usize) -> impl Strategy<Value = (Value, u8, bool)> {
    (
        pair(n),
        0u8..3,
        magnitude(),
        magnitude(),
        option::weighted(0.3, magnitude()),
        prop::bool::weighted(0.9),
    )
        .prop_map(|(nodes, kind, a, b, damping, derived)| {
            let fd = kind == 1;
            let cable = table(vec![
                ("nodes", Some(nodes)),
                (
                    "control",
                    match kind {
                        1 => Some(Value::String("force_density".into())),
                        2 => Some(Value::String("rest_length".into())),
                        _ => None,
                    },
                ),
                ("stiffness", (!fd).then_some(float(100.0 * a))),
                ("rest_length", (!fd).then_some(float(0.5 * b))),
                ("damping", if fd { None } else { damping.map(float) }),
                ("force_density", fd.then_some(float(a))),
            ]);
            (cable, kind, derived)
        })
}

fn load(n: usize) -> impl Strategy<Value = Value> {
    (free_node(n), 0u8..3, vec3(-10.0..10.0f64), magnitude()).prop_map(|(node, kind, force, x)| {
        let (name, key) = match kind {
            0 => ("constant", "force"),
            1 => ("sinusoidal", "amplitude"),
            _ => ("step", "force"),
        };
        table(vec![
            ("kind", Some(Value::String(name.into()))),
            ("node", Some(node)),
            (key, Some(force)),
            ("frequency", (kind == 1).then_some(float(x))),
            ("time", (kind == 2).then_some(float(0.001 * x))),
        ])
    })
}

fn ground() -> impl Strategy<Value = Value> {
    (
        coordinate(),
        vec3(coordinate()),
        magnitude(),
        magnitude(),
        magnitude(),
    )
        .prop_map(|(height, normal, k, c, mu)| {
            table(vec![
                ("height", Some(float(height - 1.0))),
                ("normal", Some(normal)),
                ("stiffness", Some(float(1e4 * k))),
                ("damping", Some(float(10.0 * c))),
                ("friction", Some(float(0.1 * mu))),
            ])
        })
}

/// The contact law of a terrain shape or of collisions.
fn law() -> impl Strategy<Value = [(&'static str, Option<Value>); 3]> {
    (magnitude(), magnitude(), magnitude()).prop_map(|(k, c, mu)| {
        [
            ("stiffness", Some(float(1e4 * k))),
            ("damping", Some(float(10.0 * c))),
            ("friction", Some(float(0.1 * mu))),
        ]
    })
}

/// A plane, a box or a small heightfield near the structure.
fn terrain_shape() -> impl Strategy<Value = Value> {
    (
        0u8..3,
        vec3(coordinate()),
        vec3(magnitude()),
        law(),
        vec(coordinate(), 6),
    )
        .prop_map(|(kind, at, size, law, heights)| {
            let mut entries = match kind {
                0 => vec![
                    ("kind", Some(Value::String("plane".into()))),
                    ("point", Some(at)),
                ],
                1 => vec![
                    ("kind", Some(Value::String("box".into()))),
                    ("center", Some(at)),
                    ("size", Some(size)),
                    ("yaw", Some(float(30.0))),
                ],
                _ => {
                    let rows = heights
                        .chunks(3)
                        .map(|r| Value::Array(r.iter().map(|&h| float(h - 1.0)).collect()))
                        .collect();
                    vec![
                        ("kind", Some(Value::String("heightfield".into()))),
                        ("heights", Some(Value::Array(rows))),
                        ("origin", Some(Value::Array(vec![float(-1.0), float(-1.0)]))),
                        ("spacing", Some(Value::Array(vec![float(1.0), float(2.0)]))),
                    ]
                }
            };
            entries.extend(law);
            table(entries)
        })
}

/// Terrain shapes, collisions and a bar radius, each optional.
fn contact() -> impl Strategy<Value = Contact> {
    (
        option::weighted(0.2, ground()),
        option::weighted(0.2, vec(terrain_shape(), 1..3)),
        option::weighted(0.15, law()),
        option::weighted(0.3, magnitude()),
    )
}

type Contact = (
    Option<Value>,
    Option<Vec<Value>>,
    Option<[(&'static str, Option<Value>); 3]>,
    Option<f64>,
);

fn solver() -> impl Strategy<Value = Value> {
    (
        select(vec!["dopri5", "dopri5", "rk4", "rattle", "sdirk3", "euler"]),
        magnitude(),
        any::<[bool; 2]>(),
        1i64..400,
    )
        .prop_map(|(method, h, [correction, locate], max_steps)| {
            table(vec![
                ("method", Some(Value::String(method.into()))),
                ("step_size", Some(float(1e-3 * h))),
                ("correction", Some(Value::Boolean(correction))),
                ("locate_events", Some(Value::Boolean(locate))),
                ("max_steps", Some(Value::Integer(max_steps))),
            ])
        })
}

/// How an edit changes one place of the document.
#[derive(Debug, Clone)]
pub enum Edit {
    /// Replace a leaf by an extreme number (an integer where it held one).
    Extreme(f64, i64),
    /// Replace a value by one of another type.
    WrongType(Value),
    /// Remove a key or an array element.
    Remove,
    /// Add an unknown key beside it.
    Unknown(String),
    /// Copy an array element to the end of its array.
    Duplicate,
    /// Give a node the position of another (coincident nodes, zero-length members).
    Coincide(usize, usize),
}

fn edit() -> impl Strategy<Value = (usize, Edit)> {
    let wrong = prop_oneof![
        Just(Value::String("1.0".into())),
        Just(Value::String(String::new())),
        Just(Value::Boolean(true)),
        Just(Value::Array(vec![])),
        Just(Value::Table(Table::new())),
        Just(Value::Integer(1)),
        Just(Value::Float(1.5)),
        Just(Value::Array(vec![Value::Float(0.0); 4])),
        Just(Value::String("é\u{0}\u{7}/../x".into())),
    ];
    let edit = prop_oneof![
        3 => (select(&EXTREMES[..]), select(&EXTREME_INTEGERS[..])).prop_map(|(x, i)| Edit::Extreme(x, i)),
        2 => wrong.prop_map(Edit::WrongType),
        2 => Just(Edit::Remove),
        1 => select(vec!["colour", "mass", "nodes", "Stiffness", "stifness", ""]).prop_map(|k| Edit::Unknown(k.into())),
        1 => Just(Edit::Duplicate),
        2 => (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Edit::Coincide(a, b)),
    ];
    (any::<usize>(), edit)
}

/// A scene of `n` nodes, valid in shape: bars on pairs of nodes (plus a few joints),
/// pinned leftovers, random cables and optional parts, then up to four edits.
pub fn structured() -> impl Strategy<Value = Input> {
    (2usize..=12).prop_flat_map(|n| {
        let parts = (
            vec(vec3(coordinate()), n),
            vec((pair(n), magnitude()), 0..3),
            vec(magnitude(), n / 2),
            vec(cable(n), 0..=2 * n),
            prop::bool::weighted(0.3),
            proptest::sample::subsequence(
                (2..=(n - n % 2) as i64).collect::<Vec<_>>(),
                0..=(n / 2).min(2),
            ),
            option::weighted(0.5, vec3(-10.0..10.0f64)),
        );
        let more = (
            vec(load(n), 0..3),
            vec((free_node(n), magnitude()), 0..2),
            contact(),
            option::weighted(0.2, magnitude()),
            option::weighted(0.2, vec(vec3(coordinate()), n)),
            solver(),
            (
                prop::bool::weighted(0.3),
                prop::bool::weighted(0.15),
                prop::bool::weighted(0.2),
            ),
            prop_oneof![2 => Just(vec![]), 3 => vec(edit(), 1..4)],
        );
        (parts, more).prop_map(move |(parts, more)| assemble(n, parts, more))
    })
}

type Parts = (
    Vec<Value>,
    Vec<(Value, f64)>,
    Vec<f64>,
    Vec<(Value, u8, bool)>,
    bool,
    Vec<i64>,
    Option<Value>,
);
type More = (
    Vec<Value>,
    Vec<(Value, f64)>,
    Contact,
    Option<f64>,
    Option<Vec<Value>>,
    Value,
    (bool, bool, bool),
    Vec<(usize, Edit)>,
);

fn assemble(n: usize, parts: Parts, more: More) -> Input {
    let (nodes, joints, masses, cables, pin_first, forces, gravity) = parts;
    let (loads, payloads, contact, prestress, velocities, solver, (json, equilibrium, fmu), edits) =
        more;
    let (ground, terrain, collisions, radius) = contact;
    let radius = radius.map(|r| float(0.01 * r));
    let mut bars: Vec<Value> = masses
        .iter()
        .enumerate()
        .map(|(i, &m)| {
            let nodes = [2 * i as i64 + 1, 2 * i as i64 + 2].map(Value::Integer);
            table(vec![
                ("nodes", Some(Value::Array(nodes.into()))),
                ("mass", Some(float(m))),
                ("radius", radius.clone()),
            ])
        })
        .collect();
    bars.extend(joints.into_iter().map(|(nodes, m)| {
        table(vec![
            ("nodes", Some(nodes)),
            ("mass", Some(float(m))),
            ("radius", radius.clone()),
        ])
    }));
    let mut pinned = Vec::new();
    if pin_first {
        pinned.push(Value::Integer(1));
    }
    if n % 2 == 1 {
        pinned.push(Value::Integer(n as i64));
    }
    let forces = forces.into_iter().map(Value::Integer).collect();
    let prestressed = prestress.is_some();
    let cables: Vec<Value> = cables
        .into_iter()
        .map(|(mut c, kind, derived)| {
            if prestressed && derived {
                let t = c.as_table_mut().expect("a table");
                t.remove(if kind == 1 {
                    "force_density"
                } else {
                    "rest_length"
                });
            }
            c
        })
        .collect();
    let list = |v: Vec<Value>| (!v.is_empty()).then_some(Value::Array(v));
    let mut doc = table(vec![
        ("name", Some(Value::String(format!("fuzz{n}")))),
        ("nodes", Some(Value::Array(nodes))),
        ("fixed", list(pinned)),
        ("force_inputs", list(forces)),
        ("gravity", gravity),
        ("velocities", velocities.map(Value::Array)),
        ("ground", ground),
        ("terrain", terrain.map(Value::Array)),
        ("collisions", collisions.map(|law| table(law.into()))),
        (
            "prestress",
            prestress.map(|t| table(vec![("min_tension", Some(float(t)))])),
        ),
        (
            "start",
            equilibrium.then_some(Value::String("equilibrium".into())),
        ),
        ("solver", Some(solver)),
        ("bars", Some(Value::Array(bars))),
        ("cables", list(cables)),
        ("loads", list(loads)),
        (
            "point_masses",
            list(
                payloads
                    .into_iter()
                    .map(|(node, m)| table(vec![("node", Some(node)), ("mass", Some(float(m)))]))
                    .collect(),
            ),
        ),
    ]);
    for (place, e) in &edits {
        apply(&mut doc, *place, e);
    }
    let text = if json {
        serde_json::to_string(&doc).ok()
    } else {
        toml::to_string(&doc).ok()
    };
    match text {
        Some(text) => Input { json, text, fmu },
        // TOML cannot write every tree an edit makes (e.g. a value after a table in an
        // array): JSON can.
        None => Input {
            json: true,
            text: serde_json::to_string(&doc).expect("JSON holds any tree"),
            fmu,
        },
    }
}

/// Paths to every value in the tree, parents before children.
fn paths(v: &Value, here: &mut Vec<Seg>, out: &mut Vec<Vec<Seg>>) {
    out.push(here.clone());
    match v {
        Value::Table(t) => {
            for (k, child) in t {
                here.push(Seg::Key(k.clone()));
                paths(child, here, out);
                here.pop();
            }
        }
        Value::Array(a) => {
            for (i, child) in a.iter().enumerate() {
                here.push(Seg::Index(i));
                paths(child, here, out);
                here.pop();
            }
        }
        _ => {}
    }
}

#[derive(Debug, Clone)]
enum Seg {
    Key(String),
    Index(usize),
}

fn at<'a>(v: &'a mut Value, path: &[Seg]) -> &'a mut Value {
    path.iter().fold(v, |v, s| match (s, v) {
        (Seg::Key(k), Value::Table(t)) => t.get_mut(k).expect("a listed path"),
        (Seg::Index(i), Value::Array(a)) => &mut a[*i],
        _ => unreachable!("a listed path"),
    })
}

fn apply(doc: &mut Value, place: usize, edit: &Edit) {
    if let Edit::Coincide(a, b) = edit {
        if let Some(Value::Array(nodes)) = doc.get_mut("nodes") {
            if !nodes.is_empty() {
                let from = nodes[a % nodes.len()].clone();
                let len = nodes.len();
                nodes[b % len] = from;
            }
        }
        return;
    }
    let mut all = Vec::new();
    paths(doc, &mut Vec::new(), &mut all);
    let path = &all[place % all.len()];
    let Some((last, parent_path)) = path.split_last() else {
        // The root: only an unknown key makes sense there.
        if let (Edit::Unknown(k), Value::Table(t)) = (edit, doc) {
            t.insert(k.clone(), Value::Float(1.0));
        }
        return;
    };
    let parent = at(doc, parent_path);
    match edit {
        Edit::Extreme(x, i) => {
            let v = at(parent, std::slice::from_ref(last));
            *v = match v {
                Value::Integer(_) => Value::Integer(*i),
                _ => Value::Float(*x),
            };
        }
        Edit::WrongType(w) => *at(parent, std::slice::from_ref(last)) = w.clone(),
        Edit::Remove => match (parent, last) {
            (Value::Table(t), Seg::Key(k)) => {
                t.remove(k);
            }
            (Value::Array(a), Seg::Index(i)) => {
                a.remove(*i);
            }
            _ => {}
        },
        Edit::Unknown(k) => {
            if let Value::Table(t) = parent {
                t.insert(k.clone(), Value::Float(1.0));
            }
        }
        Edit::Duplicate => {
            if let (Value::Array(a), Seg::Index(i)) = (parent, last) {
                a.push(a[*i].clone());
            }
        }
        Edit::Coincide(..) => {}
    }
}
