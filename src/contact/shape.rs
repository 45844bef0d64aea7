//! Terrain shapes as signed distance functions `φ(x)` (m, positive outside) with their
//! outward unit normals, and the points along a segment where `φ` is not smooth, which
//! the capsule contact samples.

use nalgebra::{Matrix3, Vector3};

/// One terrain shape.
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    /// The half-space `n·x ≤ h`.
    Plane {
        /// Unit outward normal.
        normal: Vector3<f64>,
        /// Offset h along the normal, m.
        offset: f64,
    },
    /// A box.
    Cuboid {
        /// Centre, m.
        center: Vector3<f64>,
        /// Its axes in world coordinates (columns), orthonormal.
        axes: Matrix3<f64>,
        /// Half edge lengths along those axes, m.
        half: Vector3<f64>,
    },
    /// Ground `z ≤ h(x, y)` over a grid of heights.
    Heightfield(Grid),
}

/// A grid of heights, interpolated bilinearly.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    /// `(x, y)` of the first height, m.
    pub origin: [f64; 2],
    /// Spacing along x and y, m.
    pub spacing: [f64; 2],
    /// Heights along x.
    pub nx: usize,
    /// Heights along y.
    pub ny: usize,
    /// `heights[j * nx + i]` at `(x₀ + i dx, y₀ + j dy)`, m.
    pub heights: Vec<f64>,
    /// The highest height, m.
    pub top: f64,
    /// The smallest z component of the normal anywhere (from the steepest slopes): a
    /// sphere of radius r can touch only below `top + r / min_nz`.
    pub min_nz: f64,
}

impl Grid {
    /// A grid from rows of heights (row j at `y₀ + j dy`), all of one length ≥ 2, at least 2.
    pub fn new(origin: [f64; 2], spacing: [f64; 2], rows: &[Vec<f64>]) -> Self {
        let heights: Vec<f64> = rows.iter().flatten().copied().collect();
        let top = heights.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        // Within a cell each slope is a mix of its edges' differences, so the steepest
        // edges bound the gradient everywhere (and beyond the border it is flatter).
        let steepest = |d: &mut dyn Iterator<Item = f64>| d.fold(0.0, |m: f64, x| m.max(x.abs()));
        let sx = steepest(&mut rows.iter().flat_map(|r| r.windows(2).map(|w| w[1] - w[0])));
        let sy = steepest(
            &mut rows
                .windows(2)
                .flat_map(|w| w[0].iter().zip(&w[1]).map(|(a, b)| b - a)),
        );
        let (gx, gy) = (sx / spacing[0], sy / spacing[1]);
        Self {
            origin,
            spacing,
            nx: rows[0].len(),
            ny: rows.len(),
            heights,
            top,
            min_nz: 1.0 / (1.0 + gx * gx + gy * gy).sqrt(),
        }
    }

    /// Height and gradient `(h, ∂h/∂x, ∂h/∂y)` at `(x, y)`. Beyond the grid the border
    /// heights extend outward (flat across the border); on a grid line inside, where the
    /// two cells' slopes differ, the gradient across it is their mean, so that a ridge
    /// pushes straight up rather than to one side.
    pub fn height(&self, x: f64, y: f64) -> (f64, f64, f64) {
        let (mx, my) = ((self.nx - 1) as f64, (self.ny - 1) as f64);
        let fx = ((x - self.origin[0]) / self.spacing[0]).clamp(0.0, mx);
        let fy = ((y - self.origin[1]) / self.spacing[1]).clamp(0.0, my);
        let i = (fx.floor() as usize).min(self.nx - 2);
        let j = (fy.floor() as usize).min(self.ny - 2);
        let (u, v) = (fx - i as f64, fy - j as f64);
        let (h, mut hx, mut hy) = self.cell(i, j, u, v);
        if u == 0.0 && i > 0 {
            hx = 0.5 * (hx + self.cell(i - 1, j, 1.0, v).1);
        }
        if v == 0.0 && j > 0 {
            hy = 0.5 * (hy + self.cell(i, j - 1, u, 1.0).2);
        }
        // Beyond the border the height no longer changes across it.
        if !(0.0..=mx).contains(&((x - self.origin[0]) / self.spacing[0])) {
            hx = 0.0;
        }
        if !(0.0..=my).contains(&((y - self.origin[1]) / self.spacing[1])) {
            hy = 0.0;
        }
        (h, hx, hy)
    }

    /// Height and gradient in cell `(i, j)` at its fractions `(u, v)`.
    fn cell(&self, i: usize, j: usize, u: f64, v: f64) -> (f64, f64, f64) {
        let at = |i: usize, j: usize| self.heights[j * self.nx + i];
        let (h00, h10, h01, h11) = (at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1));
        let h =
            h00 * (1.0 - u) * (1.0 - v) + h10 * u * (1.0 - v) + h01 * (1.0 - u) * v + h11 * u * v;
        let hx = ((h10 - h00) * (1.0 - v) + (h11 - h01) * v) / self.spacing[0];
        let hy = ((h01 - h00) * (1.0 - u) + (h11 - h10) * u) / self.spacing[1];
        (h, hx, hy)
    }
}

impl Shape {
    /// A box from its centre, full edge lengths and yaw about z (degrees).
    pub fn cuboid(center: [f64; 3], size: [f64; 3], yaw_degrees: f64) -> Self {
        let (s, c) = yaw_degrees.to_radians().sin_cos();
        let axes = Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
        Self::Cuboid {
            center: Vector3::from(center),
            axes,
            half: Vector3::from(size) * 0.5,
        }
    }

    /// A plane through `point` with outward `normal` (any length > 0).
    pub fn plane(point: [f64; 3], normal: [f64; 3]) -> Self {
        let n = Vector3::from(normal).normalize();
        Self::Plane {
            normal: n,
            offset: n.dot(&Vector3::from(point)),
        }
    }

    /// Signed distance `φ(x)` (m, negative inside) and the outward unit normal there
    /// (`None` would be a place the shape cannot touch; every shape here can).
    #[inline]
    pub fn distance(&self, x: &Vector3<f64>) -> Option<(f64, Vector3<f64>)> {
        match self {
            Self::Plane { normal, offset } => Some((normal.dot(x) - offset, *normal)),
            Self::Cuboid { center, axes, half } => {
                let p = axes.tr_mul(&(x - center));
                let q = p.abs() - half;
                let outside = q.map(|v| v.max(0.0));
                let d = outside.norm();
                if d > 0.0 {
                    let local = outside.component_mul(&p.map(f64::signum)) / d;
                    Some((d, axes * local))
                } else {
                    let k = q.imax();
                    Some((q[k], axes.column(k) * p[k].signum()))
                }
            }
            Self::Heightfield(grid) => {
                let (h, hx, hy) = grid.height(x.x, x.y);
                let n = Vector3::new(-hx, -hy, 1.0).normalize();
                Some(((x.z - h) * n.z, n))
            }
        }
    }

    /// Whether a capsule around `a`–`b` of radius `r` may touch the shape: a cheap bound,
    /// so that shapes far from a bar cost one test.
    #[inline]
    pub fn may_touch(&self, a: &Vector3<f64>, b: &Vector3<f64>, r: f64) -> bool {
        match self {
            Self::Plane { normal, offset } => normal.dot(a).min(normal.dot(b)) - r < *offset,
            Self::Cuboid { center, axes, half } => {
                // The segment's bounds in the box's frame against the box grown by r.
                let (pa, pb) = (axes.tr_mul(&(a - center)), axes.tr_mul(&(b - center)));
                (0..3).all(|k| pa[k].min(pb[k]) - r < half[k] && pa[k].max(pb[k]) + r > -half[k])
            }
            // The depth is the vertical gap times n_z: a steep slope reaches up to r / n_z.
            Self::Heightfield(grid) => a.z.min(b.z) - r / grid.min_nz < grid.top,
        }
    }

    /// Calls `f(s)` for each `s ∈ (0, 1)` where `φ(a + s (b − a))` has a kink: where the
    /// segment crosses a box's face planes, the planes inside it where the nearest face
    /// changes, or a heightfield's grid lines. A plane has none.
    pub fn kinks(&self, a: &Vector3<f64>, b: &Vector3<f64>, mut f: impl FnMut(f64)) {
        let mut inside = |s: f64| {
            if s > 0.0 && s < 1.0 {
                f(s)
            }
        };
        match self {
            Self::Plane { .. } => {}
            Self::Cuboid { center, axes, half } => {
                let pa = axes.tr_mul(&(a - center));
                let d = axes.tr_mul(&(b - a));
                let pb = pa + d;
                for k in 0..3 {
                    if d[k] != 0.0 {
                        inside((half[k] - pa[k]) / d[k]);
                        inside((-half[k] - pa[k]) / d[k]);
                    }
                }
                // The planes where the nearest face changes lie inside the box: a segment
                // outside it crosses none.
                if (0..3).any(|k| pa[k].min(pb[k]) > half[k] || pa[k].max(pb[k]) < -half[k]) {
                    return;
                }
                // |p_k| − h_k = |p_l| − h_l where those two are the largest: inside the box,
                // where the nearest face changes from k to l.
                for (k, l) in [(0, 1), (0, 2), (1, 2)] {
                    for (sk, sl) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
                        let den = sk * d[k] - sl * d[l];
                        if den == 0.0 {
                            continue;
                        }
                        let s = (half[k] - half[l] - sk * pa[k] + sl * pa[l]) / den;
                        let p = pa + d * s;
                        let q = p.abs() - half;
                        let m = 3 - k - l;
                        if sk * p[k] >= 0.0 && sl * p[l] >= 0.0 && q[k] <= 0.0 && q[k] >= q[m] {
                            inside(s);
                        }
                    }
                }
            }
            Self::Heightfield(grid) => {
                for axis in 0..2 {
                    let (ea, eb) = (a[axis], b[axis]);
                    if ea == eb {
                        continue;
                    }
                    let (o, h) = (grid.origin[axis], grid.spacing[axis]);
                    let n = if axis == 0 { grid.nx } else { grid.ny };
                    let (lo, hi) = (ea.min(eb), ea.max(eb));
                    let first = (((lo - o) / h).ceil().max(0.0)) as usize;
                    let last = ((hi - o) / h).floor();
                    if last < 0.0 {
                        continue;
                    }
                    let last = (last as usize).min(n - 1);
                    for i in first..=last {
                        inside((o + i as f64 * h - ea) / (eb - ea));
                    }
                }
            }
        }
    }
}
