//! Scene files: the user-facing description of a structure (TOML or JSON, same schema).
//!
//! Nodes are numbered from 1 in the order listed; every index in a scene, an error
//! message, a CSV column or an FMU variable uses that numbering.

mod builtin;
mod extreme;
pub mod limits;
mod read;
mod terrain;
mod validate;

pub use builtin::{
    builtin, builtin_names, generate, steel_prism_scene, tower_scene, tower_with_rest_lengths,
    BUILTIN_DEFAULT,
};
pub use extreme::{extreme_scenes, Extreme};
pub use terrain::{CollisionSpec, FrictionModel, TerrainKind, TerrainSpec, MAX_HEIGHTS};

use serde::{Deserialize, Serialize};
use std::path::Path;

use crate::error::SceneError;
use crate::integrator::Method;

/// A whole scene as read from a file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Model name; also the FMU's model name.
    pub name: String,
    /// Free text shown in the FMU documentation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// Node positions `[x, y, z]` in m.
    pub nodes: Vec<[f64; 3]>,
    /// Pinned node numbers (1-based).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub fixed: Vec<usize>,
    /// Rigid bars. A node shared by several bars is a class-k joint.
    pub bars: Vec<BarSpec>,
    /// Cables, elastic or force-density controlled.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub cables: Vec<CableSpec>,
    /// Gravity `[gx, gy, gz]` in m/s²; absent means none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gravity: Option<[f64; 3]>,
    /// Node numbers that receive external force inputs.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub force_inputs: Vec<usize>,
    /// Initial node velocities `[vx, vy, vz]` in m/s, one per node.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub velocities: Option<Vec<[f64; 3]>>,
    /// Output groups to expose (CSV columns and FMU variables); all when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub outputs: Option<Vec<OutputGroup>>,
    /// Scripted loads on nodes, evaluated at the integrator's stage times.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub loads: Vec<LoadSpec>,
    /// Payloads carried by nodes (kg), added to the bar ends' inertia and weight.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub point_masses: Vec<PointMassSpec>,
    /// A ground plane the bar ends touch; absent means none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground: Option<GroundSpec>,
    /// Planes, boxes and heightfields the bars touch along their length.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub terrain: Vec<TerrainSpec>,
    /// Contact between bars that share no node; absent means bars pass through each other.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub collisions: Option<CollisionSpec>,
    /// Equilibrium prestress: derive rest lengths / start force densities from a self-stress.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prestress: Option<PrestressSpec>,
    /// Where the simulation starts: the given geometry, or the static equilibrium.
    #[serde(default, skip_serializing_if = "Start::is_as_given")]
    pub start: Start,
    /// Solver settings.
    #[serde(default)]
    pub solver: SolverSpec,
}

/// The start state a scene asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Start {
    /// The node positions as written (default).
    #[default]
    AsGiven,
    /// The static equilibrium under everything the scene declares, solved when the scene
    /// is loaded (Newton's method in the constrained coordinates).
    Equilibrium,
}

impl Start {
    fn is_as_given(&self) -> bool {
        *self == Self::AsGiven
    }
}

/// A bar between two nodes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BarSpec {
    /// End node numbers `[a, b]` (1-based); the bar vector is `b - a`.
    pub nodes: [usize; 2],
    /// Mass in kg (thin uniform bar).
    pub mass: f64,
    /// Radius in m: the bar is a capsule that touches terrain (and other bars) along its
    /// length; 0 (default) is a line.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub radius: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

/// A payload rigidly attached to a node.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointMassSpec {
    /// Node number (1-based); it must be a free node of some bar.
    pub node: usize,
    /// Mass in kg.
    pub mass: f64,
}

/// A ground plane `normal · x = height` with penalty contact and Coulomb friction.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GroundSpec {
    /// Plane offset along the normal, m.
    #[serde(default)]
    pub height: f64,
    /// Outward normal (any length > 0); `[0, 0, 1]` by default.
    #[serde(default = "GroundSpec::default_normal")]
    pub normal: [f64; 3],
    /// Penalty stiffness, N/m.
    pub stiffness: f64,
    /// Penalty damping on the normal approach speed, N·s/m.
    #[serde(default)]
    pub damping: f64,
    /// Coulomb friction coefficient μ (0: frictionless).
    #[serde(default)]
    pub friction: f64,
    /// Tangential speed below which friction is viscous (regularised Coulomb), m/s.
    #[serde(default = "GroundSpec::default_slip_velocity")]
    pub slip_velocity: f64,
}

impl GroundSpec {
    fn default_normal() -> [f64; 3] {
        [0.0, 0.0, 1.0]
    }

    fn default_slip_velocity() -> f64 {
        1e-2
    }
}

/// How a cable's force density is set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CableControl {
    /// The force density is an input (N/m).
    ForceDensity,
    /// An elastic cable whose rest length is an input (m): a motor reeling the cable.
    RestLength,
}

/// A cable between two nodes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct CableSpec {
    /// End node numbers `[a, b]` (1-based).
    pub nodes: [usize; 2],
    /// Elastic stiffness κ in N/m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f64>,
    /// Rest length s₀ in m (elastic cables; omit when `prestress` derives it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rest_length: Option<f64>,
    /// Damping in N·s/m, acting on the extension rate while taut.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping: Option<f64>,
    /// Present for a controlled cable.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub control: Option<CableControl>,
    /// Start force density in N/m (controlled cables; omit when `prestress` derives it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force_density: Option<f64>,
}

/// Groups of outputs a scene can select.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OutputGroup {
    /// `node[i].x/y/z`.
    Positions,
    /// `node[i].vx/vy/vz`.
    Velocities,
    /// `cable[j].tension`.
    Tensions,
    /// `bar[k].force`.
    BarForces,
    /// `constraint.length_error`, `constraint.orthogonality_error`.
    Diagnostics,
    /// `energy.total`.
    Energy,
    /// `node[i].contact_force`, `ground.force_x/y/z` (scenes with a ground).
    Contact,
    /// `node[i].reaction_x/y/z` at pinned nodes.
    Reactions,
}

/// A scripted load on one node (N), a function of time only.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum LoadSpec {
    /// `F(t) = force`.
    Constant {
        /// Node number (1-based).
        node: usize,
        /// Force in N.
        force: [f64; 3],
    },
    /// `F(t) = amplitude · sin(2π frequency t + phase)`.
    Sinusoidal {
        /// Node number (1-based).
        node: usize,
        /// Amplitude in N.
        amplitude: [f64; 3],
        /// Frequency in Hz.
        frequency: f64,
        /// Phase in rad.
        #[serde(default)]
        phase: f64,
    },
    /// `F(t) = force` from `time` on, 0 before.
    Step {
        /// Node number (1-based).
        node: usize,
        /// Force in N.
        force: [f64; 3],
        /// Switch-on time in s.
        time: f64,
    },
}

impl LoadSpec {
    /// Its node number (1-based).
    pub fn node(&self) -> usize {
        match *self {
            Self::Constant { node, .. }
            | Self::Sinusoidal { node, .. }
            | Self::Step { node, .. } => node,
        }
    }

    /// The force at time `t`, N.
    pub fn force_at(&self, t: f64) -> [f64; 3] {
        match *self {
            Self::Constant { force, .. } => force,
            Self::Sinusoidal {
                amplitude,
                frequency,
                phase,
                ..
            } => {
                let s = (2.0 * std::f64::consts::PI * frequency * t + phase).sin();
                amplitude.map(|a| a * s)
            }
            Self::Step { force, time, .. } => {
                if t >= time {
                    force
                } else {
                    [0.0; 3]
                }
            }
        }
    }
}

/// Request for an equilibrium self-stress of the start geometry.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrestressSpec {
    /// The smallest cable tension of the self-stress, in N.
    pub min_tension: f64,
}

/// Solver settings of a scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SolverSpec {
    /// Internal step in s.
    pub step_size: f64,
    /// Apply the paper's constraint correction after every step.
    pub correction: bool,
    /// Split a step where a cable goes slack or taut or a contact point touches or leaves
    /// the ground, so the method keeps its order across these kinks.
    pub locate_events: bool,
    /// Integration method.
    pub method: Method,
    /// Relative tolerance of the adaptive method.
    pub rtol: f64,
    /// Absolute tolerance of the adaptive method (m and m/s).
    pub atol: f64,
    /// Most internal steps (accepted or rejected) one call may take: one `fmi2DoStep`,
    /// one CSV interval. Bounds the work of a hostile communication step.
    pub max_steps: u64,
}

impl SolverSpec {
    /// Default of [`SolverSpec::max_steps`]: about 3 s of tower20 at 32 µs per step.
    pub const DEFAULT_MAX_STEPS: u64 = 100_000;

    /// "dopri5 (rtol 1e-6, atol 1e-9), switches located, correction on" or "rk4, step
    /// 0.001 s, …": the settings a run uses, for logs and documentation.
    pub fn summary(&self) -> String {
        let method = match self.method {
            Method::Dopri5 => format!("dopri5 (rtol {:e}, atol {:e})", self.rtol, self.atol),
            m => format!("{}, step {} s", m.name(), self.step_size),
        };
        let on = |b: bool| if b { "on" } else { "off" };
        format!(
            "{method}, event location {}, correction {}",
            on(self.locate_events),
            on(self.correction)
        )
    }
}

impl Default for SolverSpec {
    fn default() -> Self {
        Self {
            step_size: 1e-3,
            correction: true,
            locate_events: true,
            method: Method::Dopri5,
            rtol: 1e-6,
            atol: 1e-9,
            max_steps: Self::DEFAULT_MAX_STEPS,
        }
    }
}

impl Scene {
    /// A built-in name or a file path. A name that is neither lists the built-ins and
    /// suggests the nearest.
    pub fn from_name_or_file(arg: &str) -> Result<Self, SceneError> {
        if let Some(scene) = builtin(arg) {
            return Ok(scene);
        }
        let path = Path::new(arg);
        if !path.exists() {
            return Err(SceneError::Io {
                path: arg.to_string(),
                message: format!("no such file, and {}", unknown_builtin(arg)),
            });
        }
        Self::from_file(path)
    }

    /// TOML text of this scene, numbers in their shortest round-trip form.
    pub fn to_toml_string(&self) -> String {
        crate::numbers::plain_toml(&toml::to_string(self).expect("a scene always serializes"))
    }

    /// Checks everything that can be checked without building the model.
    pub fn validate(&self) -> Result<(), SceneError> {
        validate::validate(self)
    }
}

/// "no built-in scene is called …": the built-ins, and the nearest one when it is close.
pub fn unknown_builtin(name: &str) -> String {
    let names = builtin_names();
    let mut text = format!(
        "no built-in scene is called '{name}' (built-ins: {})",
        names.join(", ")
    );
    let nearest = names
        .iter()
        .map(|n| (strsim::damerau_levenshtein(name, n), n))
        .min();
    if let Some((distance, n)) = nearest {
        if distance <= 3.max(n.len() / 3) {
            text.push_str(&format!("; did you mean '{n}'?"));
        }
    }
    text
}
