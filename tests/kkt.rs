//! Independent checks of the dynamics against textbook formulations:
//! - the closed-form λ / reaction solve against a dense saddle-point (KKT) solve in
//!   physical node coordinates,
//! - cable forces against the gradient of the library's own potential energy,
//! - the sparse joint/pin basis against the dense SVD basis of the paper's full P.

mod kkt_support;

use kkt_support::*;
use nalgebra::Vector3;
use tensegrity_fmu::dynamics::energy::potential;
use tensegrity_fmu::dynamics::{applied_forces, kinematics, Inputs, Workspace};
use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::model::{BasisKind, CableLaw, Model};
use tensegrity_fmu::scene::{builtin, Scene};
use tensegrity_fmu::Simulation;

/// Runs a loaded simulation and compares every bar end's acceleration and every bar force
/// with the KKT solve; also checks the solve's cable force densities against the library's.
fn check_against_kkt(scene: Scene, seed: u64) {
    let c = compare_with_kkt(&scene, &vec![0.0; scene.nodes.len()], seed);
    let ws = c.sim.workspace();
    for (j, &g) in c.kkt.gamma.iter().enumerate() {
        assert!(
            (g - ws.gamma[j]).abs() <= 1e-12 * (1.0 + g.abs()),
            "cable {j}: γ {g} vs library {}",
            ws.gamma[j]
        );
    }
    let taut = ws.gamma.iter().filter(|&&g| g > 0.0).count();
    println!(
        "{}: max |Δä| = {:.3e} (scale {:.3e}, rel {:.3e}); \
         max |Δ bar force| = {:.3e} N (scale {:.3e}, rel {:.3e}); \
         {taut}/{} cables taut",
        c.name,
        c.err_acc,
        c.scale,
        c.err_acc / c.scale,
        c.err_force,
        c.force_scale,
        c.err_force / c.force_scale,
        c.sim.model().cables.len()
    );
    c.assert_agree(1e-9);
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
        grip: sim.inputs.grip.clone(),
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
    // Fixed steps: an adaptive method's step choice would follow the bases' round-off.
    let run = |mut model: Model| {
        model.solver.method = Method::Rk4;
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
