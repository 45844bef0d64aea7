//! Built-in scenes. Each is shipped as a file under `fmu/scenes/` (so users can copy it)
//! and embedded here; `generate` rebuilds each from its formula, and a test holds the
//! shipped files to it.

use super::{BarSpec, CableControl, CableSpec, LoadSpec, PrestressSpec, Scene, SolverSpec, Start};

/// The default scene, built when no scene is named.
pub const BUILTIN_DEFAULT: &str = "prism2";

const FILES: [(&str, &str); 4] = [
    ("prism2", include_str!("../../fmu/scenes/prism2.toml")),
    (
        "prism2-elastic",
        include_str!("../../fmu/scenes/prism2-elastic.toml"),
    ),
    (
        "icosahedron",
        include_str!("../../fmu/scenes/icosahedron.toml"),
    ),
    ("tower20", include_str!("../../fmu/scenes/tower20.toml")),
];

/// Names of the built-in scenes.
pub fn builtin_names() -> Vec<&'static str> {
    FILES.iter().map(|(n, _)| *n).collect()
}

/// A built-in scene by name, parsed from its shipped file.
pub fn builtin(name: &str) -> Option<Scene> {
    let (_, text) = FILES.iter().find(|(n, _)| *n == name)?;
    Some(Scene::from_toml_str(text).expect("built-in scenes parse"))
}

/// Rebuilds a built-in scene from its defining formula.
pub fn generate(name: &str) -> Option<Scene> {
    let elastic = Some(500.0);
    Some(match name {
        "prism2" => tower_scene(2, None, "prism2"),
        "prism2-elastic" => tower_scene(2, elastic, "prism2-elastic"),
        "tower20" => tower_scene(20, elastic, "tower20"),
        "icosahedron" => icosahedron(),
        _ => return None,
    })
}

/// Minimum cable tension of the built-in prestress, in N.
const PRESTRESS_TENSION: f64 = 10.0;

/// [`tower_scene`] with elastic cables (500 N/m) at 98% of their lengths: explicit rest
/// lengths and no prestress solve, so it builds in linear time at any height (the scaling
/// benchmarks' scene).
pub fn tower_with_rest_lengths(stages: usize, name: &str) -> Scene {
    let mut scene = tower_scene(stages, Some(500.0), name);
    scene.prestress = None;
    for c in &mut scene.cables {
        let [a, b] = c.nodes;
        let d: f64 = (0..3)
            .map(|i| (scene.nodes[b - 1][i] - scene.nodes[a - 1][i]).powi(2))
            .sum::<f64>()
            .sqrt();
        c.rest_length = Some(0.98 * d);
    }
    scene
}

/// A class-2 tower of `stages` prism stages with the paper's geometry (`dynamics.md`):
/// elastic cables of the given stiffness, or force-density controlled cables when `None`.
/// Prestressed, nodes 1–3 pinned, force inputs on the top ring.
pub fn tower_scene(stages: usize, stiffness: Option<f64>, name: &str) -> Scene {
    let radius = 1.0 / 3f64.sqrt();
    let h = 0.5 + 3f64.sqrt() / 6.0;
    let id = |ring: usize, i: usize| 3 * ring + i + 1;
    let mut nodes = Vec::new();
    for ring in 0..=stages {
        for i in 0..3 {
            let angle = (ring as f64 * 150.0 + i as f64 * 120.0).to_radians();
            nodes.push([radius * angle.cos(), radius * angle.sin(), ring as f64 * h]);
        }
    }
    let bars = (0..stages)
        .flat_map(|k| (0..3).map(move |i| (k, i)))
        .map(|(k, i)| BarSpec {
            nodes: [id(k, i), id(k + 1, i)],
            mass: 1.0,
            radius: 0.0,
        })
        .collect();
    let cable = |a: usize, b: usize| CableSpec {
        nodes: [a, b],
        stiffness,
        control: stiffness.is_none().then_some(CableControl::ForceDensity),
        ..CableSpec::default()
    };
    let mut cables = Vec::new();
    for ring in 0..=stages {
        for i in 0..3 {
            cables.push(cable(id(ring, i), id(ring, (i + 1) % 3)));
        }
    }
    for k in 0..stages {
        for i in 0..3 {
            cables.push(cable(id(k, i), id(k + 1, (i + 2) % 3)));
        }
    }
    let kind = if stiffness.is_some() {
        "elastic cables (500 N/m)"
    } else {
        "force-density controlled cables"
    };
    Scene {
        name: name.to_string(),
        description: Some(format!(
            "{stages}-stage class-2 tensegrity tower (Cheong, Skelton & Cho 2014), {kind}, \
             prestressed to a {PRESTRESS_TENSION} N minimum cable tension, bottom ring pinned, \
             force inputs on the top ring."
        )),
        nodes,
        fixed: vec![1, 2, 3],
        bars,
        cables,
        gravity: None,
        force_inputs: (0..3).map(|i| id(stages, i)).collect(),
        velocities: None,
        loads: Vec::new(),
        point_masses: Vec::new(),
        ground: None,
        terrain: Vec::new(),
        collisions: None,
        outputs: None,
        prestress: Some(PrestressSpec {
            min_tension: PRESTRESS_TENSION,
        }),
        start: Start::AsGiven,
        solver: SolverSpec::default(),
    }
}

/// The paper's 6-bar icosahedron (bars of 1 m and 1 kg): one cable face pinned and force
/// inputs on the opposite face.
fn icosahedron() -> Scene {
    let l = 1.0;
    let mut nodes = Vec::new();
    for axis in 0..3 {
        for (s4, s2) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
            let mut p = [0.0f64; 3];
            p[(axis + 1) % 3] = s4 * l / 4.0;
            p[(axis + 2) % 3] = s2 * l / 2.0;
            nodes.push(p);
        }
    }
    let dist = |a: usize, b: usize| {
        (0..3)
            .map(|k| (nodes[a][k] - nodes[b][k]).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    // Nodes 4a+0/4a+1 and 4a+2/4a+3 differ only in the sign of the L/2 coordinate.
    let bars = (0..6)
        .map(|k| BarSpec {
            nodes: [2 * k + 1, 2 * k + 2],
            mass: 1.0,
            radius: 0.0,
        })
        .collect();
    let cable_length = 6f64.sqrt() / 4.0 * l;
    let mut cables = Vec::new();
    for a in 0..12 {
        for b in a + 1..12 {
            if (dist(a, b) - cable_length).abs() < 1e-9 {
                cables.push(CableSpec {
                    nodes: [a + 1, b + 1],
                    stiffness: Some(500.0),
                    ..CableSpec::default()
                });
            }
        }
    }
    let linked = |a: usize, b: usize| (dist(a, b) - cable_length).abs() < 1e-9;
    let face = (0..12)
        .flat_map(|a| (a + 1..12).flat_map(move |b| (b + 1..12).map(move |c| [a, b, c])))
        .find(|&[a, b, c]| linked(a, b) && linked(b, c) && linked(a, c))
        .expect("the icosahedron has cable faces");
    // Central symmetry maps a face to the opposite one.
    let opposite = |a: usize| {
        (0..12)
            .find(|&b| (0..3).all(|k| (nodes[a][k] + nodes[b][k]).abs() < 1e-12))
            .expect("every node has an antipode")
    };
    Scene {
        name: "icosahedron".to_string(),
        description: Some(
            "6-bar tensegrity icosahedron (class 1), bars 1 m and 1 kg, elastic cables \
             (500 N/m) prestressed to a 10 N minimum tension, one cable face pinned, force \
             inputs on the opposite face."
                .to_string(),
        ),
        fixed: face.iter().map(|&a| a + 1).collect(),
        force_inputs: face.iter().map(|&a| opposite(a) + 1).collect(),
        nodes,
        bars,
        cables,
        gravity: None,
        velocities: None,
        loads: Vec::new(),
        point_masses: Vec::new(),
        ground: None,
        terrain: Vec::new(),
        collisions: None,
        outputs: None,
        prestress: Some(PrestressSpec {
            min_tension: PRESTRESS_TENSION,
        }),
        start: Start::AsGiven,
        solver: SolverSpec::default(),
    }
}

/// The paper's prism with steel-stiff cables (κ = 1e7 N/m, 100 N prestress), settled
/// under gravity (`start = "equilibrium"`) and swayed by a slow 0.5 Hz, 20 N load on node
/// 7: the stiff method's benchmark and test case (`bench stiff`, tests/stiff.rs).
pub fn steel_prism_scene() -> Scene {
    let mut scene = builtin("prism2-elastic").expect("a built-in scene");
    scene.name = "steel-prism".into();
    for cable in &mut scene.cables {
        cable.stiffness = Some(1e7);
    }
    scene.prestress = Some(PrestressSpec { min_tension: 100.0 });
    scene.gravity = Some([0.0, 0.0, -9.81]);
    scene.start = Start::Equilibrium;
    scene.loads = vec![LoadSpec::Sinusoidal {
        node: 7,
        amplitude: [20.0, 0.0, 0.0],
        frequency: 0.5,
        phase: 0.0,
    }];
    scene
}
