//! Natural frequencies and mode shapes about a state at rest: `ω² = eig(Zᵀ K Z, Zᵀ M Z)`
//! in the minimal coordinates of the bar-constraint tangent space. K includes the
//! geometric stiffness of the cable and bar force densities, so a prestress-stabilized
//! structure is stable here too. Zero modes are named: rigid-body motions of a free
//! structure, or a mechanism.

use std::f64::consts::PI;

use nalgebra::{DMatrix, DVector, Vector3};

use super::reduced::symmetric_eigen;
use super::{Reduced, Tangent};
use crate::dynamics::Inputs;
use crate::model::Model;

/// Relative size (of the largest ω²) below which a mode that is not a rigid motion counts
/// as a mechanism: a few hundred times round-off in assembling and reducing K.
pub const MECHANISM: f64 = 1e-12;
/// Relative size below which a rigid motion the supports allow counts as unresisted (at
/// an equilibrium its stiffness is the unbalanced force's, round-off on the solve).
const RIGID_STIFFNESS: f64 = 1e-8;

/// What a mode is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModeKind {
    /// A vibration at a positive frequency.
    Vibration,
    /// A rigid-body motion of an unpinned structure (zero frequency).
    RigidBody,
    /// A motion that stretches nothing and is not rigid (zero frequency).
    Mechanism,
    /// A direction of negative stiffness: the state is an unstable equilibrium.
    Unstable,
}

impl ModeKind {
    /// The name written in reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::Vibration => "vibration",
            Self::RigidBody => "rigid-body",
            Self::Mechanism => "mechanism",
            Self::Unstable => "unstable",
        }
    }
}

/// One mode.
#[derive(Debug, Clone)]
pub struct Mode {
    /// Eigenvalue ω² of `(Zᵀ K Z, Zᵀ M Z)`, 1/s².
    pub omega_squared: f64,
    /// What it is.
    pub kind: ModeKind,
    /// Displacement of every node (0 for pinned ones), scaled so the largest is 1 m.
    pub shape: Vec<Vector3<f64>>,
    /// The same motion in η₂, scaled alike (for animation and the linear model).
    pub reduced: DVector<f64>,
}

impl Mode {
    /// Natural frequency in Hz: 0 for rigid-body motions and mechanisms; for an unstable
    /// direction, none (see [`Mode::growth_rate`]).
    pub fn frequency_hz(&self) -> f64 {
        match self.kind {
            ModeKind::Vibration => self.omega_squared.sqrt() / (2.0 * PI),
            _ => 0.0,
        }
    }

    /// Growth rate `√(−ω²)` of an unstable direction, 1/s (0 otherwise).
    pub fn growth_rate(&self) -> f64 {
        match self.kind {
            ModeKind::Unstable => (-self.omega_squared).sqrt(),
            _ => 0.0,
        }
    }
}

/// All modes of a state, lowest ω² first.
#[derive(Debug, Clone)]
pub struct Spectrum {
    /// The modes.
    pub modes: Vec<Mode>,
}

impl Spectrum {
    /// The mode shapes (in the constrained coordinates) as the columns of one matrix, Φ.
    pub fn shapes(&self) -> DMatrix<f64> {
        DMatrix::from_columns(
            &self
                .modes
                .iter()
                .map(|m| m.reduced.clone())
                .collect::<Vec<_>>(),
        )
    }

    /// The modes of `model` about positions `q` at rest with `inputs`, at time `t`.
    pub fn new(model: &Model, inputs: &Inputs, t: f64, q: &[f64]) -> Self {
        let tangent = Tangent::new(model, inputs, t, q, &vec![0.0; q.len()]);
        Self::of(model, &tangent)
    }

    /// The modes of a tangent taken at rest.
    pub fn of(model: &Model, tangent: &Tangent) -> Self {
        let reduced = Reduced::new(tangent);
        let m = reduced.dim();
        if m == 0 {
            return Self { modes: Vec::new() };
        }
        let l = reduced
            .mass
            .clone()
            .cholesky()
            .expect("the mass matrix is positive definite")
            .l();
        let l_inv = l
            .clone()
            .try_inverse()
            .expect("a Cholesky factor is invertible");
        let a = &l_inv * &reduced.stiffness * l_inv.transpose();
        let a = (&a + a.transpose()) * 0.5;
        let scale = a.amax().max(f64::MIN_POSITIVE);
        // In y = Lᵀ ξ the mass is the identity: rigid motions with no stiffness are taken
        // out first, the rest is an ordinary symmetric eigenproblem on their complement.
        let rigid = zero_stiffness_rigid_motions(model, tangent, &reduced, &l, &a, scale);
        let complement = orthogonal_complement(&rigid, m);
        let eigen = symmetric_eigen(complement.tr_mul(&(&a * &complement)));
        let largest = eigen.eigenvalues.amax().max(f64::MIN_POSITIVE);
        let mut others: Vec<(f64, DVector<f64>)> = (0..complement.ncols())
            .map(|k| {
                (
                    eigen.eigenvalues[k],
                    &complement * eigen.eigenvectors.column(k),
                )
            })
            .collect();
        others.sort_by(|x, y| x.0.total_cmp(&y.0));
        let rigid_modes = rigid.column_iter().map(|y| {
            let y = y.into_owned();
            (y.dot(&(&a * &y)), y, ModeKind::RigidBody)
        });
        let other_modes = others.into_iter().map(|(value, y)| {
            let kind = if value.abs() <= MECHANISM * largest {
                ModeKind::Mechanism
            } else if value < 0.0 {
                ModeKind::Unstable
            } else {
                ModeKind::Vibration
            };
            (value, y, kind)
        });
        let modes = rigid_modes
            .chain(other_modes)
            .map(|(value, y, kind)| {
                let xi = l
                    .transpose()
                    .solve_upper_triangular(&y)
                    .expect("invertible");
                shape(model, tangent, &reduced.basis * xi, value, kind)
            })
            .collect();
        Self { modes }
    }

    /// Frequencies in Hz, every mode listed.
    pub fn frequencies_hz(&self) -> Vec<f64> {
        self.modes.iter().map(Mode::frequency_hz).collect()
    }

    /// How many modes are of `kind`.
    pub fn count(&self, kind: ModeKind) -> usize {
        self.modes.iter().filter(|m| m.kind == kind).count()
    }
}

fn shape(model: &Model, tangent: &Tangent, q: DVector<f64>, value: f64, kind: ModeKind) -> Mode {
    let x = &tangent.ends * &q;
    let mut nodes = vec![Vector3::zeros(); model.n_nodes()];
    for (n, end) in model.coords.node_end.iter().enumerate() {
        if let Some(e) = *end {
            nodes[n] = Vector3::new(x[3 * e], x[3 * e + 1], x[3 * e + 2]);
        }
    }
    let largest = nodes.iter().map(|d| d.norm()).fold(0.0, f64::max);
    // A sign convention makes shapes reproducible: the largest component is positive.
    let biggest = x
        .iter()
        .copied()
        .fold(0.0f64, |a, v| if v.abs() > a.abs() { v } else { a });
    let s = if largest > 0.0 {
        biggest.signum() / largest
    } else {
        1.0
    };
    Mode {
        omega_squared: value,
        kind,
        shape: nodes.iter().map(|d| d * s).collect(),
        reduced: q * s,
    }
}

/// The rigid motions the supports allow (translations and rotations that move no pinned
/// node) that the stiffness does not resist, as orthonormal columns in y = Lᵀ ξ.
fn zero_stiffness_rigid_motions(
    model: &Model,
    tangent: &Tangent,
    reduced: &Reduced,
    l: &DMatrix<f64>,
    a: &DMatrix<f64>,
    scale: f64,
) -> DMatrix<f64> {
    let m = a.nrows();
    let allowed = allowed_rigid_motions(model, tangent);
    if allowed.ncols() == 0 {
        return DMatrix::zeros(m, 0);
    }
    let n_ends = model.coords.n_ends();
    let ws = &tangent.workspace;
    let centre = ws.end_pos.iter().sum::<Vector3<f64>>() / n_ends as f64;
    let mut fields = DMatrix::zeros(3 * n_ends, allowed.ncols());
    for e in 0..n_ends {
        let p = ws.end_pos[e] - centre;
        for (c, motion) in allowed.column_iter().enumerate() {
            let d = Vector3::new(motion[0], motion[1], motion[2])
                + Vector3::new(motion[3], motion[4], motion[5]).cross(&p);
            for k in 0..3 {
                fields[(3 * e + k, c)] = d[k];
            }
        }
    }
    let y = l.transpose() * reduced.basis.tr_mul(&tangent.ends.tr_mul(&fields));
    let basis = orthonormal_columns(&y);
    if basis.ncols() == 0 {
        return basis;
    }
    let within = symmetric_eigen(basis.tr_mul(&(a * &basis)));
    let free: Vec<DVector<f64>> = (0..basis.ncols())
        .filter(|&k| within.eigenvalues[k].abs() <= RIGID_STIFFNESS * scale)
        .map(|k| &basis * within.eigenvectors.column(k))
        .collect();
    stack(m, &free)
}

/// Combinations (6 × k: translation, rotation about the ends' centroid) of rigid motions
/// that keep every pinned node in place: all six without pins, rotations about the axis
/// through two pins, none with three pins off one line.
fn allowed_rigid_motions(model: &Model, tangent: &Tangent) -> DMatrix<f64> {
    let ws = &tangent.workspace;
    let n_ends = model.coords.n_ends();
    let centre = ws.end_pos.iter().sum::<Vector3<f64>>() / n_ends as f64;
    let pins: Vec<Vector3<f64>> = (0..model.n_nodes())
        .filter(|&n| model.pinned[n])
        .map(|n| model.positions[n] - centre)
        .collect();
    if pins.is_empty() {
        return DMatrix::identity(6, 6);
    }
    // Displacement of pin p: t + ω × p = t − [p]× ω.
    let mut rows = DMatrix::zeros(3 * pins.len(), 6);
    for (k, p) in pins.iter().enumerate() {
        for i in 0..3 {
            rows[(3 * k + i, i)] = 1.0;
        }
        let skew = -p.cross_matrix();
        rows.view_mut((3 * k, 3), (3, 3)).copy_from(&skew);
    }
    let size = rows.amax().max(1.0);
    let eigen = symmetric_eigen(rows.tr_mul(&rows));
    let keep: Vec<DVector<f64>> = (0..6)
        .filter(|&k| eigen.eigenvalues[k] <= 1e-12 * size * size)
        .map(|k| eigen.eigenvectors.column(k).into_owned())
        .collect();
    stack(6, &keep)
}

/// An orthonormal basis of the column space of `y` (columns that are numerically
/// dependent dropped).
fn orthonormal_columns(y: &DMatrix<f64>) -> DMatrix<f64> {
    let svd = y.clone().svd(true, false);
    let u = svd.u.expect("requested U");
    let top = svd.singular_values.max();
    let keep: Vec<DVector<f64>> = (0..svd.singular_values.len())
        .filter(|&k| svd.singular_values[k] > 1e-8 * top)
        .map(|k| u.column(k).into_owned())
        .collect();
    stack(y.nrows(), &keep)
}

/// An orthonormal basis of the complement of the orthonormal columns `r` in ℝᵐ.
fn orthogonal_complement(r: &DMatrix<f64>, m: usize) -> DMatrix<f64> {
    if r.ncols() == 0 {
        return DMatrix::identity(m, m);
    }
    let projector = DMatrix::identity(m, m) - r * r.transpose();
    let eigen = symmetric_eigen(projector);
    let keep: Vec<DVector<f64>> = (0..m)
        .filter(|&k| eigen.eigenvalues[k] > 0.5)
        .map(|k| eigen.eigenvectors.column(k).into_owned())
        .collect();
    stack(m, &keep)
}

/// Columns side by side (`rows × 0` when there are none).
fn stack(rows: usize, columns: &[DVector<f64>]) -> DMatrix<f64> {
    if columns.is_empty() {
        DMatrix::zeros(rows, 0)
    } else {
        DMatrix::from_columns(columns)
    }
}
