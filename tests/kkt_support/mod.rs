//! Helpers shared by `tests/kkt.rs` and `tests/point_masses.rs`: a deterministic generator,
//! the random class-k scene, perturbed loads, and a dense saddle-point (KKT) solve in
//! physical node coordinates (with optional per-node payload masses) to hold the library's
//! closed-form accelerations and bar forces against.

use nalgebra::{DMatrix, DVector, Vector3};
use tensegrity_fmu::dynamics::Inputs;
use tensegrity_fmu::model::CableLaw;
use tensegrity_fmu::scene::{BarSpec, CableControl, CableSpec, Scene, SolverSpec};
use tensegrity_fmu::{Model, Simulation};

/// Communication step of the runs, s.
pub const H: f64 = 1e-3;

/// Deterministic linear congruential generator (Knuth's MMIX constants).
pub struct Lcg(pub u64);

impl Lcg {
    pub fn unit(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
    pub fn vec3(&mut self, scale: f64) -> Vector3<f64> {
        Vector3::new(
            self.range(-scale, scale),
            self.range(-scale, scale),
            self.range(-scale, scale),
        )
    }
}

/// A class-k structure: a tree of 8 bars with a class-4 hub (node 1), a pinned class-2
/// joint (node 2), a free class-2 joint (node 3), a pinned leaf (node 7) and a pinned
/// bar-less cable anchor (node 9). Elastic cables with rest lengths far from equilibrium
/// (half of them damped), one controlled cable, gravity, force inputs on nodes 10 and 8
/// and initial velocities that violate the constraints (the library projects them).
pub fn random_scene(seed: u64) -> Scene {
    let mut rng = Lcg(seed);
    let base = [
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [-0.6, 0.8, 1.1],
        [-0.5, -0.8, 0.9],
        [1.6, 0.7, 1.3],
        [-1.4, 1.2, 0.8],
        [-2.0, 0.6, 0.2],
        [-0.9, -1.6, 0.5],
        [0.0, 0.0, 0.0],
        [0.1, 0.2, 2.0],
    ];
    let nodes: Vec<[f64; 3]> = base
        .iter()
        .map(|p| {
            let d = rng.vec3(0.1);
            [p[0] + d[0], p[1] + d[1], p[2] + d[2]]
        })
        .collect();
    let dist = |a: usize, b: usize| (Vector3::from(nodes[b]) - Vector3::from(nodes[a])).norm();
    // 0-based pairs; scenes are 1-based.
    let bar_pairs = [
        (0, 1),
        (0, 2),
        (0, 3),
        (0, 9),
        (1, 4),
        (2, 5),
        (5, 6),
        (3, 7),
    ];
    let bars = bar_pairs
        .iter()
        .map(|&(a, b)| BarSpec {
            nodes: [a + 1, b + 1],
            mass: rng.range(0.5, 2.0),
            radius: 0.0,
        })
        .collect();
    let cable_pairs = [
        (8, 0),
        (8, 3),
        (8, 2),
        (9, 4),
        (9, 2),
        (9, 3),
        (4, 0),
        (7, 8),
        (5, 8),
        (3, 2),
        (4, 8),
        (9, 5),
    ];
    let mut cables: Vec<CableSpec> = cable_pairs
        .iter()
        .enumerate()
        .map(|(j, &(a, b))| CableSpec {
            nodes: [a + 1, b + 1],
            stiffness: Some(rng.range(100.0, 600.0)),
            rest_length: Some(dist(a, b) * rng.range(0.6, 0.8)),
            damping: (j % 2 == 0).then(|| rng.range(0.5, 5.0)),
            ..CableSpec::default()
        })
        .collect();
    cables.push(CableSpec {
        nodes: [8, 1],
        control: Some(CableControl::ForceDensity),
        force_density: Some(40.0),
        ..CableSpec::default()
    });
    let velocities = (0..nodes.len())
        .map(|_| {
            let v = rng.vec3(0.5);
            [v[0], v[1], v[2]]
        })
        .collect();
    Scene {
        name: "random-class-k".to_string(),
        description: None,
        nodes,
        fixed: vec![2, 7, 9],
        bars,
        cables,
        gravity: Some([0.0, 0.0, -9.81]),
        force_inputs: vec![10, 8],
        velocities: Some(velocities),
        loads: Vec::new(),
        point_masses: Vec::new(),
        ground: None,
        terrain: Vec::new(),
        collisions: None,
        outputs: None,
        prestress: None,
        start: Default::default(),
        solver: SolverSpec::default(),
    }
}

/// Sets perturbed cable force densities and nodal loads.
pub fn set_loads(sim: &mut Simulation, rng: &mut Lcg) {
    for g in sim.inputs.force_density.iter_mut() {
        *g *= rng.range(0.6, 1.4);
    }
    for f in sim.inputs.node_force.iter_mut() {
        *f = rng.vec3(8.0);
    }
}

/// Cable force density from the law in dynamics.md, computed independently of the library.
fn gamma(law: &CableLaw, inputs: &Inputs, s: &Vector3<f64>, sd: &Vector3<f64>) -> f64 {
    let (stiffness, rest_length, damping) = match *law {
        CableLaw::Controlled { input } => return inputs.force_density[input].max(0.0),
        CableLaw::Elastic {
            stiffness,
            rest_length,
            damping,
        } => (stiffness, rest_length, damping),
        CableLaw::RestLengthControlled {
            stiffness,
            damping,
            input,
        } => (stiffness, inputs.rest_length[input].max(0.0), damping),
    };
    let l = s.norm();
    if l > rest_length {
        let g = stiffness * (1.0 - rest_length / l) + damping.unwrap_or(0.0) * s.dot(sd) / (l * l);
        g.max(0.0)
    } else {
        0.0
    }
}

/// The result of [`kkt_solve`].
pub struct Kkt {
    /// Per-node accelerations (zero at pins).
    pub acc: Vec<Vector3<f64>>,
    /// λ per bar (compression positive).
    pub lambda: Vec<f64>,
    /// Force density per cable from [`gamma`], computed here rather than by the library.
    /// Only tests/kkt.rs checks it; each test crate compiles this module on its own.
    #[allow(dead_code)]
    pub gamma: Vec<f64>,
}

/// Dense saddle-point solve in physical node coordinates at the simulation's current state:
/// `[M −Gᵀ; G 0] [ä; λ] = [F; −|ḃ|²]`. M is assembled from every bar's `m [1/3 1/6; 1/6 1/3]`
/// on its two nodes plus `payload[n]` on node n's diagonal; a class-k joint is one node, so
/// its payload is counted once whatever the number of bars. F holds cable forces, node
/// inputs and the weights `m g / 2` per bar end plus `payload[n] g` per node. Row `i` of G
/// holds `−bᵢᵀ` / `+bᵢᵀ` at the start / end node, so `Gᵀλ` puts `+λ b` on the end node
/// (compression positive). A node whose payload is 0 is skipped, so all-zero payloads run
/// exactly the payload-free arithmetic.
pub fn kkt_solve(sim: &Simulation, payload: &[f64]) -> Kkt {
    let model = sim.model();
    let n_nodes = model.n_nodes();
    assert_eq!(payload.len(), n_nodes, "one payload per node");
    let mut index = vec![None; n_nodes];
    let mut n_free = 0;
    for (n, slot) in index.iter_mut().enumerate() {
        if !model.pinned[n] {
            *slot = Some(n_free);
            n_free += 1;
        }
    }
    let x: Vec<_> = (0..n_nodes).map(|n| sim.node_position(n)).collect();
    let v: Vec<_> = (0..n_nodes).map(|n| sim.node_velocity(n)).collect();
    let nb = model.bars.len();
    let dim = 3 * n_free + nb;
    let mut a = DMatrix::<f64>::zeros(dim, dim);
    let mut rhs = DVector::<f64>::zeros(dim);
    let mut force = vec![Vector3::zeros(); n_nodes];
    let mut cable_gamma = Vec::with_capacity(model.cables.len());
    for cable in &model.cables {
        let [p, q] = cable.nodes;
        let s = x[q] - x[p];
        let g = gamma(&cable.law, &sim.inputs, &s, &(v[q] - v[p]));
        cable_gamma.push(g);
        force[p] += s * g;
        force[q] -= s * g;
    }
    for (k, &n) in model.force_inputs.iter().enumerate() {
        force[n] += sim.inputs.node_force[k];
    }
    for n in 0..n_nodes {
        if payload[n] == 0.0 {
            continue;
        }
        if let Some(g) = model.gravity {
            force[n] += g * payload[n];
        }
        if let Some(i) = index[n] {
            for k in 0..3 {
                a[(3 * i + k, 3 * i + k)] += payload[n];
            }
        }
    }
    for (i, bar) in model.bars.iter().enumerate() {
        let [p, q] = bar.nodes;
        if let Some(g) = model.gravity {
            force[p] += g * (bar.mass / 2.0);
            force[q] += g * (bar.mass / 2.0);
        }
        let m = bar.mass;
        let block = [[m / 3.0, m / 6.0], [m / 6.0, m / 3.0]];
        let ends = [p, q];
        let b = x[q] - x[p];
        let bd = v[q] - v[p];
        let row = 3 * n_free + i;
        for (r, &nr) in ends.iter().enumerate() {
            let Some(ir) = index[nr] else { continue };
            for (c, &nc) in ends.iter().enumerate() {
                let Some(ic) = index[nc] else { continue };
                for k in 0..3 {
                    a[(3 * ir + k, 3 * ic + k)] += block[r][c];
                }
            }
            let sign = if r == 0 { -1.0 } else { 1.0 };
            for k in 0..3 {
                a[(row, 3 * ir + k)] = sign * b[k];
                a[(3 * ir + k, row)] = -sign * b[k];
            }
        }
        rhs[row] = -bd.norm_squared();
    }
    for n in 0..n_nodes {
        if let Some(i) = index[n] {
            for k in 0..3 {
                rhs[3 * i + k] = force[n][k];
            }
        }
    }
    let sol = a.lu().solve(&rhs).expect("the KKT matrix is non-singular");
    let acc = (0..n_nodes)
        .map(|n| index[n].map_or(Vector3::zeros(), |i| sol.fixed_rows::<3>(3 * i).into()))
        .collect();
    let lambda = (0..nb).map(|i| sol[3 * n_free + i]).collect();
    Kkt {
        acc,
        lambda,
        gamma: cable_gamma,
    }
}

/// A loaded simulation next to the dense solve at the same state, with the largest
/// disagreements; the caller prints and bounds them.
pub struct Comparison {
    pub name: String,
    pub sim: Simulation,
    pub kkt: Kkt,
    /// Largest |ä| of the dense solve.
    pub scale: f64,
    /// Largest |Δä| over every node and every bar end (not just the representative end of
    /// each node).
    pub err_acc: f64,
    /// Largest |bar force| of the dense solve (`λ L`), N.
    pub force_scale: f64,
    /// Largest |Δ bar force|, N.
    pub err_force: f64,
}

impl Comparison {
    /// Asserts that the accelerations and bar forces agree to `rel` of their scales and
    /// that the bars carry force at all.
    pub fn assert_agree(&self, rel: f64) {
        let name = &self.name;
        assert!(
            self.err_acc <= rel * self.scale,
            "{name}: accelerations disagree"
        );
        assert!(self.force_scale > 1e-3, "{name}: bars carry no force");
        assert!(
            self.err_force <= rel * self.force_scale,
            "{name}: bar forces disagree"
        );
    }
}

/// Runs `scene` for 300 steps under loads drawn from `seed`, draws new loads, and compares
/// every node's and bar end's acceleration and every bar force with [`kkt_solve`] given
/// `payload` (kg per node). Asserts only that the state is generic (moving and loaded).
pub fn compare_with_kkt(scene: &Scene, payload: &[f64], seed: u64) -> Comparison {
    let name = scene.name.clone();
    let mut rng = Lcg(seed);
    let mut sim = Simulation::new(Model::new(scene).expect("scene builds"));
    set_loads(&mut sim, &mut rng);
    sim.advance(300, H).expect("steps");
    set_loads(&mut sim, &mut rng);
    sim.refresh();
    let kkt = kkt_solve(&sim, payload);
    let model = sim.model();
    let ws = sim.workspace();
    let scale = kkt.acc.iter().map(|a| a.norm()).fold(0.0, f64::max);
    let speed = (0..model.n_nodes())
        .map(|n| sim.node_velocity(n).norm())
        .fold(0.0, f64::max);
    assert!(scale > 1.0 && speed > 0.05, "{name}: state is not generic");
    let mut err_acc = 0.0f64;
    for (n, a) in kkt.acc.iter().enumerate() {
        err_acc = err_acc.max((sim.node_acceleration(n) - a).norm());
    }
    for (e, &n) in model.coords.end_node.iter().enumerate() {
        err_acc = err_acc.max((ws.end_acc[e] - kkt.acc[n]).norm());
    }
    let forces: Vec<f64> = (0..model.bars.len()).map(|i| sim.bar_force(i)).collect();
    let kkt_forces: Vec<f64> = model
        .bars
        .iter()
        .zip(&kkt.lambda)
        .map(|(b, l)| l * b.length)
        .collect();
    let force_scale = kkt_forces.iter().fold(0.0f64, |m, f| m.max(f.abs()));
    let err_force = forces
        .iter()
        .zip(&kkt_forces)
        .fold(0.0f64, |m, (f, g)| m.max((f - g).abs()));
    Comparison {
        name,
        sim,
        kkt,
        scale,
        err_acc,
        force_scale,
        err_force,
    }
}
