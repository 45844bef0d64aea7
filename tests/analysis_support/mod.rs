//! Helpers of the analysis suites (`tests/analysis_modes.rs`, `tests/analysis_linear.rs`):
//! an independent dense saddle-point (KKT) model in bar-end coordinates, where bar lengths,
//! class-k joints and pins are all Lagrange multipliers, its finite-difference
//! linearization about a state at rest, and Richardson-extrapolated central differences.
#![allow(dead_code)] // each suite uses part of it

use nalgebra::{DMatrix, DVector, Vector3};
use tensegrity_fmu::dynamics::Inputs;
use tensegrity_fmu::model::CableLaw;
use tensegrity_fmu::Simulation;

/// Central difference of `f` at step `h`, Richardson-extrapolated from `h` and `h/2`:
/// `(4 D(h/2) − D(h)) / 3` has an O(h⁴) truncation error.
pub fn richardson(h: f64, mut f: impl FnMut(f64) -> DVector<f64>) -> DVector<f64> {
    let mut d = |h: f64| (f(h) - f(-h)) / (2.0 * h);
    let coarse = d(h);
    (d(h / 2.0) * 4.0 - coarse) / 3.0
}

/// Largest |entry|.
pub fn amax(m: &DMatrix<f64>) -> f64 {
    m.iter().fold(0.0f64, |a, x| a.max(x.abs()))
}

/// An orthonormal basis of null(a) (a: rows × n), from the full SVD of `a` padded with
/// zero rows to a square matrix.
pub fn null_space(a: &DMatrix<f64>) -> DMatrix<f64> {
    let n = a.ncols();
    let mut square = DMatrix::zeros(n.max(a.nrows()), n);
    square.view_mut((0, 0), (a.nrows(), n)).copy_from(a);
    let svd = square.svd(false, true);
    let vt = svd.v_t.expect("requested Vᵀ");
    let largest = svd.singular_values.max();
    let keep: Vec<usize> = (0..n)
        .filter(|&k| svd.singular_values[k] <= 1e-10 * largest)
        .collect();
    DMatrix::from_fn(n, keep.len(), |r, c| vt[(keep[c], r)])
}

/// Force density of a cable law (dynamics.md), written here rather than taken from the
/// library.
fn gamma(law: &CableLaw, inputs: &Inputs, s: &Vector3<f64>, sd: &Vector3<f64>) -> f64 {
    let (stiffness, rest, damping) = match *law {
        CableLaw::Controlled { input } => return inputs.force_density[input].max(0.0),
        CableLaw::Elastic {
            stiffness,
            rest_length,
            damping,
        } => (stiffness, rest_length, damping),
        CableLaw::RestLengthControlled {
            stiffness,
            damping,
            input,
        } => (stiffness, inputs.rest_length[input].max(0.0), damping),
    };
    let l = s.norm();
    if l <= rest {
        return 0.0;
    }
    (stiffness * (1.0 - rest / l) + damping.unwrap_or(0.0) * s.dot(sd) / (l * l)).max(0.0)
}

/// The structure in bar-end coordinates `X` (3 per end, end `2i + k` is node
/// `bars[i].nodes[k]`): mass `m [1/3 1/6; 1/6 1/3]` per bar (plus payloads), and the
/// constraints as multipliers: `|bᵢ|² = lᵢ²`, `x_e = x_e'` for the ends of one node (a
/// class-k joint), `x_e = const` for a pinned node. Cable forces, node inputs and payloads
/// act on a node's first end; bar-less nodes must be pinned anchors.
pub struct EndKkt {
    /// Node of each end.
    pub end_node: Vec<usize>,
    /// First end of each node (None for a bar-less anchor).
    first: Vec<Option<usize>>,
    /// Every end of each node.
    node_ends: Vec<Vec<usize>>,
    pinned: Vec<bool>,
    mass: DMatrix<f64>,
    /// Node positions of the state the model was taken at (anchors stay there).
    anchors: Vec<Vector3<f64>>,
    /// Gravity force per end.
    weight: Vec<Vector3<f64>>,
    cables: Vec<([usize; 2], CableLaw)>,
    force_inputs: Vec<usize>,
}

impl EndKkt {
    /// The structure of `sim`'s model, anchors at `sim`'s current node positions.
    pub fn new(sim: &Simulation) -> Self {
        let model = sim.model();
        assert!(
            model.ground.is_none() && model.loads.is_empty(),
            "not modelled here"
        );
        let n_nodes = model.n_nodes();
        let end_node: Vec<usize> = model.bars.iter().flat_map(|b| b.nodes).collect();
        let mut node_ends = vec![Vec::new(); n_nodes];
        for (e, &n) in end_node.iter().enumerate() {
            node_ends[n].push(e);
        }
        let first: Vec<Option<usize>> = node_ends.iter().map(|e| e.first().copied()).collect();
        for (end, &pinned) in first.iter().zip(&model.pinned) {
            assert!(end.is_some() || pinned, "free bar-less node");
        }
        let mut payload = vec![0.0; n_nodes];
        for pm in &model.scene.point_masses {
            payload[pm.node - 1] += pm.mass;
        }
        let dim = 3 * end_node.len();
        let mut mass = DMatrix::zeros(dim, dim);
        let g = model.gravity.unwrap_or_else(Vector3::zeros);
        let mut weight = vec![Vector3::zeros(); end_node.len()];
        for (i, bar) in model.bars.iter().enumerate() {
            let m = bar.mass;
            let block = [[m / 3.0, m / 6.0], [m / 6.0, m / 3.0]];
            for r in 0..2 {
                weight[2 * i + r] += g * (m / 2.0);
                for c in 0..2 {
                    for k in 0..3 {
                        mass[(3 * (2 * i + r) + k, 3 * (2 * i + c) + k)] += block[r][c];
                    }
                }
            }
        }
        for n in 0..n_nodes {
            if let (Some(e), true) = (first[n], payload[n] > 0.0) {
                weight[e] += g * payload[n];
                for k in 0..3 {
                    mass[(3 * e + k, 3 * e + k)] += payload[n];
                }
            }
        }
        Self {
            end_node,
            first,
            node_ends,
            pinned: model.pinned.clone(),
            mass,
            anchors: (0..n_nodes).map(|n| sim.node_position(n)).collect(),
            weight,
            cables: model
                .cables
                .iter()
                .map(|c| (c.nodes, c.law.clone()))
                .collect(),
            force_inputs: model.force_inputs.clone(),
        }
    }

    /// Number of coordinates, 6β.
    pub fn dim(&self) -> usize {
        3 * self.end_node.len()
    }

    /// `X` of `sim`'s current state (every end at its node).
    pub fn positions(&self, sim: &Simulation) -> DVector<f64> {
        self.gather(|n| sim.node_position(n))
    }

    /// `Ẋ` of `sim`'s current state.
    pub fn velocities(&self, sim: &Simulation) -> DVector<f64> {
        self.gather(|n| sim.node_velocity(n))
    }

    fn gather(&self, f: impl Fn(usize) -> Vector3<f64>) -> DVector<f64> {
        let mut x = DVector::zeros(self.dim());
        for (e, &n) in self.end_node.iter().enumerate() {
            x.fixed_rows_mut::<3>(3 * e).copy_from(&f(n));
        }
        x
    }

    fn end(x: &DVector<f64>, e: usize) -> Vector3<f64> {
        x.fixed_rows::<3>(3 * e).into_owned()
    }

    fn node(&self, x: &DVector<f64>, n: usize) -> Vector3<f64> {
        self.first[n].map_or(self.anchors[n], |e| Self::end(x, e))
    }

    /// The constraint Jacobian `A` at `X` (bars, then joints, then pins) and the
    /// acceleration-level right-hand side at `(X, Ẋ)`.
    pub fn constraints(&self, x: &DVector<f64>, v: &DVector<f64>) -> (DMatrix<f64>, DVector<f64>) {
        let mut rows: Vec<(DVector<f64>, f64)> = Vec::new();
        let dim = self.dim();
        for i in 0..self.end_node.len() / 2 {
            let b = Self::end(x, 2 * i + 1) - Self::end(x, 2 * i);
            let bd = Self::end(v, 2 * i + 1) - Self::end(v, 2 * i);
            let mut row = DVector::zeros(dim);
            row.fixed_rows_mut::<3>(6 * i).copy_from(&-b);
            row.fixed_rows_mut::<3>(6 * i + 3).copy_from(&b);
            rows.push((row, -bd.norm_squared()));
        }
        for ends in &self.node_ends {
            for &e in ends.iter().skip(1) {
                for k in 0..3 {
                    let mut row = DVector::zeros(dim);
                    row[3 * e + k] = 1.0;
                    row[3 * ends[0] + k] = -1.0;
                    rows.push((row, 0.0));
                }
            }
        }
        for (n, ends) in self.node_ends.iter().enumerate() {
            if self.pinned[n] && !ends.is_empty() {
                for k in 0..3 {
                    let mut row = DVector::zeros(dim);
                    row[3 * ends[0] + k] = 1.0;
                    rows.push((row, 0.0));
                }
            }
        }
        let a = DMatrix::from_fn(rows.len(), dim, |r, c| rows[r].0[c]);
        let rhs = DVector::from_iterator(rows.len(), rows.iter().map(|r| r.1));
        (a, rhs)
    }

    /// Applied end forces: cables, weights and node inputs.
    pub fn forces(&self, inputs: &Inputs, x: &DVector<f64>, v: &DVector<f64>) -> DVector<f64> {
        let mut f = DVector::zeros(self.dim());
        let mut add = |n: usize, value: Vector3<f64>| {
            if let Some(e) = self.first[n] {
                let mut block = f.fixed_rows_mut::<3>(3 * e);
                block += value;
            }
        };
        let vel = |n: usize| self.first[n].map_or(Vector3::zeros(), |e| Self::end(v, e));
        for ([a, b], law) in &self.cables {
            let s = self.node(x, *b) - self.node(x, *a);
            let g = gamma(law, inputs, &s, &(vel(*b) - vel(*a)));
            add(*a, s * g);
            add(*b, -s * g);
        }
        for (k, &n) in self.force_inputs.iter().enumerate() {
            add(n, inputs.node_force[k]);
        }
        for (e, w) in self.weight.iter().enumerate() {
            let mut block = f.fixed_rows_mut::<3>(3 * e);
            block += w;
        }
        f
    }

    /// `Ẍ` from `[M Aᵀ; A 0] [Ẍ; μ] = [F; r]`.
    pub fn accelerations(
        &self,
        inputs: &Inputs,
        x: &DVector<f64>,
        v: &DVector<f64>,
    ) -> DVector<f64> {
        let (a, r) = self.constraints(x, v);
        let (n, c) = (self.dim(), a.nrows());
        let mut kkt = DMatrix::zeros(n + c, n + c);
        kkt.view_mut((0, 0), (n, n)).copy_from(&self.mass);
        kkt.view_mut((0, n), (n, c)).copy_from(&a.transpose());
        kkt.view_mut((n, 0), (c, n)).copy_from(&a);
        let mut rhs = DVector::zeros(n + c);
        rhs.rows_mut(0, n).copy_from(&self.forces(inputs, x, v));
        rhs.rows_mut(n, c).copy_from(&r);
        let sol = kkt
            .lu()
            .solve(&rhs)
            .expect("the KKT matrix is non-singular");
        sol.rows(0, n).into_owned()
    }
}

/// The finite-difference linearization of [`EndKkt`] about `sim`'s state at rest.
pub struct KktSpectrum {
    /// `−ω²` restricted to the tangent space of every constraint, ascending in ω².
    pub omega_squared: Vec<f64>,
    /// Dimension of that tangent space and of the full coordinates.
    pub tangent_dim: usize,
    pub full_dim: usize,
    /// `‖(I − Z Zᵀ) J‖ / ‖J‖`: how far the Jacobian's range leaves the tangent space.
    pub range_leak: f64,
    /// `‖∂Ẍ/∂Ẋ‖ / ‖J‖` (zero for an undamped structure at rest).
    pub velocity_coupling: f64,
    /// Largest |Im| of the restricted eigenvalues, relative to the largest |eigenvalue|.
    pub imaginary: f64,
}

/// Linearizes [`EndKkt`] about `sim`'s current state by Richardson-extrapolated central
/// differences: `J = ∂Ẍ/∂X`, restricted to `T = null(A)`: `Zᵀ J Z`. `J` maps every
/// direction into T (the linearized constraints at rest), so its nonzero eigenvalues are
/// those of `Zᵀ J Z`; the directions that violate a constraint only add zeros.
pub fn kkt_spectrum(sim: &Simulation) -> KktSpectrum {
    let kkt = EndKkt::new(sim);
    let x0 = kkt.positions(sim);
    let v0 = kkt.velocities(sim);
    assert!(v0.amax() == 0.0, "the state must be at rest");
    let n = kkt.dim();
    let h = 1e-3;
    let mut j = DMatrix::zeros(n, n);
    let mut jv = DMatrix::zeros(n, n);
    for k in 0..n {
        let unit = DVector::from_fn(n, |i, _| if i == k { 1.0 } else { 0.0 });
        let col = richardson(h, |d| {
            kkt.accelerations(&sim.inputs, &(&x0 + &unit * d), &v0)
        });
        j.set_column(k, &col);
        let col = richardson(h, |d| {
            kkt.accelerations(&sim.inputs, &x0, &(&v0 + &unit * d))
        });
        jv.set_column(k, &col);
    }
    let (a, _) = kkt.constraints(&x0, &v0);
    let z = null_space(&a);
    let leak = &j - &z * z.tr_mul(&j);
    let restricted = z.tr_mul(&(&j * &z));
    let eig = restricted.complex_eigenvalues();
    let largest = eig.iter().fold(0.0f64, |m, c| m.max(c.norm()));
    let imaginary = eig.iter().fold(0.0f64, |m, c| m.max(c.im.abs())) / largest;
    let mut omega_squared: Vec<f64> = eig.iter().map(|c| -c.re).collect();
    omega_squared.sort_by(f64::total_cmp);
    KktSpectrum {
        omega_squared,
        tangent_dim: z.ncols(),
        full_dim: n,
        range_leak: amax(&leak) / amax(&j),
        velocity_coupling: amax(&jv) / amax(&j),
        imaginary,
    }
}
