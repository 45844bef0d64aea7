//! Rest-length-controlled cables (issue 6, item 2.4): the actuation of tensegrity robots,
//! with `cable[j].rest_length` as an input.

use fmi2_model_description::Causality;
use nalgebra::Vector3;
use tensegrity_fmu::fmi::variables::VariableTable;
use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::scene::{builtin, CableControl, Scene};
use tensegrity_fmu::{Model, Simulation};

fn positions(sim: &mut Simulation) -> Vec<Vector3<f64>> {
    sim.refresh();
    (0..sim.model().n_nodes())
        .map(|n| sim.node_position(n))
        .collect()
}

/// prism2 with every cable reeled: stiffness κ_j = the start force density γ_j and rest
/// length 0, so `κ (1 − 0/|s|) s = γ s` exactly.
fn reeled_twin() -> Scene {
    let controlled = Model::new(&builtin("prism2").unwrap()).unwrap();
    let mut scene = controlled.explicit_scene();
    for (spec, gamma) in scene.cables.iter_mut().zip(&controlled.controlled_start) {
        spec.control = Some(CableControl::RestLength);
        spec.force_density = None;
        spec.stiffness = Some(*gamma);
        spec.rest_length = Some(0.0);
    }
    scene
}

#[test]
fn rest_length_control_reproduces_force_density_control() {
    let mut by_density = Simulation::new(Model::new(&builtin("prism2").unwrap()).unwrap());
    let mut by_reel = Simulation::new(Model::new(&reeled_twin()).unwrap());
    assert_eq!(by_reel.inputs.force_density.len(), 0);
    assert_eq!(by_reel.inputs.rest_length.len(), 15);
    for sim in [&mut by_density, &mut by_reel] {
        sim.inputs.node_force[0] = Vector3::new(2.0, 0.0, -1.0);
        sim.advance_to(0.5).unwrap();
    }
    let (a, b) = (positions(&mut by_density), positions(&mut by_reel));
    let moved = (a[6] - Vector3::from(builtin("prism2").unwrap().nodes[6])).norm();
    let diff = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).norm())
        .fold(0.0, f64::max);
    println!(
        "node 7 moved {moved:.3e} m; force-density vs rest-length control differ by {diff:.1e} m"
    );
    assert!(moved > 1e-2);
    assert!(diff <= 1e-12, "{diff}");
}

#[test]
fn reeling_in_shortens_the_cable_and_prestress_holds_at_rest() {
    let mut scene = builtin("prism2-elastic").unwrap();
    scene.cables[9].control = Some(CableControl::RestLength); // a saddle cable, nodes 4–9
                                                              // rk4 at 1 ms: dopri5's 1e-9 m tolerance would hide a drift below it.
    scene.solver.method = Method::Rk4;
    let mut sim = Simulation::new(Model::new(&scene).unwrap());
    let start = positions(&mut sim);
    sim.advance_to(0.5).unwrap();
    let at_rest = positions(&mut sim);
    let still = start
        .iter()
        .zip(&at_rest)
        .map(|(x, y)| (x - y).norm())
        .fold(0.0, f64::max);
    assert!(
        still <= 1e-10,
        "prestressed start rest length holds: {still}"
    );
    let [a, b] = sim.model().cables[9].nodes;
    let before = (at_rest[b] - at_rest[a]).norm();
    sim.inputs.rest_length[0] *= 0.9;
    sim.advance_to(1.0).unwrap();
    let after = positions(&mut sim);
    assert!((after[b] - after[a]).norm() < before - 1e-3);
    assert!(sim.length_error() <= 1e-12);
}

#[test]
fn reeled_cable_is_an_fmu_input_with_its_stiffness_a_parameter() {
    let mut scene = builtin("prism2-elastic").unwrap();
    scene.cables[9].control = Some(CableControl::RestLength);
    let table = VariableTable::new(&Simulation::new(Model::new(&scene).unwrap()));
    let rest = table.by_name("cable[10].rest_length").unwrap();
    assert_eq!(rest.causality, Causality::Input);
    assert_eq!(rest.unit, Some("m"));
    assert_eq!(
        table.by_name("cable[10].stiffness").unwrap().causality,
        Causality::Parameter
    );
    assert_eq!(
        table.by_name("cable[9].rest_length").unwrap().causality,
        Causality::Parameter
    );
    assert!(table.by_name("cable[10].force_density").is_none());
}
