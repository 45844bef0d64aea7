//! modelDescription.xml grows about linearly with the structure: a tower ten times taller
//! has a description at most twelve times larger, with or without inputs. Its bar forces
//! read most of the cable parameters of their column, so lists written in full would grow a
//! hundredfold. `<Outputs>` stays exact at any size.

use quick_xml::events::Event;
use quick_xml::Reader;
use tensegrity_fmu::fmi::package::golden_model_description;
use tensegrity_fmu::scene::{tower_scene, Scene};

/// A tower of `3 * stages` bars, no inputs, cables at 98% of their lengths (so no
/// prestress solve is needed).
fn loose_tower(stages: usize) -> Scene {
    let mut scene = pushed_tower(stages);
    scene.force_inputs.clear();
    scene
}

/// [`loose_tower`] with its force inputs on the three top nodes: each column's bar forces
/// read the three forces on its own top node and not the other six.
fn pushed_tower(stages: usize) -> Scene {
    let mut scene = tower_scene(stages, Some(500.0), &format!("loose{stages}"));
    scene.prestress = None;
    let nodes = scene.nodes.clone();
    for cable in &mut scene.cables {
        let [a, b] = cable.nodes.map(|n| nodes[n - 1]);
        let length = (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt();
        cable.rest_length = Some(0.98 * length);
    }
    scene
}

/// The description of `tower(10 * stages)` is 8 to 12 times that of `tower(stages)`.
fn grows_tenfold(tower: fn(usize) -> Scene, stages: usize) {
    let bytes = |k: usize| {
        golden_model_description(&tower(k))
            .expect("the tower packages")
            .len()
    };
    let (small, large) = (bytes(stages), bytes(10 * stages));
    let ratio = large as f64 / small as f64;
    assert!(
        (8.0..=12.0).contains(&ratio),
        "{} bars: {small} bytes, {} bars: {large} bytes, ratio {ratio:.2}",
        3 * stages,
        30 * stages
    );
}

#[test]
fn a_ten_times_larger_tower_has_at_most_a_twelve_times_larger_description() {
    grows_tenfold(loose_tower, 20);
}

#[test]
fn a_ten_times_larger_tower_with_inputs_has_at_most_a_twelve_times_larger_description() {
    // From 600 bars, where the exact lists no longer fit, to 6,000 (tower20 is exact).
    grows_tenfold(pushed_tower, 200);
}

/// Each `Unknown` of a `<ModelStructure>` section: its variable's name and its
/// `dependencies` (`None` where omitted), named.
fn section(xml: &str, name: &str) -> Vec<(String, Option<Vec<String>>)> {
    let (mut names, mut rows, mut inside) = (Vec::new(), Vec::new(), false);
    let mut reader = Reader::from_str(xml);
    loop {
        match reader.read_event().expect("well-formed XML") {
            Event::Start(e) | Event::Empty(e) => {
                let attr = |key: &str| {
                    e.try_get_attribute(key)
                        .unwrap()
                        .map(|a| a.value.into_owned())
                };
                match e.name().as_ref() {
                    "ScalarVariable" => names.push(attr("name").unwrap()),
                    "Unknown" if inside => rows.push((attr("index"), attr("dependencies"))),
                    n => inside |= n == name,
                }
            }
            Event::End(e) if e.name().as_ref() == name => inside = false,
            Event::Eof => break,
            _ => {}
        }
    }
    let named = |i: &str| names[i.parse::<usize>().unwrap() - 1].clone();
    rows.into_iter()
        .map(|(index, deps)| {
            let deps = deps.map(|d| d.split_whitespace().map(named).collect());
            (named(&index.unwrap()), deps)
        })
        .collect()
}

#[test]
fn outputs_stay_exact_at_scale_and_only_the_initial_rows_lose_their_lists() {
    let stages = 200;
    let xml = golden_model_description(&pushed_tower(stages)).unwrap();
    let top = 3 * stages + 1;
    let bar_forces = |rows: Vec<(String, Option<Vec<String>>)>| -> Vec<_> {
        rows.into_iter()
            .filter(|(n, _)| n.ends_with("].force"))
            .collect()
    };
    let outputs = bar_forces(section(&xml, "Outputs"));
    assert_eq!(outputs.len(), 3 * stages);
    for (k, (name, deps)) in outputs.iter().enumerate() {
        let node = top + k % 3;
        let own: Vec<String> = ["fx", "fy", "fz"]
            .iter()
            .map(|a| format!("node[{node}].{a}"))
            .collect();
        assert_eq!(deps.as_ref(), Some(&own), "{name}");
    }
    // The exact lists of the initial bar forces would hold 3 * 200 rows of about 4,000
    // Knowns each; past the budget they claim all Knowns.
    let initial = bar_forces(section(&xml, "InitialUnknowns"));
    let omitted = initial.iter().filter(|(_, d)| d.is_none()).count();
    assert!(omitted > stages, "{omitted} of {} omitted", initial.len());
}
