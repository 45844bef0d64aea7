//! Helpers of the stress suite (`tests/stress.rs`): result rows appended to a JSON-lines
//! file, a tracker of constraint errors and energy, the scenes and runs of the cases.

use nalgebra::Vector3;
use std::f64::consts::PI;
use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::scene::{builtin, BarSpec, CableSpec, Scene};
use tensegrity_fmu::{Model, Simulation, StepError};

mod record;
mod scenes;
pub use record::*;
pub use scenes::*;

/// Length error at which a run without the correction counts as violating, m.
pub const VIOLATION: f64 = 1e-6;
/// Constraint errors allowed with the correction on (m and m²/s).
pub const EXACT: f64 = 1e-12;

/// Largest constraint errors, energy drift and first violation time seen at the samples.
#[derive(Debug, Clone)]
pub struct Tracker {
    pub max_length: f64,
    pub max_orthogonality: f64,
    /// `max |E − E₀| / |E₀|`, with E counting the potential of the (constant) loads.
    pub max_drift: f64,
    pub finite: bool,
    /// Largest `|b||ḃ|` over bars and samples, m²/s.
    pub speed_scale: f64,
    /// First sample time with a length error above [`VIOLATION`].
    pub first_violation: Option<f64>,
    pub steps: u64,
    /// The message of a failed step, if any.
    pub error: Option<String>,
    /// After a failed step: the state is exactly the one before it.
    pub kept: bool,
    e0: f64,
}

impl Tracker {
    pub fn new(sim: &mut Simulation) -> Self {
        sim.refresh();
        let mut t = Self {
            max_length: 0.0,
            max_orthogonality: 0.0,
            max_drift: 0.0,
            finite: true,
            speed_scale: 0.0,
            first_violation: None,
            steps: 0,
            error: None,
            kept: true,
            e0: energy_with_loads(sim),
        };
        t.sample(sim);
        t
    }

    /// Re-evaluates the outputs at the current state and updates the maxima.
    pub fn sample(&mut self, sim: &mut Simulation) {
        sim.refresh();
        let (len, orth) = (sim.length_error(), sim.orthogonality_error());
        self.max_length = self.max_length.max(len);
        self.max_orthogonality = self.max_orthogonality.max(orth);
        let e = energy_with_loads(sim);
        self.max_drift = self
            .max_drift
            .max((e - self.e0).abs() / self.e0.abs().max(1e-300));
        let n = sim.model().n_nodes();
        let finite = len.is_finite()
            && orth.is_finite()
            && e.is_finite()
            && (0..n).all(|i| {
                sim.node_position(i).iter().all(|x| x.is_finite())
                    && sim.node_velocity(i).iter().all(|x| x.is_finite())
            })
            && (0..sim.model().cables.len()).all(|j| sim.cable_tension(j).is_finite());
        self.finite &= finite;
        for b in &sim.model().bars {
            let [i, j] = b.nodes;
            let bv = sim.node_position(j) - sim.node_position(i);
            let bd = sim.node_velocity(j) - sim.node_velocity(i);
            self.speed_scale = self.speed_scale.max(bv.norm() * bd.norm());
        }
        if len > VIOLATION && self.first_violation.is_none() {
            self.first_violation = Some(sim.time());
        }
        self.steps = sim.stats().steps;
    }

    /// Advances to `t_end` in communication steps of `dt`, calling `inputs(sim, t)` before
    /// each and sampling after each. A failed step is recorded in `error`, with `kept`
    /// telling whether the state was left exactly at the start of that step.
    pub fn run(
        &mut self,
        sim: &mut Simulation,
        t_end: f64,
        dt: f64,
        mut inputs: impl FnMut(&mut Simulation, f64),
    ) -> Result<(), StepError> {
        let t0 = sim.time();
        let n = ((t_end - t0) / dt).round() as u64;
        for k in 0..n {
            inputs(sim, t0 + k as f64 * dt);
            let before = sim.state().clone();
            if let Err(e) = sim.advance_to(t0 + (k + 1) as f64 * dt) {
                self.kept = *sim.state() == before;
                self.error = Some(e.to_string());
                return Err(e);
            }
            self.sample(sim);
        }
        Ok(())
    }

    /// "t = …" of the first violation, or "not within horizon".
    pub fn violation_text(&self, horizon: f64) -> String {
        match self.first_violation {
            Some(t) => format!("length error first > 1e-6 m at t = {t:.4} s"),
            None => format!("length error never > 1e-6 m: not within horizon ({horizon} s)"),
        }
    }
}

/// Kinetic + strain + gravity energy minus the work potential `Σ F·x` of the node loads
/// (conserved when the loads are constant and nothing is damped).
pub fn energy_with_loads(sim: &Simulation) -> f64 {
    let m = sim.model();
    let load: f64 = m
        .force_inputs
        .iter()
        .zip(&sim.inputs.node_force)
        .map(|(&n, f)| f.dot(&sim.node_position(n)))
        .sum();
    sim.energy() - load
}

pub fn positions(sim: &Simulation) -> Vec<Vector3<f64>> {
    (0..sim.model().n_nodes())
        .map(|n| sim.node_position(n))
        .collect()
}

pub fn max_distance(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).norm())
        .fold(0.0, f64::max)
}

/// The bars (1-based) the correction skips, and whether `warnings()` reports each.
pub fn skipped_and_warned(sim: &Simulation) -> (Vec<usize>, bool) {
    let skipped: Vec<usize> = sim
        .model()
        .correction
        .skipped
        .iter()
        .map(|b| b + 1)
        .collect();
    let warned = skipped.iter().all(|b| {
        let tag = format!("bar {b}:");
        sim.warnings()
            .iter()
            .any(|w| w.starts_with(&tag) && w.contains("skips it"))
    });
    (skipped, warned)
}

/// Sets every force-input node's load.
pub fn load_all(sim: &mut Simulation, f: Vector3<f64>) {
    sim.inputs.node_force.iter_mut().for_each(|x| *x = f);
}

pub fn bar(a: usize, b: usize) -> BarSpec {
    BarSpec {
        nodes: [a, b],
        mass: 1.0,
        radius: 0.0,
    }
}

/// Elastic cable with a rest length of `factor` × its start length.
pub fn cable(scene: &Scene, a: usize, b: usize, stiffness: f64, factor: f64) -> CableSpec {
    let d = Vector3::from(scene.nodes[b - 1]) - Vector3::from(scene.nodes[a - 1]);
    CableSpec {
        nodes: [a, b],
        stiffness: Some(stiffness),
        rest_length: Some(factor * d.norm()),
        ..CableSpec::default()
    }
}

/// A scene with nodes and solver defaults only; bars and cables are added by the caller.
pub fn bare(name: &str, nodes: Vec<[f64; 3]>, fixed: Vec<usize>) -> Scene {
    Scene {
        name: name.to_string(),
        description: None,
        nodes,
        fixed,
        bars: Vec::new(),
        cables: Vec::new(),
        gravity: None,
        force_inputs: Vec::new(),
        velocities: None,
        loads: Vec::new(),
        point_masses: Vec::new(),
        ground: None,
        terrain: Vec::new(),
        collisions: None,
        outputs: None,
        prestress: None,
        start: Default::default(),
        solver: Default::default(),
    }
}

/// Scientific notation with 2 digits, for notes.
pub fn sci(x: f64) -> String {
    format!("{x:.2e}")
}

// ------------------------------------------------------------------ runs and scenes of the cases

/// The scene with `method`, step (or first trial step) `h` and rtol = atol = `tol`.
pub fn with_solver(mut s: Scene, method: Method, h: f64, tol: f64) -> Scene {
    s.solver.method = method;
    s.solver.step_size = h;
    s.solver.rtol = tol;
    s.solver.atol = tol;
    s
}

/// The scene with rk4 at 1 ms, the method the cases that name no other are run with.
pub fn rk4(s: Scene) -> Scene {
    with_solver(s, Method::Rk4, 1e-3, 1e-6)
}

/// A simulation of a scene that must build.
pub fn build(s: &Scene) -> Simulation {
    Simulation::new(Model::new(s).expect("the scene builds"))
}

/// A run of `scene` to `t_end` in communication steps `dt` under constant node loads.
pub fn run_loaded(s: &Scene, t_end: f64, dt: f64, load: Vector3<f64>) -> (Simulation, Tracker) {
    let mut sim = build(s);
    load_all(&mut sim, load);
    let mut t = Tracker::new(&mut sim);
    let _ = t.run(&mut sim, t_end, dt, |_, _| {});
    (sim, t)
}

/// Settings per method: rk4, rattle and sdirk3 at 1 ms, dopri5 at `tol`.
pub fn methods(tol: f64) -> [(Method, f64, f64); 4] {
    [
        (Method::Rk4, 1e-3, 1e-6),
        (Method::Rattle, 1e-3, 1e-6),
        (Method::Dopri5, 1e-3, tol),
        (Method::Sdirk3, 1e-3, 1e-6),
    ]
}

/// prism2-elastic with every κ replaced, prestressed to 1e-3·κ N (so the prestress keeps
/// rest lengths consistent and the strain is the same for every κ) and loaded with 5 % of
/// that along +x on the top ring: the cables stay taut and the top moves ~1.4 mm.
pub fn stiff_scene(kappa: f64, method: Method, h: f64) -> Scene {
    let mut s = builtin("prism2-elastic").unwrap();
    s.cables.iter_mut().for_each(|c| c.stiffness = Some(kappa));
    s.prestress.as_mut().unwrap().min_tension = 1e-3 * kappa;
    with_solver(s, method, h, 1e-9)
}

/// [`stiff_scene`] under its load for 1 s in communication steps `comm`; also returns
/// the least cable tension seen.
pub fn stiff_run(kappa: f64, method: Method, h: f64, comm: f64) -> (Simulation, Tracker, f64) {
    let mut sim = build(&stiff_scene(kappa, method, h));
    load_all(&mut sim, Vector3::new(5e-5 * kappa, 0.0, 0.0));
    let mut t = Tracker::new(&mut sim);
    let mut min_tension = f64::INFINITY;
    let _ = t.run(&mut sim, 1.0, comm, |sim, _| {
        let n = sim.model().cables.len();
        min_tension = (0..n)
            .map(|j| sim.cable_tension(j))
            .fold(min_tension, f64::min);
    });
    (sim, t, min_tension)
}

/// The icosahedron (one face pinned) started with a velocity disturbance of 0.3 m/s.
pub fn disturbed_icosahedron() -> Scene {
    let mut s = builtin("icosahedron").unwrap();
    s.velocities = Some(
        (0..s.nodes.len())
            .map(|i| {
                let x = i as f64;
                [
                    0.3 * (1.7 * x).sin(),
                    0.3 * (2.3 * x).cos(),
                    0.3 * (0.7 * x).sin(),
                ]
            })
            .collect(),
    );
    s
}

/// prism2-elastic under a heavy sinusoid (30 N at 2 Hz along x on the top ring, held
/// for each 1 ms communication step), 2 s. Returns the samples (every 10 ms), the least
/// tension seen and the most slack→taut re-tensionings of one cable.
pub fn slack_run(method: Method, h: f64, tol: f64) -> (Tracker, Vec<Vec<Vector3<f64>>>, f64, u32) {
    let s = with_solver(builtin("prism2-elastic").unwrap(), method, h, tol);
    let mut sim = build(&s);
    let mut t = Tracker::new(&mut sim);
    let n = sim.model().cables.len();
    let (mut slack, mut retension) = (vec![false; n], vec![0u32; n]);
    let (mut samples, mut least) = (Vec::new(), f64::INFINITY);
    for k in 0..200 {
        let _ = t.run(&mut sim, (k + 1) as f64 * 0.01, 1e-3, |sim, time| {
            sinusoid(sim, time);
            for j in 0..n {
                let tension = sim.cable_tension(j);
                least = least.min(tension);
                if slack[j] && tension > 0.0 {
                    retension[j] += 1;
                }
                slack[j] = tension == 0.0;
            }
        });
        samples.push(positions(&sim));
    }
    (t, samples, least, retension.into_iter().max().unwrap())
}

/// Largest node distance over matching samples of two runs.
pub fn sample_distance(a: &[Vec<Vector3<f64>>], b: &[Vec<Vector3<f64>>]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| max_distance(x, y))
        .fold(0.0, f64::max)
}

/// Runs every method on `scene` for `t_end` under `load`; check: exact constraints and
/// energy (counting the constant load's potential, undamped) drifting ≤ `drift[method]`.
pub fn conservative_rows(
    case: &str,
    s: &Scene,
    t_end: f64,
    load: f64,
    drift: [f64; 4],
    note: &str,
) -> Vec<Outcome> {
    methods(1e-9)
        .iter()
        .zip(drift)
        .map(|(&(m, h, tol), limit)| {
            let s = with_solver(s.clone(), m, h, tol);
            let (_, t) = run_loaded(&s, t_end, 1e-3, Vector3::new(load, 0.0, 0.0));
            let mut o = Outcome::from_tracker(case, m.name(), &t, true);
            o.check_exact()
                .check(t.error.is_none(), "no step error")
                .check(t.max_drift <= limit, format!("energy drift <= {limit:.0e}"));
            o.note(format!("{note}; energy drift limit {limit:.0e}"));
            o
        })
        .collect()
}

/// Number of nodes shared by ≥ 2 bars, and the most bars at one node.
pub fn joints(s: &Scene) -> (usize, usize) {
    let mut count = vec![0; s.nodes.len() + 1];
    s.bars
        .iter()
        .flat_map(|b| b.nodes)
        .for_each(|n| count[n] += 1);
    (
        count.iter().filter(|&&c| c >= 2).count(),
        *count.iter().max().unwrap(),
    )
}

/// The icosahedron with no pins or loads, spinning and drifting as a rigid body.
pub fn free_spinning_icosahedron() -> Scene {
    let mut s = builtin("icosahedron").unwrap();
    s.fixed.clear();
    s.force_inputs.clear();
    let omega = Vector3::new(0.3, -0.5, 2.0);
    let drift = Vector3::new(0.1, 0.05, -0.02);
    s.velocities = Some(
        s.nodes
            .iter()
            .map(|p| (omega.cross(&Vector3::from(*p)) + drift).into())
            .collect(),
    );
    s
}

/// Centre of mass of the bars.
pub fn centre(sim: &Simulation) -> Vector3<f64> {
    let m = sim.model();
    let mass: f64 = m.bars.iter().map(|b| b.mass).sum();
    m.bars
        .iter()
        .map(|b| (sim.node_position(b.nodes[0]) + sim.node_position(b.nodes[1])) * (b.mass / 2.0))
        .sum::<Vector3<f64>>()
        / mass
}

/// One hard case run with the correction on and off.
pub struct Hard {
    pub case: &'static str,
    pub scene: Scene,
    pub t_end: f64,
    pub inputs: fn(&mut Simulation, f64),
    /// Constant loads only, so the energy (with the loads' potential) is conserved.
    pub conservative: bool,
}

/// The heavy sinusoid: 30 N at 2 Hz along x on every force-input node.
pub fn sinusoid(sim: &mut Simulation, time: f64) {
    load_all(sim, Vector3::new(30.0 * (4.0 * PI * time).sin(), 0.0, 0.0));
}

/// The hard cases re-run without the correction (constant inputs set each step).
pub fn hard_cases() -> Vec<Hard> {
    let huge = |sim: &mut Simulation, _: f64| sim.inputs.force_density[6] = 1e9;
    let stiff = |sim: &mut Simulation, _: f64| load_all(sim, Vector3::new(50.0, 0.0, 0.0));
    let none = |_: &mut Simulation, _: f64| {};
    let one_newton = |sim: &mut Simulation, _: f64| load_all(sim, Vector3::new(1.0, 0.0, 0.0));
    vec![
        Hard {
            case: "long_horizon_icosahedron_1e6_steps",
            scene: disturbed_icosahedron(),
            t_end: 1000.0,
            inputs: none,
            conservative: true,
        },
        Hard {
            case: "stiff_cables_1e6",
            scene: stiff_scene(1e6, Method::Dopri5, 1e-3),
            t_end: 1.0,
            inputs: stiff,
            conservative: true,
        },
        Hard {
            case: "slack_and_taut_heavy_sinusoid",
            scene: rk4(builtin("prism2-elastic").unwrap()),
            t_end: 2.0,
            inputs: sinusoid,
            conservative: false,
        },
        Hard {
            case: "class_k_many_joints_tower20 (10 s)",
            scene: rk4(builtin("tower20").unwrap()),
            t_end: 10.0,
            inputs: one_newton,
            conservative: true,
        },
        Hard {
            case: "class_k_tripod_joint",
            scene: tripod(),
            t_end: 3.0,
            inputs: none,
            conservative: true,
        },
        Hard {
            case: "fast_spin_100_rad_s",
            scene: spinning_bar(100.0),
            t_end: 1.0,
            inputs: none,
            conservative: true,
        },
        Hard {
            case: "free_floating_icosahedron",
            scene: free_spinning_icosahedron(),
            t_end: 10.0,
            inputs: none,
            conservative: true,
        },
        Hard {
            case: "huge_force_density_1e9",
            scene: with_solver(builtin("prism2").unwrap(), Method::Dopri5, 1e-3, 1e-9),
            t_end: 0.05,
            inputs: huge,
            conservative: true,
        },
    ]
}
