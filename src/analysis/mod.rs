//! Analyses of a structure about a state at rest, built on the tangent of the equations
//! of motion ([`crate::dynamics::tangent`]): the static equilibrium a scene can start from
//! ([`equilibrium`]), natural frequencies and mode shapes ([`modes`]), their damping
//! ([`damped`]) and continuous-time state-space models ([`linear`]).
//!
//! The bar lengths stay constraints in η₂, so the analyses work in minimal coordinates ξ
//! of the constraint tangent space: `δη₂ = Z ξ` with `Z` an orthonormal basis of null(G)
//! (`../shared/design/analysis.md`).

pub mod damped;
pub mod equilibrium;
#[cfg(feature = "cli")]
pub mod export;
pub mod linear;
pub mod modes;
mod reduced;

pub use crate::dynamics::tangent;
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
        check_size(&model, "start = \"equilibrium\"")
            .map_err(|e| SceneError::invalid("start", format!("{e}, or start it \"as_given\"")))?;
        settle(&mut model)?;
    }
    Ok(model)
}

/// Most reduced coordinates (3r) the dense analyses take: their cost grows as the cube
/// (900 coordinates, a 100-stage tower: about 4 s for the equilibrium check and 4 s for
/// the modes on this project's 2-core machine; near 1500, about a minute for `modes` and
/// two for `linearize`), so larger structures are refused up front.
pub const MAX_COORDINATES: usize = 1500;

/// Refuses a model too large for the dense analyses, naming `what` asks and the fix.
pub fn check_size(model: &Model, what: &str) -> Result<(), String> {
    let n = 3 * model.coords.r;
    if n > MAX_COORDINATES {
        return Err(format!(
            "{what}: the structure has {n} reduced coordinates, more than the {MAX_COORDINATES} \
             the dense analyses (equilibrium, modes, linear models) take in bounded time \
             (their cost grows as the cube); analyze a smaller structure"
        ));
    }
    Ok(())
}

/// Largest unbalanced force, relative to the applied forces, that still counts as rest.
pub const REST_TOLERANCE: f64 = 1e-8;

/// Refuses a simulation state that is not a static equilibrium (moving, or with an
/// unbalanced force), naming the fix; `what` names the analysis asking.
pub fn require_rest(sim: &crate::sim::Simulation, what: &str) -> Result<(), String> {
    let model = sim.model();
    check_size(model, what)?;
    let y = &sim.state().y;
    let (q, v) = y.split_at(y.len() / 2);
    let speed = v.iter().map(|x| x.abs()).fold(0.0, f64::max);
    let fix = if model.scene.velocities.is_some() {
        "it needs the structure at rest: remove `velocities` from the scene"
    } else if model.scene.start == Start::Equilibrium {
        "it needs a static equilibrium at rest"
    } else {
        "it needs a static equilibrium at rest: add `start = \"equilibrium\"` to the scene"
    };
    if speed > 0.0 {
        return Err(format!(
            "{what}: the start state is moving (velocities up to {speed:.3e} m/s); {fix}"
        ));
    }
    let (residual, scale, round_off) = equilibrium::unbalanced(model, &sim.inputs, q);
    if residual > (REST_TOLERANCE * scale).max(round_off) {
        return Err(format!(
            "{what}: the start state is not an equilibrium (unbalanced force {residual:.3e} N \
             against {scale:.3e} N of applied forces); {fix}"
        ));
    }
    Ok(())
}
