//! modelDescription.xml grows about linearly with the structure: a tower ten times taller
//! has a description at most twelve times larger. Its bar forces read most of the cable
//! parameters of their column, so lists written in full would grow a hundredfold.

use tensegrity_fmu::fmi::package::golden_model_description;
use tensegrity_fmu::scene::{tower_scene, Scene};

/// A tower of `3 * stages` bars, no inputs, cables at 98% of their lengths (so no
/// prestress solve is needed).
fn loose_tower(stages: usize) -> Scene {
    let mut scene = tower_scene(stages, Some(500.0), &format!("loose{stages}"));
    scene.prestress = None;
    scene.force_inputs.clear();
    let nodes = scene.nodes.clone();
    for cable in &mut scene.cables {
        let [a, b] = cable.nodes.map(|n| nodes[n - 1]);
        let length = (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt();
        cable.rest_length = Some(0.98 * length);
    }
    scene
}

fn description_bytes(stages: usize) -> usize {
    golden_model_description(&loose_tower(stages))
        .expect("the tower packages")
        .len()
}

#[test]
fn a_ten_times_larger_tower_has_at_most_a_twelve_times_larger_description() {
    let (small, large) = (description_bytes(20), description_bytes(200));
    let ratio = large as f64 / small as f64;
    assert!(
        (8.0..=12.0).contains(&ratio),
        "60 bars: {small} bytes, 600 bars: {large} bytes, ratio {ratio:.2}"
    );
}
