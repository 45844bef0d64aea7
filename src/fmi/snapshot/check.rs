//! A restored state is checked field by field against the model of the instance that
//! restores it, since a buffer with a recomputed checksum can hold anything: sizes,
//! modes and flags, parameters (by the checks of fmi2SetReal/Integer/Boolean), what the
//! integrator carries, node positions and speeds (by the scene's limits), and bar lengths
//! (to the tolerance the correction holds them to, or the drift a run without it allows).

use super::{parameter_variables, Snapshot};
use crate::correction::{HELD_TO, MAX_UNCORRECTED_DRIFT};
use crate::fmi::instance::time_tolerance;
use crate::fmi::parameters::{apply_parameter, refused_value};
use crate::fmi::state::Core;
use crate::fmi::Mode;
use crate::numbers::shortest;
use crate::scene::{limits, Scene};

/// How many times [`HELD_TO`] of the coordinates' magnitude a corrected bar length may be
/// off: the correction works to it, and rounding the end positions adds a few ulps.
const ROUNDING_SLACK: f64 = 64.0;

impl Snapshot {
    /// Checks every field against what `core`'s model allows; returns the scene that the
    /// state's parameters give.
    pub(in crate::fmi) fn check(&self, core: &Core) -> Result<Scene, String> {
        self.check_sizes(core)?;
        self.check_grips(core)?;
        self.check_flow()?;
        let scene = self.check_parameters(core)?;
        self.check_integrator(&scene)?;
        self.check_motion(core, &scene)?;
        Ok(scene)
    }

    fn check_sizes(&self, core: &Core) -> Result<(), String> {
        let model = core.sim.model();
        let sizes = [
            (
                "parameter values",
                self.parameters.len(),
                parameter_variables(core).count(),
            ),
            (
                "state vector values (η₂ and η̇₂)",
                self.state.y.len(),
                model.state_len(),
            ),
            (
                "force-density inputs",
                self.force_density.len(),
                model.controlled.len(),
            ),
            (
                "node-force inputs",
                self.node_force.len(),
                model.force_inputs.len(),
            ),
            (
                "rest-length inputs",
                self.rest_length.len(),
                model.reeled.len(),
            ),
            (
                "friction-grip values",
                self.grips.len(),
                4 * model.terrain.as_ref().map_or(0, |t| t.grips()),
            ),
            (
                "negative-input warning flags",
                self.warned_negative.len(),
                core.warned_negative.len(),
            ),
        ];
        match sizes.iter().find(|(_, found, wanted)| found != wanted) {
            Some((what, found, wanted)) => {
                Err(format!("it holds {found} {what}, this FMU has {wanted}"))
            }
            None => Ok(()),
        }
    }

    /// The mode, the times and the pending-rebuild flag.
    fn check_flow(&self) -> Result<(), String> {
        if self.mode == Mode::Error {
            return Err(
                "mode is Error, in which fmi2GetFMUstate takes no state (allowed: \
                        Instantiated, InitializationMode, StepComplete, Terminated)"
                    .into(),
            );
        }
        if self.rebuild && matches!(self.mode, Mode::StepComplete | Mode::Terminated) {
            return Err(format!(
                "the pending-rebuild flag is 1 in mode {:?}; parameter changes wait for a \
                 rebuild only before initialization ends (allowed there: 0)",
                self.mode
            ));
        }
        if let Some(stop) = self.stop_time {
            if self.time > stop + time_tolerance(stop) {
                return Err(format!(
                    "time = {} s is past its stop time {} s (allowed: time ≤ stop time)",
                    shortest(self.time),
                    shortest(stop)
                ));
            }
        }
        Ok(())
    }

    /// A grip holds only where a bar end can grip: on a shape whose friction sticks, at an
    /// end that moves.
    fn check_grips(&self, core: &Core) -> Result<(), String> {
        let Some(terrain) = &core.sim.model().terrain else {
            return Ok(());
        };
        let per_capsule = 2 * terrain.shapes.len();
        for (k, grip) in self.grips().iter().enumerate() {
            let (capsule, shape, end) = (k / per_capsule, k % per_capsule / 2, k % 2);
            let can = terrain.sticks[shape] && terrain.capsules[capsule].ends[end].is_some();
            if !can && *grip != crate::contact::Grip::Free {
                return Err(format!(
                    "friction grip {} holds where nothing grips (terrain[{}] with \
                     friction_model = \"regularized\", or a pinned end; allowed: mode 0 there)",
                    k + 1,
                    shape + 1
                ));
            }
        }
        Ok(())
    }

    /// Each parameter value by the check of fmi2SetReal/Integer/Boolean, then the scene
    /// they give by the scene's validation, as a set call does.
    fn check_parameters(&self, core: &Core) -> Result<Scene, String> {
        let mut scene = core.scene.clone();
        for (variable, &value) in parameter_variables(core).zip(&self.parameters) {
            if let Some(why) = refused_value(variable, value) {
                return Err(why);
            }
            apply_parameter(&mut scene, variable.binding, value);
        }
        scene
            .validate()
            .map_err(|e| format!("its parameters give an invalid scene: {e}"))?;
        Ok(scene)
    }

    fn check_integrator(&self, scene: &Scene) -> Result<(), String> {
        if self.h_next <= 0.0 {
            return Err(format!(
                "the adaptive method's next step = {} s is not positive (allowed: > 0)",
                shortest(self.h_next)
            ));
        }
        let s = &scene.solver;
        let carries = s
            .method
            .integrator(self.state.y.len(), s.rtol, s.atol)
            .carried_len();
        if !self.carried.is_empty() && self.carried.len() != carries {
            return Err(format!(
                "it holds {} values carried by the integrator; {} carries 0 or {carries}",
                self.carried.len(),
                s.method.name()
            ));
        }
        Ok(())
    }

    /// Node positions and velocities within the scene's limits, bar lengths as the model
    /// has them, and (with the correction on) bar velocities orthogonal to the bars.
    fn check_motion(&self, core: &Core, scene: &Scene) -> Result<(), String> {
        let model = core.sim.model();
        let coords = &model.coords;
        let (q, v) = self.state.y.split_at(self.state.y.len() / 2);
        let end = |e: usize| {
            (
                coords.end_vector(e, q, true),
                coords.end_vector(e, v, false),
            )
        };
        for e in 0..coords.n_ends() {
            let node = coords.end_node[e] + 1;
            let (x, xdot) = end(e);
            limits::check_position(&format!("node[{node}] position"), &x.into())
                .and_then(|()| {
                    limits::check_velocity(&format!("node[{node}] velocity"), &xdot.into())
                })
                .map_err(|e| e.to_string())?;
        }
        // Every end is finite and within the limits from here on: no NaN below.
        let correction = scene.solver.correction;
        for (i, bar) in model.bars.iter().enumerate() {
            let ((a, va), (b, vb)) = (end(2 * i), end(2 * i + 1));
            let length = (b - a).norm();
            let allowed = if correction {
                ROUNDING_SLACK * HELD_TO * (bar.length + a.norm() + b.norm())
            } else {
                MAX_UNCORRECTED_DRIFT * bar.length
            };
            let error = (length - bar.length).abs();
            if error > allowed {
                return Err(format!(
                    "bar[{}] is {} m long, but the model's bar is {} m (allowed error \
                     {allowed:.1e} m with solver.correction = {})",
                    i + 1,
                    shortest(length),
                    shortest(bar.length),
                    u8::from(correction)
                ));
            }
            if correction {
                let along = (b - a).dot(&(vb - va)).abs();
                let allowed = ROUNDING_SLACK * HELD_TO * length * (va.norm() + vb.norm());
                if along > allowed {
                    return Err(format!(
                        "bar[{}]'s ends separate at {:.3e} m/s, but a rigid bar's length does \
                         not change (allowed {:.1e} m/s with solver.correction = 1)",
                        i + 1,
                        along / length,
                        allowed / length
                    ));
                }
            }
        }
        Ok(())
    }
}
