//! A terrain force along a bar: a contact force `f` at `x(s) = a + s (b − a)` is split
//! onto the bar's ends as `(1 − s) f` and `s f` (docs/design.md, "A force along a bar").
//! A free bar touched once on its side moves as the rigid rod of the same mass under `f`
//! at `x(s)`, and for random bars over random terrain the end forces have the contacts'
//! resultant and moment about any point.

use nalgebra::Vector3;
use tensegrity_fmu::contact::capsule::KINK_SLACK;
use tensegrity_fmu::contact::{Grid, Grip, Penalty, Proximity, Shape};
use tensegrity_fmu::dynamics::terrain::{apply, capsule_forces, mark_far, TerrainSink};
use tensegrity_fmu::model::terrain::{Capsule, Terrain};
use tensegrity_fmu::scene::Scene;
use tensegrity_fmu::{Model, Simulation};

// ------------------------------------------------------- 1. one contact on a free bar

/// Box: 0.1 m thin along x, 1 m along y and z, centred at the origin (top face z = 0.5).
const HALF_X: f64 = 0.05;
const TOP: f64 = 0.5;
const STIFFNESS: f64 = 1.0e4;
const RADIUS: f64 = 0.02;
const MASS: f64 = 2.5;
/// Depth of the axis below `TOP + RADIUS` where the bar crosses the face plane x = +0.05.
const DEPTH: f64 = 0.004;

/// End nodes of a bar along `(1, 0.3, −0.1)` that crosses the plane x = +0.05 at `s`,
/// `DEPTH` into the capsule there. Falling by 0.01 m across the box's 0.1 m, it clears
/// the other face plane (x = −0.05) by 0.006 m, and its ends lie 0.2 m or more beside
/// the box: its side touches at that one point.
fn bar_over_edge(s: f64) -> [Vector3<f64>; 2] {
    let at = Vector3::new(HALF_X, 0.0, TOP + RADIUS - DEPTH);
    let d = Vector3::new(1.0, 0.3, -0.1);
    [at - d * s, at + d * (1.0 - s)]
}

fn scene(ends: &[Vector3<f64>; 2]) -> Scene {
    let [a, b] = ends;
    Scene::from_toml_str(&format!(
        "name = \"wrench\"\n\
         nodes = [[{}, {}, {}], [{}, {}, {}]]\n\
         bars = [{{ nodes = [1, 2], mass = {MASS}, radius = {RADIUS} }}]\n\
         [[terrain]]\n\
         kind = \"box\"\n\
         center = [0, 0, 0]\n\
         size = [{}, 1, {}]\n\
         stiffness = {STIFFNESS}\n\
         damping = 3\n\
         friction = 0.5\n",
        a.x,
        a.y,
        a.z,
        b.x,
        b.y,
        b.z,
        2.0 * HALF_X,
        2.0 * TOP,
    ))
    .expect("scene")
}

/// `|x − y| ≤ tol · scale`, with a message.
fn close(what: &str, x: &Vector3<f64>, y: &Vector3<f64>, scale: f64, tol: f64) {
    let err = (x - y).norm() / scale;
    assert!(err <= tol, "{what}: {x:?} vs {y:?} ({err:.1e} relative)");
}

#[test]
fn a_free_bar_touched_on_its_side_moves_as_a_rigid_rod() {
    for s in [0.3, 0.55, 0.8] {
        let ends = bar_over_edge(s);
        let mut sim = Simulation::new(Model::new(&scene(&ends)).expect("model"));
        sim.refresh();

        // The contact, from the geometry alone: at rest the penalty is k d along the top
        // face's normal (no damping or friction without motion), d less the kinks'
        // round-off slack.
        let [a, b] = ends;
        let s_cross = (HALF_X - a.x) / (b.x - a.x);
        let x_c = a + (b - a) * s_cross;
        let depth = RADIUS - (x_c.z - TOP);
        let f = Vector3::z() * (STIFFNESS * (depth - KINK_SLACK));
        assert!((s_cross - s).abs() <= 1e-15 && (depth - DEPTH).abs() <= 1e-15);

        let load = sim.shape_load(0);
        assert_eq!(load.contacts, 1, "s = {s}: contacts");
        close("shape load", &load.force, &f, f.norm(), 1e-12);
        // The rigid thin rod at rest (ω = 0): a_cm = f/m, and about its centre the
        // inertia is m L²/12 across the axis, where r × f lies (r is along the axis), so
        // α = (r × f) / (m L²/12); an end at r_e from the centre has a_cm + α × r_e.
        let centre = (a + b) * 0.5;
        let length = (b - a).norm();
        let a_cm = f / MASS;
        let alpha = (x_c - centre).cross(&f) / (MASS * length * length / 12.0);
        let scale = a_cm.norm() + alpha.norm() * length;
        for (n, end) in ends.iter().enumerate() {
            let expected = a_cm + alpha.cross(&(end - centre));
            let got = sim.node_acceleration(n);
            close(
                &format!("s = {s}: node {}", n + 1),
                &got,
                &expected,
                scale,
                1e-9,
            );
        }
        // The contact turns the rod as much as it pushes it (α L ≥ 0.57 |f|/m here), so
        // a split with the wrong moment fails above.
        assert!(alpha.norm() * length >= 0.1 * a_cm.norm(), "s = {s}");

        // The generalized force Jᵀ f (no gravity, no cables: the ends carry nothing else).
        let end_force = &sim.workspace().end_force;
        close("end a", &end_force[0], &(f * (1.0 - s)), f.norm(), 1e-12);
        close("end b", &end_force[1], &(f * s), f.norm(), 1e-12);
    }
}

// ------------------------------------------------------ 2. resultant and moment, random

/// splitmix64: a fixed sequence of uniform numbers in [0, 1).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }

    fn vector(&mut self, lo: f64, hi: f64) -> Vector3<f64> {
        Vector3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }
}

/// End forces of every capsule, by bar end.
struct Ends {
    force: Vec<Vector3<f64>>,
    shapes: Vector3<f64>,
}

impl TerrainSink for Ends {
    fn add(&mut self, end: usize, f: Vector3<f64>) {
        self.force[end] += f;
    }
    fn shape(&mut self, _shape: usize, f: Vector3<f64>) {
        self.shapes += f;
    }
}

/// Bumpy ground (a random 9 × 9 heightfield over [−2, 2]²) and a yawed box standing on it,
/// with damping and friction so that the forces leave the normals.
fn random_terrain(rng: &mut Rng) -> Vec<(Shape, Penalty)> {
    let rows: Vec<Vec<f64>> = (0..9)
        .map(|_| (0..9).map(|_| rng.range(-0.2, 0.2)).collect())
        .collect();
    let law = |stiffness: f64| Penalty {
        stiffness,
        damping: 40.0,
        friction: 0.6,
        slip_velocity: 0.01,
    };
    vec![
        (
            Shape::Heightfield(Grid::new([-2.0, -2.0], [0.5, 0.5], &rows)),
            law(5.0e3),
        ),
        (
            Shape::cuboid([0.3, -0.2, 0.1], [0.8, 0.5, 0.6], 25.0),
            law(2.0e4),
        ),
    ]
}

#[test]
fn end_forces_have_the_contacts_resultant_and_moment() {
    let mut rng = Rng(0x7e45_e961);
    let (bars, trials) = (40, 25);
    let (mut interior, mut checked, mut far) = (0, 0, 0);
    for _ in 0..trials {
        let shapes = random_terrain(&mut rng);
        // Bars of 0.3–2 m around the terrain's surface, each with its own two nodes, moving.
        let mut x = Vec::new();
        let mut v = Vec::new();
        let mut capsules = Vec::new();
        for i in 0..bars {
            let centre = Vector3::new(rng.range(-1.5, 1.5), rng.range(-1.5, 1.5), 0.0);
            let dir = rng.vector(-1.0, 1.0).normalize() * rng.range(0.3, 2.0);
            let mut a = centre - dir * 0.5;
            let mut b = centre + dir * 0.5;
            a.z = rng.range(-0.25, 0.55);
            b.z = rng.range(-0.25, 0.55);
            x.extend([a, b]);
            v.extend([rng.vector(-1.0, 1.0), rng.vector(-1.0, 1.0)]);
            capsules.push(Capsule {
                bar: i,
                nodes: [2 * i, 2 * i + 1],
                ends: [Some(2 * i), Some(2 * i + 1)],
                radius: rng.range(0.0, 0.08),
            });
        }
        // Regularised friction: the forces below are recomputed with the penalty law.
        let sticks = vec![false; shapes.len()];
        let terrain = Terrain {
            shapes,
            capsules,
            sticks,
            margin: 0.2,
            trail: 0.2 / 500.0,
        };
        let grips = vec![Grip::Free; terrain.grips()];
        let mut sink = Ends {
            force: vec![Vector3::zeros(); 2 * bars],
            shapes: Vector3::zeros(),
        };
        // The far marks set where every node was up to just under half the margin away:
        // they still hold, and must not drop a contact that the full test below finds.
        let marked: Vec<_> = x
            .iter()
            .map(|p| p + rng.vector(-1.0, 1.0).normalize() * rng.range(0.0, 0.0999))
            .collect();
        let mut near = Proximity::default();
        mark_far(&terrain, &marked, &mut near);
        far += (0..terrain.capsules.len() * terrain.shapes.len())
            .filter(|&i| near.is_far(i))
            .count();
        apply(&terrain, &grips, &near, (&x, &v), &mut sink);

        let mut total = Vector3::zeros();
        for cap in &terrain.capsules {
            let [na, nb] = cap.nodes;
            let (a, b) = (x[na], x[nb]);
            let p = rng.vector(-3.0, 3.0);
            // The contacts themselves: resultant and moment about p of f at x(s).
            let (mut force, mut moment, mut scale) = (Vector3::zeros(), Vector3::zeros(), 0.0);
            capsule_forces(
                &terrain,
                [&a, &b],
                [&v[na], &v[nb]],
                cap.radius,
                &grips[..2 * terrain.shapes.len()],
                |_, s, f| {
                    force += f;
                    moment += (a + (b - a) * s - p).cross(&f);
                    scale += f.norm();
                    if s > 0.0 && s < 1.0 {
                        interior += 1;
                    }
                },
            );
            total += force;
            if scale == 0.0 {
                assert_eq!(sink.force[na], Vector3::zeros());
                assert_eq!(sink.force[nb], Vector3::zeros());
                continue;
            }
            checked += 1;
            let (fa, fb) = (sink.force[na], sink.force[nb]);
            let lever = (a - p).norm().max((b - p).norm());
            close("resultant", &(fa + fb), &force, scale, 1e-13);
            close(
                "moment",
                &((a - p).cross(&fa) + (b - p).cross(&fb)),
                &moment,
                scale * lever,
                1e-13,
            );
        }
        close(
            "shapes' load",
            &sink.shapes,
            &total,
            total.norm().max(1.0),
            1e-12,
        );
    }
    // The terrain touches bars on their sides, not only at their ends.
    println!(
        "{checked} touching bars, {interior} contacts between the ends, {far} pairs marked far"
    );
    assert!(checked >= 200, "{checked} touching bars");
    assert!(far >= 500, "{far} capsule–shape pairs skipped as far");
    assert!(interior >= 200, "{interior} interior contacts");
}

#[test]
fn a_steep_heightfield_touches_a_capsule_above_its_top_where_its_depth_says() {
    // Heights 0 and 1 m, 0.1 m apart: a slope of 10, n_z = 1/√101. Ends over the slope
    // at x = 0.095 (h = 0.95) and 5 cm above the top: the vertical gap 0.1 m times n_z is
    // 9.95 mm, inside the 2 cm radius.
    let grid = Grid::new([0.0, 0.0], [0.1, 0.1], &[vec![0.0, 1.0], vec![0.0, 1.0]]);
    let shape = Shape::Heightfield(grid);
    let (a, b) = (
        Vector3::new(0.095, 0.02, 1.05),
        Vector3::new(0.095, 0.08, 1.05),
    );
    let mut depths = Vec::new();
    tensegrity_fmu::contact::capsule_contacts(&shape, &a, &b, 0.02, |c| depths.push(c.depth));
    let expected = 0.02 - (1.05 - 0.95) / 101f64.sqrt();
    println!("depths {depths:?}, expected {expected}");
    assert_eq!(depths.len(), 2, "both ends touch: {depths:?}");
    for d in depths {
        assert!((d - expected).abs() < 1e-12, "depth {d} against {expected}");
    }
}
