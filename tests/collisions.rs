//! Bar–bar contact: crossed bars resting on each other at the depth the stiffness gives,
//! joined bars never colliding, momentum kept in a collision, and the broad phase finding
//! exactly the pairs a brute-force search finds.

use nalgebra::Vector3;
use tensegrity_fmu::contact::segments::{capsule_bounds, closest_params, overlapping_pairs};
use tensegrity_fmu::{Model, Scene, Simulation};

const G: f64 = 9.81;

fn sim(toml: &str) -> Simulation {
    Simulation::new(Model::new(&Scene::from_toml_str(toml).unwrap()).unwrap())
}

#[test]
fn crossed_bars_rest_on_each_other_at_the_depth_the_stiffness_gives() {
    // A pinned bar along x; a free 1.5 kg bar along y lies across it, centred above it.
    let (m, ra, rb, k) = (1.5, 0.03, 0.02, 2e5);
    let z = ra + rb;
    let text = format!(
        "name = \"crossed\"\nnodes = [[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, -0.5, {z}], [0.0, 0.5, {z}]]\n\
         fixed = [1, 2]\n\
         bars = [{{ nodes = [1, 2], mass = 1.0, radius = {ra} }}, {{ nodes = [3, 4], mass = {m}, radius = {rb} }}]\n\
         gravity = [0.0, 0.0, -{G}]\n\
         collisions = {{ stiffness = {k}, damping = 300.0, friction = 0.5 }}\n"
    );
    let mut s = sim(&text);
    s.advance_to(2.0).unwrap();
    s.refresh();
    // One contact carries the whole weight: interpenetration m g / k.
    let depth = m * G / k;
    for n in 2..4 {
        let zn = s.node_position(n).z;
        assert!((zn - (z - depth)).abs() < 1e-8, "node {}: {zn}", n + 1);
    }
    let found = &s.workspace().collision;
    assert_eq!(found.contacts, 1);
    assert!(
        (found.max_penetration - depth).abs() < 1e-9,
        "{}",
        found.max_penetration
    );
}

#[test]
fn bars_that_share_a_node_never_collide() {
    // Two bars meeting at node 2 at a right angle, both wide: their capsules overlap near
    // the joint, but a joint is not a collision.
    let text = "name = \"joint\"\nnodes = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]]\n\
                bars = [{ nodes = [1, 2], mass = 1.0, radius = 0.1 }, { nodes = [2, 3], mass = 1.0, radius = 0.1 }]\n\
                collisions = { stiffness = 1e5 }\n";
    let mut s = sim(text);
    s.refresh();
    assert_eq!(s.workspace().collision.contacts, 0);
    for n in 0..3 {
        assert_eq!(s.node_acceleration(n), Vector3::zeros());
    }
}

#[test]
fn a_frictionless_collision_keeps_momentum_and_separates_the_bars() {
    // Two free bars in space, crossed at right angles, approaching each other along z.
    let (r, k) = (0.05, 1e5);
    let text = format!(
        "name = \"collide\"\nnodes = [[-0.5, 0.1, 0.0], [0.5, 0.1, 0.0], [0.2, -0.5, 0.3], [0.2, 0.5, 0.3]]\n\
         bars = [{{ nodes = [1, 2], mass = 1.0, radius = {r} }}, {{ nodes = [3, 4], mass = 2.0, radius = {r} }}]\n\
         velocities = [[0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.0, 0.0, -0.5], [0.0, 0.0, -0.5]]\n\
         collisions = {{ stiffness = {k} }}\n\
         [solver]\nrtol = 1e-10\natol = 1e-12\n"
    );
    let mut s = sim(&text);
    s.refresh();
    let (p0, l0, e0) = (s.linear_momentum(), s.angular_momentum(), s.energy());
    let mut touched = 0;
    for step in 1..=100 {
        s.advance_to(0.005 * f64::from(step)).unwrap();
        s.refresh();
        touched += s.workspace().collision.contacts;
    }
    let (p1, l1, e1) = (s.linear_momentum(), s.angular_momentum(), s.energy());
    println!(
        "momentum change {:.2e}, angular {:.2e}, energy {:.2e} J",
        (p1 - p0).norm(),
        (l1 - l0).norm(),
        e1 - e0
    );
    assert!(touched > 0, "they touch on the way");
    assert_eq!(s.workspace().collision.contacts, 0, "and part again");
    assert!((p1 - p0).norm() < 1e-9, "{p0} → {p1}");
    assert!((l1 - l0).norm() < 1e-9, "{l0} → {l1}");
    // Without damping or friction the penalty is elastic: the kinetic energy comes back.
    assert!((e1 - e0).abs() < 1e-6 * e0, "{e0} → {e1}");
    // The bars bounced: the lighter one's centre now moves down, the heavier one's up.
    let centre = |a: usize| 0.5 * (s.node_velocity(a) + s.node_velocity(a + 1)).z;
    assert!(
        centre(0) < 0.0 && centre(2) > 0.0,
        "{} {}",
        centre(0),
        centre(2)
    );
}

#[test]
fn the_broad_phase_finds_exactly_the_overlapping_pairs() {
    // A deterministic cloud of 400 capsules in a 4 m cube (sizes 0.1–0.6 m).
    let mut seed = 12345u64;
    let mut next = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut boxes = Vec::new();
    for _ in 0..400 {
        let a = Vector3::new(4.0 * next(), 4.0 * next(), 4.0 * next());
        let d = Vector3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 1.0;
        boxes.push(capsule_bounds(&a, &(a + d), 0.05 * next()));
    }
    let mut order: Vec<u32> = (0..400).rev().collect();
    let mut found = Vec::new();
    overlapping_pairs(&boxes, &mut order, |i, j| found.push((i, j)));
    let mut expected = Vec::new();
    for i in 0..400 {
        for j in i + 1..400 {
            if (0..3).all(|k| boxes[i][k][0] <= boxes[j][k][1] && boxes[j][k][0] <= boxes[i][k][1])
            {
                expected.push((i, j));
            }
        }
    }
    let mut sorted = found.clone();
    sorted.sort_unstable();
    assert!(expected.len() > 50, "{} pairs overlap", expected.len());
    assert_eq!(sorted, expected);
    // The same boxes from another starting order give the same calls in the same order.
    let mut again = Vec::new();
    let mut shuffled: Vec<u32> = (0..400).map(|i| (i * 7) % 400).collect();
    overlapping_pairs(&boxes, &mut shuffled, |i, j| again.push((i, j)));
    assert_eq!(again, found);
}

#[test]
fn closest_points_of_segments_match_a_dense_search() {
    let cases = [
        (
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.3, -1.0, 0.5],
            [0.3, 1.0, 0.5],
        ),
        (
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.5, 0.2, 0.0],
            [2.5, 1.0, 0.3],
        ),
        (
            [0.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.2, 0.0, 0.1],
            [1.2, 1.0, 0.1],
        ),
        (
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 2.0],
            [-1.0, 0.4, 3.0],
            [1.0, 0.4, 1.0],
        ),
    ];
    for (p1, q1, p2, q2) in cases {
        let [p1, q1, p2, q2] = [p1, q1, p2, q2].map(Vector3::from);
        let (s, t) = closest_params(&p1, &q1, &p2, &q2);
        let at = |s: f64, t: f64| ((p1 + (q1 - p1) * s) - (p2 + (q2 - p2) * t)).norm();
        let mut best = f64::INFINITY;
        for i in 0..=400 {
            for j in 0..=400 {
                best = best.min(at(f64::from(i) / 400.0, f64::from(j) / 400.0));
            }
        }
        assert!(
            at(s, t) <= best + 1e-12,
            "({s}, {t}): {} vs {best}",
            at(s, t)
        );
    }
}
