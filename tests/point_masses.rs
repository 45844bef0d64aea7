//! Point masses (payloads) at nodes, held to predictions made independently of the code:
//! - accelerations and bar forces against a dense saddle-point (KKT) solve in physical node
//!   coordinates, where a payload is nothing but extra mass on a node's diagonal;
//! - a free-floating icosahedron with payloads: linear momentum, centre-of-mass motion,
//!   angular momentum and energy from this file's own mass bookkeeping; a 0 kg payload is
//!   bit-identical to none;
//! - validation of `point_masses` (the key is named).
//!
//! The natural frequencies with payloads (pendulum, cable-held bar) are in
//! tests/point_mass_frequencies.rs. Scenes are written as JSON text and parsed by
//! `Scene::from_json_str`, so the scene key `point_masses` itself is exercised. Figures are
//! printed (run with `--nocapture`).

mod kkt_support;
mod point_mass_support;

use kkt_support::{compare_with_kkt, kkt_solve, random_scene, H};
use nalgebra::Vector3;
use point_mass_support::{cable_held_bar, node_payload, payloads, scene_from};
use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::model::CableLaw;
use tensegrity_fmu::scene::builtin;
use tensegrity_fmu::{Model, Scene, SceneError, Simulation};

// ---------------------------------------------------------------------------------------
// 1. Dense KKT solve with payloads
// ---------------------------------------------------------------------------------------

/// The class-k structure of tests/kkt.rs (see `kkt_support::random_scene`: a class-4 hub at
/// node 1, a pinned class-2 joint at node 2, a free class-2 joint at node 3, force inputs on
/// nodes 10 and 8), sent through JSON text like this file's other scenes.
fn random_scene_json(seed: u64) -> Scene {
    scene_from(&serde_json::to_value(random_scene(seed)).expect("the scene serializes"))
}

/// Runs a loaded simulation with payloads and compares every bar end's acceleration (through
/// `dynamics::accelerations`, which `refresh` runs) and every bar force with the dense
/// solve; also checks that the same solve without the payloads is far off, so the
/// comparison does see them.
fn check_against_kkt(mut scene: Scene, list: &[(usize, f64)], seed: u64) {
    scene.point_masses = payloads(list);
    let payload = node_payload(&scene);
    // Every bar end is compared, not just the representative end of each node: the payload
    // sits on one end of a joint, the others must still follow the node.
    let c = compare_with_kkt(&scene, &payload, seed);
    let (name, scale) = (&c.name, c.scale);
    let acc_bare = kkt_solve(&c.sim, &vec![0.0; payload.len()]).acc;
    let payload_effect = c
        .kkt
        .acc
        .iter()
        .zip(&acc_bare)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    println!(
        "{name} with payloads {list:?}: max |Δä| = {:.3e} (scale {scale:.3e}, rel {:.3e}); \
         max |Δ bar force| = {:.3e} N (scale {:.3e}, rel {:.3e}); ignoring the payloads \
         would change ä by {payload_effect:.3e} (rel {:.3e})",
        c.err_acc,
        c.err_acc / scale,
        c.err_force,
        c.force_scale,
        c.err_force / c.force_scale,
        payload_effect / scale
    );
    // Both sides solve the same linear mechanics in double precision; tests/kkt.rs measures
    // ≤ 2e-15 relative without payloads and the payload only changes diagonal entries
    // (its condition stays moderate: masses 0.3–3 kg, lengths ~1 m). 1e-12 leaves
    // ~100× margin for the dense LU's condition-number growth.
    c.assert_agree(1e-12);
    // The payloads are comparable to the bar masses, so dropping them must change the
    // accelerations at the scale of the motion: 1e-2 is 1e10 times the tolerance.
    assert!(
        payload_effect >= 1e-2 * scale,
        "{name}: the payloads barely matter, so the comparison proves little"
    );
}

#[test]
fn accelerations_with_payloads_match_dense_kkt() {
    // Node 1: class-4 hub; node 3: free class-2 joint; node 5: end of bar 2–5 whose other
    // end (node 2) is pinned; nodes 8 and 10: leaves with force inputs.
    check_against_kkt(
        random_scene_json(2024),
        &[(1, 1.5), (3, 0.4), (5, 2.0), (8, 0.3), (10, 3.0)],
        13,
    );
    // prism2: node 4 is a class-2 joint whose lower bar 1–4 is pinned at node 1; node 8 is
    // on the top ring (force input). Gravity added so the payloads' weight is covered.
    let mut prism = builtin("prism2").unwrap();
    prism.gravity = Some([0.3, -0.2, -9.81]);
    check_against_kkt(prism, &[(4, 0.8), (5, 0.2), (8, 2.5)], 11);
    // icosahedron (one face pinned) with gravity: payloads on a force-input node and two
    // others.
    let mut ico = builtin("icosahedron").unwrap();
    ico.gravity = Some([0.3, -0.2, -9.81]);
    check_against_kkt(ico, &[(4, 1.2), (6, 0.5), (10, 2.0)], 12);
}

// ---------------------------------------------------------------------------------------
// 2. Conservation with payloads
// ---------------------------------------------------------------------------------------

/// The icosahedron floating free (no pins, no inputs, no gravity), spinning and drifting,
/// with every bar additionally spun about its centre at its own rate so that the structure
/// deforms. All these velocities keep ḃ ⟂ b, so nothing is projected.
fn free_icosahedron(list: &[(usize, f64)]) -> Scene {
    let mut scene = builtin("icosahedron").unwrap();
    scene.fixed.clear();
    scene.force_inputs.clear();
    scene.gravity = None;
    let omega = Vector3::new(0.3, -0.5, 2.0);
    let drift = Vector3::new(0.1, 0.05, -0.02);
    let mut v: Vec<Vector3<f64>> = scene
        .nodes
        .iter()
        .map(|p| omega.cross(&Vector3::from(*p)) + drift)
        .collect();
    for (k, bar) in scene.bars.iter().enumerate() {
        let [a, b] = [bar.nodes[0] - 1, bar.nodes[1] - 1];
        let axis = Vector3::from(scene.nodes[b]) - Vector3::from(scene.nodes[a]);
        let w = axis.cross(&Vector3::new(0.3, 0.7, -0.4)).normalize() * (0.05 + 0.03 * k as f64);
        v[a] += w;
        v[b] -= w;
    }
    scene.velocities = Some(v.iter().map(|x| [x.x, x.y, x.z]).collect());
    scene.point_masses = payloads(list);
    scene
}

/// This file's mass bookkeeping for a class-1 structure: half of each bar on each of its
/// nodes plus the node's payload.
struct Masses {
    node: Vec<f64>,
    payload: Vec<f64>,
}

impl Masses {
    fn of(scene: &Scene) -> Self {
        let payload = node_payload(scene);
        let mut node = payload.clone();
        for bar in &scene.bars {
            node[bar.nodes[0] - 1] += bar.mass / 2.0;
            node[bar.nodes[1] - 1] += bar.mass / 2.0;
        }
        Self { node, payload }
    }

    fn total(&self) -> f64 {
        self.node.iter().sum()
    }
}

struct Snapshot {
    momentum: Vector3<f64>,
    centre: Vector3<f64>,
    angular: Vector3<f64>,
    energy: f64,
}

/// Momenta, centre of mass and energy from node positions and velocities, computed here:
/// a uniform rod has `p = m ṙ`, `L = m (r × ṙ + b × ḃ / 12)`, `T = (m/6)(|v_a|² + v_a·v_b +
/// |v_b|²)`; a payload adds `p v`, `p x × v`, `½ p |v|²`; an elastic cable stores
/// `½ κ (|s| − s₀)²` while taut.
fn snapshot(sim: &Simulation, masses: &Masses) -> Snapshot {
    let model = sim.model();
    let x: Vec<_> = (0..model.n_nodes()).map(|n| sim.node_position(n)).collect();
    let v: Vec<_> = (0..model.n_nodes()).map(|n| sim.node_velocity(n)).collect();
    let mut s = Snapshot {
        momentum: Vector3::zeros(),
        centre: Vector3::zeros(),
        angular: Vector3::zeros(),
        energy: 0.0,
    };
    for n in 0..x.len() {
        s.momentum += v[n] * masses.node[n];
        s.centre += x[n] * (masses.node[n] / masses.total());
        s.angular += x[n].cross(&v[n]) * masses.payload[n];
        s.energy += 0.5 * masses.payload[n] * v[n].norm_squared();
    }
    for bar in &sim.model().scene.bars {
        let (a, b, m) = (bar.nodes[0] - 1, bar.nodes[1] - 1, bar.mass);
        let (r, rd) = ((x[a] + x[b]) / 2.0, (v[a] + v[b]) / 2.0);
        let (bv, bd) = (x[b] - x[a], v[b] - v[a]);
        s.angular += (r.cross(&rd) + bv.cross(&bd) / 12.0) * m;
        s.energy += m / 6.0 * (v[a].norm_squared() + v[a].dot(&v[b]) + v[b].norm_squared());
    }
    for cable in &model.cables {
        let CableLaw::Elastic {
            stiffness,
            rest_length,
            damping: None,
        } = cable.law
        else {
            panic!("the icosahedron's cables are undamped elastic")
        };
        let stretch = (x[cable.nodes[1]] - x[cable.nodes[0]]).norm() - rest_length;
        s.energy += 0.5 * stiffness * stretch.max(0.0).powi(2);
    }
    s
}

/// Largest deviations over a run of the free icosahedron (relative unless noted).
struct Drifts {
    momentum: f64,
    angular: f64,
    energy: f64,
    /// Distance of the centre of mass from its straight line `x_c(0) + P t / M`, m.
    centre: f64,
    /// Smallest cable force density seen, N/m (0: a cable went slack).
    min_gamma: f64,
}

/// Runs the free icosahedron with `list` for 5 s at step `h`, with or without the
/// correction, checking every 10 steps against the start.
fn free_run(list: &[(usize, f64)], h: f64, correction: bool) -> Drifts {
    let mut scene = free_icosahedron(list);
    scene.solver.method = Method::Rk4;
    let masses = Masses::of(&scene);
    let mut sim = Simulation::new(Model::new(&scene).unwrap());
    sim.correction = correction;
    let s0 = snapshot(&sim, &masses);
    let mut d = Drifts {
        momentum: 0.0,
        angular: 0.0,
        energy: 0.0,
        centre: 0.0,
        min_gamma: f64::INFINITY,
    };
    let steps = (5.0 / h).round() as u64;
    for k in 0..steps {
        sim.step_to(k as f64 * h, (k + 1) as f64 * h).unwrap();
        if k % 10 == 9 {
            sim.refresh();
            let t = (k + 1) as f64 * h;
            let s = snapshot(&sim, &masses);
            d.momentum = d
                .momentum
                .max((s.momentum - s0.momentum).norm() / s0.momentum.norm());
            d.angular = d
                .angular
                .max((s.angular - s0.angular).norm() / s0.angular.norm());
            d.energy = d.energy.max((s.energy - s0.energy).abs() / s0.energy);
            let expected = s0.centre + s0.momentum * (t / masses.total());
            d.centre = d.centre.max((s.centre - expected).norm());
            let gmin = sim
                .workspace()
                .gamma
                .iter()
                .fold(f64::INFINITY, |m, &g| m.min(g));
            d.min_gamma = d.min_gamma.min(gmin);
        }
    }
    println!(
        "free icosahedron with payloads, 5 s at h = {h:e} s, correction {correction}: linear \
         momentum drift {:.2e}, angular {:.2e}, energy {:.2e} (relative); centre of mass off \
         its straight line by {:.2e} m; smallest cable force density {:.2} N/m",
        d.momentum, d.angular, d.energy, d.centre, d.min_gamma
    );
    d
}

#[test]
fn free_icosahedron_with_payloads_conserves_momentum_and_energy() {
    let list = [(1, 0.5), (4, 2.0), (7, 0.25), (11, 1.0), (12, 3.0)];
    let scene = free_icosahedron(&list);
    let masses = Masses::of(&scene);
    assert!((masses.total() - (6.0 + 6.75)).abs() < 1e-12);
    let sim = Simulation::new(Model::new(&scene).unwrap());
    assert!(
        sim.warnings().is_empty(),
        "ḃ ⟂ b everywhere, so nothing is projected: {:?}",
        sim.warnings()
    );
    let s0 = snapshot(&sim, &masses);
    // The library's reported totals agree with this bookkeeping at the start (the same
    // sums in another order: round-off).
    let dp_lib = (sim.linear_momentum() - s0.momentum).norm() / s0.momentum.norm();
    let dl_lib = (sim.angular_momentum() - s0.angular).norm() / s0.angular.norm();
    let de_lib = (sim.energy() - s0.energy).abs() / s0.energy;
    let travelled = (s0.momentum * (5.0 / masses.total())).norm();
    println!(
        "free icosahedron with payloads: library vs own bookkeeping at t = 0: momentum \
         {dp_lib:.2e}, angular {dl_lib:.2e}, energy {de_lib:.2e} (relative); the centre of \
         mass travels {travelled:.3} m in 5 s"
    );
    assert!(dp_lib <= 1e-13 && dl_lib <= 1e-13 && de_lib <= 1e-13);
    assert!(travelled > 0.3, "the structure should drift");

    // The equations of motion alone (correction off): internal forces (cables, bar forces)
    // cancel pairwise against this file's masses, and RK4 preserves linear invariants
    // exactly, so Σ m v stays at round-off (measured ~6e-15) and the centre of mass on its
    // line. A payload missing from the inertia (or the momentum weights) would leave a
    // drift of the size of the internal forces' impulse, orders above round-off.
    let raw = free_run(&list, H, false);
    assert!(raw.momentum <= 1e-13, "momentum drift {}", raw.momentum);
    assert!(
        raw.centre <= 1e-12,
        "centre of mass off by {} m",
        raw.centre
    );

    // With the correction (the default): it changes a bar's two ends by equal and opposite
    // amounts (a Euclidean minimum-norm change, not a mass-weighted one), which is
    // momentum-neutral only when the end masses are equal. With payloads it exchanges
    // (p_a − p_b) × (the along-bar velocity error it removes) per step, i.e. RK4's local
    // error: O(h⁴) overall. Measured 1.6e-11 at 1 ms, 1e-12 at 0.5 ms.
    let coarse = free_run(&list, H, true);
    let fine = free_run(&list, H / 2.0, true);
    for d in [&raw, &coarse, &fine] {
        // Every cable stays taut, so the run is smooth and RK4 shows its full order.
        assert!(d.min_gamma > 0.0, "a cable went slack");
    }
    assert!(
        coarse.momentum <= 1e-9,
        "momentum drift {}",
        coarse.momentum
    );
    assert!(coarse.centre <= 1e-9, "centre off by {} m", coarse.centre);
    assert!(
        fine.momentum < coarse.momentum / 8.0,
        "the correction's momentum exchange must shrink like RK4's error: {} -> {}",
        coarse.momentum,
        fine.momentum
    );
    // Energy (this file's T + V): RK4's error, measured 3.8e-9 at 1 ms and 1.2e-10 at
    // 0.5 ms; 1e-7 is 25× above, and halving h must gain more than 8× (order > 3).
    assert!(coarse.energy <= 1e-7, "energy drift {}", coarse.energy);
    assert!(
        fine.energy < coarse.energy / 8.0,
        "energy drift does not shrink at RK4's order: {} -> {}",
        coarse.energy,
        fine.energy
    );
    // Angular momentum: conserved by the equations; RK4 keeps it only to its error (it is
    // quadratic in the state), and the correction adds the same kind of exchange as
    // above. Measured 1.8e-11 (off) and 7.7e-11 (on) at 1 ms: bound 1e-9.
    assert!(
        coarse.angular <= 1e-9,
        "angular momentum drift {}",
        coarse.angular
    );
    assert!(
        raw.angular <= 1e-9,
        "angular momentum drift {}",
        raw.angular
    );
}

#[test]
fn zero_payload_is_bit_identical_to_none() {
    let compare = |with: Scene, without: Scene, steps: u64| {
        let name = with.name.clone();
        let mut a = Simulation::new(Model::new(&with).unwrap());
        let mut b = Simulation::new(Model::new(&without).unwrap());
        a.advance(steps, H).unwrap();
        b.advance(steps, H).unwrap();
        a.refresh();
        b.refresh();
        let bits = |s: &Simulation| s.state().y.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&a), bits(&b), "{name}: states differ");
        assert_eq!(a.energy().to_bits(), b.energy().to_bits(), "{name}: energy");
        let (pa, pb) = (a.linear_momentum(), b.linear_momentum());
        assert!(
            pa.iter()
                .zip(pb.iter())
                .all(|(x, y)| x.to_bits() == y.to_bits()),
            "{name}: momentum"
        );
        println!("{name}: a 0 kg payload is bit-identical to none after {steps} steps");
    };
    // Free icosahedron: the 0 kg entries sit next to real payloads.
    compare(
        free_icosahedron(&[(1, 0.5), (3, 0.0), (4, 2.0), (9, 0.0)]),
        free_icosahedron(&[(1, 0.5), (4, 2.0)]),
        2000,
    );
    // prism2 under gravity, 0 kg on a class-2 joint and a top node vs no key at all.
    let mut without = builtin("prism2").unwrap();
    without.gravity = Some([0.0, 0.0, -9.81]);
    let mut with = without.clone();
    with.point_masses = payloads(&[(5, 0.0), (8, 0.0)]);
    compare(with, without, 2000);
}

// ---------------------------------------------------------------------------------------
// 3. Validation
// ---------------------------------------------------------------------------------------

fn rejected_key(scene: &Scene) -> String {
    match Model::new(scene) {
        Err(SceneError::Invalid { key, reason }) => {
            println!("rejected: {key}: {reason}");
            key
        }
        Err(other) => panic!("expected an invalid key, got {other}"),
        Ok(_) => panic!("the scene was accepted"),
    }
}

#[test]
fn invalid_point_masses_name_the_key() {
    // The icosahedron pins nodes 1, 5 and 9; node 2 is a free bar end.
    let ico = || builtin("icosahedron").unwrap();
    let with = |mut scene: Scene, list: &[(usize, f64)]| {
        scene.point_masses = payloads(list);
        scene
    };
    // On a pinned node (the first entry is fine, so the index must be the second's).
    assert_eq!(
        rejected_key(&with(ico(), &[(2, 1.0), (5, 1.0)])),
        "point_masses[2].node"
    );
    // On a node with no bar: the cable anchors of the cable-held bar (nodes 3 and 4; a
    // bar-less node must be pinned, or the scene is rejected for that already).
    assert_eq!(
        rejected_key(&with(cable_held_bar(None, [0.0; 3]), &[(3, 0.5)])),
        "point_masses[1].node"
    );
    // A free bar-less node is rejected either for itself or for the payload.
    let mut stray = with(ico(), &[(13, 1.0)]);
    stray.nodes.push([2.0, 2.0, 2.0]);
    let key = rejected_key(&stray);
    assert!(
        key == "nodes[13]" || key == "point_masses[1].node",
        "unexpected key {key}"
    );
    // Out of range.
    assert_eq!(
        rejected_key(&with(ico(), &[(13, 1.0)])),
        "point_masses[1].node"
    );
    assert_eq!(
        rejected_key(&with(ico(), &[(2, 1.0), (0, 1.0)])),
        "point_masses[2].node"
    );
    // Negative and non-finite masses.
    assert_eq!(
        rejected_key(&with(ico(), &[(2, 1.0), (3, -0.5)])),
        "point_masses[2].mass"
    );
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let mut scene = with(ico(), &[(2, 1.0), (3, 1.0), (4, 1.0)]);
        scene.point_masses[2].mass = bad;
        assert_eq!(rejected_key(&scene), "point_masses[3].mass", "mass {bad}");
    }
    // NaN through a TOML file (TOML spells it `nan`).
    let text = format!(
        "{}\n[[point_masses]]\nnode = 2\nmass = nan\n",
        ico().to_toml_string()
    );
    let parsed = Scene::from_toml_str(&text).expect("TOML accepts nan");
    assert_eq!(rejected_key(&parsed), "point_masses[1].mass");
    // Zero is allowed (and inert, see zero_payload_is_bit_identical_to_none).
    assert!(Model::new(&with(ico(), &[(2, 0.0)])).is_ok());
}
