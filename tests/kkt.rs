//! Independent checks of the dynamics against textbook formulations:
//! - the closed-form λ / reaction solve against a dense saddle-point (KKT) solve in
//!   physical node coordinates,
//! - cable forces against the gradient of the library's own potential energy,
//! - the sparse joint/pin basis against the dense SVD basis of the paper's full P.

use nalgebra::{DMatrix, DVector, Vector3};
use tensegrity_fmu::dynamics::energy::potential;
use tensegrity_fmu::dynamics::{applied_forces, kinematics, Inputs, Workspace};
use tensegrity_fmu::model::{BasisKind, CableLaw, Model};
use tensegrity_fmu::scene::{builtin, BarSpec, CableControl, CableSpec, Scene, SolverSpec};
use tensegrity_fmu::Simulation;

const H: f64 = 1e-3;

/// Deterministic linear congruential generator (Knuth's MMIX constants).
struct Lcg(u64);

impl Lcg {
    fn unit(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
    fn vec3(&mut self, scale: f64) -> Vector3<f64> {
        Vector3::new(
            self.range(-scale, scale),
            self.range(-scale, scale),
            self.range(-scale, scale),
        )
    }
}

/// A class-k structure: a tree of 8 bars with a class-4 hub (node 1), a pinned class-2
/// joint (node 2), a pinned leaf (node 7) and a pinned bar-less cable anchor (node 9).
/// Elastic cables with rest lengths far from equilibrium (half of them damped), one
/// controlled cable, gravity, force inputs and initial velocities that violate the
/// constraints (the library projects them).
fn random_scene(seed: u64) -> Scene {
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
        outputs: None,
        prestress: None,
        solver: SolverSpec::default(),
    }
}

/// Sets perturbed cable force densities and nodal loads.
fn set_loads(sim: &mut Simulation, rng: &mut Lcg) {
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

/// Dense saddle-point solve in physical node coordinates at the simulation's current state:
/// `[M −Gᵀ; G 0] [ä; λ] = [F; −|ḃ|²]`, with row `i` of G holding `−bᵢᵀ` / `+bᵢᵀ` at the
/// start / end node, so `Gᵀλ` puts `+λ b` on the end node (compression positive).
/// Returns per-node accelerations (zero at pins) and λ per bar.
fn kkt_solve(sim: &Simulation) -> (Vec<Vector3<f64>>, Vec<f64>) {
    let model = sim.model();
    let n_nodes = model.n_nodes();
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
    for (j, cable) in model.cables.iter().enumerate() {
        let [p, q] = cable.nodes;
        let s = x[q] - x[p];
        let g = gamma(&cable.law, &sim.inputs, &s, &(v[q] - v[p]));
        assert!(
            (g - sim.workspace().gamma[j]).abs() <= 1e-12 * (1.0 + g.abs()),
            "cable {j}: γ {g} vs library {}",
            sim.workspace().gamma[j]
        );
        force[p] += s * g;
        force[q] -= s * g;
    }
    for (k, &n) in model.force_inputs.iter().enumerate() {
        force[n] += sim.inputs.node_force[k];
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
    (acc, lambda)
}

/// Runs a loaded simulation and compares every bar end's acceleration and every bar force
/// with the KKT solve.
fn check_against_kkt(scene: Scene, seed: u64) {
    let name = scene.name.clone();
    let mut rng = Lcg(seed);
    let mut sim = Simulation::new(Model::new(&scene).expect("scene builds"));
    set_loads(&mut sim, &mut rng);
    sim.advance(300, H).expect("steps");
    set_loads(&mut sim, &mut rng);
    sim.refresh();
    let (acc, lambda) = kkt_solve(&sim);
    let model = sim.model();
    let ws = sim.workspace();
    let scale = acc.iter().map(|a| a.norm()).fold(0.0, f64::max);
    let taut = ws.gamma.iter().filter(|&&g| g > 0.0).count();
    let speed = (0..model.n_nodes())
        .map(|n| sim.node_velocity(n).norm())
        .fold(0.0, f64::max);
    assert!(scale > 1.0 && speed > 0.05, "{name}: state is not generic");
    let mut err_acc = 0.0f64;
    for (n, a) in acc.iter().enumerate() {
        err_acc = err_acc.max((sim.node_acceleration(n) - a).norm());
    }
    // Every bar end, not just the representative end of each node.
    for (e, &n) in model.coords.end_node.iter().enumerate() {
        err_acc = err_acc.max((ws.end_acc[e] - acc[n]).norm());
    }
    let forces: Vec<f64> = (0..model.bars.len()).map(|i| sim.bar_force(i)).collect();
    let kkt_forces: Vec<f64> = model
        .bars
        .iter()
        .zip(&lambda)
        .map(|(b, l)| l * b.length)
        .collect();
    let force_scale = kkt_forces.iter().fold(0.0f64, |m, f| m.max(f.abs()));
    let err_force = forces
        .iter()
        .zip(&kkt_forces)
        .fold(0.0f64, |m, (f, g)| m.max((f - g).abs()));
    println!(
        "{name}: max |Δä| = {err_acc:.3e} (scale {scale:.3e}, rel {:.3e}); \
         max |Δ bar force| = {err_force:.3e} N (scale {force_scale:.3e}, rel {:.3e}); \
         {taut}/{} cables taut",
        err_acc / scale,
        err_force / force_scale,
        model.cables.len()
    );
    assert!(err_acc <= 1e-9 * scale, "{name}: accelerations disagree");
    assert!(force_scale > 1e-3, "{name}: bars carry no force");
    assert!(
        err_force <= 1e-9 * force_scale,
        "{name}: bar forces disagree"
    );
}

#[test]
fn closed_form_matches_kkt_prism2() {
    check_against_kkt(builtin("prism2").unwrap(), 11);
}

#[test]
fn closed_form_matches_kkt_icosahedron() {
    // The built-in plus gravity, so the m g / 2 end loads are covered too.
    let mut scene = builtin("icosahedron").unwrap();
    scene.gravity = Some([0.3, -0.2, -9.81]);
    check_against_kkt(scene, 12);
}

#[test]
fn closed_form_matches_kkt_random_class_k() {
    let scene = random_scene(2024);
    let model = Model::new(&scene).unwrap();
    assert!(Simulation::new(model)
        .warnings()
        .iter()
        .any(|w| w.contains("projected")));
    check_against_kkt(scene, 13);
}

/// Check: the library's cable + gravity forces are minus the gradient of the library's
/// `potential()`. The state comes from a loaded run; `kinematics` rebuilds the workspace
/// with zero velocities (so cable damping drops out), and `applied_forces` runs with zero
/// node inputs, so the total force on a node (summed over its bar ends) must equal
/// `−∂V/∂x_n`. V is differentiated by central differences, moving the node and all its
/// bar ends together. Controlled cables store `½ γ |s|²`, whose gradient is `γ s` too.
fn check_energy_gradient(scene: Scene, seed: u64) {
    let name = scene.name.clone();
    let mut rng = Lcg(seed);
    let mut sim = Simulation::new(Model::new(&scene).unwrap());
    set_loads(&mut sim, &mut rng);
    sim.advance(300, H).unwrap();
    let model = sim.model();
    let half = sim.state().y.len() / 2;
    let q = &sim.state().y[..half];
    let inputs = Inputs {
        force_density: sim.inputs.force_density.clone(),
        node_force: vec![Vector3::zeros(); model.force_inputs.len()],
        rest_length: sim.inputs.rest_length.clone(),
    };
    let mut ws = Workspace::new(model);
    kinematics(model, q, &vec![0.0; half], &mut ws);
    applied_forces(model, &inputs, 0.0, &mut ws);
    // The finite differences must not straddle a slack/taut kink.
    let (mut taut, mut elastic) = (0, 0);
    for cable in &model.cables {
        if let CableLaw::Elastic { rest_length, .. } = cable.law {
            elastic += 1;
            let s = ws.node_pos[cable.nodes[1]] - ws.node_pos[cable.nodes[0]];
            assert!(
                (s.norm() - rest_length).abs() > 1e-5,
                "{name}: cable at its kink"
            );
            taut += usize::from(s.norm() > rest_length);
        }
    }
    let delta = 1e-6;
    let (mut err, mut scale) = (0.0f64, 0.0f64);
    let ends = &model.coords.end_node;
    for n in 0..model.n_nodes() {
        let mine: Vec<usize> = (0..ends.len()).filter(|&e| ends[e] == n).collect();
        if mine.is_empty() {
            continue; // a bar-less pinned anchor: its pin takes the force
        }
        let f: Vector3<f64> = mine.iter().map(|&e| ws.end_force[e]).sum();
        for k in 0..3 {
            let v = |d: f64| {
                let mut w = ws.clone();
                w.node_pos[n][k] += d;
                for &e in &mine {
                    w.end_pos[e][k] += d;
                }
                potential(model, &inputs, &w)
            };
            let grad = (v(delta) - v(-delta)) / (2.0 * delta);
            err = err.max((f[k] + grad).abs());
            scale = scale.max(f[k].abs());
        }
    }
    println!(
        "{name}: max |F + ∇V| = {err:.3e} N (scale {scale:.3e}, rel {:.3e}), {taut}/{elastic} elastic cables taut",
        err / scale
    );
    assert!(scale > 1.0, "{name}: no forces");
    assert!(2 * taut >= elastic, "{name}: too few taut cables");
    assert!(err <= 1e-6 * scale, "{name}: forces are not −∇V");
}

#[test]
fn cable_forces_are_energy_gradient() {
    check_energy_gradient(builtin("prism2-elastic").unwrap(), 21);
    check_energy_gradient(builtin("prism2").unwrap(), 22);
    check_energy_gradient(random_scene(2024), 13);
}

/// Runs the scene with both bases under identical loads and compares node positions.
fn check_bases(scene: Scene, seed: u64) {
    let name = scene.name.clone();
    let sparse = Model::with_basis(&scene, BasisKind::Sparse).unwrap();
    let dense = Model::with_basis(&scene, BasisKind::Dense).unwrap();
    assert_eq!(sparse.coords.r, dense.coords.r, "{name}: rank of P");
    let run = |model: Model| {
        let mut rng = Lcg(seed);
        let mut sim = Simulation::new(model);
        set_loads(&mut sim, &mut rng);
        sim.advance(500, H).unwrap();
        (0..sim.model().n_nodes())
            .map(|n| sim.node_position(n))
            .collect::<Vec<_>>()
    };
    let (a, b) = (run(sparse), run(dense));
    let moved = a
        .iter()
        .zip(&scene.nodes)
        .map(|(x, p)| (x - Vector3::from(*p)).norm())
        .fold(0.0, f64::max);
    let diff = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).norm())
        .fold(0.0, f64::max);
    println!(
        "{name}: max |x_sparse − x_dense| = {diff:.3e} m after 500 steps (moved {moved:.3e} m)"
    );
    assert!(moved > 1e-3, "{name}: nothing moved");
    assert!(diff <= 1e-9, "{name}: bases disagree");
}

#[test]
fn dense_svd_basis_agrees_with_sparse_basis() {
    check_bases(builtin("prism2").unwrap(), 31);
    // Node 2 is a pinned class-2 joint: the dense P has a redundant column there.
    check_bases(random_scene(99), 32);
}
