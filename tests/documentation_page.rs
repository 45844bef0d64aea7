//! `documentation/index.html` (issue 10, item 9): a usage section, inputs and outputs
//! before parameters, values by name and counts with the right plural.

use tensegrity_fmu::fmi::documentation::index_html;
use tensegrity_fmu::fmi::variables::VariableTable;
use tensegrity_fmu::model::Model;
use tensegrity_fmu::scene::{builtin, LoadSpec, PointMassSpec, Scene};
use tensegrity_fmu::sim::Simulation;

fn page(scene: &Scene) -> String {
    let sim = Simulation::new(Model::new(scene).unwrap());
    index_html(sim.model(), &VariableTable::new(&sim))
}

/// The cells of the table row of variable `name`.
fn row(html: &str, name: &str) -> Vec<String> {
    let start = html
        .find(&format!("<tr><td><code>{name}</code>"))
        .unwrap_or_else(|| panic!("no row for {name}"));
    let end = start + html[start..].find("</tr>").unwrap();
    html[start..end]
        .split("<td>")
        .skip(1)
        .map(|c| c.trim_end_matches("</td>").to_string())
        .collect()
}

fn pos(html: &str, needle: &str) -> usize {
    html.find(needle)
        .unwrap_or_else(|| panic!("{needle:?} not in the page"))
}

#[test]
fn usage_section_runs_it_with_fmpy_and_says_inputs_are_held() {
    let html = page(&builtin("prism2").unwrap());
    let usage = &html[pos(&html, "<h2>Usage</h2>")..pos(&html, "<h2>Structure")];
    assert!(usage.contains("from fmpy import simulate_fmu"));
    assert!(usage.contains("simulate_fmu(\"prism2.fmu\", stop_time=1.0, output_interval=0.01)"));
    assert!(usage.contains("held constant over each communication step"));
    let code = &usage[pos(usage, "<code>")..pos(usage, "</code></pre>")];
    assert_eq!(code.lines().count(), 3, "{code}");
}

#[test]
fn inputs_and_outputs_come_before_parameters() {
    let html = page(&builtin("prism2").unwrap());
    let (i, o, p) = (
        pos(&html, "<h3>Inputs</h3>"),
        pos(&html, "<h3>Outputs</h3>"),
        pos(&html, "<h3>Parameters</h3>"),
    );
    assert!(i < o && o < p);
    assert!(pos(&html, "<tr><td><code>cable[1].force_density</code>") < o);
    assert!(o < pos(&html, "<tr><td><code>node[1].x</code>"));
    assert!(p < pos(&html, "<tr><td><code>solver.step_size</code>"));
    assert!(p < pos(&html, "<tr><td><code>bar[1].mass</code>"));
}

#[test]
fn values_are_shown_by_name_with_variability() {
    let html = page(&builtin("prism2").unwrap());
    // name, causality, variability, type, unit, start, meaning
    let method = row(&html, "solver.method");
    assert_eq!(method[2..6], ["Fixed", "Integer", "", "1 (rk4)"]);
    let correction = row(&html, "solver.correction");
    assert_eq!(correction[3..6], ["Boolean", "", "true"]);
    let steps = row(&html, "solver.max_steps");
    assert_eq!(steps[2..6], ["Tunable", "Integer", "", "100000"]);
    assert_eq!(row(&html, "bar[2].mass")[2], "Tunable");
    let mut scene = builtin("prism2").unwrap();
    scene.solver.method = tensegrity_fmu::integrator::Method::Rattle;
    scene.solver.correction = false;
    let html = page(&scene);
    assert_eq!(row(&html, "solver.method")[5], "3 (rattle)");
    assert_eq!(row(&html, "solver.correction")[5], "false");
}

#[test]
fn counts_have_the_right_plural() {
    let mut scene = builtin("prism2-elastic").unwrap();
    let load = |node| LoadSpec::Constant {
        node,
        force: [1.0, 0.0, 0.0],
    };
    scene.point_masses = vec![PointMassSpec { node: 7, mass: 0.5 }];
    scene.loads = vec![load(7)];
    scene.force_inputs = vec![8];
    scene.cables[0].damping = Some(1.0);
    let one = page(&scene);
    for phrase in [
        "1 point mass (",
        "1 scripted load (",
        "force inputs on node 8<",
        "1 cable with damping on",
        "15 elastic cables",
        "9 nodes (numbered from 1), 6 rigid bars",
        "pinned nodes: 1, 2, 3",
    ] {
        assert!(one.contains(phrase), "{phrase:?} missing");
    }
    scene
        .point_masses
        .push(PointMassSpec { node: 8, mass: 0.5 });
    scene.loads.push(load(8));
    scene.force_inputs = vec![7, 8];
    scene.cables[1].damping = Some(1.0);
    scene.fixed = vec![1];
    let two = page(&scene);
    for phrase in [
        "2 point masses (",
        "2 scripted loads (",
        "force inputs on nodes 7, 8<",
        "2 cables with damping on",
        "pinned node: 1<",
    ] {
        assert!(two.contains(phrase), "{phrase:?} missing");
    }
    for wrong in [
        "1 point masses",
        "1 scripted loads",
        "1 cables",
        "2 point mass (",
    ] {
        assert!(!one.contains(wrong) && !two.contains(wrong), "{wrong:?}");
    }
}
