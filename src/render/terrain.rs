//! The scene's terrain as the renderers draw it: planes kept as planes (each renderer spans
//! them over the structure), boxes and heightfields as meshes of quads computed once from
//! the model, big heightfields subsampled.

use nalgebra::Vector3;
use serde::Serialize;

use crate::contact::{Grid, Shape};
use crate::model::terrain::Terrain;

/// Most quads a heightfield is drawn with: a picture stays quick to draw and a page small.
pub const MAX_QUADS: usize = 3000;

/// Points and four-cornered faces, each face counter-clockwise seen from outside.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Mesh {
    /// Corners, m.
    pub points: Vec<[f64; 3]>,
    /// 0-based corner indices.
    pub quads: Vec<[usize; 4]>,
}

/// One terrain shape as drawn.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum TerrainShape {
    /// The half-space `normal · x ≤ height`.
    Plane {
        /// Unit outward normal.
        normal: [f64; 3],
        /// Offset along the normal, m.
        height: f64,
    },
    /// A box: its 8 corners and 6 faces.
    Box(Mesh),
    /// A heightfield's grid.
    Heightfield(Mesh),
}

impl TerrainShape {
    /// The drawn shapes of the model's terrain, in scene order.
    pub fn all(terrain: Option<&Terrain>) -> Vec<Self> {
        terrain.map_or_else(Vec::new, |t| {
            t.shapes.iter().map(|(s, _)| from(s)).collect()
        })
    }

    /// The scene's name of the kind.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Plane { .. } => "plane",
            Self::Box(_) => "box",
            Self::Heightfield(_) => "heightfield",
        }
    }

    /// The mesh drawn, planes spanned over `points` (the structure over the run) as in
    /// [`plane_quad`].
    pub fn mesh(&self, points: &[[f64; 3]]) -> Mesh {
        match self {
            Self::Plane { normal, height } => Mesh {
                points: plane_quad(*normal, *height, points).to_vec(),
                quads: vec![[0, 1, 2, 3]],
            },
            Self::Box(m) | Self::Heightfield(m) => m.clone(),
        }
    }
}

fn from(shape: &Shape) -> TerrainShape {
    match shape {
        Shape::Plane { normal, offset } => TerrainShape::Plane {
            normal: [normal.x, normal.y, normal.z],
            height: *offset,
        },
        Shape::Cuboid { center, axes, half } => {
            let corner = |i: usize| {
                let sign = |bit: usize| if (i >> bit) & 1 == 1 { 1.0 } else { -1.0 };
                let local = Vector3::new(sign(0), sign(1), sign(2)).component_mul(half);
                let p: Vector3<f64> = center + axes * local;
                [p.x, p.y, p.z]
            };
            // Corner i has bit 0 for +x, bit 1 for +y, bit 2 for +z (box axes).
            let quads = vec![
                [0, 2, 3, 1], // −z
                [4, 5, 7, 6], // +z
                [0, 1, 5, 4], // −y
                [2, 6, 7, 3], // +y
                [0, 4, 6, 2], // −x
                [1, 3, 7, 5], // +x
            ];
            TerrainShape::Box(Mesh {
                points: (0..8).map(corner).collect(),
                quads,
            })
        }
        Shape::Heightfield(grid) => TerrainShape::Heightfield(grid_mesh(grid, MAX_QUADS)),
    }
}

/// The grid's heights at every `step`-th row and column (and the last), so that at most
/// about `max_quads` quads remain.
pub fn grid_mesh(grid: &Grid, max_quads: usize) -> Mesh {
    let cells = ((grid.nx - 1) * (grid.ny - 1)) as f64;
    let step = (cells / max_quads.max(1) as f64).sqrt().ceil().max(1.0) as usize;
    let pick = |n: usize| {
        let mut v: Vec<usize> = (0..n - 1).step_by(step).collect();
        v.push(n - 1);
        v
    };
    let (xs, ys) = (pick(grid.nx), pick(grid.ny));
    let mut points = Vec::with_capacity(xs.len() * ys.len());
    for &j in &ys {
        for &i in &xs {
            let x = grid.origin[0] + i as f64 * grid.spacing[0];
            let y = grid.origin[1] + j as f64 * grid.spacing[1];
            points.push([x, y, grid.heights[j * grid.nx + i]]);
        }
    }
    let w = xs.len();
    let mut quads = Vec::with_capacity((xs.len() - 1) * (ys.len() - 1));
    for j in 0..ys.len() - 1 {
        for i in 0..w - 1 {
            let a = j * w + i;
            quads.push([a, a + 1, a + w + 1, a + w]);
        }
    }
    Mesh { points, quads }
}

/// The corners of the quad drawn for the plane `normal · x = height`: the extent of
/// `points` projected onto the plane, widened by a quarter (at least 0.5 m across).
pub fn plane_quad(normal: [f64; 3], height: f64, points: &[[f64; 3]]) -> [[f64; 3]; 4] {
    let n = normal;
    let a = if n[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let e1 = unit(cross(n, a));
    let e2 = cross(n, e1);
    let count = points.len().max(1) as f64;
    let mut c = [0.0; 3];
    for p in points {
        (0..3).for_each(|i| c[i] += p[i] / count);
    }
    let off = dot(c, n) - height;
    let c = [c[0] - off * n[0], c[1] - off * n[1], c[2] - off * n[2]];
    let r = points
        .iter()
        .map(|p| {
            let d = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
            dot(d, e1).abs().max(dot(d, e2).abs())
        })
        .fold(0.25_f64, f64::max)
        * 1.25;
    let at = |s: f64, t: f64| [0, 1, 2].map(|i| c[i] + r * (s * e1[i] + t * e2[i]));
    [at(-1.0, -1.0), at(1.0, -1.0), at(1.0, 1.0), at(-1.0, 1.0)]
}

/// The outward unit normal of a quad (by its diagonals, so a warped grid cell gets its
/// mean tilt).
pub fn quad_normal(m: &Mesh, q: [usize; 4]) -> [f64; 3] {
    let p = |k: usize| m.points[q[k]];
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    unit(cross(sub(p(2), p(0)), sub(p(3), p(1))))
}

pub(super) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = dot(a, a).sqrt();
    if n > 0.0 {
        a.map(|x| x / n)
    } else {
        [0.0, 0.0, 1.0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_faces_point_outwards() {
        let shape = from(&Shape::cuboid([1.0, 2.0, 3.0], [2.0, 4.0, 6.0], 30.0));
        let TerrainShape::Box(m) = shape else {
            panic!("a box")
        };
        assert_eq!((m.points.len(), m.quads.len()), (8, 6));
        for &q in &m.quads {
            let n = quad_normal(&m, q);
            let c = q.map(|k| m.points[k]);
            let mid = [0, 1, 2].map(|i| c.iter().map(|p| p[i]).sum::<f64>() / 4.0);
            let out = [mid[0] - 1.0, mid[1] - 2.0, mid[2] - 3.0];
            assert!(dot(n, out) > 0.0, "face {q:?} normal {n:?}");
        }
        assert!(m.points.iter().all(|p| (p[2] - 3.0).abs() == 3.0));
    }

    #[test]
    fn heightfield_mesh_and_subsampling() {
        let rows = vec![vec![0.0, 1.0, 2.0, 3.0], vec![0.5; 4], vec![1.0; 4]];
        let grid = Grid::new([1.0, -1.0], [0.5, 0.25], &rows);
        let m = grid_mesh(&grid, MAX_QUADS);
        assert_eq!((m.points.len(), m.quads.len()), (12, 6));
        assert_eq!(m.points[3], [2.5, -1.0, 3.0]);
        assert_eq!(m.points[11], [2.5, -0.5, 1.0]);
        assert!(quad_normal(&m, m.quads[0])[2] > 0.0);
        let big = Grid::new([0.0, 0.0], [1.0, 1.0], &vec![vec![0.0; 1000]; 700]);
        let m = grid_mesh(&big, MAX_QUADS);
        assert!(m.quads.len() <= MAX_QUADS && m.quads.len() > MAX_QUADS / 3);
        // The far corner stays.
        assert_eq!(*m.points.last().unwrap(), [999.0, 699.0, 0.0]);
    }
}
