//! One run of the sweep: a simulation under the report's excitation, sampled on the output
//! grid, with wall time measured around the integration only.

use std::time::Instant;

use nalgebra::Vector3;

use crate::integrator::Method;
use crate::model::Model;
use crate::sim::Simulation;

/// The output grid `t_k = k Δ`, `k = 0..=n`, and the load on the force-input nodes.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Grid {
    /// Output interval Δ, s.
    pub interval: f64,
    /// Number of intervals: the horizon is `n Δ`.
    pub n: usize,
    /// Constant load on every force-input node, N.
    pub load: Vector3<f64>,
}

impl Grid {
    /// The output indices a run with fixed step `h` can reach without shortened steps:
    /// every `s`-th, with `s` the smallest stride for which `s Δ / h` is a whole number
    /// (every one when none is found or the method is adaptive).
    pub fn stride(&self, fixed_step: Option<f64>) -> usize {
        let Some(h) = fixed_step else { return 1 };
        (1..=self.n.max(1))
            .find(|&s| {
                let ratio = s as f64 * self.interval / h;
                (ratio - ratio.round()).abs() <= 1e-9 * ratio.max(1.0) && ratio.round() >= 1.0
            })
            .unwrap_or(1)
    }
}

/// What one run saw at the output times it reached.
#[derive(Debug, Clone)]
pub(crate) struct Sampled {
    /// Output indices reached (into the grid), starting with 0.
    pub index: Vec<usize>,
    /// Node positions at each reached output, m.
    pub positions: Vec<Vec<Vector3<f64>>>,
    /// Bar-length error at each reached output, m.
    pub length_error: Vec<f64>,
    /// Orthogonality error at each reached output, m²/s.
    pub orthogonality_error: Vec<f64>,
    /// Energy including the load potential at each reached output, J.
    pub energy: Vec<f64>,
    /// Wall time spent in `advance_to`, s.
    pub wall_time: f64,
    /// Right-hand-side evaluations of the integrator.
    pub rhs_evaluations: u64,
    /// Accepted and rejected steps.
    pub steps: (u64, u64),
    /// The step error that ended the run early, if any.
    pub failure: Option<String>,
}

/// Runs `model` (already excited by `grid.load`) with the given method and setting
/// (step size in s for fixed-step methods, `rtol = atol` for dopri5).
pub(crate) fn simulate(
    model: &Model,
    method: Method,
    setting: f64,
    correction: bool,
    grid: &Grid,
) -> Sampled {
    let mut model = model.clone();
    model.solver.method = method;
    model.solver.correction = correction;
    let fixed = match method {
        Method::Dopri5 => {
            model.solver.rtol = setting;
            model.solver.atol = setting;
            None
        }
        Method::Rk4 | Method::Rattle | Method::Sdirk3 => {
            model.solver.step_size = setting;
            Some(setting)
        }
    };
    let stride = grid.stride(fixed);
    let mut sim = Simulation::new(model);
    for f in &mut sim.inputs.node_force {
        *f = grid.load;
    }
    let loaded: Vec<usize> = sim.model().force_inputs.clone();
    let start: Vec<Vector3<f64>> = loaded.iter().map(|&n| sim.node_position(n)).collect();
    let mut out = Sampled {
        index: Vec::new(),
        positions: Vec::new(),
        length_error: Vec::new(),
        orthogonality_error: Vec::new(),
        energy: Vec::new(),
        wall_time: 0.0,
        rhs_evaluations: 0,
        steps: (0, 0),
        failure: None,
    };
    let mut k = 0;
    loop {
        sim.refresh();
        // A constant load F on node n has the potential −F·(x_n − x_n(0)).
        let work: f64 = loaded
            .iter()
            .zip(&start)
            .map(|(&n, x0)| grid.load.dot(&(sim.node_position(n) - x0)))
            .sum();
        out.index.push(k);
        out.positions.push(
            (0..sim.model().n_nodes())
                .map(|n| sim.node_position(n))
                .collect(),
        );
        out.length_error.push(sim.length_error());
        out.orthogonality_error.push(sim.orthogonality_error());
        out.energy.push(sim.energy() - work);
        k += stride;
        if k > grid.n {
            break;
        }
        // The sample's refresh is not the method's work: its steps evaluate for themselves.
        sim.forget_refresh();
        let started = Instant::now();
        let result = sim.advance_to(k as f64 * grid.interval);
        out.wall_time += started.elapsed().as_secs_f64();
        if let Err(e) = result {
            out.failure = Some(e.to_string());
            break;
        }
    }
    out.rhs_evaluations = sim.integrator().rhs_evaluations();
    let stats = sim.stats();
    out.steps = (stats.steps, stats.rejected);
    out
}

/// Largest node distance between a run and the reference over the outputs the run
/// reached, m.
pub(crate) fn position_error(run: &Sampled, reference: &Sampled) -> f64 {
    run.index
        .iter()
        .zip(&run.positions)
        .map(|(&k, xs)| {
            let r = reference
                .index
                .iter()
                .position(|&j| j == k)
                .expect("the reference reaches every output");
            xs.iter()
                .zip(&reference.positions[r])
                .map(|(a, b)| (a - b).norm())
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max)
}

/// `max |E − E₀| / |E₀|` (relative to the largest |E| when E₀ = 0; 0 if E ≡ 0).
pub(crate) fn energy_drift(run: &Sampled) -> f64 {
    let e0 = run.energy.first().copied().unwrap_or(0.0);
    let scale = if e0 != 0.0 {
        e0.abs()
    } else {
        run.energy.iter().map(|e| e.abs()).fold(0.0, f64::max)
    };
    if scale == 0.0 {
        return 0.0;
    }
    run.energy
        .iter()
        .map(|e| (e - e0).abs() / scale)
        .fold(0.0, f64::max)
}
