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
