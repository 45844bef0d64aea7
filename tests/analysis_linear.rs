//! State-space models (`analysis::linear`) and the force tangent (`analysis::tangent`) held
//! to central finite differences (Richardson-extrapolated) of the nonlinear model:
//! - `A`, `B` against `dynamics::accelerations` along the mode directions (the modal
//!   accelerations are the least-squares coordinates of δη̈₂ in the mode shapes, which
//!   must span it), for force-density, node-force and rest-length inputs, damped cables,
//!   and a structure settled on a ground with friction;
//! - the analytic rows of `C`, `D` (positions, velocities, tensions, bar forces) against
//!   the outputs of a simulation set to the perturbed state;
//! - `Tangent::stiffness` and `::damping` against the applied generalized forces at a
//!   generic moving state, with contacts on both friction branches.
//!
//! Figures are printed: `cargo test --release --test analysis_linear -- --nocapture`.

mod analysis_support;
mod cli_support;
#[allow(dead_code)] // only part of it is used here
mod ground_support;
#[allow(dead_code)] // only part of it is used here
mod kkt_support;

use analysis_support::{amax, richardson};
use ground_support::{ground, icosahedron_over, CONTACT_DAMPING, STIFFNESS};
use kkt_support::Lcg;
use nalgebra::{DMatrix, DVector, Vector3};
use tensegrity_fmu::analysis::linear::{linearize, LinearModel};
use tensegrity_fmu::analysis::modes::{ModeKind, Spectrum};
use tensegrity_fmu::analysis::tangent::end_jacobian;
use tensegrity_fmu::analysis::{self, equilibrium, InputChannel, Tangent};
use tensegrity_fmu::dynamics::{self, Inputs, Workspace};
use tensegrity_fmu::fmi::variables::VariableTable;
use tensegrity_fmu::outputs::{self, OutputGroup};
use tensegrity_fmu::scene::{builtin, CableControl, GroundSpec, Scene, Start};
use tensegrity_fmu::sim::State;
use tensegrity_fmu::Simulation;

/// The FMU's input channels, named as the `linearize` command names them.
fn channels(sim: &Simulation) -> Vec<(String, InputChannel)> {
    VariableTable::new(sim).input_channels()
}

fn set_input(inputs: &mut Inputs, channel: InputChannel, delta: f64) {
    match channel {
        InputChannel::ForceDensity(k) => inputs.force_density[k] += delta,
        InputChannel::RestLength(k) => inputs.rest_length[k] += delta,
        InputChannel::NodeForce(k, axis) => inputs.node_force[k][axis] += delta,
    }
}

/// Largest entry of `a − b` relative to the largest of `b` (the finite differences).
fn rel_err(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    amax(&(a - b)) / amax(b).max(f64::MIN_POSITIVE)
}

/// Checks `A`, `B`, `C`, `D` of `linearize` at `sim`'s state against finite differences.
fn check_linear_model(sim: &Simulation) -> LinearModel {
    let name = &sim.model().scene.name;
    let model = sim.model();
    let chans = channels(sim);
    let outs = outputs::outputs(sim);
    let lin = linearize(sim, &chans, &outs);
    let y0 = sim.state().y.clone();
    let n = y0.len() / 2;
    let (q0, v0) = y0.split_at(n);
    let spectrum = Spectrum::new(model, &sim.inputs, sim.time(), q0);
    let phi = spectrum.shapes();
    let (m, nu) = (phi.ncols(), chans.len());
    assert_eq!(lin.a.shape(), (2 * m, 2 * m));
    assert_eq!(lin.b.shape(), (2 * m, nu));
    assert_eq!(lin.c.shape(), (outs.len(), 2 * m));
    assert_eq!(lin.states[m], "mode[1].rate");
    let phi_svd = phi.clone().svd(true, true);
    // Modal accelerations of the nonlinear model at a state and inputs.
    let mut ws = Workspace::new(model);
    let mut leak = 0.0f64;
    let mut modal = |q: &[f64], v: &[f64], inputs: &Inputs| {
        let mut acc = vec![0.0; n];
        dynamics::accelerations(model, inputs, sim.time(), q, v, &mut ws, &mut acc);
        DVector::from_vec(acc)
    };
    let shifted = |base: &[f64], k: usize, d: f64| -> Vec<f64> {
        base.iter()
            .enumerate()
            .map(|(i, x)| x + d * phi[(i, k)])
            .collect()
    };
    let mut a_fd = DMatrix::zeros(2 * m, 2 * m);
    a_fd.view_mut((0, m), (m, m))
        .copy_from(&DMatrix::identity(m, m));
    let mut b_fd = DMatrix::zeros(2 * m, nu);
    let mut columns = Vec::new();
    for k in 0..m {
        let dq = richardson(1e-4, |d| modal(&shifted(q0, k, d), v0, &sim.inputs));
        let dv = richardson(1e-4, |d| modal(q0, &shifted(v0, k, d), &sim.inputs));
        columns.push((k, dq));
        columns.push((m + k, dv));
    }
    for (col, &(_, channel)) in chans.iter().enumerate() {
        let d = richardson(1e-4, |h| {
            let mut inputs = sim.inputs.clone();
            set_input(&mut inputs, channel, h);
            modal(q0, v0, &inputs)
        });
        columns.push((2 * m + col, d));
    }
    let scale = columns.iter().fold(0.0f64, |s, (_, d)| s.max(d.amax()));
    for (col, d) in columns {
        let xi = phi_svd.solve(&d, 1e-12).expect("least squares");
        leak = leak.max((&d - &phi * &xi).amax() / scale);
        if col < 2 * m {
            a_fd.view_mut((m, col), (m, 1)).copy_from(&xi);
        } else {
            b_fd.view_mut((m, col - 2 * m), (m, 1)).copy_from(&xi);
        }
    }
    let (err_a, err_b) = (rel_err(&lin.a, &a_fd), rel_err(&lin.b, &b_fd));
    println!(
        "{name}: {m} modes, {nu} inputs; δη̈₂ outside the mode span {leak:.1e}; \
         |A − A_fd| {err_a:.1e}, |B − B_fd| {err_b:.1e} (relative to the largest entry)"
    );
    assert!(
        leak <= 1e-7,
        "{name}: accelerations leave the tangent space"
    );
    assert!(err_a <= 1e-7, "{name}: A disagrees");
    assert!(err_b <= 1e-7, "{name}: B disagrees");
    assert!(amax(&lin.b) > 0.0);

    // C and D: the outputs of a simulation set to the perturbed state.
    let analytic: Vec<usize> = (0..outs.len())
        .filter(|&r| {
            matches!(
                outs[r].quantity.group(),
                OutputGroup::Positions
                    | OutputGroup::Velocities
                    | OutputGroup::Tensions
                    | OutputGroup::BarForces
            )
        })
        .collect();
    let mut probe = sim.clone();
    let mut values = |y: Vec<f64>, inputs: &Inputs| {
        probe.inputs.clone_from(inputs);
        probe.set_state(State {
            time: sim.time(),
            y,
        });
        probe.refresh();
        DVector::from_iterator(
            analytic.len(),
            analytic.iter().map(|&r| outs[r].quantity.value(&probe)),
        )
    };
    let mut c_fd = DMatrix::zeros(analytic.len(), 2 * m);
    let mut d_fd = DMatrix::zeros(analytic.len(), nu);
    for k in 0..2 * m {
        let (offset, mode) = if k < m { (0, k) } else { (n, k - m) };
        let col = richardson(1e-4, |d| {
            let mut y = y0.clone();
            for i in 0..n {
                y[offset + i] += d * phi[(i, mode)];
            }
            values(y, &sim.inputs)
        });
        c_fd.set_column(k, &col);
    }
    for (col, &(_, channel)) in chans.iter().enumerate() {
        let d = richardson(1e-4, |h| {
            let mut inputs = sim.inputs.clone();
            set_input(&mut inputs, channel, h);
            values(y0.clone(), &inputs)
        });
        d_fd.set_column(col, &d);
    }
    let c = DMatrix::from_fn(analytic.len(), 2 * m, |r, k| lin.c[(analytic[r], k)]);
    let d = DMatrix::from_fn(analytic.len(), nu, |r, k| lin.d[(analytic[r], k)]);
    for group in [
        OutputGroup::Positions,
        OutputGroup::Velocities,
        OutputGroup::Tensions,
        OutputGroup::BarForces,
    ] {
        let rows: Vec<usize> = (0..analytic.len())
            .filter(|&r| outs[analytic[r]].quantity.group() == group)
            .collect();
        let pick =
            |m: &DMatrix<f64>| DMatrix::from_fn(rows.len(), m.ncols(), |r, k| m[(rows[r], k)]);
        let (err_c, err_d) = (
            rel_err(&pick(&c), &pick(&c_fd)),
            rel_err(&pick(&d), &pick(&d_fd)),
        );
        println!(
            "{name}: {group:?}: {} rows; |C − C_fd| {err_c:.1e} (largest {:.2e}), \
             |D − D_fd| {err_d:.1e} (largest {:.2e})",
            rows.len(),
            amax(&pick(&c_fd)),
            amax(&pick(&d_fd))
        );
        assert!(amax(&pick(&c_fd)) > 0.0, "{name}: {group:?} rows are empty");
        assert!(err_c <= 1e-7, "{name}: C rows of {group:?} disagree");
        assert!(err_d <= 1e-7, "{name}: D rows of {group:?} disagree");
    }
    lin
}

fn at_rest(scene: &Scene) -> Simulation {
    let mut sim = Simulation::new(analysis::load(scene).expect("scene loads"));
    analysis::require_rest(&sim, "test").expect("at rest");
    sim.refresh();
    sim
}

#[test]
fn linear_model_prism2_force_density_and_node_force_inputs() {
    let lin = check_linear_model(&at_rest(&builtin("prism2").unwrap()));
    assert_eq!(lin.inputs.len(), 15 + 9);
    // Tensions of controlled cables depend on their force density directly: D = |s_j|.
    let row = lin.outputs.iter().position(|o| o == "cable[1].tension");
    let col = lin
        .inputs
        .iter()
        .position(|i| i == "cable[1].force_density");
    assert!(lin.d[(row.unwrap(), col.unwrap())] > 0.1);
}

/// prism2-elastic with damped cables, the six diagonal cables reeled (rest-length inputs).
#[test]
fn linear_model_damped_reeled_prism2() {
    let mut scene = builtin("prism2-elastic").unwrap();
    scene.name = "damped reeled prism2-elastic".into();
    for (j, cable) in scene.cables.iter_mut().enumerate() {
        cable.damping = Some(3.0);
        if j >= 9 {
            cable.control = Some(CableControl::RestLength);
        }
    }
    let lin = check_linear_model(&at_rest(&scene));
    assert_eq!(lin.inputs.len(), 6 + 9);
    let m = lin.states.len() / 2;
    assert!(
        amax(&lin.a.view((m, m), (m, m)).into_owned()) > 1.0,
        "no damping"
    );
}

/// The free icosahedron under gravity settled on a ground with friction (start =
/// "equilibrium"): contact stiffness, the viscous friction at rest in A's rate block.
#[test]
fn linear_model_icosahedron_settled_on_ground() {
    // On a cable face, three contacts (tests/ground_support), written exactly onto the
    // surface: rounding leaves nodes within 1e-16 m above it, which still count as touching.
    let friction = ground(Vector3::z(), STIFFNESS, CONTACT_DAMPING, 0.5);
    let mut scene = icosahedron_over(friction, 0.0, None);
    scene.name = "icosahedron on a ground".into();
    scene.force_inputs = vec![2];
    scene.start = Start::Equilibrium;
    let sim = at_rest(&scene);
    let y = &sim.state().y;
    let spectrum = Spectrum::new(sim.model(), &sim.inputs, 0.0, &y[..y.len() / 2]);
    println!(
        "icosahedron on a ground: {} rigid-body modes, frequencies {:?}",
        spectrum.count(ModeKind::RigidBody),
        &spectrum.frequencies_hz()[..8]
    );
    let lin = check_linear_model(&sim);
    let m = lin.states.len() / 2;
    assert!(
        amax(&lin.a.view((m, m), (m, m)).into_owned()) > 1.0,
        "no friction"
    );
}

// ---------------------------------------------------------------- the force tangent

/// `∂f/∂q` and `∂f/∂q̇` of `Tangent` against central differences of `Tangent::force` at
/// `(q, v)`; returns the relative errors.
fn check_tangent(name: &str, model: &tensegrity_fmu::Model, inputs: &Inputs, q: &[f64], v: &[f64]) {
    let tangent = Tangent::new(model, inputs, 0.0, q, v);
    let n = q.len();
    let force = |q: &[f64], v: &[f64]| Tangent::new(model, inputs, 0.0, q, v).force;
    let shifted = |x: &[f64], k: usize, d: f64| {
        let mut x = x.to_vec();
        x[k] += d;
        x
    };
    let mut k_fd = DMatrix::zeros(n, n);
    let mut c_fd = DMatrix::zeros(n, n);
    for k in 0..n {
        k_fd.set_column(k, &richardson(1e-6, |d| force(&shifted(q, k, d), v)));
        c_fd.set_column(k, &richardson(1e-6, |d| force(q, &shifted(v, k, d))));
    }
    let (ek, ec) = (
        rel_err(&tangent.stiffness, &k_fd),
        rel_err(&tangent.damping, &c_fd),
    );
    println!(
        "{name}: |∂f/∂q − FD| {ek:.1e} of {:.2e}, |∂f/∂q̇ − FD| {ec:.1e} of {:.2e}",
        amax(&k_fd),
        amax(&c_fd)
    );
    assert!(ek <= 1e-8, "{name}: stiffness disagrees");
    assert!(ec <= 1e-8, "{name}: damping disagrees");
}

/// The free icosahedron, two nodes 1 mm into a ground with friction — one sliding below
/// the slip velocity (viscous branch), one above (Coulomb branch) — damped cables, three
/// force-density cables, gravity, and every node moving.
#[test]
fn force_tangent_matches_differences_with_contact_and_friction() {
    let mut scene = builtin("icosahedron").unwrap();
    scene.fixed.clear();
    scene.force_inputs.clear();
    scene.gravity = Some([0.0, 0.0, -9.81]);
    for (j, cable) in scene.cables.iter_mut().enumerate() {
        if j < 3 {
            cable.control = Some(CableControl::ForceDensity);
            cable.stiffness = None;
        } else {
            cable.damping = Some(4.0);
        }
    }
    let lowest = scene
        .nodes
        .iter()
        .map(|p| p[2])
        .fold(f64::INFINITY, f64::min);
    let slip = 0.01;
    scene.ground = Some(GroundSpec {
        height: lowest + 1e-3,
        normal: [0.0, 0.0, 1.0],
        stiffness: 1e4,
        damping: 100.0,
        friction: 0.6,
        slip_velocity: slip,
    });
    let model = analysis::load(&scene).unwrap();
    let ground = model.ground.clone().unwrap();
    let contacts: Vec<usize> = ground
        .nodes
        .iter()
        .map(|&(n, _)| n)
        .filter(|&n| model.positions[n].z < ground.height)
        .collect();
    assert_eq!(contacts.len(), 2, "two nodes in contact");
    // End velocities: random, then the contacts' set to a slow and a fast slide.
    let mut rng = Lcg(7);
    let mut ends = DVector::zeros(3 * model.coords.n_ends());
    for e in 0..model.coords.n_ends() {
        let node = model.coords.end_node[e];
        let v = match contacts.iter().position(|&c| c == node) {
            Some(0) => Vector3::new(0.004, -0.003, -0.01),
            Some(_) => Vector3::new(0.2, -0.1, 0.02),
            None => rng.vec3(0.3),
        };
        ends.fixed_rows_mut::<3>(3 * e).copy_from(&v);
    }
    let je = end_jacobian(&model);
    let v = je.clone().svd(true, true).solve(&ends, 1e-12).unwrap();
    assert!(
        (&je * &v - &ends).amax() <= 1e-12,
        "end velocities are reachable"
    );
    let q = equilibrium::reduced_positions(&model);
    let mut inputs = Inputs::start(&model);
    inputs.force_density.iter_mut().for_each(|g| *g *= 1.3);
    let tangent = Tangent::new(&model, &inputs, 0.0, &q, v.as_slice());
    let ws = &tangent.workspace;
    for (k, &n) in contacts.iter().enumerate() {
        let vel = ws.node_vel[n];
        let f = ws.contact_force[ground.nodes.iter().position(|&(m, _)| m == n).unwrap()];
        let vt = (vel - ground.normal * ground.normal.dot(&vel)).norm();
        println!(
            "contact at node {}: |v_t| = {vt:.4} m/s (slip {slip}), force {f:?}",
            n + 1
        );
        assert!(f.z > 1.0 && (vt < slip) == (k == 0));
    }
    let taut = ws.gamma.iter().filter(|&&g| g > 0.0).count();
    assert_eq!(taut, model.cables.len(), "every cable taut");
    check_tangent(
        "icosahedron on a ground, moving",
        &model,
        &inputs,
        &q,
        v.as_slice(),
    );
}

/// A class-2 tower (joints and pins: the reactions drop out of J_eᵀ F) with damped and
/// force-density cables at a perturbed, moving state.
#[test]
fn force_tangent_matches_differences_class2_tower() {
    let mut scene = tensegrity_fmu::scene::tower_scene(3, Some(500.0), "tower3");
    for (j, cable) in scene.cables.iter_mut().enumerate() {
        if j % 4 == 0 {
            cable.control = Some(CableControl::ForceDensity);
            cable.stiffness = None;
        } else {
            cable.damping = Some(2.0);
        }
    }
    let model = analysis::load(&scene).unwrap();
    let mut rng = Lcg(11);
    let q: Vec<f64> = equilibrium::reduced_positions(&model)
        .iter()
        .map(|x| x + rng.range(-0.01, 0.01))
        .collect();
    let v: Vec<f64> = q.iter().map(|_| rng.range(-0.3, 0.3)).collect();
    let inputs = Inputs::start(&model);
    check_tangent("tower3, moving", &model, &inputs, &q, &v);
}

// ---------------------------------------------------------------------------- CLI

#[test]
fn linearize_command_writes_the_model() {
    let path = cli_support::temp("prism2.json");
    let (ok, out, err) = cli_support::run(&["linearize", "prism2", "-o", path.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(out.contains("prism2.json"));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let sim = at_rest(&builtin("prism2").unwrap());
    let lin = linearize(&sim, &channels(&sim), &outputs::outputs(&sim));
    for (key, m) in [("A", &lin.a), ("B", &lin.b), ("C", &lin.c), ("D", &lin.d)] {
        let rows = v[key].as_array().unwrap();
        assert_eq!(rows.len(), m.nrows(), "{key}");
        for (r, row) in rows.iter().enumerate() {
            for (c, x) in row.as_array().unwrap().iter().enumerate() {
                // serde_json's default parser may be off by an ulp.
                let (x, y) = (x.as_f64().unwrap(), m[(r, c)]);
                assert!(
                    (x - y).abs() <= 1e-15 * y.abs(),
                    "{key}[{r}][{c}]: {x} vs {y}"
                );
            }
        }
    }
    assert_eq!(v["states"].as_array().unwrap().len(), 24);
    assert_eq!(v["inputs"][0], lin.inputs[0]);
}

/// A force-density cable commanded at exactly 0 still acts for a positive command: its B
/// column and its tension's D entry are those of the clamp's right side, equal to the
/// model's at a start of 1e-12 N/m (where the law is smooth).
#[test]
fn a_force_density_commanded_at_zero_still_acts() {
    let with_extra = |start: f64| {
        let mut scene = builtin("prism2").unwrap();
        let mut extra = scene.cables[0].clone();
        extra.nodes = [1, 5];
        extra.force_density = Some(start);
        scene.prestress = None;
        let model = analysis::load(&builtin("prism2").unwrap()).unwrap();
        for (spec, &gamma) in scene.cables.iter_mut().zip(&model.controlled_start) {
            spec.force_density = Some(gamma);
        }
        scene.cables.push(extra);
        let sim = at_rest(&scene);
        let outputs = outputs::outputs(&sim);
        linearize(&sim, &channels(&sim), &outputs)
    };
    let (zero, tiny) = (with_extra(0.0), with_extra(1e-12));
    let col = zero
        .inputs
        .iter()
        .position(|i| i == "cable[16].force_density")
        .unwrap();
    let row = zero
        .outputs
        .iter()
        .position(|o| o == "cable[16].tension")
        .unwrap();
    // Node accelerations per unit command (independent of how repeated modes are split).
    let node_response = |lin: &LinearModel| {
        let m = lin.states.len() / 2;
        let pos: Vec<usize> = (0..lin.outputs.len())
            .filter(|&r| lin.outputs[r].starts_with("node[") && !lin.outputs[r].contains(".v"))
            .collect();
        let c = DMatrix::from_fn(pos.len(), m, |r, k| lin.c[(pos[r], k)]);
        c * lin.b.view((m, col), (m, 1))
    };
    let (r0, r1) = (node_response(&zero), node_response(&tiny));
    let b0 = r0.norm();
    let diff = (&r0 - &r1).norm();
    println!(
        "cable[16] at 0: node accelerations per N/m {b0:.4e} m/s², vs at 1e-12 N/m {diff:.1e}; D {:.6}",
        zero.d[(row, col)]
    );
    assert!(b0 > 0.1, "the command acts: {b0}");
    // The two models' spectra agree to round-off of the eigensolver (1e-9 measured).
    assert!(diff <= 1e-7 * b0, "{diff:e}");
    let s = (Vector3::from(builtin("prism2").unwrap().nodes[4])
        - Vector3::from(builtin("prism2").unwrap().nodes[0]))
    .norm();
    assert!((zero.d[(row, col)] - s).abs() < 1e-12, "D = |s| = {s}");
}
