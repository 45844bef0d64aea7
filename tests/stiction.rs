//! Friction that sticks (`friction_model = "stick_slip"`, the default) against Coulomb's
//! law: a prism holds on a slope below its friction angle, without creep, and slides at
//! `g (sin θ − μ cos θ)` above it; the regularised model, for contrast, creeps. Located
//! stick–slip switches keep rk4's error falling fast with the step.

mod terrain_support;

use nalgebra::Vector3;
use tensegrity_fmu::{Model, Scene, Simulation};
use terrain_support::{damped_prism_on_slope, G};

/// The prism's centre of mass, m.
fn centre(s: &Simulation) -> Vector3<f64> {
    (0..6).map(|n| s.node_position(n)).sum::<Vector3<f64>>() / 6.0
}

/// Cable damping that lets the prism's own vibration die out within seconds, N·s/m.
const CABLE_DAMPING: f64 = 300.0;

/// How far the prism's centre moves from 10 s (its vibration spent) to 20 s on a slope of
/// `theta`, m.
fn drift(theta: f64, mu: f64, extra: &str) -> f64 {
    let mut s = damped_prism_on_slope(theta, mu, false, extra, CABLE_DAMPING);
    s.advance_to(10.0).unwrap();
    let start = centre(&s);
    s.advance_to(20.0).unwrap();
    (centre(&s) - start).norm()
}

#[test]
fn a_prism_below_the_friction_angle_holds_without_creep() {
    let theta = 10f64.to_radians();
    let held = drift(theta, 0.5, "");
    let crept = drift(theta, 0.5, "friction_model = \"regularized\"\n");
    println!(
        "10° slope, μ 0.5, 10 s to 20 s: stick–slip moves {held:.3e} m, regularized {crept:.3e} m"
    );
    assert!(held < 1e-6, "held prism drifted {held} m");
    assert!(crept > 1e-2, "the regularised law creeps: {crept} m");
}

#[test]
fn just_below_the_friction_angle_it_holds_and_just_above_it_slides_as_coulomb_says() {
    let mu: f64 = 0.5;
    let below = (0.95 * mu).atan();
    let held = drift(below, mu, "");
    println!("tan θ = 0.95 μ: moves {held:.3e} m from 10 s to 20 s");
    assert!(held < 1e-6, "held prism drifted {held} m");
    for ratio in [1.05, 1.2, 2.0] {
        let theta = (ratio * mu).atan();
        let (a, expected) = slide(theta, mu, 2.0, 4.0);
        println!(
            "tan θ = {ratio} μ: a = {a:.5} m/s², g (sin θ − μ cos θ) = {expected:.5} ({:+.3} %)",
            100.0 * (a - expected) / expected
        );
        assert!(
            (a - expected).abs() < 0.02 * expected,
            "a = {a}, expected {expected}"
        );
    }
}

/// The prism's acceleration down a slope of `theta` (from its momentum at `t1` and `t2`)
/// and Coulomb's `g (sin θ − μ cos θ)`, m/s².
fn slide(theta: f64, mu: f64, t1: f64, t2: f64) -> (f64, f64) {
    let mut s = damped_prism_on_slope(theta, mu, false, "", CABLE_DAMPING);
    let downhill = Vector3::new(-theta.cos(), 0.0, -theta.sin());
    let speed = |s: &mut Simulation, t: f64| {
        s.advance_to(t).unwrap();
        s.refresh();
        s.linear_momentum().dot(&downhill) / 3.0
    };
    let (v1, v2) = (speed(&mut s, t1), speed(&mut s, t2));
    ((v2 - v1) / (t2 - t1), G * (theta.sin() - mu * theta.cos()))
}

/// A 2 kg bar (2 cm capsule) lying on the plane z = 0 (k = 1e5 N/m, c = 600 N·s/m, μ 0.5),
/// pushed sideways by 15 N sin(2π t) (half on each end): it sticks until the load passes
/// μ m g = 9.81 N at 0.1134 s, slides, stops at 0.535 s and sticks, slides back from 0.613 s.
/// Its first node after `time` s of rk4 at step `h`, and the events located.
fn pushed_bar(h: f64, locate: bool, time: f64) -> (Vector3<f64>, u64) {
    let (r, k) = (0.02, 1e5);
    let z = r - 2.0 * G / (2.0 * k);
    let load = |node: u32| {
        format!(
            "{{ kind = \"sinusoidal\", node = {node}, amplitude = [7.5, 0.0, 0.0], frequency = 1.0 }}"
        )
    };
    let text = format!(
        "name = \"pushed\"\nnodes = [[0.0, -0.5, {z:?}], [0.0, 0.5, {z:?}]]\n\
         bars = [{{ nodes = [1, 2], mass = 2.0, radius = {r} }}]\n\
         gravity = [0.0, 0.0, -{G}]\nloads = [{}, {}]\n\
         [solver]\nmethod = \"rk4\"\nstep_size = {h}\nlocate_events = {locate}\n\
         [[terrain]]\nkind = \"plane\"\npoint = [0.0, 0.0, 0.0]\n\
         stiffness = {k}\ndamping = 600.0\nfriction = 0.5\n",
        load(1),
        load(2)
    );
    let scene = Scene::from_toml_str(&text).unwrap();
    let mut s = Simulation::new(Model::new(&scene).unwrap());
    s.advance_to(time).unwrap();
    (s.node_position(0), s.stats().events)
}

#[test]
fn located_stick_slip_switches_keep_rk4_fourth_order() {
    let time = 1.0;
    let (reference, _) = pushed_bar(1.0 / 32000.0, true, time);
    let steps = [1.0 / 1000.0, 1.0 / 2000.0, 1.0 / 4000.0, 1.0 / 8000.0];
    let errors = |locate: bool| -> Vec<f64> {
        steps
            .iter()
            .map(|&h| (pushed_bar(h, locate, time).0 - reference).norm())
            .collect()
    };
    let (located, unlocated) = (errors(true), errors(false));
    let (_, events) = pushed_bar(1e-3, true, time);
    println!("errors located {located:?}, not located {unlocated:?}, {events} events");
    let orders: Vec<f64> = located.windows(2).map(|e| (e[0] / e[1]).log2()).collect();
    println!("observed orders located {orders:.2?}");
    assert_eq!(events, 3, "slip, stick, slip again");
    assert!(orders.iter().all(|&p| p > 3.5), "orders {orders:?}");
    assert!(
        unlocated[2] > 1e4 * located[2],
        "switching only at step ends costs orders: {unlocated:?} vs {located:?}"
    );
}

/// Coulomb's law for a block sliding at `v0` (m/s, along x) under a constant sideways
/// force `f` (N, along y) smaller than `μ m g`: `m v̇ = f ŷ − μ m g v̂` until it stops,
/// integrated here in the plane (rk4, 1 µs steps): where it stops, m, and when, s.
fn coulomb_stop(v0: f64, f: f64, m: f64, mu: f64) -> ([f64; 2], f64) {
    let accel = |v: [f64; 2]| {
        let s = v[0].hypot(v[1]);
        [-mu * G * v[0] / s, f / m - mu * G * v[1] / s]
    };
    let (mut x, mut v, mut t, h) = ([0.0; 2], [v0, 0.0], 0.0, 1e-6);
    // The speed falls at least at μ g − f / m: stop one step before it would vanish.
    while v[0].hypot(v[1]) > h * (mu * G + f / m) {
        let k1 = accel(v);
        let v2 = [v[0] + 0.5 * h * k1[0], v[1] + 0.5 * h * k1[1]];
        let k2 = accel(v2);
        let v3 = [v[0] + 0.5 * h * k2[0], v[1] + 0.5 * h * k2[1]];
        let k3 = accel(v3);
        let v4 = [v[0] + h * k3[0], v[1] + h * k3[1]];
        let k4 = accel(v4);
        for i in 0..2 {
            x[i] += h / 6.0 * (v[i] + 2.0 * v2[i] + 2.0 * v3[i] + v4[i]);
            v[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        t += h;
    }
    (x, t)
}

#[test]
fn a_sliding_bar_turned_by_a_sideways_load_follows_coulomb_and_stops() {
    // A 2 kg bar (along y) sliding sideways at 1 m/s on the plane (μ 0.5) with 6 N along
    // its axis: its velocity turns toward the load while friction brings it to rest, and
    // there, with 6 N < μ m g, it holds. Friction must turn with the velocity: the slip
    // anchors trail the ends by 0.1 mm (a ten-thousandth of the bar), and the bar must stop
    // within ten trails of Coulomb's point.
    let (m, mu, f, k, r) = (2.0, 0.5, 6.0, 1e5, 0.02);
    let z = r - G / k;
    let text = format!(
        "name = \"turned\"\nnodes = [[0.0, -0.5, {z:?}], [0.0, 0.5, {z:?}]]\n\
         velocities = [[1.0, 0.0, 0.0], [1.0, 0.0, 0.0]]\n\
         bars = [{{ nodes = [1, 2], mass = {m:?}, radius = {r} }}]\n\
         gravity = [0.0, 0.0, -{G}]\n\
         loads = [{{ kind = \"constant\", node = 1, force = [0.0, 3.0, 0.0] }},\n\
                  {{ kind = \"constant\", node = 2, force = [0.0, 3.0, 0.0] }}]\n\
         [solver]\nmethod = \"dopri5\"\nrtol = 1e-10\natol = 1e-10\n\
         [[terrain]]\nkind = \"plane\"\npoint = [0.0, 0.0, 0.0]\n\
         stiffness = {k:?}\ndamping = 600.0\nfriction = {mu}\n"
    );
    let mut s = terrain_support::sim(&text);
    let (stop, at) = coulomb_stop(1.0, f, m, mu);
    let centre = |s: &Simulation| (s.node_position(0) + s.node_position(1)) / 2.0;
    s.advance_to(at + 0.5).unwrap();
    let rest = centre(&s);
    s.advance_to(at + 1.5).unwrap();
    let held = (centre(&s) - rest).norm();
    let miss = (rest.x - stop[0]).hypot(rest.y - stop[1]);
    println!(
        "Coulomb stops at ({:.6}, {:.6}) m after {at:.4} s; the bar rests at ({:.6}, {:.6}) m \
         ({miss:.2e} m off), then moves {held:.2e} m in 1 s",
        stop[0], stop[1], rest.x, rest.y
    );
    assert!(stop[1] > 0.02, "the load turns the slide: {stop:?}");
    assert!(miss < 1e-3, "{miss} m from Coulomb's stop");
    assert!(held < 1e-9, "the stopped bar moved {held} m");
}

/// The icosahedron of fmu/scenes/icosahedron-step.toml with dopri5 at `tol`: its node
/// positions every 10 ms to `time`.
fn tumbling(tol: f64, time: f64) -> Vec<Vector3<f64>> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/fmu/scenes/icosahedron-step.toml"
    );
    let mut scene = Scene::from_file(std::path::Path::new(path)).expect("the shipped scene");
    scene.solver.method = tensegrity_fmu::integrator::Method::Dopri5;
    (scene.solver.rtol, scene.solver.atol) = (tol, tol);
    let mut s = Simulation::new(Model::new(&scene).unwrap());
    let mut out = Vec::new();
    for i in 1..=(time * 100.0).round() as usize {
        s.advance_to(i as f64 * 0.01).unwrap();
        out.extend((0..12).map(|n| s.node_position(n)));
    }
    out
}

#[test]
fn a_tumbling_structure_converges_as_the_tolerance_falls() {
    // The icosahedron lands on a box step, tips off its edge and slides onto the ground:
    // hundreds of located switches (onsets, stick, slip, dragged anchors). Every switch
    // keeps the force continuous or is located, so the run converges like a smooth one.
    let time = 0.6;
    let reference = tumbling(1e-12, time);
    let errors: Vec<f64> = [1e-9, 1e-10, 1e-11]
        .iter()
        .map(|&tol| {
            let x = tumbling(tol, time);
            x.iter()
                .zip(&reference)
                .map(|(a, b)| (a - b).norm())
                .fold(0.0, f64::max)
        })
        .collect();
    println!("dopri5 at 1e-9, 1e-10, 1e-11 against 1e-12: {errors:?} m");
    assert!(errors.windows(2).all(|e| e[1] < e[0] / 3.0), "{errors:?}");
    assert!(errors[2] < 1e-8, "{errors:?}");
}
