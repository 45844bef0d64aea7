//! A running simulation: the immutable model, the state, the inputs, the scratch space and
//! the integrator. One step is: integrate → correct positions → correct velocities →
//! check finiteness (restoring the last good state on failure).

use nalgebra::{DMatrix, Vector3};

use crate::dynamics::tangent::Tangent;
use crate::dynamics::{self, energy, Inputs, Workspace};
use crate::error::StepError;
use crate::integrator::{Integrator, Rhs};
use crate::model::Model;

mod cause;
mod contact_rates;
mod events;
mod grip;
mod locate;
mod rate;
mod stability;
mod stepping;
mod work;

pub use cause::{Cause, Rate};
pub use stability::stability_limit;
pub use work::{fixed_steps, Pace, Work, RESOLVING_STEP, STABLE_ATTEMPTS_PER_RATE};

/// The integrated state.
#[derive(Debug, Clone, PartialEq)]
pub struct State {
    /// Time in s.
    pub time: f64,
    /// `[η₂ (3r, m); η̇₂ (3r, m/s)]`, column g of η₂ at `3g..3g+3`.
    pub y: Vec<f64>,
}

/// The last stability check of a fixed-step method.
#[derive(Debug, Clone, Default, PartialEq)]
struct Stability {
    /// Largest commanded force density at the check (it adds stiffness), N/m.
    checked_density: Option<f64>,
    /// Why the step would blow up, if it would.
    problem: Option<String>,
}

/// Counters of the work done so far.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Stats {
    /// Accepted steps.
    pub steps: u64,
    /// Rejected steps: by the adaptive method's error control, or trial steps redone in
    /// parts because a force law switched inside them.
    pub rejected: u64,
    /// Located events: switches of a force law (a cable going slack or taut, a contact
    /// point touching or leaving the ground) at which a step was split.
    pub events: u64,
}

/// Model + state + inputs + workspace + integrator.
pub struct Simulation {
    model: Model,
    /// Current inputs (set between steps).
    pub inputs: Inputs,
    state: State,
    last_good: Vec<f64>,
    /// The grips at `last_good` and at `advance_start`.
    last_good_grip: Vec<crate::contact::Grip>,
    advance_grip: Vec<crate::contact::Grip>,
    advance_start: State,
    /// The inputs of the last step: carried integrator values are stale once they change.
    stepped_inputs: Inputs,
    /// Next trial step of an adaptive method, s.
    h_next: f64,
    stats: Stats,
    ws: Workspace,
    /// The accelerations of the last [`Simulation::refresh`].
    acc: Vec<f64>,
    /// The time `acc` was evaluated at while the state has not moved since, and the inputs
    /// then: a step from there takes `acc` as its first stage instead of evaluating again.
    evaluated: Option<f64>,
    evaluated_inputs: Inputs,
    integrator: Box<dyn Integrator>,
    /// Apply the paper's correction after each step.
    pub correction: bool,
    /// Refuse fixed steps above the explicit method's stability limit (on by default).
    pub guard_stability: bool,
    /// Split steps where a force law switches (see `events`); `solver.locate_events`.
    pub locate_events: bool,
    events: events::Events,
    stability: Stability,
    warnings: Vec<String>,
}

impl Clone for Simulation {
    fn clone(&self) -> Self {
        Self {
            model: self.model.clone(),
            inputs: self.inputs.clone(),
            state: self.state.clone(),
            last_good: self.last_good.clone(),
            last_good_grip: self.last_good_grip.clone(),
            advance_grip: self.advance_grip.clone(),
            advance_start: self.advance_start.clone(),
            stepped_inputs: self.stepped_inputs.clone(),
            h_next: self.h_next,
            stats: self.stats,
            ws: self.ws.clone(),
            acc: self.acc.clone(),
            evaluated: self.evaluated,
            evaluated_inputs: self.evaluated_inputs.clone(),
            integrator: self.integrator.boxed_clone(),
            correction: self.correction,
            guard_stability: self.guard_stability,
            locate_events: self.locate_events,
            events: self.events.clone(),
            stability: self.stability.clone(),
            warnings: self.warnings.clone(),
        }
    }
}

/// The right-hand side seen by the integrators.
struct System<'a> {
    model: &'a Model,
    inputs: &'a Inputs,
    ws: &'a mut Workspace,
    correction: bool,
    /// The accelerations at the start of the step, when the simulation has them.
    start: Option<&'a [f64]>,
}

impl Rhs for System<'_> {
    fn eval(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
        let half = y.len() / 2;
        let (q, v) = y.split_at(half);
        let (dq, dv) = dy.split_at_mut(half);
        self.ws.copy_in_halves(dq, v);
        dynamics::accelerations(self.model, self.inputs, t, q, v, self.ws, dv);
    }

    fn eval_start(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> bool {
        let Some(acc) = self.start.take() else {
            self.eval(t, y, dy);
            return true;
        };
        let half = y.len() / 2;
        let (dq, dv) = dy.split_at_mut(half);
        self.ws.copy_in_halves(dq, &y[half..]);
        self.ws.copy_in_halves(dv, acc);
        false
    }

    fn for_each_half(&self, out: &mut [f64], f: &(dyn Fn(usize, &mut [f64]) + Sync)) {
        self.ws.for_each_half(out, f);
    }

    fn jacobian(&mut self, t: f64, y: &[f64]) -> Option<(DMatrix<f64>, DMatrix<f64>)> {
        let (q, v) = y.split_at(y.len() / 2);
        Some(Tangent::new(self.model, self.inputs, t, q, v).acceleration_jacobian(v))
    }

    fn project_positions(&mut self, y: &mut [f64], before: &[f64], moved: &mut [f64]) {
        if self.correction {
            let half = y.len() / 2;
            let coords = &self.model.coords;
            let plan = &self.model.correction;
            plan.correct_positions_shake(coords, &mut y[..half], &before[..half], moved);
        }
    }
}

impl Simulation {
    /// Starts at the scene's geometry and (projected) velocities with the scene's method.
    pub fn new(model: Model) -> Self {
        let s = &model.solver;
        let integrator = s.method.integrator(model.state_len(), s.rtol, s.atol);
        Self::with_integrator(model, integrator)
    }

    /// Starts with a chosen integrator.
    pub fn with_integrator(model: Model, integrator: Box<dyn Integrator>) -> Self {
        let mut ws = Workspace::new(&model);
        let mut warnings = model.warnings.clone();
        let y = initial_state(&model, &mut ws, &mut warnings);
        let n = y.len();
        let grips = Inputs::start(&model).grip;
        let mut sim = Self {
            last_good_grip: grips.clone(),
            advance_grip: grips,
            inputs: Inputs::start(&model),
            stepped_inputs: Inputs::start(&model),
            evaluated: None,
            evaluated_inputs: Inputs::start(&model),
            correction: model.solver.correction,
            guard_stability: true,
            locate_events: model.solver.locate_events,
            events: events::Events::new(&model),
            stability: Stability::default(),
            advance_start: State {
                time: 0.0,
                y: y.clone(),
            },
            state: State { time: 0.0, y },
            last_good: vec![0.0; n],
            h_next: model.solver.step_size,
            stats: Stats::default(),
            ws,
            acc: vec![0.0; n / 2],
            integrator,
            model,
            warnings,
        };
        sim.update_grips(false);
        sim.refresh();
        sim
    }

    /// Evaluates on two threads where the structure allows and is large enough (`true`, the
    /// default: see [`crate::dynamics::parallel`]) or on this one only (`false`).
    pub fn use_two_threads(&mut self, on: bool) {
        let from = if on {
            crate::dynamics::parallel::MIN_BARS
        } else {
            usize::MAX
        };
        self.ws = Workspace::two_threads_from(&self.model, from);
        self.refresh();
    }

    /// The model.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// Model and load-time warnings.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// The current state.
    pub fn state(&self) -> &State {
        &self.state
    }

    /// Replaces the state (e.g. from a snapshot) and re-evaluates the outputs.
    pub fn set_state(&mut self, state: State) {
        assert_eq!(state.y.len(), self.state.y.len(), "state length");
        self.state = state;
        self.integrator.invalidate();
        self.reset_grips();
        self.refresh();
    }

    /// What the integrator carries between steps, and the adaptive method's next trial
    /// step: with the state, everything a bit-identical resumption needs.
    pub fn carried(&self) -> (f64, Vec<f64>) {
        let same_inputs = self.stepped_inputs == self.inputs;
        let values = if same_inputs {
            self.integrator.carried()
        } else {
            Vec::new()
        };
        (self.h_next, values)
    }

    /// Restores what [`Simulation::carried`] returned (after [`Simulation::set_state`]).
    pub fn restore_carried(&mut self, h_next: f64, values: &[f64]) {
        self.h_next = h_next;
        self.integrator.restore_carried(values);
        self.stepped_inputs.copy_from(&self.inputs);
    }

    /// Steps taken and rejected so far.
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Current time in s.
    pub fn time(&self) -> f64 {
        self.state.time
    }

    /// Sets the current time (e.g. an experiment's start time).
    pub fn set_time(&mut self, time: f64) {
        self.state.time = time;
    }

    /// The integrator in use.
    pub fn integrator(&self) -> &dyn Integrator {
        self.integrator.as_ref()
    }

    pub(crate) fn check_inputs(&self) -> Result<(), StepError> {
        for (k, &g) in self.inputs.force_density.iter().enumerate() {
            if !g.is_finite() {
                return Err(StepError::NonFiniteInput {
                    name: format!("cable[{}].force_density", self.model.controlled[k] + 1),
                    value: g,
                });
            }
        }
        for (k, &l) in self.inputs.rest_length.iter().enumerate() {
            if !l.is_finite() {
                return Err(StepError::NonFiniteInput {
                    name: format!("cable[{}].rest_length", self.model.reeled[k] + 1),
                    value: l,
                });
            }
        }
        for (k, f) in self.inputs.node_force.iter().enumerate() {
            for (axis, &x) in ["fx", "fy", "fz"].iter().zip(f.iter()) {
                if !x.is_finite() {
                    return Err(StepError::NonFiniteInput {
                        name: format!("node[{}].{axis}", self.model.force_inputs[k] + 1),
                        value: x,
                    });
                }
            }
        }
        Ok(())
    }

    /// Re-evaluates forces, λ and accelerations at the current state (for the outputs).
    pub fn refresh(&mut self) {
        let half = self.state.y.len() / 2;
        let (q, v) = self.state.y.split_at(half);
        let t = self.state.time;
        dynamics::accelerations(
            &self.model,
            &self.inputs,
            t,
            q,
            v,
            &mut self.ws,
            &mut self.acc,
        );
        self.evaluated = Some(t);
        self.evaluated_inputs.copy_from(&self.inputs);
    }

    /// Makes the next step evaluate at its start itself instead of taking the last
    /// refresh's evaluation: for timing a method alone, with samples taken between steps.
    pub fn forget_refresh(&mut self) {
        self.evaluated = None;
    }

    /// The workspace of the last evaluation (node positions, γ, λ, …).
    pub fn workspace(&self) -> &Workspace {
        &self.ws
    }

    /// Position of node `n` (0-based), m, in the current state (not the last evaluation,
    /// which after a step is the method's last stage).
    pub fn node_position(&self, n: usize) -> Vector3<f64> {
        self.node_vector(n, true)
    }

    /// Velocity of node `n` (0-based), m/s, in the current state.
    pub fn node_velocity(&self, n: usize) -> Vector3<f64> {
        self.node_vector(n, false)
    }

    /// A node's position (`position`) or velocity from the state; a node on no bar is
    /// fixed where the workspace holds it.
    fn node_vector(&self, n: usize, position: bool) -> Vector3<f64> {
        let half = self.state.y.len() / 2;
        let (q, v) = self.state.y.split_at(half);
        match self.model.coords.node_end[n] {
            Some(e) if position => self.model.coords.end_vector(e, q, true),
            Some(e) => self.model.coords.end_vector(e, v, false),
            None if position => self.ws.node_pos[n],
            None => self.ws.node_vel[n],
        }
    }

    /// Acceleration of node `n` (0-based), m/s², from the last evaluation.
    pub fn node_acceleration(&self, n: usize) -> Vector3<f64> {
        self.model.coords.node_end[n].map_or(Vector3::zeros(), |e| self.ws.end_acc[e])
    }

    /// Tension of cable `j` (0-based), N, from the last evaluation.
    pub fn cable_tension(&self, j: usize) -> f64 {
        let [a, b] = self.model.cables[j].nodes;
        self.ws.gamma[j] * (self.ws.node_pos[b] - self.ws.node_pos[a]).norm()
    }

    /// Axial force of bar `i` (0-based), N, compression positive.
    pub fn bar_force(&self, i: usize) -> f64 {
        self.ws.lambda[i] * self.model.bars[i].length
    }

    /// `max |‖bᵢ‖ − lᵢ|`, m.
    pub fn length_error(&self) -> f64 {
        energy::length_error(&self.model, &self.ws)
    }

    /// `max |bᵢ · ḃᵢ|`, m²/s.
    pub fn orthogonality_error(&self) -> f64 {
        energy::orthogonality_error(&self.model, &self.ws)
    }

    /// Normal ground force on contact point `k` (`Ground::nodes` order), N.
    pub fn contact_force(&self, k: usize) -> f64 {
        let normal = self
            .model
            .ground
            .as_ref()
            .map_or(Vector3::zeros(), |g| g.normal);
        self.ws.contact_force[k].dot(&normal)
    }

    /// Force that support `k` (`Model::supports` order) exerts on the structure, N.
    pub fn support_reaction(&self, k: usize) -> Vector3<f64> {
        self.model.supports[k].reaction(&self.model.cables, &self.ws)
    }

    /// What terrain shape `k` does to the structure at the last evaluation.
    pub fn shape_load(&self, k: usize) -> crate::dynamics::terrain::ShapeLoad {
        self.ws.shape_load[k]
    }

    /// Total ground force on the structure, N.
    pub fn ground_force(&self) -> Vector3<f64> {
        self.ws.contact_force.iter().sum()
    }

    /// Every contact point and its force in the current state (terrain, collisions and
    /// the ground, with the current grips); see [`dynamics::contact_points`].
    pub fn contact_points(&self) -> Vec<dynamics::contact_points::ContactPoint> {
        let n = self.model.n_nodes();
        let x: Vec<Vector3<f64>> = (0..n).map(|i| self.node_position(i)).collect();
        let v: Vec<Vector3<f64>> = (0..n).map(|i| self.node_velocity(i)).collect();
        dynamics::contact_points::contact_points(&self.model, &self.inputs.grip, &x, &v)
    }

    /// Kinetic + cable strain + gravity + ground penalty energy, J.
    pub fn energy(&self) -> f64 {
        energy::kinetic(&self.model, &self.ws)
            + energy::potential(&self.model, &self.inputs, &self.ws)
    }

    /// Linear momentum, kg·m/s.
    pub fn linear_momentum(&self) -> Vector3<f64> {
        energy::linear_momentum(&self.model, &self.ws)
    }

    /// Angular momentum about the origin, kg·m²/s.
    pub fn angular_momentum(&self) -> Vector3<f64> {
        energy::angular_momentum(&self.model, &self.ws)
    }
}

/// η₂ = N U₂ and η̇₂ = Ṅ U₂ from the scene, then the velocity correction; warns when the
/// scene's velocities had to be projected.
fn initial_state(model: &Model, ws: &mut Workspace, warnings: &mut Vec<String>) -> Vec<f64> {
    let coords = &model.coords;
    let r3 = 3 * coords.r;
    let mut y = vec![0.0; 2 * r3];
    let given: Vec<Vector3<f64>> = match &model.scene.velocities {
        Some(vs) => vs.iter().map(|v| Vector3::from(*v)).collect(),
        None => vec![Vector3::zeros(); model.n_nodes()],
    };
    {
        let (q, v) = y.split_at_mut(r3);
        for e in 0..coords.n_ends() {
            let node = coords.end_node[e];
            coords.scatter(e, &model.positions[node], q);
            coords.scatter(e, &given[node], v);
        }
        model.correction.correct_velocities(coords, q, v);
    }
    let (q, v) = y.split_at(r3);
    dynamics::kinematics(model, q, v, ws);
    let scale = given.iter().map(|v| v.norm()).fold(0.0, f64::max);
    let change = (0..model.n_nodes())
        .map(|n| (ws.node_vel[n] - given[n]).norm())
        .fold(0.0, f64::max);
    if change > 1e-12 * scale.max(1e-300) && scale > 0.0 {
        warnings.push(format!(
            "velocities: the initial velocities violate the constraints (pins, joints or rigid \
             bars); they were projected onto them (largest change {change:.3e} m/s)"
        ));
    }
    y
}
