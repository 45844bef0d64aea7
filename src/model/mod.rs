//! The immutable model built once from a validated scene: topology, masses, laws,
//! the constraint basis, the correction plan and the reaction-system layout.

pub mod contact;
pub mod coords;
pub mod correction_plan;
pub mod effects;
pub mod inertia;
pub mod prestress;
pub mod reactions;
pub mod supports;
pub mod terrain;

use nalgebra::Vector3;

use crate::contact::Penalty;
use crate::error::SceneError;
use crate::scene::{CableControl, LoadSpec, Scene, SolverSpec};
use contact::Ground;
pub use coords::BasisKind;
use coords::Coordinates;
use correction_plan::CorrectionPlan;
use effects::Pipeline;
use inertia::{BarInertia, InertiaLanes};
use reactions::Reactions;
use supports::Support;
use terrain::{Capsule, Collisions, Terrain};

/// A rigid bar between physical nodes (0-based).
#[derive(Debug, Clone, PartialEq)]
pub struct Bar {
    /// Start and end node; `b = x_end − x_start`.
    pub nodes: [usize; 2],
    /// Mass in kg.
    pub mass: f64,
    /// Length in m (from the start geometry).
    pub length: f64,
    /// Radius of its capsule in m (0: a line).
    pub radius: f64,
}

/// How a cable's force density γ (N/m) arises.
#[derive(Debug, Clone, PartialEq)]
pub enum CableLaw {
    /// `γ = κ (1 − s₀/|s|) + c (s·ṡ)/|s|²` while taut, else 0; clamped at ≥ 0.
    Elastic {
        /// κ in N/m.
        stiffness: f64,
        /// s₀ in m.
        rest_length: f64,
        /// c in N·s/m, if the scene gives damping.
        damping: Option<f64>,
    },
    /// γ is input number `input` of [`Inputs::force_density`](crate::dynamics::Inputs).
    Controlled {
        /// Index into the controlled-cable inputs.
        input: usize,
    },
    /// Elastic, with the rest length input number `input` of
    /// [`Inputs::rest_length`](crate::dynamics::Inputs) (clamped at ≥ 0).
    RestLengthControlled {
        /// κ in N/m.
        stiffness: f64,
        /// c in N·s/m, if the scene gives damping.
        damping: Option<f64>,
        /// Index into the rest-length inputs.
        input: usize,
    },
}

/// A cable between physical nodes (0-based).
#[derive(Debug, Clone, PartialEq)]
pub struct Cable {
    /// End nodes; `s = x_b − x_a`.
    pub nodes: [usize; 2],
    /// Its force law.
    pub law: CableLaw,
}

/// Everything constant about a simulation.
#[derive(Debug, Clone)]
pub struct Model {
    /// The scene it was built from (shipped with the FMU).
    pub scene: Scene,
    /// Start node positions in m.
    pub positions: Vec<Vector3<f64>>,
    /// Whether each node is pinned.
    pub pinned: Vec<bool>,
    /// Bars in scene order.
    pub bars: Vec<Bar>,
    /// Cables in scene order.
    pub cables: Vec<Cable>,
    /// Gravity in m/s², if any.
    pub gravity: Option<Vector3<f64>>,
    /// Nodes (0-based) that take force inputs, in scene order.
    pub force_inputs: Vec<usize>,
    /// Payload per bar end, kg (zeros without point masses).
    pub payload: Vec<f64>,
    /// Inverse mass data per bar (rod plus payloads).
    pub inertia: Vec<BarInertia>,
    /// The same, four bars to a group, for the step's λ passes (derived from `inertia` and
    /// `coords.static_bar` by [`InertiaLanes::groups`]; rebuild it after changing either).
    pub inertia_lanes: Vec<InertiaLanes>,
    /// The ground plane, if the scene has one.
    pub ground: Option<Ground>,
    /// Terrain shapes and the bars' capsules, if the scene has terrain.
    pub terrain: Option<Terrain>,
    /// Bar–bar contact, if the scene asks for it.
    pub collisions: Option<Collisions>,
    /// How to read the support reaction of each pinned node.
    pub supports: Vec<Support>,
    /// The force contributions of the declared effects, run by every evaluation.
    pub pipeline: Pipeline,
    /// Scripted loads: node (0-based) and law; empty when the scene has none.
    pub loads: Vec<(usize, LoadSpec)>,
    /// Cable index of each controlled-cable input.
    pub controlled: Vec<usize>,
    /// Start force density of each controlled-cable input, N/m.
    pub controlled_start: Vec<f64>,
    /// Cable index of each rest-length input.
    pub reeled: Vec<usize>,
    /// Start rest length of each rest-length input, m.
    pub reeled_start: Vec<f64>,
    /// Solver settings.
    pub solver: SolverSpec,
    /// Reduced coordinates.
    pub coords: Coordinates,
    /// The correction's precomputed directions.
    pub correction: CorrectionPlan,
    /// Layout of the reaction system (cloned into each workspace).
    pub reactions: Reactions,
    /// Things the user should know (skipped bars, projected velocities, …).
    pub warnings: Vec<String>,
    /// How the start positions were found, when the scene asks for its equilibrium.
    pub start: Option<StartReport>,
}

/// What the static-equilibrium solve did (see `analysis::equilibrium`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StartReport {
    /// Newton iterations taken.
    pub iterations: usize,
    /// Final unbalanced generalized force `‖M̄ η̈₂‖`, N.
    pub residual: f64,
}

impl std::fmt::Display for StartReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "start: static equilibrium in {} Newton iteration{} (unbalanced force {:.1e} N)",
            self.iterations,
            if self.iterations == 1 { "" } else { "s" },
            self.residual
        )
    }
}

impl Model {
    /// Builds a model with the sparse joint/pin basis.
    pub fn new(scene: &Scene) -> Result<Self, SceneError> {
        Self::with_basis(scene, BasisKind::Sparse)
    }

    /// Builds a model with the chosen basis of null(Pᵀ).
    pub fn with_basis(scene: &Scene, basis: BasisKind) -> Result<Self, SceneError> {
        scene.validate()?;
        let positions: Vec<Vector3<f64>> = scene.nodes.iter().map(|p| Vector3::from(*p)).collect();
        let mut pinned = vec![false; positions.len()];
        for &p in &scene.fixed {
            pinned[p - 1] = true;
        }
        let bars: Vec<Bar> = scene
            .bars
            .iter()
            .map(|b| {
                let nodes = [b.nodes[0] - 1, b.nodes[1] - 1];
                Bar {
                    nodes,
                    mass: b.mass,
                    length: (positions[nodes[1]] - positions[nodes[0]]).norm(),
                    radius: b.radius,
                }
            })
            .collect();
        let mut warnings = Vec::new();
        let built = build_cables(scene, &positions, &pinned, &bars)?;
        let bar_pairs: Vec<(usize, usize)> =
            bars.iter().map(|b| (b.nodes[0], b.nodes[1])).collect();
        let coords = Coordinates::new(&bar_pairs, &positions, &pinned, basis)?;
        let correction =
            CorrectionPlan::new(&coords, &bars.iter().map(|b| b.length).collect::<Vec<_>>());
        for &bar in &correction.skipped {
            let why = if coords.static_bar[bar] {
                "both ends are pinned, so it never moves"
            } else {
                "it closes a loop of bars or joins nodes that earlier bars already move together; \
                 its length and orthogonality are then restored by an iterative projection after \
                 the exact pass"
            };
            warnings.push(format!(
                "bar {}: its correction direction vanishes and the exact correction skips it: {why}",
                bar + 1
            ));
        }
        let mut payload = vec![0.0; coords.n_ends()];
        for pm in &scene.point_masses {
            let end = coords.node_end[pm.node - 1].expect("validated: the node is on a bar");
            payload[end] += pm.mass;
        }
        let inertia: Vec<BarInertia> = bars
            .iter()
            .enumerate()
            .map(|(i, b)| BarInertia::new(b.mass, [payload[2 * i], payload[2 * i + 1]]))
            .collect();
        // A node touches the ground as a sphere as wide as the widest bar it ends.
        let mut node_radius = vec![0.0f64; positions.len()];
        for b in &bars {
            for n in b.nodes {
                node_radius[n] = node_radius[n].max(b.radius);
            }
        }
        let ground = scene.ground.as_ref().map(|spec| {
            let contacts: Vec<(usize, usize)> = (0..positions.len())
                .filter(|&n| !pinned[n])
                .filter_map(|n| coords.node_end[n].map(|e| (n, e)))
                .collect();
            let radii = contacts.iter().map(|&(n, _)| node_radius[n]).collect();
            Ground::new(spec, contacts, radii)
        });
        let capsules: Vec<Capsule> = bars
            .iter()
            .enumerate()
            .map(|(i, b)| Capsule {
                bar: i,
                nodes: b.nodes,
                ends: b.nodes.map(|n| coords.node_end[n]),
                radius: b.radius,
            })
            .collect();
        // A twentieth of the mean bar (at least the widest radius): the terrain's marks and
        // the collisions' broad phase are renewed every few centimetres of motion for a
        // robot's metre-long bars.
        let margin = (0.05 * bars.iter().map(|b| b.length).sum::<f64>() / bars.len() as f64)
            .max(bars.iter().map(|b| b.radius).fold(0.0, f64::max));
        let terrain = (!scene.terrain.is_empty()).then(|| {
            let moving = capsules.iter().filter(|c| !coords.static_bar[c.bar]);
            Terrain::new(&scene.terrain, moving.copied().collect(), margin)
        });
        let collisions = scene.collisions.as_ref().map(|c| Collisions {
            law: Penalty {
                stiffness: c.stiffness,
                damping: c.damping,
                friction: c.friction,
                slip_velocity: c.slip_velocity,
            },
            margin,
            capsules,
        });
        let mut reactions = Reactions::new(&coords, &inertia, basis == BasisKind::Dense);
        let units: Vec<Vector3<f64>> = bars
            .iter()
            .map(|b| (positions[b.nodes[1]] - positions[b.nodes[0]]) / b.length)
            .collect();
        reactions.assemble(&units);
        let again = |r: &mut Reactions| {
            r.assemble(&units);
            r.rhs.fill(0.0);
        };
        if !reactions.solve(again) {
            warnings.push(
                "the joint reactions are statically indeterminate (bars form a rigid frame); \
                 they use the minimum-norm dense solve, whose cost grows faster than linearly"
                    .to_string(),
            );
            reactions = Reactions::new(&coords, &inertia, true);
        }
        let supports = Support::all(&coords, &pinned, &built.cables);
        let mut model = Self {
            scene: scene.clone(),
            positions,
            pinned,
            bars,
            cables: built.cables,
            gravity: scene.gravity.map(Vector3::from),
            payload,
            inertia_lanes: InertiaLanes::groups(&inertia, &coords.static_bar),
            inertia,
            ground,
            terrain,
            collisions,
            supports,
            pipeline: Pipeline::default(),
            force_inputs: scene.force_inputs.iter().map(|&n| n - 1).collect(),
            loads: scene
                .loads
                .iter()
                .map(|l| (l.node() - 1, l.clone()))
                .collect(),
            controlled: built.controlled,
            controlled_start: built.controlled_start,
            reeled: built.reeled,
            reeled_start: built.reeled_start,
            solver: scene.solver.clone(),
            coords,
            correction,
            reactions,
            warnings,
            start: None,
        };
        model.pipeline = Pipeline::new(&model);
        Ok(model)
    }

    /// Number of physical nodes.
    pub fn n_nodes(&self) -> usize {
        self.positions.len()
    }

    /// Dimension of the integrated state: η₂ and η̇₂, 3r each.
    pub fn state_len(&self) -> usize {
        6 * self.coords.r
    }

    /// Bar lengths in m.
    pub fn lengths(&self) -> Vec<f64> {
        self.bars.iter().map(|b| b.length).collect()
    }

    /// The reduced positions `η₂` of the model's node positions.
    pub fn reduced_positions(&self) -> Vec<f64> {
        let coords = &self.coords;
        let mut q = vec![0.0; 3 * coords.r];
        for e in 0..coords.n_ends() {
            coords.scatter(e, &self.positions[coords.end_node[e]], &mut q);
        }
        q
    }

    /// Mass lumped at bar end `e` for weight and momentum: half the rod plus its payload, kg.
    pub fn end_mass(&self, e: usize) -> f64 {
        self.bars[e / 2].mass / 2.0 + self.payload[e]
    }

    /// The scene with every derived value written out (no `prestress`): rest lengths and
    /// start force densities as built. It builds the same model.
    pub fn explicit_scene(&self) -> Scene {
        let mut scene = self.scene.clone();
        scene.prestress = None;
        for (spec, cable) in scene.cables.iter_mut().zip(&self.cables) {
            match cable.law {
                CableLaw::Elastic { rest_length, .. } => spec.rest_length = Some(rest_length),
                CableLaw::Controlled { input } => {
                    spec.force_density = Some(self.controlled_start[input])
                }
                CableLaw::RestLengthControlled { input, .. } => {
                    spec.rest_length = Some(self.reeled_start[input])
                }
            }
        }
        scene
    }
}

#[derive(Default)]
struct CableBuild {
    cables: Vec<Cable>,
    controlled: Vec<usize>,
    controlled_start: Vec<f64>,
    reeled: Vec<usize>,
    reeled_start: Vec<f64>,
}

fn build_cables(
    scene: &Scene,
    positions: &[Vector3<f64>],
    pinned: &[bool],
    bars: &[Bar],
) -> Result<CableBuild, SceneError> {
    let stress = match &scene.prestress {
        Some(p) => Some(prestress::self_stress(
            positions,
            pinned,
            &bars.iter().map(|b| b.nodes).collect::<Vec<_>>(),
            &scene
                .cables
                .iter()
                .map(|c| [c.nodes[0] - 1, c.nodes[1] - 1])
                .collect::<Vec<_>>(),
            p.min_tension,
        )?),
        None => None,
    };
    let mut built = CableBuild::default();
    for (j, spec) in scene.cables.iter().enumerate() {
        let nodes = [spec.nodes[0] - 1, spec.nodes[1] - 1];
        let length = (positions[nodes[1]] - positions[nodes[0]]).norm();
        let gamma = stress.as_ref().map(|s| s.cables[j]);
        let law = match spec.control {
            Some(CableControl::ForceDensity) => {
                built.controlled.push(j);
                let start = gamma.or(spec.force_density).expect("validated");
                built.controlled_start.push(start);
                CableLaw::Controlled {
                    input: built.controlled.len() - 1,
                }
            }
            control => {
                let stiffness = spec.stiffness.expect("validated");
                let rest_length = match gamma {
                    Some(g) if g >= stiffness => {
                        return Err(SceneError::invalid(
                            format!("cables[{}].stiffness", j + 1),
                            format!(
                                "{stiffness} N/m is too soft for the prestress force density \
                                 {g:.6} N/m (the rest length would be ≤ 0); raise the stiffness \
                                 or lower prestress.min_tension"
                            ),
                        ))
                    }
                    Some(g) => length * (1.0 - g / stiffness),
                    None => spec.rest_length.expect("validated"),
                };
                if control == Some(CableControl::RestLength) {
                    built.reeled.push(j);
                    built.reeled_start.push(rest_length);
                    CableLaw::RestLengthControlled {
                        stiffness,
                        damping: spec.damping,
                        input: built.reeled.len() - 1,
                    }
                } else {
                    CableLaw::Elastic {
                        stiffness,
                        rest_length,
                        damping: spec.damping,
                    }
                }
            }
        };
        built.cables.push(Cable { nodes, law });
    }
    Ok(built)
}
