//! Terrain contact against closed forms: a bar resting across two boxes, a bar tipping over
//! a box's edge as the lever says, a body sliding down a steep plane, and a heightfield
//! that is a plane giving the plane's trajectory.

mod terrain_support;

use nalgebra::Vector3;
use tensegrity_fmu::{Scene, Simulation};
use terrain_support::{prism_on_slope, sim, G};

/// A single bar of mass `m` from `a` to `b` with radius `r` and gravity, then `terrain`.
fn bar_scene(a: [f64; 3], b: [f64; 3], m: f64, r: f64, rest: &str) -> String {
    format!(
        "name = \"bar\"\nnodes = [{a:?}, {b:?}]\n\
         bars = [{{ nodes = [1, 2], mass = {m}, radius = {r} }}]\n\
         gravity = [0.0, 0.0, -{G}]\n{rest}"
    )
}

fn terrain_box(center: [f64; 3], size: [f64; 3], k: f64, c: f64, mu: f64) -> String {
    format!(
        "[[terrain]]\nkind = \"box\"\ncenter = {center:?}\nsize = {size:?}\n\
         stiffness = {k}\ndamping = {c}\nfriction = {mu}\n"
    )
}

#[test]
fn a_bar_across_two_boxes_rests_at_box_top_plus_radius() {
    let (m, r, k, top) = (2.0, 0.05, 1e5, 0.5);
    let boxes = terrain_box([-0.6, 0.0, 0.25], [0.4, 1.0, 0.5], k, 400.0, 0.5)
        + &terrain_box([0.6, 0.0, 0.25], [0.4, 1.0, 0.5], k, 400.0, 0.5);
    let mut s = sim(&bar_scene([-1.0, 0.0, 0.6], [1.0, 0.0, 0.6], m, r, &boxes));
    s.advance_to(3.0).unwrap();
    s.refresh();
    // The ends overhang both boxes: the bar rests on the four edges it crosses, each
    // carrying a quarter of its weight at a depth of m g / (4 k).
    let expected = top + r - m * G / (4.0 * k);
    for n in 0..2 {
        let z = s.node_position(n).z;
        assert!(
            (z - expected).abs() < 1e-7,
            "node {}: z = {z}, expected {expected}",
            n + 1
        );
    }
    for shape in 0..2 {
        let load = s.shape_load(shape);
        assert_eq!(
            load.contacts,
            2,
            "box {} touches at its two edges",
            shape + 1
        );
        assert!(
            (load.force.z - m * G / 2.0).abs() < 1e-6,
            "{:?}",
            load.force
        );
    }
}

/// The angle of the bar below the horizontal (positive: node 2 lower), rad.
fn tilt(s: &Simulation) -> f64 {
    let d = s.node_position(1) - s.node_position(0);
    (-d.z).atan2(d.xy().norm())
}

#[test]
fn a_bar_on_a_box_edge_tips_the_way_the_lever_says() {
    // A box whose top edge runs along y at x = 0, z = 0.5; a bar of length 1 lies on it,
    // its capsule touching the edge and the top face at its left end.
    let (m, r, k, c) = (1.0, 0.02, 1e6, 2000.0);
    let edge = terrain_box([-0.5, 0.0, 0.25], [1.0, 1.0, 0.5], k, c, 1.0);
    let z = 0.5 + r;
    // Centre of mass d = 0.2 m beyond the edge: the bar turns about the edge with
    // α = m g d / (m L²/12 + m d²), so θ(t) = α t²/2 while the angle is small.
    let d = 0.2;
    let mut over = sim(&bar_scene(
        [d - 0.5, 0.0, z],
        [d + 0.5, 0.0, z],
        m,
        r,
        &edge,
    ));
    let alpha = G * d / (1.0 / 12.0 + d * d);
    let t = 0.1;
    over.advance_to(t).unwrap();
    let expected = 0.5 * alpha * t * t;
    let theta = tilt(&over);
    println!("tipping: θ({t}) = {theta:.6} rad, lever {expected:.6} rad");
    assert!(
        over.node_position(0).z > z + 0.01,
        "the end on the box lifts"
    );
    assert!(
        (theta - expected).abs() < 0.01 * expected,
        "θ = {theta}, lever {expected}"
    );
    // Centre of mass 0.2 m short of the edge: the bar rests on its end and the edge.
    let mut short = sim(&bar_scene(
        [-d - 0.5, 0.0, z],
        [-d + 0.5, 0.0, z],
        m,
        r,
        &edge,
    ));
    short.advance_to(1.0).unwrap();
    let theta = tilt(&short);
    println!("resting: θ(1) = {theta:.3e} rad");
    assert!(theta.abs() < 1e-4, "θ = {theta}");
    assert!((short.node_position(0).z - z).abs() < 1e-4);
}

#[test]
fn a_prism_slides_down_a_steep_plane_at_g_sin_minus_mu_cos() {
    let (theta, mu) = (30f64.to_radians(), 0.3);
    let mut s = prism_on_slope(theta, mu, false, "");
    let mass = 3.0;
    let downhill = Vector3::new(-theta.cos(), 0.0, -theta.sin());
    let speed = |s: &mut Simulation| {
        s.refresh();
        s.linear_momentum().dot(&downhill) / mass
    };
    let (t1, t2) = (0.3, 0.8);
    s.advance_to(t1).unwrap();
    let v1 = speed(&mut s);
    s.advance_to(t2).unwrap();
    let v2 = speed(&mut s);
    let a = (v2 - v1) / (t2 - t1);
    let expected = G * (theta.sin() - mu * theta.cos());
    println!("sliding: a = {a:.5} m/s², g (sin θ − μ cos θ) = {expected:.5} m/s²");
    assert!(
        (a - expected).abs() < 0.02 * expected,
        "a = {a}, expected {expected}"
    );
}

#[test]
fn a_heightfield_that_is_a_plane_gives_the_plane_s_trajectory() {
    let (theta, mu) = (20f64.to_radians(), 0.2);
    let mut plane = prism_on_slope(theta, mu, false, "");
    let mut field = prism_on_slope(theta, mu, true, "");
    let mut worst: f64 = 0.0;
    for step in 1..=10 {
        let t = 0.1 * f64::from(step);
        plane.advance_to(t).unwrap();
        field.advance_to(t).unwrap();
        for n in 0..6 {
            worst = worst.max((plane.node_position(n) - field.node_position(n)).norm());
        }
    }
    let moved = (plane.node_position(0) - field.model().positions[0]).norm();
    println!("heightfield vs plane: {worst:.3e} m apart after sliding {moved:.3} m");
    assert!(moved > 0.1, "the prism slides: {moved} m");
    assert!(worst < 1e-9, "{worst} m apart");
}

#[test]
fn a_too_long_step_names_the_terrain_contact_that_limits_it() {
    let stiff = terrain_box([0.0, 0.0, 0.25], [2.0, 1.0, 0.5], 1e9, 0.0, 0.0);
    let text = bar_scene([-0.5, 0.0, 0.6], [0.5, 0.0, 0.6], 1.0, 0.05, &stiff)
        + "[solver]\nmethod = \"rk4\"\nstep_size = 1e-3\n";
    let mut s = sim(&text);
    let problem = s
        .stability_problem()
        .expect("1 ms is far too long for 1e9 N/m");
    println!("{problem}");
    // √(k w) with the end compliance w = 4/m of a 1 kg rod: 6.3e4 1/s; rk4's limit 2.83.
    assert!(problem.contains("ω ≈ 6.325e4 1/s"), "{problem}");
    assert!(
        problem.contains("terrain[1].stiffness = 1e9 N/m"),
        "{problem}"
    );
    // 10 % inside the limit: (0.9 · 2.828 / 1 ms)² / w = 1.62e6 N/m.
    assert!(
        problem.contains("terrain[1].stiffness ≤ 1.62e6 N/m"),
        "{problem}"
    );
}

/// Node positions after `time` of rk4 at steps of `h`, and the located events.
fn tipped_bar_run(h: f64, locate: bool, time: f64) -> (Vec<Vector3<f64>>, u64) {
    // A bar falling tilted onto a box's edge (its side lands first), frictionless and
    // undamped, so it lands, pivots, bounces and flies on.
    let edge = terrain_box([-0.5, 0.0, 0.25], [1.0, 1.0, 0.5], 1e4, 0.0, 0.0);
    let text = bar_scene([-0.3, 0.0, 0.66], [0.7, 0.0, 0.56], 1.0, 0.02, &edge);
    rk4_run(text, h, locate, time)
}

/// The bar of `text` after `time` of rk4 steps of `h`: its nodes and the located events.
fn rk4_run(text: String, h: f64, locate: bool, time: f64) -> (Vec<Vector3<f64>>, u64) {
    let text =
        text + &format!("[solver]\nmethod = \"rk4\"\nstep_size = {h}\nlocate_events = {locate}\n");
    let mut s = sim(&text);
    let steps = (time / h).round() as u64;
    for k in 0..steps {
        s.step_to(k as f64 * h, (k + 1) as f64 * h).unwrap();
    }
    (
        (0..2).map(|n| s.node_position(n)).collect(),
        s.stats().events,
    )
}

#[test]
fn a_landing_side_keeps_rk4_fourth_order() {
    let time = 0.3;
    let (reference, events) = tipped_bar_run(1e-5, true, time);
    println!("reference: {events} located events");
    assert!(events >= 2, "{events}: the side never landed and left");
    let mut errors = Vec::new();
    for h in [1e-3, 5e-4, 2.5e-4] {
        let (x, events) = tipped_bar_run(h, true, time);
        let e = (0..2)
            .map(|n| (x[n] - reference[n]).norm())
            .fold(0.0, f64::max);
        println!("rk4 {h:.2e} s: error {e:.3e} m, {events} events");
        errors.push(e);
    }
    let orders: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    println!("observed orders {orders:.2?}");
    for o in orders {
        assert!(o >= 3.3, "order {o:.2}");
    }
}

#[test]
fn a_heightfield_ridge_pushes_straight_up_and_its_border_extends_outward() {
    use tensegrity_fmu::contact::{Grid, Shape};
    // Heights 0, 1, 0 along x (a ridge at x = 1), two rows along y.
    let rows = vec![vec![0.0, 1.0, 0.0], vec![0.0, 1.0, 0.0]];
    let field = Shape::Heightfield(Grid::new([0.0, 0.0], [1.0, 1.0], &rows));
    let (phi, n) = field.distance(&Vector3::new(1.0, 0.5, 1.2)).unwrap();
    assert!((phi - 0.2).abs() < 1e-15, "{phi}");
    assert_eq!(
        n,
        Vector3::z(),
        "the ridge's normal is the mean of its two slopes"
    );
    // Inside a cell the normal is the cell's: slope +1 along x.
    let (_, n) = field.distance(&Vector3::new(0.5, 0.5, 1.0)).unwrap();
    assert!(
        (n - Vector3::new(-1.0, 0.0, 1.0) / 2f64.sqrt()).norm() < 1e-15,
        "{n}"
    );
    // Beyond the border (x = 3 > 2): the border height, flat across it.
    let (phi, n) = field.distance(&Vector3::new(3.0, 0.5, 0.3)).unwrap();
    assert!((phi - 0.3).abs() < 1e-15 && n == Vector3::z(), "{phi} {n}");
}

#[test]
fn collisions_need_a_bar_with_a_radius() {
    let text = bar_scene(
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        1.0,
        0.0,
        "collisions = { stiffness = 1e4 }\n",
    );
    let message = Scene::from_toml_str(&text)
        .unwrap()
        .validate()
        .unwrap_err()
        .to_string();
    assert!(
        message.starts_with("collisions: every bar has radius 0"),
        "{message}"
    );
    assert!(message.contains("bars[].radius"), "{message}");
}

#[test]
fn a_capsule_landing_on_the_ground_is_a_located_event() {
    // [ground] with a 5 cm capsule: the contact starts 5 cm above the plane, where the
    // node never reaches the plane itself.
    let ground = "[ground]\nstiffness = 1e4\n[solver]\nmethod = \"rk4\"\nstep_size = 1e-3\n";
    let mut s = sim(&bar_scene(
        [0.0, 0.0, 0.2],
        [0.6, 0.0, 0.4],
        1.0,
        0.05,
        ground,
    ));
    let mut lowest = f64::INFINITY;
    for k in 1..=300 {
        s.advance_to(1e-3 * f64::from(k)).unwrap();
        lowest = lowest.min(s.node_position(0).z);
    }
    println!("lowest node {lowest} m, {} events", s.stats().events);
    assert!(
        lowest > 0.0 && lowest < 0.05,
        "it lands on its capsule: {lowest}"
    );
    assert!(s.stats().events >= 1, "the landing was located");
}

/// Node positions after `time` of rk4 at `h` for a level bar (1 m, 2 cm capsule) dropped
/// from 4 cm above a plane, and the located events.
fn level_bar_run(h: f64, time: f64) -> (Vec<Vector3<f64>>, u64) {
    let plane = "[[terrain]]\nkind = \"plane\"\npoint = [0.0, 0.0, 0.0]\n\
                 stiffness = 1e4\ndamping = 0.0\nfriction = 0.0\n";
    let text = bar_scene([0.0, 0.0, 0.06], [1.0, 0.0, 0.06], 1.0, 0.02, plane);
    rk4_run(text, h, true, time)
}

#[test]
fn a_landing_from_beyond_the_margin_keeps_rk4_fourth_order() {
    // The bar starts farther from the plane (4 cm) than the terrain's marks reach (half
    // of a twentieth of its length): its ends are skipped as far until it has fallen
    // 2.5 cm, and the landing must still be found.
    let time = 0.15;
    let (reference, events) = level_bar_run(1e-5, time);
    assert!(events >= 2, "{events}: the ends never landed");
    let mut errors = Vec::new();
    for h in [1e-3, 5e-4, 2.5e-4] {
        let (x, events) = level_bar_run(h, time);
        let e = (0..2)
            .map(|n| (x[n] - reference[n]).norm())
            .fold(0.0, f64::max);
        println!("rk4 {h:.2e} s: error {e:.3e} m, {events} events");
        assert!(events >= 2, "{events}: the landing was not located");
        errors.push(e);
    }
    let orders: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    println!("observed orders {orders:.2?}");
    assert!(orders.iter().all(|&o| o >= 3.3), "orders {orders:.2?}");
}
