//! Seeing a structure: a run recorded as [`Frames`] (from a simulation or a CSV of the FMU's
//! output names), drawn as PNG/GIF pictures, an interactive HTML page or a ParaView time
//! series, or one mode shape animated about the start equilibrium ([`mode`]). The drawing
//! modules read only [`Frames`]; only [`Frames`] and [`mode`] touch the physics.

pub mod animation;
mod csv;
pub mod faces;
mod frames;
pub mod html;
pub mod labels;
pub mod mode;
pub mod picture;
pub mod terrain;
pub mod view;
pub mod vtk;

pub use frames::{ContactScale, Frames, GroundPlane};
