//! Scene files: validation messages, parsing, prestress and the built-in scenes.

use std::collections::BTreeSet;
use std::f64::consts::PI;
use std::path::Path;

use tensegrity_fmu::scene::{self, CableControl};
use tensegrity_fmu::{Model, Scene, SceneError, Simulation};

const BASE: &str = r#"name = "pair"
nodes = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]]
fixed = [1]
force_inputs = [4]

[[bars]]
nodes = [1, 2]
mass = 1.0

[[bars]]
nodes = [3, 4]
mass = 2.0

[[cables]]
nodes = [1, 3]
stiffness = 100.0
rest_length = 0.9

[[cables]]
nodes = [2, 4]
stiffness = 100.0
rest_length = 0.9
damping = 0.5

[[cables]]
nodes = [1, 4]
control = "force_density"
force_density = 2.0

[solver]
step_size = 0.002
"#;

const BASE_JSON: &str = r#"{
  "name": "pair",
  "nodes": [[0, 0, 0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]],
  "fixed": [1],
  "force_inputs": [4],
  "bars": [{"nodes": [1, 2], "mass": 1.0}, {"nodes": [3, 4], "mass": 2}],
  "cables": [
    {"nodes": [1, 3], "stiffness": 100.0, "rest_length": 0.9},
    {"nodes": [2, 4], "stiffness": 100.0, "rest_length": 0.9, "damping": 0.5},
    {"nodes": [1, 4], "control": "force_density", "force_density": 2.0}
  ],
  "solver": {"step_size": 0.002}
}"#;

fn base() -> Scene {
    Scene::from_toml_str(BASE).expect("base scene parses")
}

/// Parses `BASE` with `extra` inserted as top-level keys (before the first table).
fn base_with(extra: &str) -> Scene {
    let text = BASE.replacen("fixed = [1]\n", &format!("fixed = [1]\n{extra}\n"), 1);
    Scene::from_toml_str(&text).expect("modified base parses")
}

/// Asserts that building `scene` fails with `key: ...reason...`.
fn rejects(scene: &Scene, key: &str, reason: &str) {
    let err = Model::new(scene).expect_err("scene must be rejected");
    assert_eq!(err, scene.validate().expect_err("validate agrees"));
    check(&err, key, reason);
}

fn range(v: usize) -> String {
    format!("node {v} is out of range: nodes are numbered 1 to 4")
}

fn check(err: &SceneError, key: &str, reason: &str) {
    let text = err.to_string();
    assert!(
        matches!(err, SceneError::Invalid { key: k, .. } if k == key),
        "expected key {key}, got {err:?}"
    );
    assert!(text.starts_with(&format!("{key}: ")), "{text}");
    assert!(text.contains(reason), "{text:?} lacks {reason:?}");
}

#[test]
fn base_scene_is_valid() {
    let model = Model::new(&base()).expect("base builds");
    assert_eq!(model.bars.len(), 2);
    assert_eq!(model.cables.len(), 3);
    assert_eq!(model.controlled, vec![2]);
    assert_eq!(model.controlled_start, vec![2.0]);
    assert_eq!(model.solver.step_size, 0.002);
}

#[test]
fn unused_unpinned_node() {
    let mut s = base();
    s.nodes.push([2.0, 2.0, 2.0]);
    rejects(&s, "nodes[5]", "node 5 is used by no bar and not pinned");
    s.fixed.push(5); // a pinned anchor node needs no bar
    Model::new(&s).expect("pinned unused node is fine");
}

#[test]
fn zero_length_bar() {
    let mut s = base();
    s.nodes[3] = s.nodes[2];
    rejects(
        &s,
        "bars[2].nodes",
        "zero-length bar: nodes 3 and 4 coincide",
    );
}

#[test]
fn zero_length_cable() {
    let mut s = base();
    s.nodes.push([0.0, 0.0, 0.0]); // node 5 coincides with node 1
    s.bars[0].nodes = [5, 2];
    s.fixed = vec![1, 5];
    s.cables[0].nodes = [3, 4];
    s.cables[1].nodes = [1, 5];
    rejects(
        &s,
        "cables[2].nodes",
        "zero-length cable: nodes 1 and 5 coincide",
    );
}

#[test]
fn bar_node_out_of_range() {
    let mut s = base();
    s.bars[1].nodes = [3, 0];
    rejects(&s, "bars[2].nodes", &range(0));
    s.bars[1].nodes = [5, 4];
    rejects(&s, "bars[2].nodes", &range(5));
}

#[test]
fn cable_node_out_of_range() {
    let mut s = base();
    s.cables[2].nodes = [1, 5];
    rejects(&s, "cables[3].nodes", &range(5));
    s.cables[2].nodes = [0, 1];
    rejects(&s, "cables[3].nodes", &range(0));
}

#[test]
fn fixed_out_of_range() {
    let mut s = base();
    s.fixed = vec![1, 5];
    rejects(&s, "fixed[2]", &range(5));
    s.fixed = vec![0];
    rejects(&s, "fixed[1]", &range(0));
}

#[test]
fn force_inputs_out_of_range() {
    let mut s = base();
    s.force_inputs = vec![4, 9];
    rejects(&s, "force_inputs[2]", &range(9));
    s.force_inputs = vec![0];
    rejects(&s, "force_inputs[1]", &range(0));
}

#[test]
fn non_positive_mass() {
    let mut s = base();
    s.bars[1].mass = 0.0;
    rejects(&s, "bars[2].mass", "mass must be positive, got 0");
    s.bars[1].mass = -1.5;
    rejects(&s, "bars[2].mass", "mass must be positive, got -1.5");
}

#[test]
fn negative_cable_numbers() {
    let mut s = base();
    s.cables[0].stiffness = Some(-5.0);
    rejects(&s, "cables[1].stiffness", "must be ≥ 0, got -5");
    let mut s = base();
    s.cables[1].rest_length = Some(-0.25);
    rejects(&s, "cables[2].rest_length", "must be ≥ 0, got -0.25");
    let mut s = base();
    s.cables[1].damping = Some(-2.0);
    rejects(&s, "cables[2].damping", "must be ≥ 0, got -2");
}

#[test]
fn non_finite_numbers() {
    let s = Scene::from_toml_str(&BASE.replace("[1.0, 0.0, 0.0]", "[1.0, nan, 0.0]")).unwrap();
    assert!(s.nodes[1][1].is_nan());
    rejects(
        &s,
        "nodes[2]",
        "must hold finite numbers, got [1.0, NaN, 0.0]",
    );
    let s = Scene::from_toml_str(&BASE.replace("mass = 2.0", "mass = inf")).unwrap();
    rejects(&s, "bars[2].mass", "must be a finite number, got inf");
    let s = base_with("gravity = [0.0, 0.0, nan]");
    rejects(
        &s,
        "gravity",
        "must hold finite numbers, got [0.0, 0.0, NaN]",
    );
    let s = base_with("gravity = [0.0, 0.0, -9.81]");
    Model::new(&s).expect("finite gravity is fine");
}

#[test]
fn elastic_cable_without_stiffness() {
    let mut s = base();
    s.cables[0].stiffness = None;
    rejects(&s, "cables[1].stiffness", "required for an elastic cable");
}

#[test]
fn controlled_cable_with_stiffness() {
    let mut s = base();
    s.cables[2].stiffness = Some(10.0);
    rejects(
        &s,
        "cables[3].stiffness",
        "not allowed on a force-density controlled cable",
    );
}

#[test]
fn rest_length_with_prestress() {
    let s = Scene::from_toml_str(&format!("{BASE}\n[prestress]\nmin_tension = 1.0\n")).unwrap();
    rejects(
        &s,
        "cables[1].rest_length",
        "conflicts with `prestress`, which derives the rest length",
    );
}

#[test]
fn velocities_of_wrong_length() {
    let s = base_with("velocities = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]");
    rejects(&s, "velocities", "has 3 entries but the scene has 4 nodes");
}

#[test]
fn positions_and_velocities_beyond_the_limits() {
    // The scene's limits, which restored FMU states are held to as well.
    let mut s = base();
    s.nodes[3][2] = 2e9;
    rejects(
        &s,
        "nodes[4]",
        "z = 2000000000 m is outside ±1e9 m, the range of node coordinates",
    );
    // The whole structure moved to the limit.
    for p in &mut s.nodes {
        p[2] = -1e9;
    }
    Model::new(&s).expect("on the limit is within it");
    let mut s = base_with(
        "velocities = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 3e8, 0.0]]",
    );
    rejects(
        &s,
        "velocities[4]",
        "y = 300000000 m/s is outside ±2.99792458e8 m/s, the range of node velocity components",
    );
    s.velocities.as_mut().unwrap()[3][1] = 2.9e8;
    s.validate().expect("slower than light");
}

#[test]
fn non_positive_step_size() {
    let mut s = base();
    s.solver.step_size = 0.0;
    rejects(&s, "solver.step_size", "must be positive, got 0");
    s.solver.step_size = -0.001;
    rejects(&s, "solver.step_size", "must be positive, got -0.001");
}

#[test]
fn unknown_keys_are_named() {
    for (text, key) in [
        (
            BASE.replacen("fixed", "colour = \"red\"\nfixed", 1),
            "colour",
        ),
        (
            BASE.replacen("mass = 1.0", "mass = 1.0\nlenght = 1.0", 1),
            "lenght",
        ),
        (BASE.replacen("step_size", "stepsize", 1), "stepsize"),
    ] {
        let err = Scene::from_toml_str(&text).expect_err("unknown key rejected");
        let msg = err.to_string();
        assert!(msg.starts_with("malformed TOML scene: "), "{msg}");
        assert!(msg.contains(&format!("unknown field `{key}`")), "{msg}");
    }
    let json = BASE_JSON.replacen("\"fixed\"", "\"colour\": 1, \"fixed\"", 1);
    let msg = Scene::from_json_str(&json).unwrap_err().to_string();
    assert!(msg.starts_with("malformed JSON scene: "), "{msg}");
    assert!(msg.contains("unknown field `colour`"), "{msg}");
}

#[test]
fn malformed_text() {
    let text = BASE.replacen("[1.0, 1.0, 0.0]]", "[1.0, 1.0, 0.0]", 1);
    let err = Scene::from_toml_str(&text).unwrap_err();
    assert!(matches!(err, SceneError::Parse { format: "TOML", .. }));
    let msg = err.to_string();
    assert!(msg.starts_with("malformed TOML scene: "), "{msg}");
    assert!(msg.contains("line 3"), "{msg}");
    let msg = Scene::from_toml_str(&BASE.replace("mass = 2.0", "mass = \"heavy\""))
        .unwrap_err()
        .to_string();
    assert!(msg.contains("mass") && msg.contains("line 12"), "{msg}");
    let msg = Scene::from_json_str(&BASE_JSON[..100])
        .unwrap_err()
        .to_string();
    assert!(msg.starts_with("malformed JSON scene: "), "{msg}");
}

#[test]
fn json_and_toml_agree() {
    let toml = base();
    let json = Scene::from_json_str(BASE_JSON).expect("JSON parses");
    assert_eq!(toml, json);
    assert_eq!(json.cables[2].control, Some(CableControl::ForceDensity));
    assert!(json.solver.correction, "default kept");
    // from_file dispatches on the extension.
    let dir = std::env::temp_dir().join(format!("tensegrity-scene-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("s.json"), BASE_JSON).unwrap();
    std::fs::write(dir.join("s.toml"), BASE).unwrap();
    let from_json = Scene::from_file(&dir.join("s.json")).unwrap();
    let from_toml = Scene::from_file(&dir.join("s.toml")).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(from_json, toml);
    assert_eq!(from_toml, toml);
    // A serialised scene reads back identically.
    assert_eq!(Scene::from_toml_str(&toml.to_toml_string()).unwrap(), toml);
}

#[test]
fn missing_file_names_the_path() {
    let path = Path::new("/nonexistent-dir-xyz/no-such-scene.toml");
    let err = Scene::from_file(path).unwrap_err();
    assert!(
        matches!(&err, SceneError::Io { path: p, .. } if p == "/nonexistent-dir-xyz/no-such-scene.toml")
    );
    let msg = err.to_string();
    assert!(
        msg.starts_with("cannot read scene file /nonexistent-dir-xyz/no-such-scene.toml: "),
        "{msg}"
    );
}

// ---------------------------------------------------------------- prestress

#[test]
fn prism_with_wrong_saddle_direction_has_no_self_stress() {
    let mut s = scene::generate("prism2").unwrap();
    assert_eq!(s.cables.len(), 15);
    let id = |k: usize, i: usize| 3 * k + i + 1;
    for k in 0..2 {
        for i in 0..3 {
            s.cables[9 + 3 * k + i].nodes = [id(k, i), id(k + 1, (i + 1) % 3)];
        }
    }
    s.validate().expect("the scene itself is valid");
    let err = Model::new(&s).expect_err("no self-stress");
    check(&err, "prestress", "admits no self-stress");
    assert!(err.to_string().contains("self-stress"));
}

#[test]
fn too_soft_cable_for_prestress() {
    let mut s = scene::builtin("prism2-elastic").unwrap();
    s.cables[9].stiffness = Some(1.0);
    let err = Model::new(&s).expect_err("too soft");
    check(
        &err,
        "cables[10].stiffness",
        "1 N/m is too soft for the prestress",
    );
    assert!(err.to_string().contains("prestress.min_tension"));
    s.cables[9].stiffness = Some(500.0);
    assert_eq!(
        Model::new(&s).unwrap().cables,
        Model::new(&scene::builtin("prism2-elastic").unwrap())
            .unwrap()
            .cables
    );
}

/// Cable tensions and bar forces of a built-in scene at its start state.
fn start_forces(name: &str) -> (Vec<f64>, Vec<f64>) {
    let model = Model::new(&scene::builtin(name).unwrap()).unwrap();
    let (nc, nb) = (model.cables.len(), model.bars.len());
    let sim = Simulation::new(model);
    let t = (0..nc).map(|j| sim.cable_tension(j)).collect();
    let f = (0..nb).map(|i| sim.bar_force(i)).collect();
    (t, f)
}

#[test]
fn builtin_prestress_is_a_self_stress() {
    for name in ["prism2", "prism2-elastic", "icosahedron", "tower20"] {
        let (t, f) = start_forces(name);
        let min = t.iter().copied().fold(f64::INFINITY, f64::min);
        assert!((min - 10.0).abs() <= 1e-9, "{name}: min tension {min}");
        assert!(t.iter().all(|&x| x > 0.0), "{name}: {t:?}");
        assert!(f.iter().all(|&x| x > 0.0), "{name}: bar forces {f:?}");
    }
}

#[test]
fn icosahedron_self_stress_is_symmetric() {
    let (t, f) = start_forces("icosahedron");
    let s = scene::builtin("icosahedron").unwrap();
    // Equal cable force densities γ with bar force densities 3/2 γ: with L = 1 and
    // cables of sqrt(6)/4, every bar force is sqrt(6) times the cable tension.
    for &x in &f {
        assert!((x - 6f64.sqrt() * 10.0).abs() <= 1e-9 * x, "{f:?}");
    }
    let differ = |j: usize| (t[j] - 10.0).abs() > 1e-9 * 10.0;
    let both_pinned = |j: usize| s.cables[j].nodes.iter().all(|n| s.fixed.contains(n));
    let free: Vec<_> = (0..t.len()).filter(|&j| !both_pinned(j)).collect();
    assert_eq!(free.len(), 21);
    let bad: Vec<_> = free
        .iter()
        .filter(|&&j| differ(j))
        .map(|&j| (j + 1, t[j]))
        .collect();
    assert!(bad.is_empty(), "cables with a free end: {bad:?}");
    // The three cables of the pinned face belong to the same symmetric self-stress.
    let bad: Vec<_> = (0..t.len())
        .filter(|&j| differ(j))
        .map(|j| (j + 1, s.cables[j].nodes, t[j]))
        .collect();
    assert!(bad.is_empty(), "tensions differ from 10 N: {bad:?}");
}

// ---------------------------------------------------------------- built-ins

#[test]
fn shipped_files_match_the_generator() {
    let names = scene::builtin_names();
    assert_eq!(
        names,
        ["prism2", "prism2-elastic", "icosahedron", "tower20"]
    );
    assert!(names.contains(&scene::BUILTIN_DEFAULT));
    for name in names {
        let shipped = scene::builtin(name).unwrap();
        assert_eq!(Some(shipped.clone()), scene::generate(name), "{name}");
        assert_eq!(shipped.name, name);
        Model::new(&shipped).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
    assert_eq!(scene::builtin("nope"), None);
    assert_eq!(scene::generate("nope"), None);
}

fn dist(s: &Scene, [a, b]: [usize; 2]) -> f64 {
    let (p, q) = (s.nodes[a - 1], s.nodes[b - 1]);
    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
}

fn pair(a: usize, b: usize) -> [usize; 2] {
    [a.min(b), a.max(b)]
}

#[test]
fn prism2_geometry_matches_the_design() {
    let s = scene::builtin("prism2").unwrap();
    let r = 1.0 / 3f64.sqrt();
    let h = 0.5 + 3f64.sqrt() / 6.0;
    assert_eq!(s.nodes.len(), 9);
    for k in 0..3 {
        for i in 0..3 {
            let a = (k as f64 * 150.0 + i as f64 * 120.0) * PI / 180.0;
            let want = [r * a.cos(), r * a.sin(), k as f64 * h];
            let got = s.nodes[3 * k + i];
            for c in 0..3 {
                assert!(
                    (got[c] - want[c]).abs() <= 1e-15,
                    "node {}: {got:?}",
                    3 * k + i + 1
                );
            }
        }
    }
    let bars: Vec<_> = s.bars.iter().map(|b| b.nodes).collect();
    let want: Vec<_> = (0..2)
        .flat_map(|k| (0..3).map(move |i| [3 * k + i + 1, 3 * (k + 1) + i + 1]))
        .collect();
    assert_eq!(bars, want);
    for b in &s.bars {
        assert!((dist(&s, b.nodes) - (1.0 + 3f64.sqrt()) / 2.0).abs() <= 1e-14);
        assert_eq!(b.mass, 1.0);
    }
    let got: BTreeSet<_> = s
        .cables
        .iter()
        .map(|c| pair(c.nodes[0], c.nodes[1]))
        .collect();
    let mut want = BTreeSet::new();
    for k in 0..3 {
        for i in 0..3 {
            want.insert(pair(3 * k + i + 1, 3 * k + (i + 1) % 3 + 1));
            if k < 2 {
                want.insert(pair(3 * k + i + 1, 3 * (k + 1) + (i + 2) % 3 + 1));
            }
        }
    }
    assert_eq!(s.cables.len(), 15);
    assert_eq!(got, want);
    assert_eq!(s.fixed, vec![1, 2, 3]);
    assert_eq!(s.force_inputs, vec![7, 8, 9]);
    for c in &s.cables {
        assert_eq!(c.control, Some(CableControl::ForceDensity));
        assert_eq!(
            (c.stiffness, c.rest_length, c.force_density),
            (None, None, None)
        );
    }
    assert_eq!(s.prestress.as_ref().map(|p| p.min_tension), Some(10.0));
}

#[test]
fn tower20_size() {
    let s = scene::builtin("tower20").unwrap();
    assert_eq!((s.bars.len(), s.cables.len(), s.nodes.len()), (60, 123, 63));
    assert_eq!(s.fixed, vec![1, 2, 3]);
    assert_eq!(s.force_inputs, vec![61, 62, 63]);
    assert!(s.cables.iter().all(|c| c.stiffness == Some(500.0)));
}

#[test]
fn icosahedron_geometry() {
    let s = scene::builtin("icosahedron").unwrap();
    assert_eq!(s.nodes.len(), 12);
    assert_eq!(s.bars.len(), 6);
    for b in &s.bars {
        assert!((dist(&s, b.nodes) - 1.0).abs() <= 1e-15);
        assert_eq!(b.mass, 1.0);
    }
    let cl = 6f64.sqrt() / 4.0;
    assert_eq!(s.cables.len(), 24);
    let cables: BTreeSet<_> = s
        .cables
        .iter()
        .map(|c| pair(c.nodes[0], c.nodes[1]))
        .collect();
    assert_eq!(cables.len(), 24);
    for c in &s.cables {
        assert!((dist(&s, c.nodes) - cl).abs() <= 1e-15, "{:?}", c.nodes);
    }
    let triangle = |ns: &[usize]| {
        ns.len() == 3 && (0..3).all(|i| cables.contains(&pair(ns[i], ns[(i + 1) % 3])))
    };
    assert!(triangle(&s.fixed), "fixed {:?}", s.fixed);
    assert_eq!(s.force_inputs.len(), 3);
    assert!(triangle(&s.force_inputs), "inputs {:?}", s.force_inputs);
    assert!(s.force_inputs.iter().all(|n| !s.fixed.contains(n)));
}

// ---------------------------------------------------------------- skipped bars

#[test]
fn fully_pinned_bar_is_reported_as_skipped() {
    let mut s = base();
    s.fixed = vec![3, 4]; // bar 2 joins two pinned nodes
    s.force_inputs = vec![2];
    let model = Model::new(&s).expect("builds");
    assert_eq!(model.correction.skipped, vec![1]);
    let hits: Vec<_> = model
        .warnings
        .iter()
        .filter(|w| w.starts_with("bar 2:"))
        .collect();
    assert_eq!(hits.len(), 1, "{:?}", model.warnings);
    assert!(hits[0].contains("skips it"), "{}", hits[0]);
    assert!(!model.warnings.iter().any(|w| w.starts_with("bar 1:")));
    assert!(Simulation::new(model)
        .warnings()
        .iter()
        .any(|w| w.starts_with("bar 2:")));
}
