//! A run as the renderers see it: the fixed topology and, per recorded time, node
//! positions and velocities and cable tensions and bar forces, and the contact points and
//! forces where they were asked for.

use std::path::Path;

use serde::Serialize;

use super::terrain::{Mesh, TerrainShape};
use crate::dynamics::contact_points::ContactPoint;
use crate::model::Model;
use crate::scene::Scene;
use crate::sim::Simulation;

/// The ground plane `normal · x = height`, where the scene has one.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GroundPlane {
    /// Unit outward normal.
    pub normal: [f64; 3],
    /// Offset along the normal, m.
    pub height: f64,
}

/// A recorded run. Node, bar and cable numbers are 1-based in every label and message,
/// as in the scene; the vectors here are 0-based.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Frames {
    /// The scene's name.
    pub name: String,
    /// Bars as 0-based node pairs.
    pub bars: Vec<[usize; 2]>,
    /// Cables as 0-based node pairs.
    pub cables: Vec<[usize; 2]>,
    /// 0-based pinned nodes.
    pub pinned: Vec<usize>,
    /// 0-based nodes carrying point masses.
    pub point_masses: Vec<usize>,
    /// The ground plane, if any.
    pub ground: Option<GroundPlane>,
    /// Terrain shapes in scene order.
    pub terrain: Vec<TerrainShape>,
    /// `bar_radius[b]`: bar `b`'s contact radius, m (0 for a line).
    pub bar_radius: Vec<f64>,
    /// Recorded times, s (increasing).
    pub times: Vec<f64>,
    /// `positions[k][i]`: node `i` at `times[k]`, m.
    pub positions: Vec<Vec<[f64; 3]>>,
    /// `velocities[k][i]`: node `i` at `times[k]`, m/s.
    pub velocities: Vec<Vec<[f64; 3]>>,
    /// `tensions[k][j]`: cable `j` at `times[k]`, N (0 when slack).
    pub tensions: Vec<Vec<f64>>,
    /// `bar_forces[k][b]`: bar `b` at `times[k]`, N, compression positive.
    pub bar_forces: Vec<Vec<f64>>,
    /// `contacts[k]`: every contact point and force at `times[k]`; empty (no frame at all)
    /// unless recorded with [`Frames::record_contacts`].
    #[serde(skip)]
    pub contacts: Vec<Vec<ContactPoint>>,
}

/// How contact forces are drawn: an arrow from the point along the force, the largest
/// force of the run as long as [`ContactScale::FRACTION`] of the structure's size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactScale {
    /// The largest contact force over the recorded run, N (0: nothing touched).
    pub max_force: f64,
    /// Arrow length per newton, m/N (0 when nothing touched).
    pub metres_per_newton: f64,
}

impl ContactScale {
    /// The longest arrow as a fraction of the structure's size (the largest side of the box
    /// around every node over the run).
    pub const FRACTION: f64 = 0.15;
}

impl Frames {
    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.positions.first().map_or(0, Vec::len)
    }

    /// Number of recorded times.
    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// No recorded time.
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }
}

impl Frames {
    /// The topology of `model` with no recorded time.
    pub fn topology(model: &Model) -> Self {
        let scene = &model.scene;
        let ground = model.ground.as_ref().map(|g| GroundPlane {
            normal: [g.normal.x, g.normal.y, g.normal.z],
            height: g.height,
        });
        Self {
            name: scene.name.clone(),
            bars: model.bars.iter().map(|b| b.nodes).collect(),
            cables: model.cables.iter().map(|c| c.nodes).collect(),
            pinned: (0..model.n_nodes()).filter(|&i| model.pinned[i]).collect(),
            point_masses: scene.point_masses.iter().map(|p| p.node - 1).collect(),
            ground,
            terrain: TerrainShape::all(model.terrain.as_ref()),
            bar_radius: model.bars.iter().map(|b| b.radius).collect(),
            times: Vec::new(),
            positions: Vec::new(),
            velocities: Vec::new(),
            tensions: Vec::new(),
            bar_forces: Vec::new(),
            contacts: Vec::new(),
        }
    }

    /// Simulates `scene` with its own solver settings and inputs at their start values,
    /// recording at `times` (increasing, from 0).
    pub fn from_run(scene: &Scene, times: &[f64]) -> Result<Self, String> {
        Self::from_checked_run(scene, times, false, |_| Ok(()))
    }

    /// [`Frames::from_run`], once `check` has accepted the simulation about to run, with
    /// the contacts at each time when `contacts` ([`Frames::record_contacts`]).
    pub fn from_checked_run(
        scene: &Scene,
        times: &[f64],
        contacts: bool,
        check: impl FnOnce(&mut Simulation) -> Result<(), String>,
    ) -> Result<Self, String> {
        let model = crate::analysis::load(scene).map_err(|e| e.to_string())?;
        let mut sim = Simulation::new(model);
        if let Some(why) = sim.step_size_problem() {
            return Err(why);
        }
        check(&mut sim)?;
        Self::record_as(&mut sim, times, contacts)
    }

    /// Runs `sim` on from its current time, recording at `times` (increasing, none before
    /// the simulation's time). The inputs are whatever `sim.inputs` holds.
    pub fn record(sim: &mut Simulation, times: &[f64]) -> Result<Self, String> {
        Self::record_as(sim, times, false)
    }

    /// [`Frames::record`], with every contact point and force at each time
    /// ([`Simulation::contact_points`]).
    pub fn record_contacts(sim: &mut Simulation, times: &[f64]) -> Result<Self, String> {
        Self::record_as(sim, times, true)
    }

    fn record_as(sim: &mut Simulation, times: &[f64], contacts: bool) -> Result<Self, String> {
        let mut frames = Self::topology(sim.model());
        for &t in times {
            if !(t.is_finite() && t >= sim.time()) {
                return Err(format!(
                    "cannot record at t = {t} s: times must be finite and increasing from {} s",
                    sim.time()
                ));
            }
            if t > sim.time() {
                sim.advance_to(t)
                    .map_err(|e| format!("the run stopped at t = {} s: {e}", sim.time()))?;
            }
            sim.refresh();
            frames.push_state(sim, sim.time());
            if contacts {
                frames.contacts.push(sim.contact_points());
            }
        }
        Ok(frames)
    }

    /// Appends the state `sim` last evaluated (see [`Simulation::refresh`]), stamped `time`.
    pub(super) fn push_state(&mut self, sim: &Simulation, time: f64) {
        let model = sim.model();
        let vec3 = |v: nalgebra::Vector3<f64>| [v.x, v.y, v.z];
        let nodes = 0..model.n_nodes();
        self.times.push(time);
        self.positions
            .push(nodes.clone().map(|i| vec3(sim.node_position(i))).collect());
        self.velocities
            .push(nodes.map(|i| vec3(sim.node_velocity(i))).collect());
        self.tensions.push(
            (0..model.cables.len())
                .map(|j| sim.cable_tension(j))
                .collect(),
        );
        self.bar_forces
            .push((0..model.bars.len()).map(|b| sim.bar_force(b)).collect());
    }

    /// Reads a CSV written by `tensegrity-fmu simulate` or by fmpy for this scene; see
    /// [`super::csv`]. Node positions are required; velocities, tensions and bar forces
    /// without a column read as zeros.
    pub fn from_csv(scene: &Scene, path: &Path) -> Result<Self, String> {
        let model = crate::analysis::load(scene).map_err(|e| e.to_string())?;
        super::csv::read(Self::topology(&model), model.n_nodes(), path)
    }

    /// The recorded time nearest to `t` (the first of equals).
    pub fn nearest(&self, t: f64) -> Option<usize> {
        (0..self.len()).min_by(|&a, &b| {
            let (da, db) = ((self.times[a] - t).abs(), (self.times[b] - t).abs());
            da.total_cmp(&db)
        })
    }

    /// The frames at the given indices (in that order).
    pub fn select(&self, keep: &[usize]) -> Self {
        let pick = |v: &Vec<Vec<f64>>| keep.iter().map(|&k| v[k].clone()).collect();
        let pick3 = |v: &Vec<Vec<[f64; 3]>>| keep.iter().map(|&k| v[k].clone()).collect();
        Self {
            times: keep.iter().map(|&k| self.times[k]).collect(),
            positions: pick3(&self.positions),
            velocities: pick3(&self.velocities),
            tensions: pick(&self.tensions),
            bar_forces: pick(&self.bar_forces),
            contacts: keep
                .iter()
                .filter_map(|&k| self.contacts.get(k).cloned())
                .collect(),
            ..self.topology_only()
        }
    }

    /// The indices of the first recorded time at or after each multiple of `interval`
    /// from the first time (a CSV written every step thinned to an animation's frame rate).
    pub fn every(&self, interval: f64) -> Vec<usize> {
        let mut keep = Vec::new();
        let Some(&t0) = self.times.first() else {
            return keep;
        };
        let mut k = 0u64;
        for (i, &t) in self.times.iter().enumerate() {
            let due = t0 + k as f64 * interval;
            if t >= due - 1e-9 * interval {
                keep.push(i);
                k = ((t - t0) / interval + 1e-9).floor() as u64 + 1;
            }
        }
        keep
    }

    /// Each terrain shape's mesh, planes spanned over the structure's extent over the run.
    pub fn terrain_meshes(&self) -> Vec<Mesh> {
        let points: Vec<[f64; 3]> = self.positions.iter().flatten().copied().collect();
        self.terrain.iter().map(|t| t.mesh(&points)).collect()
    }

    /// The largest cable tension over the whole run, N (0 if none).
    pub fn max_tension(&self) -> f64 {
        self.tensions
            .iter()
            .flatten()
            .fold(0.0, |m: f64, &t| if t.is_finite() { m.max(t) } else { m })
    }

    fn topology_only(&self) -> Self {
        Self {
            name: self.name.clone(),
            bars: self.bars.clone(),
            cables: self.cables.clone(),
            pinned: self.pinned.clone(),
            point_masses: self.point_masses.clone(),
            ground: self.ground.clone(),
            terrain: self.terrain.clone(),
            bar_radius: self.bar_radius.clone(),
            times: Vec::new(),
            positions: Vec::new(),
            velocities: Vec::new(),
            tensions: Vec::new(),
            bar_forces: Vec::new(),
            contacts: Vec::new(),
        }
    }

    /// The scale of the contact arrows, if contacts were recorded.
    pub fn contact_scale(&self) -> Option<ContactScale> {
        if self.contacts.is_empty() {
            return None;
        }
        let max_force = self
            .contacts
            .iter()
            .flatten()
            .map(|c| c.force.norm())
            .filter(|f| f.is_finite())
            .fold(0.0, f64::max);
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in self.positions.iter().flatten() {
            for i in 0..3 {
                (lo[i], hi[i]) = (lo[i].min(p[i]), hi[i].max(p[i]));
            }
        }
        let size = (0..3).map(|i| hi[i] - lo[i]).fold(0.0, f64::max);
        let size = if size > 0.0 && size.is_finite() {
            size
        } else {
            1.0
        };
        let metres_per_newton = if max_force > 0.0 {
            ContactScale::FRACTION * size / max_force
        } else {
            0.0
        };
        Some(ContactScale {
            max_force,
            metres_per_newton,
        })
    }
}
