//! Continuous-time state-space models `ẋ = A x + B u`, `y = C x + D u` about a state at
//! rest. The states are the modal amplitudes and their rates (`mode[k]`, `mode[k].rate`,
//! the shapes of [`Spectrum`] scaled to 1 m at their largest node): minimal coordinates of
//! the bar-constraint tangent space, so `A` has no spurious zero eigenvalues.
//!
//! `A` and `B` come from the tangent: `M_m ä + C_m ȧ + K_m a = Φᵀ (∂f/∂u) u`. In `C` and
//! `D`, positions, velocities, cable tensions and bar forces are analytic (the bar force
//! densities through `Gᵀ δμ = M̄ δη̈₂ − δf − Σλ DᵀD δη₂`); the remaining outputs (energy,
//! constraint residuals, contact and support forces) are central differences of the output
//! map along the same directions.

use nalgebra::{DMatrix, DVector};

use super::damped::ModalMatrices;
use super::modes::Spectrum;
use super::{InputChannel, Tangent};
use crate::dynamics::Inputs;
use crate::model::{CableLaw, Model};
use crate::outputs::{Output, Quantity};
use crate::sim::{Simulation, State};

/// A linear model with named states, inputs and outputs.
#[derive(Debug, Clone)]
pub struct LinearModel {
    /// State names.
    pub states: Vec<String>,
    /// Input names (the FMU's).
    pub inputs: Vec<String>,
    /// Output names (the FMU's).
    pub outputs: Vec<String>,
    /// `∂ẋ/∂x`.
    pub a: DMatrix<f64>,
    /// `∂ẋ/∂u`.
    pub b: DMatrix<f64>,
    /// `∂y/∂x`.
    pub c: DMatrix<f64>,
    /// `∂y/∂u`.
    pub d: DMatrix<f64>,
    /// Output values at the operating point.
    pub output_values: Vec<f64>,
    /// Input values at the operating point.
    pub input_values: Vec<f64>,
    /// Natural frequency of each mode, Hz (0 for rigid-body motions and mechanisms).
    pub frequencies_hz: Vec<f64>,
}

/// Linearizes `sim` about its current state, which must be at rest, for the named
/// `channels` and `outputs`.
pub fn linearize(
    sim: &Simulation,
    channels: &[(String, InputChannel)],
    outputs: &[Output],
) -> LinearModel {
    let model = sim.model();
    let inputs = &sim.inputs;
    let t = sim.time();
    let y0 = &sim.state().y;
    let n = y0.len() / 2;
    let q = &y0[..n];
    let tangent = Tangent::new(model, inputs, t, q, &vec![0.0; n]);
    let spectrum = Spectrum::of(model, &tangent);
    let phi = spectrum.shapes();
    let m = phi.ncols();
    let kinds: Vec<InputChannel> = channels.iter().map(|(_, c)| *c).collect();
    let matrices = ModalMatrices::new(&tangent, &phi);
    let mass_inv = &matrices.mass_inverse;
    let force_input = tangent.input_matrix(model, inputs, &kinds);
    let a = matrices.state_matrix();
    let mut b = DMatrix::zeros(2 * m, kinds.len());
    b.view_mut((m, 0), (m, kinds.len()))
        .copy_from(&(mass_inv * phi.tr_mul(&force_input)));
    let ctx = Context {
        model,
        inputs,
        tangent: &tangent,
        phi: &phi,
        a: &a,
        b: &b,
        force_input: &force_input,
        kinds: &kinds,
    };
    let mut c = DMatrix::zeros(outputs.len(), 2 * m);
    let mut d = DMatrix::zeros(outputs.len(), kinds.len());
    let bar_rows = ctx.bar_force_rows();
    for (row, output) in outputs.iter().enumerate() {
        let analytic = ctx.output_row(output.quantity, &bar_rows);
        let (c_row, d_row) =
            analytic.unwrap_or_else(|| differenced_row(sim, &ctx, output.quantity));
        c.row_mut(row).copy_from(&c_row.transpose());
        d.row_mut(row).copy_from(&d_row.transpose());
    }
    let mut refreshed = sim.clone();
    refreshed.refresh();
    LinearModel {
        states: (1..=m)
            .map(|k| format!("mode[{k}]"))
            .chain((1..=m).map(|k| format!("mode[{k}].rate")))
            .collect(),
        inputs: channels.iter().map(|(name, _)| name.clone()).collect(),
        outputs: outputs.iter().map(|o| o.name.clone()).collect(),
        output_values: outputs
            .iter()
            .map(|o| o.quantity.value(&refreshed))
            .collect(),
        input_values: kinds.iter().map(|&k| input_value(inputs, k)).collect(),
        frequencies_hz: spectrum.frequencies_hz(),
        a,
        b,
        c,
        d,
    }
}

/// The current value of an input channel.
pub fn input_value(inputs: &Inputs, channel: InputChannel) -> f64 {
    match channel {
        InputChannel::ForceDensity(k) => inputs.force_density[k],
        InputChannel::RestLength(k) => inputs.rest_length[k],
        InputChannel::NodeForce(k, axis) => inputs.node_force[k][axis],
    }
}

fn set_input(inputs: &mut Inputs, channel: InputChannel, value: f64) {
    match channel {
        InputChannel::ForceDensity(k) => inputs.force_density[k] = value,
        InputChannel::RestLength(k) => inputs.rest_length[k] = value,
        InputChannel::NodeForce(k, axis) => inputs.node_force[k][axis] = value,
    }
}

struct Context<'a> {
    model: &'a Model,
    inputs: &'a Inputs,
    tangent: &'a Tangent,
    phi: &'a DMatrix<f64>,
    a: &'a DMatrix<f64>,
    b: &'a DMatrix<f64>,
    force_input: &'a DMatrix<f64>,
    kinds: &'a [InputChannel],
}

/// A row of `C` (over the 2m states) and of `D`.
type Row = (DVector<f64>, DVector<f64>);

impl Context<'_> {
    fn m(&self) -> usize {
        self.phi.ncols()
    }

    /// `∂x_e/∂a` for the end standing for `node` (None for a bar-less node).
    fn node_rows(&self, node: usize, axis: usize) -> Option<DVector<f64>> {
        let e = self.model.coords.node_end[node]?;
        Some((self.tangent.ends.row(3 * e + axis) * self.phi).transpose())
    }

    fn output_row(
        &self,
        quantity: Quantity,
        bar_rows: &(DMatrix<f64>, DMatrix<f64>),
    ) -> Option<Row> {
        let (m, nu) = (self.m(), self.kinds.len());
        let mut c = DVector::zeros(2 * m);
        let mut d = DVector::zeros(nu);
        match quantity {
            Quantity::NodePosition(n, axis) => {
                if let Some(r) = self.node_rows(n, axis) {
                    c.rows_mut(0, m).copy_from(&r);
                }
            }
            Quantity::NodeVelocity(n, axis) => {
                if let Some(r) = self.node_rows(n, axis) {
                    c.rows_mut(m, m).copy_from(&r);
                }
            }
            Quantity::CableTension(j) => self.tension_row(j, &mut c, &mut d),
            Quantity::BarForce(i) => {
                c.copy_from(&bar_rows.0.row(i).transpose());
                d.copy_from(&bar_rows.1.row(i).transpose());
            }
            _ => return None,
        }
        Some((c, d))
    }

    fn tension_row(&self, j: usize, c: &mut DVector<f64>, d: &mut DVector<f64>) {
        let cable = &self.model.cables[j];
        let ws = &self.tangent.workspace;
        let [na, nb] = cable.nodes;
        let s = ws.node_pos[nb] - ws.node_pos[na];
        let len = s.norm();
        let unit = s / len;
        let gamma = ws.gamma[j];
        // A commanded density at 0 still acts for increasing u (the clamp's right side).
        let commanded_at_zero = matches!(cable.law, CableLaw::Controlled { input }
            if self.inputs.force_density[input] >= 0.0);
        if gamma <= 0.0 && !commanded_at_zero {
            return;
        }
        // T = γ|s|: dT = (κ or γ) û·ds + c û·dṡ, plus the input's own term.
        let (along, rate, input) = match cable.law {
            CableLaw::Elastic {
                stiffness, damping, ..
            } => (stiffness, damping.unwrap_or(0.0), None),
            CableLaw::RestLengthControlled {
                stiffness,
                damping,
                input,
            } => (
                stiffness,
                damping.unwrap_or(0.0),
                Some((InputChannel::RestLength(input), -stiffness)),
            ),
            CableLaw::Controlled { input } => {
                (gamma, 0.0, Some((InputChannel::ForceDensity(input), len)))
            }
        };
        let m = self.m();
        for axis in 0..3 {
            for (node, sign) in [(nb, 1.0), (na, -1.0)] {
                if let Some(r) = self.node_rows(node, axis) {
                    let mut pos = c.rows_mut(0, m);
                    pos.axpy(sign * along * unit[axis], &r, 1.0);
                    let mut vel = c.rows_mut(m, m);
                    vel.axpy(sign * rate * unit[axis], &r, 1.0);
                }
            }
        }
        if let Some((channel, value)) = input {
            if let Some(col) = self.kinds.iter().position(|&k| k == channel) {
                d[col] += value;
            }
        }
    }

    /// Rows of `C` and `D` for every bar force `λᵢ lᵢ`: `Gᵀ δμ = M̄ δη̈₂ − δf − Σλ DᵀD δη₂`,
    /// with `λ = 2μ`, solved by least squares (`G` has full row rank unless bars form loops).
    fn bar_force_rows(&self) -> (DMatrix<f64>, DMatrix<f64>) {
        let (m, nu) = (self.m(), self.kinds.len());
        let t = self.tangent;
        let beta = self.model.bars.len();
        let mut c = DMatrix::zeros(beta, 2 * m);
        let mut d = DMatrix::zeros(beta, nu);
        let g = &t.constraints;
        if g.nrows() == 0 {
            return (c, d);
        }
        // Generalized force residual per state and per input (3r × 2m and 3r × nu).
        let accel_states = self.a.rows(m, m);
        let accel_inputs = self.b.rows(m, m);
        let phi = self.phi;
        let mut per_state = &t.mass * phi * accel_states;
        let positional = (&t.stiffness + &t.geometric) * phi;
        per_state
            .columns_mut(0, m)
            .zip_apply(&positional, |x, p| *x -= p);
        let velocity = &t.damping * phi;
        per_state
            .columns_mut(m, m)
            .zip_apply(&velocity, |x, p| *x -= p);
        let per_input = &t.mass * phi * accel_inputs - self.force_input;
        let pinv = (g * g.transpose())
            .pseudo_inverse(1e-12)
            .expect("non-negative tolerance")
            * g;
        let mu_states = &pinv * per_state;
        let mu_inputs = &pinv * per_input;
        for (r, &bar) in t.constraint_bars.iter().enumerate() {
            let scale = 2.0 * self.model.bars[bar].length;
            c.row_mut(bar).copy_from(&(mu_states.row(r) * scale));
            d.row_mut(bar).copy_from(&(mu_inputs.row(r) * scale));
        }
        (c, d)
    }
}

/// Central differences of an output along each state and input direction.
fn differenced_row(sim: &Simulation, ctx: &Context, quantity: Quantity) -> Row {
    let (m, nu) = (ctx.m(), ctx.kinds.len());
    let y0 = &sim.state().y;
    let n = y0.len() / 2;
    let mut probe = sim.clone();
    let mut value = |y: &[f64], inputs: &Inputs| {
        probe.inputs.copy_from(inputs);
        probe.set_state(State {
            time: sim.time(),
            y: y.to_vec(),
        });
        probe.refresh();
        quantity.value(&probe)
    };
    let eps = 1e-6;
    let mut c = DVector::zeros(2 * m);
    for k in 0..2 * m {
        let (offset, mode) = if k < m { (0, k) } else { (n, k - m) };
        let mut plus = y0.clone();
        let mut minus = y0.clone();
        for i in 0..n {
            plus[offset + i] += eps * ctx.phi[(i, mode)];
            minus[offset + i] -= eps * ctx.phi[(i, mode)];
        }
        c[k] = (value(&plus, ctx.inputs) - value(&minus, ctx.inputs)) / (2.0 * eps);
    }
    let mut d = DVector::zeros(nu);
    for (col, &channel) in ctx.kinds.iter().enumerate() {
        let u0 = input_value(ctx.inputs, channel);
        let h = eps * u0.abs().max(1.0);
        let mut plus = ctx.inputs.clone();
        set_input(&mut plus, channel, u0 + h);
        let mut minus = ctx.inputs.clone();
        set_input(&mut minus, channel, u0 - h);
        d[col] = (value(y0, &plus) - value(y0, &minus)) / (2.0 * h);
    }
    (c, d)
}
