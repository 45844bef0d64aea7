//! Damped frequencies and damping ratios of the undamped modes of [`Spectrum`], from the
//! eigenvalues of the linear model's `A` (the state matrix in modal coordinates of
//! [`super::linear`]).
//!
//! Pairing: `A` acts on `(a, ȧ)`, the amplitudes of the undamped modes and their rates, so
//! the position part `x` of an eigenvector says how much of each undamped mode it moves;
//! its share of mode k is `M_k |x_k|²` over the sum (`M_k` the modal mass; the shapes are
//! mass-orthogonal, so this is the kinetic-energy share). Each conjugate pair of complex
//! eigenvalues goes to the mode it moves most (largest shares first, one pair per mode);
//! the real eigenvalues (overdamped, zero-frequency and unstable modes) then go two by two
//! to the modes left, largest shares first. Matching by nearest frequency instead fails
//! where damping matters: damping moves the eigenvalues off the undamped frequencies, an
//! overdamped mode has no frequency at all, and modes of equal frequency but different
//! damping are told apart only by their shapes.
//!
//! From a mode's two eigenvalues `λ₁, λ₂`: `ω² = λ₁λ₂`, `ζ = −(λ₁ + λ₂)/(2ω)` and
//! `f_d = |Im λ|/2π`. For a complex pair that is `ζ = −Re λ/|λ|`; two real ones (an
//! overdamped mode) give `f_d = 0` and `ζ ≥ 1`. With proportional damping `ω` is the
//! undamped `ω_n` and `f_d = f_n √(1 − ζ²)`.

use std::f64::consts::PI;

use nalgebra::{Complex, DMatrix, DVector, Schur};

use super::modes::{ModeKind, Spectrum};
use super::Tangent;

/// The mass, stiffness and damping of the linearized motion in the amplitudes of the
/// undamped modes (columns of `phi`): `M ä + C ȧ + K a = Φᵀ (∂f/∂u) u`.
#[derive(Debug, Clone)]
pub struct ModalMatrices {
    /// `Φᵀ M̄ Φ`.
    pub mass: DMatrix<f64>,
    /// Its inverse.
    pub mass_inverse: DMatrix<f64>,
    /// `Φᵀ K Φ` with the tangent stiffness K.
    pub stiffness: DMatrix<f64>,
    /// `−Φᵀ (∂f/∂q̇) Φ`.
    pub damping: DMatrix<f64>,
}

impl ModalMatrices {
    /// The matrices of `tangent` in the mode shapes `phi` (reduced coordinates, one column
    /// per mode).
    pub fn new(tangent: &Tangent, phi: &DMatrix<f64>) -> Self {
        let mass = phi.tr_mul(&(&tangent.mass * phi));
        let mass_inverse = mass
            .clone()
            .try_inverse()
            .expect("modal mass is invertible");
        Self {
            mass,
            mass_inverse,
            stiffness: phi.tr_mul(&(tangent.tangent_stiffness() * phi)),
            damping: -phi.tr_mul(&(&tangent.damping * phi)),
        }
    }

    /// `A = [[0, I], [−M⁻¹K, −M⁻¹C]]` over the states `(a, ȧ)`.
    pub fn state_matrix(&self) -> DMatrix<f64> {
        let m = self.mass.nrows();
        let mut a = DMatrix::zeros(2 * m, 2 * m);
        a.view_mut((0, m), (m, m))
            .copy_from(&DMatrix::identity(m, m));
        a.view_mut((m, 0), (m, m))
            .copy_from(&(-&self.mass_inverse * &self.stiffness));
        a.view_mut((m, m), (m, m))
            .copy_from(&(-&self.mass_inverse * &self.damping));
        a
    }
}

/// One mode's damping.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Damping {
    /// Damped frequency `|Im λ|/2π`, Hz: 0 for an overdamped mode and for a mode that does
    /// not vibrate.
    pub frequency_hz: f64,
    /// Damping ratio ζ; `None` for a mode that does not vibrate (rigid-body, mechanism,
    /// unstable), where it is undefined.
    pub ratio: Option<f64>,
    /// The two eigenvalues of `A` attributed to the mode, 1/s.
    pub eigenvalues: [Complex<f64>; 2],
}

/// The damping of every mode of `spectrum` (same order), which was computed from `tangent`.
pub fn damping(tangent: &Tangent, spectrum: &Spectrum) -> Vec<Damping> {
    if spectrum.modes.is_empty() {
        return Vec::new();
    }
    let phi = spectrum.shapes();
    let matrices = ModalMatrices::new(tangent, &phi);
    let kinds: Vec<ModeKind> = spectrum.modes.iter().map(|m| m.kind).collect();
    if matrices.damping.iter().all(|&c| c == 0.0) {
        // No damping at all: A's eigenvalues are ±iω exactly; round-off would only blur it.
        return spectrum
            .modes
            .iter()
            .map(|mode| {
                let omega = mode.frequency_hz() * 2.0 * PI;
                let vibrates = mode.kind == ModeKind::Vibration;
                Damping {
                    frequency_hz: mode.frequency_hz(),
                    ratio: vibrates.then_some(0.0),
                    eigenvalues: [Complex::new(0.0, omega), Complex::new(0.0, -omega)],
                }
            })
            .collect();
    }
    of_state_matrix(&matrices.state_matrix(), &matrices.mass.diagonal(), &kinds)
}

/// The damping of each mode from the state matrix `a` over `(a, ȧ)` in modal amplitudes,
/// with the modal masses and the kinds of the undamped modes (see the module's pairing).
pub fn of_state_matrix(
    a: &DMatrix<f64>,
    modal_mass: &DVector<f64>,
    kinds: &[ModeKind],
) -> Vec<Damping> {
    let m = kinds.len();
    assert_eq!(
        a.nrows(),
        2 * m,
        "A is over the modes' amplitudes and rates"
    );
    let pairs = eigenpairs(a);
    let share = |x: &DVector<Complex<f64>>| -> Vec<f64> {
        let energy: Vec<f64> = (0..m).map(|k| modal_mass[k] * x[k].norm_sqr()).collect();
        let total = energy.iter().sum::<f64>().max(f64::MIN_POSITIVE);
        energy.iter().map(|e| e / total).collect()
    };
    let (complex, real): (Vec<_>, Vec<_>) = pairs.into_iter().partition(|(l, _)| l.im > 0.0);
    let mut taken: Vec<Vec<Complex<f64>>> = vec![Vec::new(); m];
    // Conjugate pairs first, each to a mode of its own.
    let shares: Vec<Vec<f64>> = complex.iter().map(|(_, x)| share(x)).collect();
    greedy(
        &shares,
        m,
        |k, taken: &[Vec<Complex<f64>>]| taken[k].is_empty(),
        &mut taken,
        |j| vec![complex[j].0, complex[j].0.conj()],
    );
    let shares: Vec<Vec<f64>> = real.iter().map(|(_, x)| share(x)).collect();
    greedy(
        &shares,
        m,
        |k, taken: &[Vec<Complex<f64>>]| taken[k].len() < 2,
        &mut taken,
        |j| vec![real[j].0],
    );
    taken
        .iter()
        .zip(kinds)
        .map(|(lambdas, &kind)| of_pair([lambdas[0], lambdas[1]], kind))
        .collect()
}

/// Assigns every item (rows of `shares`) to a mode that `open` accepts, largest share
/// first, pushing `values(item)` onto the mode's list.
fn greedy(
    shares: &[Vec<f64>],
    m: usize,
    open: impl Fn(usize, &[Vec<Complex<f64>>]) -> bool,
    taken: &mut [Vec<Complex<f64>>],
    values: impl Fn(usize) -> Vec<Complex<f64>>,
) {
    let mut candidates: Vec<(f64, usize, usize)> = shares
        .iter()
        .enumerate()
        .flat_map(|(j, s)| (0..m).map(move |k| (s[k], j, k)))
        .collect();
    candidates.sort_by(|x, y| y.0.total_cmp(&x.0));
    let mut placed = vec![false; shares.len()];
    for (_, j, k) in candidates {
        if !placed[j] && open(k, taken) {
            placed[j] = true;
            taken[k].extend(values(j));
        }
    }
}

/// ζ and f_d from a mode's two eigenvalues.
fn of_pair(eigenvalues: [Complex<f64>; 2], kind: ModeKind) -> Damping {
    let [l1, l2] = eigenvalues;
    let omega_squared = (l1 * l2).re;
    let vibrates = kind == ModeKind::Vibration && omega_squared > 0.0;
    Damping {
        frequency_hz: if vibrates {
            l1.im.abs().max(l2.im.abs()) / (2.0 * PI)
        } else {
            0.0
        },
        ratio: vibrates.then(|| -(l1 + l2).re / (2.0 * omega_squared.sqrt())),
        eigenvalues,
    }
}

/// The eigenvalues of `a` with their eigenvectors: every real one, and of each complex
/// conjugate pair the member with `Im λ > 0`. From the real Schur form `A = Q T Qᵀ` by back
/// substitution in `T` (nalgebra gives eigenvalues only).
fn eigenpairs(a: &DMatrix<f64>) -> Vec<(Complex<f64>, DVector<Complex<f64>>)> {
    let n = a.nrows();
    let (q, t) = Schur::new(a.clone()).unpack();
    let q = q.map(|x| Complex::new(x, 0.0));
    let mut blocks = Vec::new();
    let mut i = 0;
    while i < n {
        let size = if i + 1 < n && t[(i + 1, i)] != 0.0 {
            2
        } else {
            1
        };
        blocks.push((i, size));
        i += size;
    }
    let scale = t.amax().max(f64::MIN_POSITIVE);
    let mut out = Vec::new();
    for (b, &(start, size)) in blocks.iter().enumerate() {
        let values = if size == 1 {
            vec![Complex::new(t[(start, start)], 0.0)]
        } else {
            let (p, r) = (t[(start, start)], t[(start + 1, start + 1)]);
            let half = Complex::new(0.5 * (p - r), 0.0);
            let root = (half * half + t[(start, start + 1)] * t[(start + 1, start)]).sqrt();
            let mean = Complex::new(0.5 * (p + r), 0.0);
            let (hi, lo) = (mean + root, mean - root);
            if hi.im.abs() > 0.0 {
                vec![if hi.im > 0.0 { hi } else { lo }]
            } else {
                vec![hi, lo]
            }
        };
        for lambda in values {
            let y = triangular_eigenvector(&t, &blocks[..=b], lambda, scale);
            let v = &q * y;
            out.push((lambda, v));
        }
    }
    out
}

/// A solution of `(T − λ) y = 0` nonzero in the last of `blocks` (λ is one of its
/// eigenvalues) and zero below it, by back substitution over the blocks above.
fn triangular_eigenvector(
    t: &DMatrix<f64>,
    blocks: &[(usize, usize)],
    lambda: Complex<f64>,
    scale: f64,
) -> DVector<Complex<f64>> {
    let n = t.nrows();
    let c = |i: usize, j: usize| Complex::new(t[(i, j)], 0.0);
    // Where T − λ is (numerically) singular in a block above, a tiny pivot stands in
    // (as LAPACK's trevc does): the vector then lies along that repeated eigenvalue.
    let tiny = f64::EPSILON * scale;
    let guard = |z: Complex<f64>| {
        if z.norm() < tiny {
            Complex::new(tiny, 0.0)
        } else {
            z
        }
    };
    let mut y = DVector::from_element(n, Complex::new(0.0, 0.0));
    let &(start, size) = blocks.last().expect("at least the target block");
    if size == 1 {
        y[start] = Complex::new(1.0, 0.0);
    } else {
        // A null vector of the 2×2 block minus λ, from whichever row is larger.
        let (a00, a01, a10, a11) = (
            c(start, start) - lambda,
            c(start, start + 1),
            c(start + 1, start),
            c(start + 1, start + 1) - lambda,
        );
        if a00.norm() + a01.norm() >= a10.norm() + a11.norm() {
            y[start] = a01;
            y[start + 1] = -a00;
        } else {
            y[start] = a11;
            y[start + 1] = -a10;
        }
    }
    let end = start + size;
    for &(row, rows) in blocks[..blocks.len() - 1].iter().rev() {
        let rhs = |i: usize| -> Complex<f64> {
            -(row + rows..end)
                .map(|j| c(i, j) * y[j])
                .sum::<Complex<f64>>()
        };
        if rows == 1 {
            y[row] = rhs(row) / guard(c(row, row) - lambda);
        } else {
            let (a00, a01, a10, a11) = (
                c(row, row) - lambda,
                c(row, row + 1),
                c(row + 1, row),
                c(row + 1, row + 1) - lambda,
            );
            let (r0, r1) = (rhs(row), rhs(row + 1));
            let det = guard(a00 * a11 - a01 * a10);
            y[row] = (r0 * a11 - a01 * r1) / det;
            y[row + 1] = (a00 * r1 - a10 * r0) / det;
        }
    }
    let norm = y.iter().map(|z| z.norm_sqr()).sum::<f64>().sqrt();
    y / Complex::new(norm, 0.0)
}
