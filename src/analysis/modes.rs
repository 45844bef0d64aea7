//! Natural frequencies and mode shapes about a state at rest: `ω² = eig(Zᵀ K Z, Zᵀ M Z)`
//! in the minimal coordinates of the bar-constraint tangent space. K includes the
//! geometric stiffness of the cable and bar force densities, so a prestress-stabilized
//! structure is stable here too. Zero modes are named: rigid-body motions of a free
//! structure, or a mechanism.

use std::f64::consts::PI;

use nalgebra::{DMatrix, DVector, SymmetricEigen, Vector3};

use super::{Reduced, Tangent};
use crate::dynamics::Inputs;
use crate::model::Model;

/// Relative size below which a stiffness eigenvalue counts as zero.
pub const ZERO_STIFFNESS: f64 = 1e-9;

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
        let eigen = SymmetricEigen::new((&a + a.transpose()) * 0.5);
        let mut order: Vec<usize> = (0..m).collect();
        order.sort_by(|&x, &y| eigen.eigenvalues[x].total_cmp(&eigen.eigenvalues[y]));
        let scale = eigen.eigenvalues.amax().max(f64::MIN_POSITIVE);
        let zero = |v: f64| v.abs() <= ZERO_STIFFNESS * scale;
        // Eigenvectors in y = Lᵀ ξ; the zero cluster is rotated so rigid motions come first.
        let mut vectors: Vec<(f64, DVector<f64>)> = order
            .iter()
            .map(|&k| {
                (
                    eigen.eigenvalues[k],
                    eigen.eigenvectors.column(k).into_owned(),
                )
            })
            .collect();
        let zero_idx: Vec<usize> = (0..m).filter(|&k| zero(vectors[k].0)).collect();
        let rigid_count = rotate_rigid_first(model, tangent, &reduced, &l, &mut vectors, &zero_idx);
        let modes = vectors
            .into_iter()
            .enumerate()
            .map(|(k, (value, y))| {
                let kind = if let Some(p) = zero_idx.iter().position(|&z| z == k) {
                    if p < rigid_count {
                        ModeKind::RigidBody
                    } else {
                        ModeKind::Mechanism
                    }
                } else if value < 0.0 {
                    ModeKind::Unstable
                } else {
                    ModeKind::Vibration
                };
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

/// Counts the rigid-body motions inside the zero cluster and rotates the cluster's basis
/// so that they come first. Only an unpinned structure has rigid-body motions.
fn rotate_rigid_first(
    model: &Model,
    tangent: &Tangent,
    reduced: &Reduced,
    l: &DMatrix<f64>,
    vectors: &mut [(f64, DVector<f64>)],
    zero_idx: &[usize],
) -> usize {
    let anchored = model.pinned.iter().any(|&p| p);
    if anchored || zero_idx.is_empty() {
        return 0;
    }
    // The six rigid fields of the ends, mapped to y = Lᵀ Zᵀ J_eᵀ δx_E, orthonormalized.
    let n_ends = model.coords.n_ends();
    let ws = &tangent.workspace;
    let centre = ws.end_pos.iter().sum::<Vector3<f64>>() / n_ends as f64;
    let mut fields = DMatrix::zeros(3 * n_ends, 6);
    for e in 0..n_ends {
        let p = ws.end_pos[e] - centre;
        for axis in 0..3 {
            fields[(3 * e + axis, axis)] = 1.0;
            let w = Vector3::ith(axis, 1.0).cross(&p);
            for k in 0..3 {
                fields[(3 * e + k, 3 + axis)] = w[k];
            }
        }
    }
    let y = l.transpose() * reduced.basis.tr_mul(&tangent.ends.tr_mul(&fields));
    let rigid = y.svd(true, false);
    let u = rigid.u.expect("requested U");
    let s_max = rigid.singular_values.max();
    let rigid_basis: Vec<DVector<f64>> = (0..rigid.singular_values.len())
        .filter(|&k| rigid.singular_values[k] > 1e-8 * s_max)
        .map(|k| u.column(k).into_owned())
        .collect();
    let cluster = DMatrix::from_columns(
        &zero_idx
            .iter()
            .map(|&k| vectors[k].1.clone())
            .collect::<Vec<_>>(),
    );
    let r = DMatrix::from_columns(&rigid_basis);
    // Principal directions between the cluster and the rigid fields.
    let overlap = cluster.tr_mul(&r).svd(true, false);
    let u = overlap.u.expect("requested U");
    let mut order: Vec<usize> = (0..overlap.singular_values.len()).collect();
    order.sort_by(|&a, &b| overlap.singular_values[b].total_cmp(&overlap.singular_values[a]));
    let count = order
        .iter()
        .filter(|&&k| overlap.singular_values[k] > 1.0 - 1e-6)
        .count();
    let rotation = DMatrix::from_columns(&order.iter().map(|&k| u.column(k)).collect::<Vec<_>>());
    let mut rotated = &cluster * &rotation;
    // `svd` leaves U thin when the cluster is larger than the rigid space: complete it.
    if rotated.ncols() < zero_idx.len() {
        rotated = complete(&cluster, &rotated);
    }
    for (c, &k) in zero_idx.iter().enumerate() {
        vectors[k].1 = rotated.column(c).into_owned();
    }
    count
}

/// Extends orthonormal columns `part` (inside span `all`) to an orthonormal basis of it.
fn complete(all: &DMatrix<f64>, part: &DMatrix<f64>) -> DMatrix<f64> {
    let residual = all - part * part.tr_mul(all);
    let svd = residual.svd(true, false);
    let u = svd.u.expect("requested U");
    let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
    order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
    let extra = all.ncols() - part.ncols();
    let mut columns: Vec<DVector<f64>> = part.column_iter().map(|c| c.into_owned()).collect();
    columns.extend(order[..extra].iter().map(|&k| u.column(k).into_owned()));
    DMatrix::from_columns(&columns)
}
