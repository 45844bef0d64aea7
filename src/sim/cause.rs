//! What sets the fastest rate the stability guard sees, named as scene keys, with the
//! change of that key that would bring the rate under a target.
//!
//! The power iteration's mode is attributed by splitting the second variation of the
//! potential along the mode's node displacements `δx` into the cables' terms
//! `δs·∂(γ s)/∂s·δs` and the penalty terms `k (n·δx)²` of contacts pressed at rest: the
//! largest terms name the cables (or the ground) that make the mode stiff. The contact
//! bounds (penalty oscillator, viscous friction) name themselves.

use nalgebra::Vector3;

use crate::dynamics::{self, Inputs, Workspace};
use crate::model::{CableLaw, Model};
use crate::scene::LoadSpec;

pub use super::contact_rates::contact_rates;
use super::contact_rates::{
    collision_compliance, contact_compliance, raise_slip, soften_penalty, terrain_compliance,
    terrain_laws, weight,
};
pub use super::rate::{num, Cause, Rate};

/// A cable counts among the mode's stiff ones when its term is at least this fraction of
/// the largest.
const GROUP: f64 = 0.5;
/// Cables named one by one before "and N more".
const NAMED: usize = 3;

/// Names what makes the mode with node displacements `dx` (per node, any scale) stiff, at
/// the positions `x`.
pub fn attribute(model: &Model, inputs: &Inputs, x: &[Vector3<f64>], dx: &[Vector3<f64>]) -> Rate {
    let node = (0..dx.len()).max_by(|&a, &b| dx[a].norm().total_cmp(&dx[b].norm()));
    let zero = Vector3::zeros();
    let cables: Vec<f64> = model
        .cables
        .iter()
        .map(|c| {
            let [a, b] = c.nodes;
            let (s, ds) = (x[b] - x[a], dx[b] - dx[a]);
            let eps = 1e-6 * s.norm() / ds.norm().max(1e-300);
            let f = |s: Vector3<f64>| s * dynamics::cable_force_density(&c.law, inputs, &s, &zero);
            (ds.dot(&(f(s + ds * eps) - f(s - ds * eps))) / (2.0 * eps)).max(0.0)
        })
        .collect();
    let ground: f64 = model.ground.as_ref().map_or(0.0, |g| {
        g.nodes
            .iter()
            .zip(&g.radii)
            .filter(|&(&(n, _), &r)| g.penetration(&x[n], r) > 0.0)
            .map(|(&(n, _), _)| g.stiffness * g.normal.dot(&dx[n]).powi(2))
            .sum()
    });
    let total = cables.iter().sum::<f64>() + ground;
    let largest = cables.iter().copied().fold(0.0, f64::max);
    let cause = if total.is_nan() || total <= 0.0 {
        Cause::Structure
    } else if ground > largest {
        Cause::GroundPenalty
    } else {
        let mut stiff: Vec<usize> = (0..cables.len())
            .filter(|&j| cables[j] >= GROUP * largest)
            .collect();
        stiff.sort_by(|&a, &b| cables[b].total_cmp(&cables[a]));
        let share = stiff.iter().map(|&j| cables[j]).sum::<f64>() / total;
        let family = family(model, inputs, &stiff);
        let family_share = family.iter().map(|&j| cables[j]).sum::<f64>() / total;
        if share >= 0.5 {
            Cause::Cables {
                cables: stiff,
                share,
                family,
                family_share,
            }
        } else {
            Cause::Structure
        }
    };
    Rate {
        omega: 0.0,
        cause,
        node,
    }
}

impl Rate {
    /// What sets the rate, in scene keys, e.g. "ground friction (ground.friction = 0.6, …)".
    pub fn describe(&self, model: &Model, inputs: &Inputs) -> String {
        let at = self.node.map_or(String::new(), |n| node_mass(model, n));
        match &self.cause {
            Cause::Cables { cables, share, .. } => {
                format!(
                "the stiffness of {}, {} {:.0} % of the fastest mode's stiffness (the mode moves \
                 {at} most)",
                cable_list(model, inputs, cables),
                if cables.len() > 1 { "together" } else { "alone" },
                100.0 * share,
            )
            }
            Cause::GroundPenalty => {
                let g = model.ground.as_ref().expect("a ground");
                let w = contact_compliance(model).0;
                format!(
                    "the ground penalty, ground.stiffness = {} N/m with ground.damping = {} N·s/m \
                     (rate √(k w) + c w, with the end compliance w = {} 1/kg of {at})",
                    num(g.stiffness),
                    num(g.damping),
                    num(w)
                )
            }
            Cause::Friction => {
                let g = model.ground.as_ref().expect("a ground");
                let w = contact_compliance(model).0;
                format!(
                    "ground friction, ground.friction = {} with ground.slip_velocity = {} m/s \
                     (below the slip velocity friction is viscous: rate μ W w / slip_velocity, \
                     with the weight W = {} N and the end compliance w = {} 1/kg of {at})",
                    num(g.friction),
                    num(g.slip_velocity),
                    num(weight(model)),
                    num(w)
                )
            }
            Cause::TerrainPenalty(k) => {
                let law = terrain_laws(model).nth(*k).expect("a shape");
                format!(
                    "the contact penalty of terrain[{k1}], terrain[{k1}].stiffness = {} N/m with \
                     terrain[{k1}].damping = {} N·s/m (rate √(k w) + c w, with the end \
                     compliance w = {} 1/kg of {at})",
                    num(law.stiffness),
                    num(law.damping),
                    num(terrain_compliance(model).0),
                    k1 = k + 1
                )
            }
            Cause::TerrainFriction(k) => {
                let law = terrain_laws(model).nth(*k).expect("a shape");
                format!(
                    "the friction of terrain[{k1}], terrain[{k1}].friction = {} with \
                     terrain[{k1}].slip_velocity = {} m/s (below the slip velocity friction is \
                     viscous: rate μ W w / slip_velocity, with the weight W = {} N and the end \
                     compliance w = {} 1/kg of {at})",
                    num(law.friction),
                    num(law.slip_velocity),
                    num(weight(model)),
                    num(terrain_compliance(model).0),
                    k1 = k + 1
                )
            }
            Cause::CollisionPenalty => {
                let law = model.collisions.as_ref().expect("collisions").law;
                format!(
                    "the contact penalty between bars, collisions.stiffness = {} N/m with \
                     collisions.damping = {} N·s/m (rate √(k w) + c w, with the compliance \
                     w = {} 1/kg of two bar ends, {at} among them)",
                    num(law.stiffness),
                    num(law.damping),
                    num(collision_compliance(model).0),
                )
            }
            Cause::CollisionFriction => {
                let law = model.collisions.as_ref().expect("collisions").law;
                format!(
                    "the friction between bars, collisions.friction = {} with \
                     collisions.slip_velocity = {} m/s (below the slip velocity friction is \
                     viscous: rate μ W w / slip_velocity, with the weight W = {} N and the \
                     compliance w = {} 1/kg of two bar ends, {at} among them)",
                    num(law.friction),
                    num(law.slip_velocity),
                    num(weight(model)),
                    num(collision_compliance(model).0),
                )
            }
            Cause::Structure => format!(
                "the structure's fastest mode, which no single cable or contact dominates (it \
                 moves {at} most)"
            ),
            Cause::CableDamping(j) => format!(
                "the damping of cables[{}], {} N·s/m (its stretch decays at the rate c (w_a + \
                 w_b) of its ends' compliances)",
                j + 1,
                num(cable_damping(model, *j))
            ),
            Cause::Gravity => format!(
                "the gravity, |gravity| = {} m/s² (the time √(L/g) to move the structure's \
                 size L = {} m)",
                num(model.gravity.map_or(0.0, |g| g.norm())),
                num(size(model))
            ),
            Cause::Load(k) => format!(
                "loads[{k1}], {} N on node {} (the time √(L/(F w)) to move the structure's size \
                 L = {} m; w = {} 1/kg)",
                num(load_force(model, *k)),
                model.scene.loads[*k].node(),
                num(size(model)),
                num(node_compliance(model, model.scene.loads[*k].node() - 1)),
                k1 = k + 1
            ),
            Cause::Unbalanced => format!(
                "the forces unbalanced at the start, which accelerate {at} the most (the time \
                 √(L/a) to move the structure's size L = {} m)",
                num(size(model))
            ),
        }
    }

    /// The change of the causing key that brings this rate down to `target`, 1/s, if one
    /// does (e.g. "raise ground.slip_velocity to ≥ 0.079 m/s (the rate falls as 1/v_s)").
    pub fn fix(&self, model: &Model, inputs: &Inputs, target: f64) -> Option<String> {
        match &self.cause {
            Cause::Cables {
                family,
                family_share: share,
                ..
            } => {
                // ω² scales with the stiffness: soften the stiff cables' share of it.
                let ratio = (target / self.omega).powi(2);
                let factor = (ratio - (1.0 - share)) / share;
                (factor > 0.0).then(|| soften(model, inputs, family, factor))
            }
            Cause::GroundPenalty => {
                let g = model.ground.as_ref()?;
                let w = contact_compliance(model).0;
                Some(soften_penalty("ground", g.penalty(), w, target))
            }
            Cause::Friction => {
                let g = model.ground.as_ref()?;
                Some(raise_slip(
                    "ground.slip_velocity",
                    g.slip_velocity,
                    self.omega,
                    target,
                ))
            }
            Cause::TerrainPenalty(k) => {
                let law = terrain_laws(model).nth(*k)?;
                let w = terrain_compliance(model).0;
                Some(soften_penalty(
                    &format!("terrain[{}]", k + 1),
                    law,
                    w,
                    target,
                ))
            }
            Cause::TerrainFriction(k) => {
                let law = terrain_laws(model).nth(*k)?;
                let key = format!("terrain[{}].slip_velocity", k + 1);
                Some(raise_slip(&key, law.slip_velocity, self.omega, target))
            }
            Cause::CollisionPenalty => {
                let law = model.collisions.as_ref()?.law;
                let w = collision_compliance(model).0;
                Some(soften_penalty("collisions", law, w, target))
            }
            Cause::CollisionFriction => {
                let law = model.collisions.as_ref()?.law;
                let key = "collisions.slip_velocity";
                Some(raise_slip(key, law.slip_velocity, self.omega, target))
            }
            Cause::CableDamping(j) => Some(format!(
                "cables[{}].damping ≤ {} N·s/m",
                j + 1,
                num(cable_damping(model, *j) * target / self.omega)
            )),
            // The rate grows as the square root of the acceleration.
            Cause::Gravity => Some(format!(
                "|gravity| ≤ {} m/s²",
                num(model.gravity.map_or(0.0, |g| g.norm()) * (target / self.omega).powi(2))
            )),
            Cause::Load(k) => Some(format!(
                "loads[{}] ≤ {} N",
                k + 1,
                num(load_force(model, *k) * (target / self.omega).powi(2))
            )),
            Cause::Structure | Cause::Unbalanced => None,
        }
    }
}

/// The structure's size, m: its longest bar (at least 1 mm).
pub fn size(model: &Model) -> f64 {
    model.lengths().into_iter().fold(1e-3, f64::max)
}

/// The compliance `w` of node `n` (0-based), 1/kg: 0 when pinned or not a bar end.
pub fn node_compliance(model: &Model, n: usize) -> f64 {
    match model.coords.node_end[n] {
        Some(e) if !model.pinned[n] => model.inertia[e / 2].w[e % 2][e % 2],
        _ => 0.0,
    }
}

/// Cable `j`'s damping, N·s/m (0 without).
pub fn cable_damping(model: &Model, j: usize) -> f64 {
    match model.cables[j].law {
        CableLaw::Elastic { damping, .. } | CableLaw::RestLengthControlled { damping, .. } => {
            damping.unwrap_or(0.0)
        }
        CableLaw::Controlled { .. } => 0.0,
    }
}

/// The largest force of scripted load `k`, N.
pub fn load_force(model: &Model, k: usize) -> f64 {
    let force = match model.scene.loads[k] {
        LoadSpec::Constant { force, .. } | LoadSpec::Step { force, .. } => force,
        LoadSpec::Sinusoidal { amplitude, .. } => amplitude,
    };
    Vector3::from(force).norm()
}

/// "node 7 (an end of bars[4], 1 kg, with point_masses[1] of 0.5 kg)".
fn node_mass(model: &Model, n: usize) -> String {
    let Some(e) = model.coords.node_end[n] else {
        return format!("node {}", n + 1);
    };
    let bar = e / 2;
    let mut text = format!(
        "node {} (an end of bars[{}], {} kg",
        n + 1,
        bar + 1,
        num(model.bars[bar].mass)
    );
    for (k, pm) in model.scene.point_masses.iter().enumerate() {
        if pm.node == n + 1 {
            text += &format!(", with point_masses[{}] of {} kg", k + 1, num(pm.mass));
        }
    }
    text + ")"
}

/// "cables[3] (elastic, stiffness 1e8 N/m)", several as "cables[3], cables[5] and 4 more
/// (elastic, stiffness 1e8 N/m)".
fn cable_list(model: &Model, inputs: &Inputs, cables: &[usize]) -> String {
    let names: Vec<String> = cables
        .iter()
        .take(NAMED)
        .map(|j| format!("cables[{}]", j + 1))
        .collect();
    let mut text = names.join(", ");
    if cables.len() > NAMED {
        text += &format!(" and {} more", cables.len() - NAMED);
    }
    let mut laws: Vec<String> = cables
        .iter()
        .map(|&j| law(&model.cables[j].law, inputs))
        .collect();
    laws.dedup();
    if laws.len() > 2 {
        laws.truncate(2);
        laws.push("…".into());
    }
    format!("{text} ({})", laws.join("; "))
}

fn law(law: &CableLaw, inputs: &Inputs) -> String {
    match *law {
        CableLaw::Elastic { stiffness, .. } => format!("elastic, stiffness {stiffness:e} N/m"),
        CableLaw::RestLengthControlled { stiffness, .. } => {
            format!("reeled, stiffness {stiffness:e} N/m")
        }
        CableLaw::Controlled { input } => {
            format!("force density {:e} N/m", inputs.force_density[input])
        }
    }
}

/// A cable's stiffness (`true`, N/m) or force density (`false`, N/m).
fn strength(law: &CableLaw, inputs: &Inputs) -> (bool, f64) {
    match *law {
        CableLaw::Elastic { stiffness, .. } | CableLaw::RestLengthControlled { stiffness, .. } => {
            (true, stiffness)
        }
        CableLaw::Controlled { input } => (false, inputs.force_density[input]),
    }
}

/// Every cable whose stiffness (or force density) is at least the smallest among `stiff`.
fn family(model: &Model, inputs: &Inputs, stiff: &[usize]) -> Vec<usize> {
    let weakest = |kind: bool| {
        stiff
            .iter()
            .map(|&j| strength(&model.cables[j].law, inputs))
            .filter(|s| s.0 == kind)
            .map(|s| s.1)
            .fold(f64::INFINITY, f64::min)
    };
    let (stiffness, density) = (weakest(true), weakest(false));
    (0..model.cables.len())
        .filter(|&j| {
            let (kind, value) = strength(&model.cables[j].law, inputs);
            value >= if kind { stiffness } else { density }
        })
        .collect()
}

/// The cables' stiffness (or force density) cut to `factor` times the weakest's.
fn soften(model: &Model, inputs: &Inputs, cables: &[usize], factor: f64) -> String {
    let mut parts = Vec::new();
    for (kind, what, verb) in [
        (true, "stiffness", "soften"),
        (false, "force density", "lower"),
    ] {
        let values: Vec<f64> = cables
            .iter()
            .map(|&j| strength(&model.cables[j].law, inputs))
            .filter(|s| s.0 == kind)
            .map(|s| s.1)
            .collect();
        let Some(weakest) = values.iter().copied().reduce(f64::min) else {
            continue;
        };
        let which = match cables {
            [j] => format!("cables[{}]", j + 1),
            _ if values.len() == 1 => "that cable".to_string(),
            _ => format!(
                "the {} cables of {what} ≥ {} N/m",
                values.len(),
                num(weakest)
            ),
        };
        parts.push(format!(
            "{verb} {which} to {what} ≤ {} N/m",
            num(factor * weakest)
        ));
    }
    parts.join(" and ")
}

/// Node positions and node displacements per unit of `dq` about `q0`, by a difference.
pub fn node_displacements(
    model: &Model,
    ws: &mut Workspace,
    q0: &[f64],
    dq: &[f64],
    eps: f64,
) -> (Vec<Vector3<f64>>, Vec<Vector3<f64>>) {
    let zero = vec![0.0; q0.len()];
    let q: Vec<f64> = q0.iter().zip(dq).map(|(a, d)| a + eps * d).collect();
    dynamics::kinematics(model, &q, &zero, ws);
    let moved = ws.node_pos.clone();
    dynamics::kinematics(model, q0, &zero, ws);
    let x = ws.node_pos.clone();
    let dx = moved.iter().zip(&x).map(|(m, p)| (m - p) / eps).collect();
    (x, dx)
}
