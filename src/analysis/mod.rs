//! Analyses of a structure about a state at rest, built on the tangent of the equations
//! of motion ([`tangent`]): the static equilibrium a scene can start from
//! ([`equilibrium`]), natural frequencies and mode shapes ([`modes`]) and continuous-time
//! state-space models ([`linear`]).
//!
//! The bar lengths stay constraints in η₂, so the analyses work in minimal coordinates ξ
//! of the constraint tangent space: `δη₂ = Z ξ` with `Z` an orthonormal basis of null(G)
//! (`../shared/design/analysis.md`).

pub mod equilibrium;
pub mod export;
pub mod linear;
pub mod modes;
mod reduced;
pub mod tangent;

pub use equilibrium::{settle, Settled};
pub use reduced::Reduced;
pub use tangent::{InputChannel, Tangent};

use crate::error::SceneError;
use crate::model::Model;
use crate::scene::{Scene, Start};

/// The model of a scene at the start it asks for: the given geometry, or (with
/// `start = "equilibrium"`) the static equilibrium under everything it declares.
pub fn load(scene: &Scene) -> Result<Model, SceneError> {
    let mut model = Model::new(scene)?;
    if scene.start == Start::Equilibrium {
        settle(&mut model)?;
    }
    Ok(model)
}

/// Largest unbalanced force, relative to the applied forces, that still counts as rest.
pub const REST_TOLERANCE: f64 = 1e-8;

/// Refuses a simulation state that is not a static equilibrium (moving, or with an
/// unbalanced force), naming the fix; `what` names the analysis asking.
pub fn require_rest(sim: &crate::sim::Simulation, what: &str) -> Result<(), String> {
    let model = sim.model();
    let y = &sim.state().y;
    let (q, v) = y.split_at(y.len() / 2);
    let speed = v.iter().map(|x| x.abs()).fold(0.0, f64::max);
    let fix = "linearize about an equilibrium: add `start = \"equilibrium\"` to the scene \
               (and no `velocities`)";
    if speed > 0.0 {
        return Err(format!(
            "{what}: the start state is moving (velocities up to {speed:.3e} m/s); {fix}"
        ));
    }
    let (residual, scale) = equilibrium::unbalanced(model, &sim.inputs, q);
    if residual > REST_TOLERANCE * scale {
        return Err(format!(
            "{what}: the start state is not an equilibrium (unbalanced force {residual:.3e} N \
             against {scale:.3e} N of applied forces); {fix}"
        ));
    }
    Ok(())
}
