//! Output selection (issue 6, item 3): a scene exposes only the output groups it names,
//! in CSV columns, FMU variables and ModelStructure.

use tensegrity_fmu::fmi::package::golden_model_description;
use tensegrity_fmu::fmi::variables::{Binding, VariableTable};
use tensegrity_fmu::outputs::{outputs, OutputGroup};
use tensegrity_fmu::scene::{builtin, Scene};
use tensegrity_fmu::{Model, Simulation};

fn tower_with(groups: Option<Vec<OutputGroup>>) -> Scene {
    let mut scene = builtin("tower20").unwrap();
    scene.outputs = groups;
    scene
}

#[test]
fn only_selected_groups_become_outputs() {
    let scene = tower_with(Some(vec![OutputGroup::Positions, OutputGroup::Diagnostics]));
    let sim = Simulation::new(Model::new(&scene).unwrap());
    let names: Vec<String> = outputs(&sim).into_iter().map(|o| o.name).collect();
    assert_eq!(names.len(), 3 * 63 + 2);
    assert!(names.iter().all(|n| n.ends_with(".x")
        || n.ends_with(".y")
        || n.ends_with(".z")
        || n.starts_with("constraint.")));
    let table = VariableTable::new(&sim);
    let outputs_in_table = table
        .variables
        .iter()
        .filter(|v| matches!(v.binding, Binding::Output(_)))
        .count();
    assert_eq!(outputs_in_table, names.len());
    // Inputs and parameters do not depend on the selection.
    let full = VariableTable::new(&Simulation::new(Model::new(&tower_with(None)).unwrap()));
    let others = |t: &VariableTable| {
        t.variables
            .iter()
            .filter(|v| !matches!(v.binding, Binding::Output(_)))
            .count()
    };
    assert_eq!(others(&table), others(&full));
    assert_eq!(
        full.variables.len() - table.variables.len(),
        3 * 63 + 123 + 60 + 1 + 3 * 3,
        "velocities, tensions, bar forces, energy and the 3 pins' reactions are left out"
    );
}

#[test]
fn model_description_lists_only_the_selected_outputs() {
    let xml = golden_model_description(&tower_with(Some(vec![OutputGroup::Energy]))).unwrap();
    assert_eq!(xml.matches("causality=\"output\"").count(), 1);
    assert!(xml.contains("name=\"energy.total\""));
    assert!(!xml.contains("name=\"node[1].x\""));
    let outputs_section = &xml[xml.find("<Outputs>").unwrap()..xml.find("</Outputs>").unwrap()];
    assert_eq!(outputs_section.matches("<Unknown").count(), 1);
}

#[test]
fn output_selection_is_validated() {
    let err = Model::new(&tower_with(Some(vec![])))
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with("outputs:") && err.contains("no output group"),
        "{err}"
    );
    let twice = Some(vec![OutputGroup::Energy, OutputGroup::Energy]);
    let err = Model::new(&tower_with(twice)).unwrap_err().to_string();
    assert!(
        err.starts_with("outputs[2]") && err.contains("twice"),
        "{err}"
    );
    let text = builtin("prism2")
        .unwrap()
        .to_toml_string()
        .replace("name = \"prism2\"", "name = \"p\"\noutputs = [\"speeds\"]");
    let err = Scene::from_toml_str(&text).unwrap_err().to_string();
    assert!(err.contains("speeds"), "{err}");
}

/// Positions and velocities are read from the state without an evaluation (issue 14, item
/// 2), and they are the very bits the evaluation's kinematics computes: for moving, pinned
/// and bar-less nodes, in the sparse and the dense basis, mid-run.
#[test]
fn positions_and_velocities_from_the_state_are_the_evaluated_bits() {
    use tensegrity_fmu::model::BasisKind;
    for (name, basis) in [
        ("tower20", BasisKind::Sparse),
        ("prism2", BasisKind::Sparse),
        ("prism2", BasisKind::Dense),
        ("icosahedron", BasisKind::Sparse),
    ] {
        let mut sim = Simulation::new(Model::with_basis(&builtin(name).unwrap(), basis).unwrap());
        if let Some(f) = sim.inputs.node_force.first_mut() {
            f.x = 2.0;
        }
        sim.advance(25, 1e-3).unwrap();
        let table = outputs(&sim);
        let from_state: Vec<f64> = table
            .iter()
            .filter(|o| !o.quantity.needs_evaluation())
            .map(|o| o.quantity.value(&sim))
            .collect();
        assert_eq!(from_state.len(), 6 * sim.model().n_nodes());
        sim.refresh();
        for (k, n) in (0..sim.model().n_nodes()).enumerate() {
            for axis in 0..3 {
                let (x, v) = (
                    from_state[3 * k + axis],
                    from_state[3 * (k + sim.model().n_nodes()) + axis],
                );
                assert_eq!(
                    x.to_bits(),
                    sim.node_position(n)[axis].to_bits(),
                    "{name} node {n}"
                );
                assert_eq!(
                    v.to_bits(),
                    sim.node_velocity(n)[axis].to_bits(),
                    "{name} node {n}"
                );
            }
        }
    }
}
