//! A run's work, announced before it starts: refused past [`MAX_STEPS`] internal steps
//! without `--force`, naming what sets the time scale and the remedies, and timed so that
//! a long run gets a progress bar ([`super::progress`]).

use std::time::Duration;

use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::sim::{fixed_steps, Pace, Work};
use tensegrity_fmu::Simulation;

/// Most internal steps a run takes without `--force`.
pub const MAX_STEPS: f64 = 1e7;

/// Most wall time spent measuring the cost of a step before a run.
const PROBE: Duration = Duration::from_millis(20);
/// Most steps measured.
const PROBE_STEPS: u32 = 50;

/// A run's predicted work and wall time.
pub struct Prediction {
    /// Steps, what holds them and why.
    pub work: Work,
    /// Wall time, s (`None` when a probe step failed).
    pub seconds: Option<f64>,
}

/// The work of a run from now to `stop` with a row every `interval`; past [`MAX_STEPS`]
/// without `force`, the refusal (`refused` starts it, e.g. "simulate refused, no CSV written").
pub fn predict(
    sim: &mut Simulation,
    stop: f64,
    interval: f64,
    force: bool,
    refused: &str,
) -> Result<Prediction, String> {
    let work = sim.predict_work(stop, interval);
    let seconds = sim
        .seconds_per_step(work.step, PROBE_STEPS, PROBE)
        .map(|s| s * work.steps);
    if work.steps > MAX_STEPS && !force {
        return Err(format!(
            "{refused}: {}",
            refusal(sim, &work, seconds, stop, interval)
        ));
    }
    Ok(Prediction { work, seconds })
}

/// "this run would take about N internal steps (…), more than 1e7: <why>. Use <remedies>".
fn refusal(
    sim: &Simulation,
    work: &Work,
    seconds: Option<f64>,
    stop: f64,
    interval: f64,
) -> String {
    let (model, inputs) = (sim.model(), &sim.inputs);
    let solver = &model.solver;
    let method = solver.method.name();
    let about = seconds.map_or(String::new(), |s| format!(", about {}", duration(s)));
    let head = format!(
        "this run would take about {:.2e} internal steps{about}, more than {MAX_STEPS:.0e}",
        work.steps
    );
    let named = |why: &str| {
        work.rate.as_ref().map_or(String::new(), |r| {
            format!("{why}{}", r.describe(model, inputs))
        })
    };
    let h = solver.step_size;
    if work.pace == Pace::Fixed {
        return format!(
            "{head}: {method} takes fixed steps of solver.step_size = {h} s{}. Use a larger \
             --step-size or a shorter --time, or pass --force to run it anyway",
            named("; the fastest time scale here is set by ")
        );
    }
    if work.pace == Pace::Rows {
        return format!(
            "{head}: each row (every --interval {interval} s) ends an internal step. Use a \
             larger --interval or a shorter --time, or pass --force to run it anyway"
        );
    }
    let why = match work.pace {
        Pace::Stability => "at its stability bound for ",
        _ => "to follow the motion set by ",
    };
    let softer = work.rate.as_ref().and_then(|r| {
        // The steps grow with the rate: aim 10 % inside the limit.
        r.fix(model, inputs, 0.9 * r.omega * MAX_STEPS / work.steps)
    });
    let softer = softer.map_or("a softer element".to_string(), |fix| {
        format!("a softer element ({fix})")
    });
    let sdirk = fixed_steps((stop - sim.time()).max(0.0), interval, h);
    format!(
        "{head}: {method} shortens its step to about {:.2e} s {}. Use solver.method = \
         \"{}\" (implicit, stable at any stiffness: fixed steps of solver.step_size = {h} s, \
         {sdirk:.0} in all; it damps what is faster than the step), {softer}, or pass --force \
         to run it anyway",
        work.step,
        named(why),
        Method::Sdirk3.name(),
    )
}

/// "0.012 s", "3.2 s", "4.1 min", "2.5 h", "3.1 days".
pub fn duration(seconds: f64) -> String {
    match seconds {
        s if s < 1.0 => format!("{s:.3} s"),
        s if s < 120.0 => format!("{s:.1} s"),
        s if s < 7200.0 => format!("{:.1} min", s / 60.0),
        s if s < 172_800.0 => format!("{:.1} h", s / 3600.0),
        s => format!("{:.1e} days", s / 86_400.0),
    }
}
