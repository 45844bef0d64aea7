//! The stiff method (`solver.method = "sdirk3"`): the exact acceleration Jacobian it uses
//! against differences of the nonlinear accelerations, its third order, and steel cables
//! (κ = 1e7 N/m) under gravity and a slow load at a 1 ms controller step against a tight
//! reference. Figures are printed (run with `--nocapture`).

use std::time::Instant;

use nalgebra::Vector3;
use tensegrity_fmu::analysis;
use tensegrity_fmu::dynamics::tangent::Tangent;
use tensegrity_fmu::dynamics::{self, Inputs, Workspace};
use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::scene::{builtin, steel_prism_scene, LoadSpec, Scene};
use tensegrity_fmu::sim::stability_limit;
use tensegrity_fmu::Simulation;

/// prism2-elastic with damped cables, under gravity, at a moving state off the
/// constraint manifold: the Jacobian must hold there too (an implicit stage is off it).
#[test]
fn acceleration_jacobian_matches_differences_off_the_manifold() {
    let mut scene = builtin("prism2-elastic").unwrap();
    scene.gravity = Some([0.0, 0.0, -9.81]);
    for cable in &mut scene.cables {
        cable.damping = Some(3.0);
    }
    let model = analysis::load(&scene).unwrap();
    let inputs = Inputs::start(&model);
    let n = 3 * model.coords.r;
    let q: Vec<f64> = analysis::equilibrium::reduced_positions(&model)
        .iter()
        .enumerate()
        .map(|(i, x)| x + 0.01 * ((i as f64 * 1.7).sin()))
        .collect();
    let v: Vec<f64> = (0..n).map(|i| 0.3 * (i as f64 * 0.9).cos()).collect();
    let (jq, jv) = Tangent::new(&model, &inputs, 0.0, &q, &v).acceleration_jacobian(&v);
    let mut ws = Workspace::new(&model);
    let mut acc = |q: &[f64], v: &[f64]| {
        let mut a = vec![0.0; n];
        dynamics::accelerations(&model, &inputs, 0.0, q, v, &mut ws, &mut a);
        a
    };
    let h = 1e-6;
    let (mut err_q, mut err_v, mut size_q, mut size_v) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for k in 0..n {
        let shifted = |x: &[f64], d: f64| {
            let mut y = x.to_vec();
            y[k] += d;
            y
        };
        let (ap, am) = (acc(&shifted(&q, h), &v), acc(&shifted(&q, -h), &v));
        let (bp, bm) = (acc(&q, &shifted(&v, h)), acc(&q, &shifted(&v, -h)));
        for i in 0..n {
            let fd_q = (ap[i] - am[i]) / (2.0 * h);
            let fd_v = (bp[i] - bm[i]) / (2.0 * h);
            err_q = err_q.max((jq[(i, k)] - fd_q).abs());
            err_v = err_v.max((jv[(i, k)] - fd_v).abs());
            size_q = size_q.max(fd_q.abs());
            size_v = size_v.max(fd_v.abs());
        }
    }
    println!(
        "∂a/∂q: {:.1e} of {size_q:.3e}; ∂a/∂v: {:.1e} of {size_v:.3e}",
        err_q / size_q,
        err_v / size_v
    );
    assert!(err_q <= 1e-7 * size_q && err_v <= 1e-7 * size_v);
}

fn with_method(mut scene: Scene, method: Method, h: f64, tol: f64) -> Scene {
    scene.solver.method = method;
    scene.solver.step_size = h;
    scene.solver.rtol = tol;
    scene.solver.atol = tol;
    scene.solver.max_steps = 10_000_000;
    scene
}

/// Node positions at every 0.1 s up to `time`, and the wall time, s.
fn run(scene: &Scene, time: f64) -> (Vec<Vec<Vector3<f64>>>, f64, f64) {
    let mut sim = Simulation::new(analysis::load(scene).expect("scene loads"));
    sim.guard_stability = false;
    let started = Instant::now();
    let mut samples = Vec::new();
    let mut worst_length = 0.0f64;
    for k in 1..=(time * 10.0).round() as usize {
        sim.advance_to(k as f64 * 0.1).expect("runs");
        sim.refresh();
        worst_length = worst_length.max(sim.length_error());
        samples.push(
            (0..sim.model().n_nodes())
                .map(|n| sim.node_position(n))
                .collect(),
        );
    }
    (samples, started.elapsed().as_secs_f64(), worst_length)
}

fn max_difference(a: &[Vec<Vector3<f64>>], b: &[Vec<Vector3<f64>>]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| (p - q).norm()))
        .fold(0.0, f64::max)
}

#[test]
fn steel_cables_at_a_controller_step() {
    let scene = steel_prism_scene();
    let (reference, t_ref, _) = run(
        &with_method(scene.clone(), Method::Dopri5, 1e-4, 1e-11),
        2.0,
    );
    let (stiff, t_stiff, length) =
        run(&with_method(scene.clone(), Method::Sdirk3, 1e-3, 1e-6), 2.0);
    let (dopri, t_dopri, _) = run(&with_method(scene.clone(), Method::Dopri5, 1e-4, 1e-6), 2.0);
    // rk4 at 90 % of its stability limit 2√2/ω for this structure.
    let omega = Simulation::new(analysis::load(&scene).unwrap()).max_frequency();
    let h_rk4 = 0.9 * stability_limit(Method::Rk4).unwrap() / omega;
    let (rk4, t_rk4, _) = run(&with_method(scene.clone(), Method::Rk4, h_rk4, 1e-6), 2.0);
    let e_rk4 = max_difference(&rk4, &reference);
    println!("steel prism: fastest mode ω = {omega:.4e} 1/s; rk4 at h = {h_rk4:.3e} s: error {e_rk4:.2e} m, {t_rk4:.3} s");
    let swing = max_difference(&reference, &vec![reference[0].clone(); reference.len()]);
    let (e_stiff, e_dopri) = (
        max_difference(&stiff, &reference),
        max_difference(&dopri, &reference),
    );
    println!(
        "steel prism, 2 s (node 7 sways {swing:.3e} m): sdirk3 at 1 ms: error {e_stiff:.2e} m, \
         {t_stiff:.3} s, bar lengths within {length:.1e} m; dopri5 rtol 1e-6: error {e_dopri:.2e} m, \
         {t_dopri:.3} s; reference (dopri5 1e-11) {t_ref:.3} s"
    );
    assert!(swing > 1e-3, "the load moves the structure ({swing:e} m)");
    assert!(e_stiff <= 1e-4, "sdirk3 error {e_stiff:e} m");
    assert!(length <= 1e-12, "bar lengths {length:e} m");
}

#[test]
fn third_order_on_a_smooth_run() {
    let mut scene = builtin("prism2-elastic").unwrap();
    scene.loads = vec![LoadSpec::Sinusoidal {
        node: 7,
        amplitude: [5.0, 0.0, 0.0],
        frequency: 2.0,
        phase: 0.0,
    }];
    let reference = run(
        &with_method(scene.clone(), Method::Dopri5, 1e-4, 1e-12),
        1.0,
    )
    .0;
    let errors: Vec<f64> = [4e-3, 2e-3, 1e-3]
        .iter()
        .map(|&h| {
            max_difference(
                &run(&with_method(scene.clone(), Method::Sdirk3, h, 1e-6), 1.0).0,
                &reference,
            )
        })
        .collect();
    let orders: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    println!("sdirk3 errors at 4, 2, 1 ms: {errors:?}; observed orders {orders:?}");
    for p in orders {
        assert!(p > 2.7 && p < 3.5, "order {p}");
    }
}
