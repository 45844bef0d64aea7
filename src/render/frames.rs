//! A run as the renderers see it: the fixed topology and, per recorded time, node
//! positions and velocities and cable tensions and bar forces.

use serde::Serialize;

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
