//! Locating the friction grips' switches. Their functions depend on the velocities, which
//! the cubic through positions and velocities gives only to O(h³): a crossing located on
//! it would cost an explicit fourth-order method an order. So where a grip's sign changed,
//! the caller evaluates the accelerations at both ends of the step and the crossing is
//! found on the quintic through positions, velocities and accelerations (velocities to
//! O(h⁵)).

use nalgebra::Vector3;

use super::super::grip::{self, Cut, GripSwitch};
use super::super::locate::crossing;
use super::{Events, CUT_TIE, EDGE, GRIP_START};
use crate::contact::Grip;
use crate::dynamics::Inputs;
use crate::model::Model;

impl Events {
    /// The grips' signs at the start of a step from the state with velocities `qd`: those
    /// of the last step's end when that is this state (`at_end`) with the same grips.
    pub(super) fn start_grips(&mut self, model: &Model, inputs: &Inputs, qd: &[f64], at_end: bool) {
        if !super::holding(inputs) {
            self.grip0.fill(true);
        } else if at_end && self.grips1 == inputs.grip {
            std::mem::swap(&mut self.grip0, &mut self.grip1);
            std::mem::swap(&mut self.v0, &mut self.v1);
        } else {
            self.grip_velocities(model, inputs, qd, false);
            let mut signs = std::mem::take(&mut self.grip0);
            self.grip_signs(inputs, &self.x0, &self.v0, &mut signs);
            self.grip0 = signs;
        }
    }

    /// The velocities of the ends that a grip holds, from the reduced velocities `qd`, into
    /// the step's end (`end`) or start: the only ones the grips' switches read.
    pub(super) fn grip_velocities(
        &mut self,
        model: &Model,
        inputs: &Inputs,
        qd: &[f64],
        end: bool,
    ) {
        let v = if end { &mut self.v1 } else { &mut self.v0 };
        for s in &self.grips {
            if inputs.grip[s.slot] != Grip::Free {
                v[s.end] = model.coords.end_vector(s.end, qd, false);
            }
        }
    }

    /// Whether the last [`Events::locate`] saw a grip's sign change; then
    /// [`Events::locate_grips`] finishes it, with the accelerations.
    pub(in crate::sim) fn grips_changed(&self) -> bool {
        self.grips_changed
    }

    /// The state at the start of the step just located, and buffers for the reduced
    /// accelerations at its start and end.
    pub(in crate::sim) fn acceleration_buffers(&mut self) -> (&[f64], &mut [f64], &mut [f64]) {
        (&self.y0, &mut self.acc0, &mut self.acc1)
    }

    /// The crossings of the grips whose signs changed over a step of `h`, on the quintic,
    /// merged with `earliest` (the other switches' earliest crossing): the earliest of all,
    /// with the cuts noted.
    pub(in crate::sim) fn locate_grips(
        &mut self,
        model: &Model,
        inputs: &Inputs,
        h: f64,
        mut earliest: Option<f64>,
    ) -> Option<f64> {
        for s in &self.grips {
            self.a0[s.end] = model.coords.end_vector(s.end, &self.acc0, false);
            self.a1[s.end] = model.coords.end_vector(s.end, &self.acc1, false);
        }
        let hi = (1.0 - EDGE) * h;
        for (j, s) in self.grips.iter().enumerate() {
            if !self.grip0[j] || self.grip1[j] {
                continue;
            }
            let g = |theta: f64| self.grip_along(s, inputs, theta, h);
            let theta = crossing(g, g(0.0), g(h), h).max(GRIP_START * h);
            self.crossed.push((Cut::Grip(j), theta));
            if theta < hi && earliest.is_none_or(|e| theta < e) {
                earliest = Some(theta);
            }
        }
        self.note_cuts(earliest, h);
        earliest
    }

    /// Notes the switches crossed by the earliest crossing (ties to round-off with it).
    pub(super) fn note_cuts(&mut self, earliest: Option<f64>, h: f64) {
        if let Some(at) = earliest {
            let by = at + CUT_TIE * h;
            let cuts = self.crossed.iter().filter(|c| c.1 <= by).map(|c| c.0);
            self.cuts.extend(cuts);
        }
    }

    /// Each grip's sign at the ends' positions `x` and velocities `v` (where the far marks
    /// hold).
    pub(super) fn grip_signs(
        &self,
        inputs: &Inputs,
        x: &[Vector3<f64>],
        v: &[Vector3<f64>],
        out: &mut [bool],
    ) {
        let Some(terrain) = &self.terrain else {
            return;
        };
        // A free grip's switch is positive, and only a grip near its shape can hold.
        out.fill(true);
        for &j in &self.near_grips {
            let s = &self.grips[j];
            out[j] = grip::value(s, terrain, &inputs.grip, &x[s.end], &v[s.end]) > 0.0;
        }
    }

    /// A grip's switch at time `theta` into the step, on the quintic Hermite through the
    /// end's position, velocity and acceleration at both ends, and its derivative.
    fn grip_along(&self, s: &GripSwitch, inputs: &Inputs, theta: f64, h: f64) -> f64 {
        let Some(terrain) = &self.terrain else {
            return f64::MAX;
        };
        let e = s.end;
        let (x0, v0, a0) = (self.x0[e], self.v0[e], self.a0[e]);
        let (x1, v1, a1) = (self.x1[e], self.v1[e], self.a1[e]);
        let u = theta / h;
        let (u2, u3, u4, u5) = (u * u, u * u * u, u * u * u * u, u * u * u * u * u);
        let w = [
            1.0 - 10.0 * u3 + 15.0 * u4 - 6.0 * u5,
            h * (u - 6.0 * u3 + 8.0 * u4 - 3.0 * u5),
            h * h * 0.5 * (u2 - 3.0 * u3 + 3.0 * u4 - u5),
            h * h * 0.5 * (u3 - 2.0 * u4 + u5),
            h * (-4.0 * u3 + 7.0 * u4 - 3.0 * u5),
            10.0 * u3 - 15.0 * u4 + 6.0 * u5,
        ];
        let dw = [
            (-30.0 * u2 + 60.0 * u3 - 30.0 * u4) / h,
            1.0 - 18.0 * u2 + 32.0 * u3 - 15.0 * u4,
            h * (u - 4.5 * u2 + 6.0 * u3 - 2.5 * u4),
            h * (1.5 * u2 - 4.0 * u3 + 2.5 * u4),
            -12.0 * u2 + 28.0 * u3 - 15.0 * u4,
            (30.0 * u2 - 60.0 * u3 + 30.0 * u4) / h,
        ];
        let at =
            |w: &[f64; 6]| w[0] * x0 + w[1] * v0 + w[2] * a0 + w[3] * a1 + w[4] * v1 + w[5] * x1;
        grip::value(s, terrain, &inputs.grip, &at(&w), &at(&dw))
    }
}
