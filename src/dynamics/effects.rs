//! Stage 2 of an evaluation: the forces of the effects a scene declares, as listed once in
//! the model's [`Pipeline`]. An effect the scene does not declare is not in it, so the step
//! never tests for it.

use nalgebra::Vector3;

use super::collisions::CollisionScratch;
use super::terrain::{ShapeLoad, TerrainSink};
use super::{Inputs, Workspace};
use crate::contact::Proximity;
pub use crate::model::effects::{CableLink, ConstraintEffect, ForceEffect, Pipeline, Target};
use crate::model::Model;

/// Stage 2: every declared force on the bar ends at time `t`.
#[inline(always)]
pub fn applied_forces(model: &Model, inputs: &Inputs, t: f64, ws: &mut Workspace) {
    ws.end_force.iter_mut().for_each(|f| *f = Vector3::zeros());
    let mut sink = Slices {
        end_force: &mut ws.end_force,
        gamma: &mut ws.gamma,
        contact_force: &mut ws.contact_force,
        shape_load: &mut ws.shape_load,
        collision: &mut ws.collision,
        terrain_near: &mut ws.terrain_near,
    };
    let nodes = (ws.node_pos.as_slice(), ws.node_vel.as_slice());
    apply(&model.pipeline.forces, inputs, t, nodes, &mut sink);
}

/// Where the forces go: the end forces, the cables' force densities and the contact
/// forces (all of them, or one thread's part).
pub(super) trait ForceSink {
    /// Adds `f` to end `end`'s force.
    fn add(&mut self, end: usize, f: Vector3<f64>);
    /// Records cable `cable`'s force density.
    fn gamma(&mut self, cable: usize, gamma: f64);
    /// Records the force of contact point `k`.
    fn contact(&mut self, k: usize, f: Vector3<f64>);
    /// The terrain shapes' loads, to fill.
    fn shape_loads(&mut self) -> &mut [ShapeLoad];
    /// The broad phase's buffers and the collisions found.
    fn collision(&mut self) -> &mut CollisionScratch;
    /// The terrain contacts too far to touch soon.
    fn terrain_near(&mut self) -> &mut Proximity;
}

/// The whole of each output.
pub(super) struct Slices<'a> {
    pub end_force: &'a mut [Vector3<f64>],
    pub gamma: &'a mut [f64],
    pub contact_force: &'a mut [Vector3<f64>],
    pub shape_load: &'a mut [ShapeLoad],
    pub collision: &'a mut CollisionScratch,
    pub terrain_near: &'a mut Proximity,
}

impl ForceSink for Slices<'_> {
    #[inline(always)]
    fn add(&mut self, end: usize, f: Vector3<f64>) {
        self.end_force[end] += f;
    }
    #[inline(always)]
    fn gamma(&mut self, cable: usize, gamma: f64) {
        self.gamma[cable] = gamma;
    }
    #[inline(always)]
    fn contact(&mut self, k: usize, f: Vector3<f64>) {
        self.contact_force[k] = f;
    }
    fn shape_loads(&mut self) -> &mut [ShapeLoad] {
        self.shape_load
    }
    fn collision(&mut self) -> &mut CollisionScratch {
        self.collision
    }
    fn terrain_near(&mut self) -> &mut Proximity {
        self.terrain_near
    }
}

/// Terrain forces into a [`ForceSink`] (which keeps the shapes' loads).
struct IntoSink<'s, S>(&'s mut S);

impl<S: ForceSink> TerrainSink for IntoSink<'_, S> {
    #[inline(always)]
    fn add(&mut self, end: usize, f: Vector3<f64>) {
        self.0.add(end, f);
    }
    #[inline(always)]
    fn shape(&mut self, shape: usize, f: Vector3<f64>) {
        let load = &mut self.0.shape_loads()[shape];
        load.force += f;
        load.contacts += 1;
    }
}

/// Adds the forces of `effects` for the node positions and velocities `(x, ẋ)` to `sink`.
#[inline(always)]
pub(super) fn apply(
    effects: &[ForceEffect],
    inputs: &Inputs,
    t: f64,
    nodes: (&[Vector3<f64>], &[Vector3<f64>]),
    sink: &mut impl ForceSink,
) {
    for effect in effects {
        match effect {
            ForceEffect::ElasticCables(cables) => elastic_cables(cables, nodes.0, sink),
            ForceEffect::DampedCables(cables) => {
                for (link, stiffness, rest, c) in cables {
                    let (s, s_dot) = (extension(link, nodes.0), extension(link, nodes.1));
                    let gamma = damped_density(*stiffness, *rest, *c, &s, &s_dot);
                    pull(link, sink, s, gamma);
                }
            }
            ForceEffect::ForceDensityCables(cables) => {
                for (link, input) in cables {
                    let gamma = inputs.force_density[*input].max(0.0);
                    pull(link, sink, extension(link, nodes.0), gamma);
                }
            }
            ForceEffect::ReeledCables(cables) => {
                for (link, stiffness, c, input) in cables {
                    let rest = inputs.rest_length[*input].max(0.0);
                    let (s, s_dot) = (extension(link, nodes.0), extension(link, nodes.1));
                    pull(
                        link,
                        sink,
                        s,
                        damped_density(*stiffness, rest, *c, &s, &s_dot),
                    );
                }
            }
            ForceEffect::NodeForces(targets) => {
                for &(k, end) in targets {
                    add(sink, end, inputs.node_force[k]);
                }
            }
            ForceEffect::ScriptedLoads(loads) => {
                for (end, law) in loads {
                    add(sink, *end, Vector3::from(law.force_at(t)));
                }
            }
            ForceEffect::Gravity(weights) => {
                for &(e, w) in weights {
                    sink.add(e, w);
                }
            }
            ForceEffect::GroundContact(ground) => {
                for (k, (&(n, e), &r)) in ground.nodes.iter().zip(&ground.radii).enumerate() {
                    let f = ground.force(&nodes.0[n], &nodes.1[n], r);
                    sink.contact(k, f);
                    sink.add(e, f);
                }
            }
            ForceEffect::Terrain(terrain) => {
                sink.shape_loads().fill(ShapeLoad::default());
                // The marks are taken out while the sink receives the forces.
                let mut near = std::mem::take(sink.terrain_near());
                super::terrain::mark_far(terrain, nodes.0, &mut near);
                let grips = &inputs.grip;
                super::terrain::apply(terrain, grips, &near, nodes, &mut IntoSink(sink));
                *sink.terrain_near() = near;
            }
            ForceEffect::Collisions(collisions) => {
                // The scratch is taken out while the sink receives the forces.
                let mut scratch = std::mem::take(sink.collision());
                super::collisions::apply(collisions, nodes, &mut scratch, |e, f| sink.add(e, f));
                *sink.collision() = scratch;
            }
        }
    }
}

/// Elastic cables two at a time: their lengths and the ratios `s₀/|s|` in one SIMD square
/// root and one division for the two, then their densities and pulls, in order. Each is the
/// arithmetic of `taut_density(κ, s₀, |s|)`, with `|s|² = (s_x² + s_y²) + s_z²` as nalgebra
/// sums it (square root and division are correctly rounded in either form), so the same
/// bits.
#[inline(always)]
fn elastic_cables(cables: &[(CableLink, f64, f64)], x: &[Vector3<f64>], sink: &mut impl ForceSink) {
    let (pairs, rest) = cables.as_chunks::<2>();
    for pair in pairs {
        // Written out, not with `[T; 2]::map`: whether its calls are inlined depends on how
        // many there are (with damped cables also taken in pairs through it, five calls
        // stayed out of line in the evaluation, and a step took 1.3× as long).
        let s = [extension(&pair[0].0, x), extension(&pair[1].0, x)];
        let l2 = [length_squared(&s[0]), length_squared(&s[1])];
        let (len, ratio) = lengths_and_ratios(l2, [pair[0].2, pair[1].2]);
        for k in 0..2 {
            let (link, stiffness, rest_length) = &pair[k];
            let gamma = if len[k] <= *rest_length {
                0.0
            } else {
                stiffness * (1.0 - ratio[k])
            };
            pull(link, sink, s[k], gamma);
        }
    }
    for (link, stiffness, rest) in rest {
        let s = extension(link, x);
        pull(link, sink, s, taut_density(*stiffness, *rest, s.norm()));
    }
}

/// `|s|²` as nalgebra's `norm_squared` sums it (`0 + ((x² + y²) + z²)`, and adding 0 to
/// a sum of squares changes nothing).
#[inline(always)]
fn length_squared(s: &Vector3<f64>) -> f64 {
    s.x * s.x + s.y * s.y + s.z * s.z
}

/// `(√l², s₀/√l²)` for two cables.
#[inline(always)]
fn lengths_and_ratios(l2: [f64; 2], rest: [f64; 2]) -> ([f64; 2], [f64; 2]) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_div_pd, _mm_loadu_pd, _mm_sqrt_pd, _mm_storeu_pd};
        let (mut len, mut ratio) = ([0.0; 2], [0.0; 2]);
        // SAFETY: SSE2 is part of x86-64; the pointers are to two f64 each.
        unsafe {
            let l = _mm_sqrt_pd(_mm_loadu_pd(l2.as_ptr()));
            _mm_storeu_pd(len.as_mut_ptr(), l);
            _mm_storeu_pd(
                ratio.as_mut_ptr(),
                _mm_div_pd(_mm_loadu_pd(rest.as_ptr()), l),
            );
        }
        (len, ratio)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let len = [l2[0].sqrt(), l2[1].sqrt()];
        (len, [rest[0] / len[0], rest[1] / len[1]])
    }
}

#[inline(always)]
fn add(sink: &mut impl ForceSink, end: Target, f: Vector3<f64>) {
    if let Some(e) = end {
        sink.add(e, f);
    }
}

/// A cable's `x_b − x_a` of node vectors `x` (positions for `s`, velocities for `ṡ`).
#[inline(always)]
fn extension(link: &CableLink, x: &[Vector3<f64>]) -> Vector3<f64> {
    let [a, b] = link.nodes;
    x[b] - x[a]
}

/// Applies `γ s` to a cable's ends and records `γ`.
#[inline(always)]
fn pull(link: &CableLink, sink: &mut impl ForceSink, s: Vector3<f64>, gamma: f64) {
    sink.gamma(link.cable, gamma);
    add(sink, link.ends[0], s * gamma);
    add(sink, link.ends[1], -s * gamma);
}

/// `κ (1 − s₀/|s|)` while taut, else 0.
#[inline(always)]
pub fn taut_density(stiffness: f64, rest_length: f64, len: f64) -> f64 {
    if len <= rest_length {
        0.0
    } else {
        stiffness * (1.0 - rest_length / len)
    }
}

/// `κ (1 − s₀/|s|) + c (s·ṡ)/|s|²` while taut, else 0; clamped at ≥ 0 (a cable only pulls).
#[inline(always)]
pub fn damped_density(
    stiffness: f64,
    rest_length: f64,
    damping: f64,
    s: &Vector3<f64>,
    s_dot: &Vector3<f64>,
) -> f64 {
    let l2 = s.norm_squared();
    let len = l2.sqrt();
    if len <= rest_length {
        return 0.0;
    }
    (stiffness * (1.0 - rest_length / len) + damping * s.dot(s_dot) / l2).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Elastic cables taken in pairs give each cable's density and end forces as one cable
    /// at a time computes them (`taut_density` of `|s|` from nalgebra), bit for bit: taut
    /// and slack cables, one exactly at its rest length, one between coincident nodes, a
    /// node pulled by four cables (so the order of the pulls shows), and an odd count (the
    /// last one alone).
    #[test]
    fn cables_in_pairs_give_the_bits_of_one_at_a_time() {
        let mut x: Vec<Vector3<f64>> = (0..8)
            .map(|i| {
                let f = i as f64;
                Vector3::new((0.7 * f).sin(), 0.3 * f, (1.3 * f).cos() / 3.0)
            })
            .collect();
        x[7] = x[6];
        let nodes = [
            (0, 1),
            (0, 2),
            (0, 3),
            (1, 4),
            (2, 5),
            (6, 7),
            (3, 5),
            (4, 0),
            (5, 6),
        ];
        let (slack, exact, coincident) = ([0, 3, 8], 7, 5);
        let cables: Vec<(CableLink, f64, f64)> = (0..nodes.len())
            .map(|j| {
                let (a, b) = nodes[j];
                let link = CableLink {
                    cable: j,
                    nodes: [a, b],
                    ends: [Some(a), Some(b)],
                };
                let length = (x[b] - x[a]).norm();
                let rest = if slack.contains(&j) {
                    1.1 * length
                } else if j == exact {
                    length
                } else {
                    length / (1.0 + 0.01 * j as f64)
                };
                (link, 100.0 + 17.0 * j as f64, rest)
            })
            .collect();
        let (mut end_force, mut gamma) = (vec![Vector3::zeros(); 8], vec![f64::NAN; 9]);
        let mut sink = Slices {
            end_force: &mut end_force,
            gamma: &mut gamma,
            contact_force: &mut [],
            shape_load: &mut [],
            collision: &mut CollisionScratch::default(),
            terrain_near: &mut Proximity::default(),
        };
        elastic_cables(&cables, &x, &mut sink);

        let mut expected_force = vec![Vector3::<f64>::zeros(); 8];
        for (j, (link, stiffness, rest)) in cables.iter().enumerate() {
            let s = x[link.nodes[1]] - x[link.nodes[0]];
            let expected = taut_density(*stiffness, *rest, s.norm());
            assert_eq!(gamma[j].to_bits(), expected.to_bits(), "cable {j}");
            let taut = !(slack.contains(&j) || j == exact || j == coincident);
            assert_eq!(expected > 0.0, taut, "cable {j} taut, or slack");
            expected_force[link.nodes[0]] += s * expected;
            expected_force[link.nodes[1]] += -s * expected;
        }
        for (f, e) in end_force.iter().zip(&expected_force) {
            assert_eq!(f.map(f64::to_bits), e.map(f64::to_bits));
        }
    }
}
