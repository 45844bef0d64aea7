//! Time integration of `ẏ = f(t, y)` behind one pluggable step interface. The correction
//! runs after each step, outside the integrator.

mod rk4;

pub use rk4::Rk4;

/// A right-hand side `f(t, y)`.
pub trait Rhs {
    /// Writes `f(t, y)` into `dy`.
    fn eval(&mut self, t: f64, y: &[f64], dy: &mut [f64]);
}

/// One step of a one-step method; buffers are owned by the integrator and sized once.
pub trait Integrator: Send {
    /// Advances `y` from `t` to `t + h` in place.
    fn step(&mut self, rhs: &mut dyn Rhs, t: f64, y: &mut [f64], h: f64);
    /// Short name, as used in reports.
    fn name(&self) -> &'static str;
    /// Right-hand-side evaluations so far.
    fn rhs_evaluations(&self) -> u64;
    /// A boxed copy (for FMU state snapshots).
    fn boxed_clone(&self) -> Box<dyn Integrator>;
}
