//! The contact bounds of the stability guard: each contact law's penalty oscillator
//! `√(k w) + c w` and viscous friction `μ W w / v_s` at the most compliant end that can
//! touch, and the changes of its keys that bring a rate down.

use super::rate::{num, round_up, Cause, Rate};
use crate::contact::{Penalty, Shape};
use crate::model::Model;

/// The ground's two rates: the penalty oscillator and the viscous friction (0 without a
/// ground or friction), at the most compliant contact end.
pub fn contact_rates(model: &Model) -> Vec<Rate> {
    let mut rates = Vec::new();
    let mut push = |law: Penalty, w: f64, node, causes: [Cause; 2]| {
        let [penalty, friction] = causes;
        rates.push(Rate {
            omega: (law.stiffness * w).sqrt() + law.damping * w,
            cause: penalty,
            node,
        });
        rates.push(Rate {
            omega: law.friction * weight(model) * w / law.slip_velocity,
            cause: friction,
            node,
        });
    };
    if let Some(ground) = &model.ground {
        let (w, node) = contact_compliance(model);
        push(
            ground.penalty(),
            w,
            node,
            [Cause::GroundPenalty, Cause::Friction],
        );
    }
    if let Some(terrain) = &model.terrain {
        let (w, node) = terrain_compliance(model);
        for (k, (shape, law)) in terrain.shapes.iter().enumerate() {
            // Sticking ends add a tangential spring as stiff as the normal one, and no
            // viscous friction: a plane, touched only at ends, has none of it.
            let ends_only = terrain.sticks[k] && matches!(shape, Shape::Plane { .. });
            let law = Penalty {
                friction: if ends_only { 0.0 } else { law.friction },
                ..*law
            };
            push(
                law,
                w,
                node,
                [Cause::TerrainPenalty(k), Cause::TerrainFriction(k)],
            );
        }
    }
    if let Some(c) = &model.collisions {
        let (w, node) = collision_compliance(model);
        push(
            c.law,
            w,
            node,
            [Cause::CollisionPenalty, Cause::CollisionFriction],
        );
    }
    rates
}

/// The largest end compliance of any moving bar, 1/kg, and its node: two bars that touch
/// move apart with at most twice it.
pub(super) fn collision_compliance(model: &Model) -> (f64, Option<usize>) {
    (0..model.coords.n_ends())
        .filter(|&e| !model.coords.static_bar[e / 2])
        .map(|e| {
            (
                2.0 * model.inertia[e / 2].w[e % 2][e % 2],
                Some(model.coords.end_node[e]),
            )
        })
        .fold((0.0, None), |best, c| if c.0 > best.0 { c } else { best })
}

/// The terrain shapes' contact laws, in scene order.
pub(super) fn terrain_laws(model: &Model) -> impl Iterator<Item = Penalty> + '_ {
    model
        .terrain
        .iter()
        .flat_map(|t| t.shapes.iter().map(|(_, law)| *law))
}

/// The largest end compliance among the bars that touch terrain, 1/kg, and its node: a
/// point along a bar is never more compliant than the bar's ends.
pub(super) fn terrain_compliance(model: &Model) -> (f64, Option<usize>) {
    let Some(terrain) = &model.terrain else {
        return (0.0, None);
    };
    terrain
        .capsules
        .iter()
        .flat_map(|c| (0..2).filter_map(move |i| c.ends[i].map(|e| (e, c.nodes[i]))))
        .map(|(e, n)| (model.inertia[e / 2].w[e % 2][e % 2], Some(n)))
        .fold((0.0, None), |best, c| if c.0 > best.0 { c } else { best })
}

/// The largest end compliance `w` among the contact points, 1/kg, and its node.
pub(super) fn contact_compliance(model: &Model) -> (f64, Option<usize>) {
    let Some(ground) = &model.ground else {
        return (0.0, None);
    };
    ground
        .nodes
        .iter()
        .map(|&(n, e)| (model.inertia[e / 2].w[e % 2][e % 2], Some(n)))
        .fold((0.0, None), |best, c| if c.0 > best.0 { c } else { best })
}

/// The whole weight, N.
pub(super) fn weight(model: &Model) -> f64 {
    model.gravity.map_or(0.0, |g| {
        g.norm()
            * (0..model.coords.n_ends())
                .map(|e| model.end_mass(e))
                .sum::<f64>()
    })
}

/// The penalty settings of `key` (`ground`, `terrain[2]`) that bring its oscillator's rate
/// `√(k w) + c w` down to `target`.
pub(super) fn soften_penalty(key: &str, law: Penalty, w: f64, target: f64) -> String {
    let damped = law.damping * w;
    if damped < 0.5 * target {
        format!(
            "{key}.stiffness ≤ {} N/m (a softer contact penalty)",
            num((target - damped).powi(2) / w)
        )
    } else {
        format!(
            "{key}.stiffness ≤ {} N/m with {key}.damping ≤ {} N·s/m",
            num((0.5 * target).powi(2) / w),
            num(0.5 * target / w)
        )
    }
}

/// Raising the slip velocity `key` (now `slip`) so that the viscous friction's rate falls
/// from `omega` to `target`.
pub(super) fn raise_slip(key: &str, slip: f64, omega: f64, target: f64) -> String {
    let raised = round_up(slip * omega / target);
    format!(
        "raise {key} to ≥ {} m/s (the rate falls as 1/slip_velocity: ÷ {})",
        num(raised),
        num(raised / slip)
    )
}
