//! Tensegrity dynamics in non-minimal coordinates with the exact recursive constraint
//! correction of Cheong, Skelton & Cho (2014).
//!
//! Layers: [`scene`] (files) → [`model`] (constants, built once) → [`dynamics`]
//! (the equations of motion) → [`integrator`] + [`correction`] → [`sim`] (a running
//! simulation) → [`outputs`] (named quantities shared by CSV and FMU). [`analysis`]
//! (equilibrium, modes, linear models) works on the model and the dynamics' tangent.
//! Underneath, `linalg` (sparse 3 × 3 block factors, knowing no physics) solves the
//! model's reaction system, and `simd` runs the hot kernels' AVX2 copies where the
//! processor has them.
#![warn(missing_docs)]

pub mod analysis;
pub mod contact;
pub mod correction;
pub mod dynamics;
pub mod error;
pub mod fmi;
pub mod integrator;
pub(crate) mod linalg;
pub mod model;
pub mod numbers;
pub mod outputs;
#[cfg(feature = "cli")]
pub mod partial;
#[cfg(feature = "cli")]
pub mod render;
#[cfg(feature = "cli")]
pub mod report;
pub mod scene;
pub mod sim;
pub mod simd;

pub use error::{SceneError, StepError};
pub use model::Model;
pub use scene::Scene;
pub use sim::Simulation;
