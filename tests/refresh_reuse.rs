//! A step right after an evaluation for the outputs (`Simulation::refresh`, before a CSV
//! row or an FMU output read) takes that evaluation as its first stage instead of
//! evaluating again (issue 14, the CSV row's cost): the same bits as a step that evaluates,
//! one evaluation fewer, and an evaluation again whenever the inputs or the time changed
//! in between.

use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::scene::{builtin, LoadSpec, Scene};
use tensegrity_fmu::{Model, Simulation};

const STEP: f64 = 1e-3;

fn prism(method: Method) -> Scene {
    let mut scene = builtin("prism2").unwrap();
    scene.solver.method = method;
    scene.solver.step_size = STEP;
    // A load that depends on time, so that an evaluation at another time differs.
    scene.loads = vec![LoadSpec::Sinusoidal {
        node: 7,
        amplitude: [3.0, -2.0, 1.0],
        frequency: 40.0,
        phase: 0.3,
    }];
    scene
}

fn sim(method: Method) -> Simulation {
    Simulation::new(Model::new(&prism(method)).unwrap())
}

fn evaluations(sim: &Simulation) -> u64 {
    sim.integrator().rhs_evaluations()
}

/// Steps of `STEP`, each after a refresh when `refresh` is set: the states after each.
fn run(sim: &mut Simulation, steps: u64, refresh: bool) -> Vec<Vec<f64>> {
    (0..steps)
        .map(|_| {
            if refresh {
                sim.refresh();
            }
            sim.advance(1, STEP).unwrap();
            sim.state().y.clone()
        })
        .collect()
}

fn bits(states: &[Vec<f64>]) -> Vec<Vec<u64>> {
    states
        .iter()
        .map(|y| y.iter().map(|x| x.to_bits()).collect())
        .collect()
}

#[test]
fn rk4_after_a_refresh_takes_it_as_its_first_stage() {
    let steps = 40;
    let (mut refreshed, mut plain) = (sim(Method::Rk4), sim(Method::Rk4));
    let with = run(&mut refreshed, steps, true);
    let without = run(&mut plain, steps, false);
    assert_eq!(bits(&with), bits(&without));
    // Three evaluations a step after a refresh, four otherwise; the plain run's first step
    // takes three too (`Simulation::new` and the stability check before it refresh).
    assert_eq!(evaluations(&refreshed), 3 * steps);
    assert_eq!(evaluations(&plain), 4 * steps - 1);
    // The motion is not trivial: the load and the prestress moved the nodes.
    let moved = (0..with[0].len() / 2)
        .map(|i| (with[steps as usize - 1][i] - with[0][i]).abs())
        .fold(0.0, f64::max);
    assert!(moved > 1e-6, "moved {moved}");
}

#[test]
fn dopri5_and_rattle_take_it_where_they_would_evaluate_at_the_start() {
    for method in [Method::Dopri5, Method::Rattle] {
        let steps = 30;
        let (mut refreshed, mut plain) = (sim(method), sim(method));
        let with = run(&mut refreshed, steps, true);
        let without = run(&mut plain, steps, false);
        assert_eq!(bits(&with), bits(&without), "{method:?}");
        let (a, b) = (evaluations(&refreshed), evaluations(&plain));
        match method {
            // Dormand–Prince evaluates at the start of every step after the correction: at
            // each `advance`'s first step the refresh stands in (the plain run's first too).
            Method::Dopri5 => assert_eq!(a + steps - 1, b),
            // RATTLE carries its acceleration, so it evaluates at a start only once.
            _ => assert_eq!(a, b, "{method:?}"),
        }
    }
}

#[test]
fn rattle_takes_it_when_new_inputs_drop_its_carried_acceleration() {
    // New inputs make RATTLE evaluate at the step's start again (its carried acceleration
    // belongs to the old ones); a refresh with the new inputs stands in for it.
    let run = |refresh: bool| {
        let mut sim = sim(Method::Rattle);
        sim.advance(3, STEP).unwrap();
        sim.inputs.force_density[0] *= 1.5;
        if refresh {
            sim.refresh();
        }
        let before = evaluations(&sim);
        sim.advance(1, STEP).unwrap();
        (evaluations(&sim) - before, sim.state().y.clone())
    };
    let ((refreshed, with), (plain, without)) = (run(true), run(false));
    assert_eq!(
        (refreshed, plain),
        (1, 2),
        "the start's and the end's, or the end's"
    );
    assert_eq!(bits(&[with]), bits(&[without]));
}

#[test]
fn inputs_changed_after_a_refresh_are_evaluated_with() {
    let change = |sim: &mut Simulation| {
        sim.inputs.force_density[0] *= 1.5;
        sim.inputs.node_force[0].x += 2.0;
    };
    // Refreshed with the old inputs, stepped with the new: the refresh is stale.
    let mut stale = sim(Method::Rk4);
    stale.advance(3, STEP).unwrap();
    stale.refresh();
    change(&mut stale);
    let before = evaluations(&stale);
    stale.advance(1, STEP).unwrap();
    assert_eq!(evaluations(&stale) - before, 4);
    // Refreshed with the new inputs: it stands in, with the same bits.
    let mut fresh = sim(Method::Rk4);
    fresh.advance(3, STEP).unwrap();
    change(&mut fresh);
    fresh.refresh();
    let before = evaluations(&fresh);
    fresh.advance(1, STEP).unwrap();
    assert_eq!(evaluations(&fresh) - before, 3);
    assert_eq!(
        bits(&[stale.state().y.clone()]),
        bits(&[fresh.state().y.clone()])
    );
    // Changed and changed back: the inputs are those of the refresh again.
    let mut back = sim(Method::Rk4);
    back.advance(3, STEP).unwrap();
    back.refresh();
    let saved = back.inputs.clone();
    change(&mut back);
    back.inputs = saved;
    let before = evaluations(&back);
    back.advance(1, STEP).unwrap();
    assert_eq!(evaluations(&back) - before, 3);
}

#[test]
fn a_refresh_at_another_time_is_not_taken() {
    // Refreshed at t = 0.003, then moved to t = 0.0105 (the load differs there).
    let mut moved = sim(Method::Rk4);
    moved.advance(3, STEP).unwrap();
    moved.refresh();
    moved.set_time(0.0105);
    let before = evaluations(&moved);
    moved.advance(1, STEP).unwrap();
    assert_eq!(evaluations(&moved) - before, 4);
    // The same state stepped from 0.0105 without a refresh in between.
    let mut direct = sim(Method::Rk4);
    direct.advance(3, STEP).unwrap();
    direct.set_time(0.0105);
    direct.advance(1, STEP).unwrap();
    assert_eq!(
        bits(&[moved.state().y.clone()]),
        bits(&[direct.state().y.clone()])
    );
}

#[test]
fn a_failed_step_leaves_a_refresh_that_is_still_good() {
    // A NaN input is refused before the step; the state and its evaluation stay.
    let mut sim = sim(Method::Rk4);
    sim.advance(2, STEP).unwrap();
    sim.refresh();
    let good = sim.inputs.clone();
    sim.inputs.force_density[0] = f64::NAN;
    assert!(sim.advance(1, STEP).is_err());
    sim.inputs = good;
    let before = evaluations(&sim);
    sim.advance(1, STEP).unwrap();
    assert_eq!(evaluations(&sim) - before, 3);
    let mut plain = self::sim(Method::Rk4);
    plain.advance(3, STEP).unwrap();
    assert_eq!(
        bits(&[sim.state().y.clone()]),
        bits(&[plain.state().y.clone()])
    );
}
