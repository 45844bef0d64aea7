//! Mode-shape animations: instead of a simulated run, [`Frames`] of one mode of the scene's
//! start equilibrium `x*` (see [`crate::analysis::modes`]) moving as
//! `x(t) = x* + A·φ·s(t)`, with `φ` the mode shape scaled so its largest node displacement
//! is 1 m and `A` the amplitude in m.
//!
//! A vibration takes `s(t) = sin(2π f t)` over one period `1/f`. A zero-frequency mode
//! (rigid-body motion or mechanism) and an unstable direction have no period: they move
//! linearly there and back over a fixed [`STILL_LOOP`] (`s` a triangle wave from 0 up to 1,
//! down to −1 and back to 0). Either way the frames split the loop into `n` equal steps,
//! `n` the multiple of 4 nearest `period × fps` (at least [`MIN_FRAMES`]), so the loop
//! closes without a jump and the peaks `x* ± A φ` fall on frames `n/4` and `3n/4`.
//!
//! The linear motion `x* + A φ s` keeps the bar lengths to first order in `A` only (on
//! prism2-elastic, bars 1.1 m long stretch 3 cm at `A` = 0.2 m), and the cables stretched
//! with them would show tensions that are not the mode's (the top ring of its torsion
//! mode 1 at 16 N above the equilibrium instead of 2 N). So every frame then restores the
//! bar lengths as the simulation does after a step (each bar moved along itself, see
//! [`crate::correction`]): the positions drawn are `x* + A φ s` to first order, off by
//! about `A²/l`, with rigid bars.
//!
//! Cable tensions and bar forces are those of each frame's geometry: the model evaluated
//! at that position at rest, with the start inputs (no damping force from the motion).
//! Node velocities are those of the linear motion, `A φ ds/dt`.

use std::f64::consts::PI;

use super::Frames;
use crate::analysis::modes::{Mode, ModeKind, Spectrum};
use crate::scene::Scene;
use crate::sim::{Simulation, State};

/// Loop of a mode without a frequency (rigid-body, mechanism, unstable), s.
pub const STILL_LOOP: f64 = 2.0;
/// Default amplitude as a fraction of the structure's largest extent.
pub const AMPLITUDE_FRACTION: f64 = 0.1;
/// Fewest frames of one loop (a mode too fast for `fps` is drawn in slow motion).
pub const MIN_FRAMES: usize = 8;
/// Most frames of one loop.
pub const MAX_FRAMES: usize = 10_000;

/// One mode, animated.
#[derive(Debug, Clone)]
pub struct ModeAnimation {
    /// The frames of one loop; the name is the scene's with the mode and its frequency.
    pub frames: Frames,
    /// Index of the frame at the peak `x* + A φ` (a quarter of the loop).
    pub peak: usize,
    /// Length of the loop, s: the period, or [`STILL_LOOP`].
    pub period: f64,
    /// Largest node displacement, m.
    pub amplitude: f64,
    /// The mode.
    pub mode: Mode,
    /// "mode 3, 1.27 Hz" (or "mode 1, 0 Hz (rigid-body)", "mode 1, unstable (…)").
    pub title: String,
}

/// Animates mode `number` (1-based, as `tensegrity-fmu modes` lists them) of `scene`'s start
/// state with largest displacement `amplitude` m (default [`AMPLITUDE_FRACTION`] of the
/// structure's size), `fps` frames per second. Refuses a start that is not at rest and a
/// number out of range, naming `--mode`.
pub fn animate(
    scene: &Scene,
    number: i64,
    amplitude: Option<f64>,
    fps: f64,
) -> Result<ModeAnimation, String> {
    if !(fps > 0.0 && fps.is_finite()) {
        return Err(format!(
            "--fps must be above 0 (got {fps}); pass e.g. --fps 10"
        ));
    }
    let model = crate::analysis::load(scene).map_err(|e| e.to_string())?;
    let mut sim = Simulation::new(model);
    crate::analysis::require_rest(&sim, &format!("--mode {number}"))
        .map_err(|e| format!("{e}; or drop --mode to draw the simulated run"))?;
    let start = sim.state().clone();
    let (q, _) = start.y.split_at(start.y.len() / 2);
    let spectrum = Spectrum::new(sim.model(), &sim.inputs, start.time, q);
    let count = spectrum.modes.len();
    let mode = match usize::try_from(number) {
        Ok(k) if (1..=count).contains(&k) => spectrum.modes[k - 1].clone(),
        _ if count == 0 => {
            return Err(format!(
                "--mode {number}: {} has no modes (nothing in it can move); drop --mode",
                scene.name
            ))
        }
        _ => {
            return Err(format!(
                "--mode {number}: {} has {count} modes, numbered 1 to {count} \
                 (`tensegrity-fmu modes SCENE` lists them); pass --mode between 1 and {count}",
                scene.name
            ))
        }
    };
    let x_star: Vec<[f64; 3]> = (0..sim.model().n_nodes())
        .map(|i| sim.node_position(i).into())
        .collect();
    let amplitude = match amplitude {
        Some(a) if a > 0.0 && a.is_finite() => a,
        Some(a) => {
            return Err(format!(
                "--amplitude must be above 0 m and finite (got {a}); pass e.g. --amplitude {:.3}",
                default_amplitude(&x_star)
            ))
        }
        None => default_amplitude(&x_star),
    };
    let period = match mode.kind {
        ModeKind::Vibration => 1.0 / mode.frequency_hz(),
        _ => STILL_LOOP,
    };
    let n = frame_count(period, fps).ok_or_else(|| {
        format!(
            "--mode {number}: one period of {period:.4} s at --fps {fps} is more than \
             {MAX_FRAMES} frames; lower --fps"
        )
    })?;
    let title = format!("mode {number}, {}", describe(&mode));
    let mut frames = Frames::topology(sim.model());
    frames.name = format!("{} — {title}", scene.name);
    for k in 0..n {
        let u = k as f64 / n as f64;
        let (s, ds) = motion(mode.kind, u);
        let mut y = start.y.clone();
        for (qi, d) in y.iter_mut().zip(mode.reduced.iter()) {
            *qi += amplitude * s * d;
        }
        let (q, v) = y.split_at_mut(start.y.len() / 2);
        v.fill(0.0);
        let model = sim.model();
        model.correction.correct_positions(&model.coords, q);
        sim.set_state(State {
            time: start.time,
            y,
        });
        frames.push_state(&sim, u * period);
        let rate = amplitude * ds / period;
        if let Some(last) = frames.velocities.last_mut() {
            for (v, phi) in last.iter_mut().zip(&mode.shape) {
                *v = (phi * rate).into();
            }
        }
    }
    Ok(ModeAnimation {
        frames,
        peak: n / 4,
        period,
        amplitude,
        mode,
        title,
    })
}

/// Frames of one loop of `period` s at `fps`: the multiple of 4 nearest `period × fps`,
/// at least [`MIN_FRAMES`]; `None` above [`MAX_FRAMES`].
pub fn frame_count(period: f64, fps: f64) -> Option<usize> {
    let quarters = (period * fps / 4.0).round();
    if !(quarters.is_finite() && quarters <= (MAX_FRAMES / 4) as f64) {
        return None;
    }
    Some((4 * quarters as usize).max(MIN_FRAMES))
}

/// `s` and `ds/du` at phase `u` (fraction of the loop): a sine for a vibration, else a
/// triangle wave through the same points 0, 1, 0, −1 at the quarters.
pub fn motion(kind: ModeKind, u: f64) -> (f64, f64) {
    match kind {
        ModeKind::Vibration => ((2.0 * PI * u).sin(), 2.0 * PI * (2.0 * PI * u).cos()),
        _ if u <= 0.25 => (4.0 * u, 4.0),
        _ if u <= 0.75 => (2.0 - 4.0 * u, -4.0),
        _ => (4.0 * u - 4.0, 4.0),
    }
}

/// "1.27 Hz", "0 Hz (rigid-body)", "unstable (grows at 2.1 1/s)".
fn describe(mode: &Mode) -> String {
    match mode.kind {
        ModeKind::Vibration => format!("{} Hz", significant(mode.frequency_hz())),
        ModeKind::Unstable => format!(
            "unstable (grows at {} 1/s)",
            significant(mode.growth_rate())
        ),
        kind => format!("0 Hz ({})", kind.name()),
    }
}

/// `x` to 3 significant digits (0.869, 1.27, 12.3, 123).
fn significant(x: f64) -> String {
    let digits = if x > 0.0 {
        (2.0 - x.log10().floor()).clamp(0.0, 12.0) as usize
    } else {
        0
    };
    format!("{x:.digits$}")
}

/// [`AMPLITUDE_FRACTION`] of the largest side of the nodes' bounding box (0.1 m if none).
fn default_amplitude(x: &[[f64; 3]]) -> f64 {
    let extent = (0..3)
        .map(|axis| {
            let (lo, hi) = x
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                    (lo.min(p[axis]), hi.max(p[axis]))
                });
            hi - lo
        })
        .fold(0.0, f64::max);
    if extent > 0.0 {
        AMPLITUDE_FRACTION * extent
    } else {
        0.1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_a_multiple_of_four_near_period_times_fps() {
        assert_eq!(frame_count(1.0 / 0.8694, 10.0), Some(12));
        assert_eq!(frame_count(2.0, 10.0), Some(20));
        assert_eq!(frame_count(0.1, 10.0), Some(MIN_FRAMES));
        assert_eq!(frame_count(1e6, 10.0), None);
    }

    #[test]
    fn motions_pass_the_quarters() {
        for kind in [ModeKind::Vibration, ModeKind::RigidBody] {
            let s: Vec<f64> = [0.0, 0.25, 0.5, 0.75].map(|u| motion(kind, u).0).into();
            let expected = [0.0, 1.0, 0.0, -1.0];
            assert!(
                s.iter().zip(expected).all(|(a, b)| (a - b).abs() < 1e-15),
                "{s:?}"
            );
        }
        assert_eq!(motion(ModeKind::Mechanism, 0.125), (0.5, 4.0));
    }

    #[test]
    fn frequencies_keep_three_digits() {
        assert_eq!(significant(1.273028), "1.27");
        assert_eq!(significant(0.869404), "0.869");
        assert_eq!(significant(0.013879), "0.0139");
        assert_eq!(significant(12.34), "12.3");
        assert_eq!(significant(0.0), "0");
    }
}
