//! What an instance is, apart from its name, GUID and logger: the scene, the running
//! simulation, the variable table and the mode. `Reset` restores it, snapshots save it.

use super::parameters::read_parameter;
use super::variables::{Binding, VariableTable};
use super::Mode;
use crate::dynamics::Inputs;
use crate::model::Model;
use crate::scene::Scene;
use crate::sim::Simulation;

/// Everything that `Reset` restores.
#[derive(Clone)]
pub(super) struct Core {
    pub(super) scene: Scene,
    pub(super) sim: Simulation,
    pub(super) table: VariableTable,
    pub(super) mode: Mode,
    pub(super) time: f64,
    pub(super) stop_time: Option<f64>,
    pub(super) rebuild: bool,
    pub(super) stale: bool,
    pub(super) warned_negative: Vec<bool>,
}

/// The parts of [`Core`] that a set call may change, applied only if all values pass.
pub(super) struct PendingSet {
    pub(super) scene: Scene,
    pub(super) inputs: Inputs,
    pub(super) warned_negative: Vec<bool>,
    pub(super) rebuild: bool,
}

impl Core {
    /// The current value behind a binding.
    pub(super) fn read(&self, binding: Binding) -> f64 {
        let core = self;
        let sim = &core.sim;
        match binding {
            Binding::Output(q) => q.value(sim),
            Binding::ForceDensity(k) => sim.inputs.force_density[k],
            Binding::NodeForce(k, axis) => sim.inputs.node_force[k][axis],
            Binding::ReelInput(k) => sim.inputs.rest_length[k],
            parameter => read_parameter(&core.scene, parameter),
        }
    }

    /// A simulation of `scene`'s parameters with this one's inputs, time and, once
    /// initialized, its state: what a parameter change rebuilds.
    pub(super) fn rebuilt(&self, scene: &Scene) -> Result<Simulation, String> {
        let keeps_state = matches!(
            self.mode,
            Mode::StepComplete | Mode::Terminated | Mode::Error
        );
        // A kept state replaces the start positions, so the equilibrium is not solved again.
        let model = if keeps_state {
            Model::new(scene)
        } else {
            crate::analysis::load(scene)
        };
        let mut sim = Simulation::new(model.map_err(|e| e.to_string())?);
        sim.inputs = self.sim.inputs.clone();
        if keeps_state {
            sim.set_state(self.sim.state().clone());
        } else {
            sim.set_time(self.time);
        }
        Ok(sim)
    }

    pub(super) fn clone_for_set(&self) -> PendingSet {
        PendingSet {
            scene: self.scene.clone(),
            inputs: self.sim.inputs.clone(),
            warned_negative: self.warned_negative.clone(),
            rebuild: self.rebuild,
        }
    }

    pub(super) fn commit_set(&mut self, next: PendingSet) {
        self.scene = next.scene;
        self.sim.inputs = next.inputs;
        self.warned_negative = next.warned_negative;
        self.rebuild = next.rebuild;
        self.stale = true;
    }
}
