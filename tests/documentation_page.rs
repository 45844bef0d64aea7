//! `documentation/index.html` (issue 10, item 9): a usage section, inputs and outputs
//! before parameters, values by name and counts with the right plural; the lowest natural
//! frequencies about a start state at rest (issue 11, item 5).

use std::process::Command;

use tensegrity_fmu::analysis;
use tensegrity_fmu::fmi::documentation::{index_html, LISTED_MODES};
use tensegrity_fmu::fmi::variables::VariableTable;
use tensegrity_fmu::model::Model;
use tensegrity_fmu::scene::{builtin, LoadSpec, PointMassSpec, Scene, Start};
use tensegrity_fmu::sim::Simulation;

fn page(scene: &Scene) -> String {
    let sim = Simulation::new(Model::new(scene).unwrap());
    index_html(
        &sim,
        &VariableTable::new(&sim),
        &format!("{}.fmu", scene.name),
    )
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
    assert_eq!(method[2..6], ["Fixed", "Integer", "", "2 (dopri5)"]);
    assert!(html.contains("dopri5 (rtol 1e-6, atol 1e-9), event location on, correction on"));
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

/// The page of a scene at the start it asks for (the equilibrium with `start = "equilibrium"`),
/// as `tensegrity-fmu build` writes it.
fn built_page(scene: &Scene) -> String {
    let sim = Simulation::new(analysis::load(scene).unwrap());
    index_html(
        &sim,
        &VariableTable::new(&sim),
        &format!("{}.fmu", scene.name),
    )
}

/// The rows (mode, frequency, kind) of the natural-frequency table.
fn frequency_rows(html: &str) -> Vec<[String; 3]> {
    let section = &html[pos(html, "<h2>Natural frequencies</h2>")..pos(html, "<h2>Variables</h2>")];
    let Some(start) = section.find("<table>") else {
        return Vec::new();
    };
    let table = &section[start..pos(section, "</table>")];
    table
        .split("<tr>")
        .skip(2)
        .map(|r| {
            let cells: Vec<String> = r
                .split("<td>")
                .skip(1)
                .map(|c| c.split("</td>").next().unwrap().to_string())
                .collect();
            [cells[0].clone(), cells[1].clone(), cells[2].clone()]
        })
        .collect()
}

#[test]
fn lowest_natural_frequencies_are_those_of_the_modes_command() {
    let out = Command::new(env!("CARGO_BIN_EXE_tensegrity-fmu"))
        .args(["modes", "prism2-elastic", "--json"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let hz = json["frequencies_hz"].as_array().unwrap();
    let kinds = json["kinds"].as_array().unwrap();
    assert!(hz.len() > LISTED_MODES);
    let rows = frequency_rows(&page(&builtin("prism2-elastic").unwrap()));
    assert_eq!(rows.len(), LISTED_MODES);
    for (k, row) in rows.iter().enumerate() {
        let f = hz[k].as_f64().unwrap();
        assert!(f > 0.0);
        assert_eq!(row[0], (k + 1).to_string());
        assert_eq!(row[1], format!("{f:.6}"), "mode {}", k + 1);
        assert_eq!(row[2], kinds[k].as_str().unwrap(), "mode {}", k + 1);
    }
    // Lowest first.
    let listed: Vec<f64> = rows.iter().map(|r| r[1].parse().unwrap()).collect();
    assert!(listed.windows(2).all(|w| w[0] <= w[1]), "{listed:?}");
}

#[test]
fn a_start_state_not_at_rest_gets_a_sentence_instead_of_frequencies() {
    // Gravity on a prestressed structure drawn without it: an unbalanced force.
    let mut scene = builtin("prism2-elastic").unwrap();
    scene.gravity = Some([0.0, 0.0, -9.81]);
    let html = page(&scene);
    assert!(frequency_rows(&html).is_empty());
    for phrase in [
        "No natural frequencies are listed: the start state is not an equilibrium (unbalanced force",
        "add <code>start = &quot;equilibrium&quot;</code> to the scene",
    ] {
        assert!(html.contains(phrase), "{phrase:?} missing");
    }
    // Moving at the start.
    let mut moving = builtin("prism2-elastic").unwrap();
    let mut v = vec![[0.0; 3]; moving.nodes.len()];
    v[6] = [0.1, 0.0, 0.0];
    moving.velocities = Some(v);
    let html = page(&moving);
    assert!(frequency_rows(&html).is_empty());
    assert!(html.contains("No natural frequencies are listed: the start state is moving"));
    // The fix the sentence names: the same scene started from its equilibrium.
    scene.start = Start::Equilibrium;
    let rows = frequency_rows(&built_page(&scene));
    assert_eq!(rows.len(), LISTED_MODES);
    assert!(rows.iter().all(|r| r[2] == "vibration"), "{rows:?}");
}

/// The usage example opens the file the FMU was written as, whatever its name.
#[test]
fn documentation_names_the_file_the_fmu_was_built_as() {
    use tensegrity_fmu::fmi::package::build_fmu;
    let dir = std::env::temp_dir().join(format!("tensegrity-doc-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // build_fmu only checks that the binary carries this build's id.
    let binary = dir.join("binary.so");
    std::fs::write(&binary, tensegrity_fmu::fmi::BUILD_ID).unwrap();
    for (file, literal) in [
        ("my-prism.fmu", "\"my-prism.fmu\""),
        ("say \"hi\".fmu", "\"say \\\"hi\\\".fmu\""),
    ] {
        let out = dir.join(file);
        build_fmu(&builtin("prism2").unwrap(), &binary, &out).unwrap();
        let mut zip = zip::ZipArchive::new(std::fs::File::open(&out).unwrap()).unwrap();
        let mut html = String::new();
        std::io::Read::read_to_string(
            &mut zip.by_name("documentation/index.html").unwrap(),
            &mut html,
        )
        .unwrap();
        let text = html.replace("&quot;", "\"").replace("&amp;", "&");
        let call = format!("simulate_fmu({literal}, stop_time=1.0");
        assert!(text.contains(&call), "{file}: no {call} in the page");
        assert!(
            !text.contains("prism2.fmu"),
            "{file}: the page names prism2.fmu"
        );
    }
}

/// The documentation of a tower of `stages` stages (3 bars each) as `build` writes it:
/// `documentation/index.html` and the viewer's `structure.html`.
fn documentation_of_tower(stages: usize) -> (Scene, String, String) {
    use tensegrity_fmu::render::{html, Frames};
    let scene = tensegrity_fmu::scene::tower_with_rest_lengths(stages, "tower");
    let mut sim = Simulation::new(Model::new(&scene).unwrap());
    let index = index_html(&sim, &VariableTable::new(&sim), "tower.fmu");
    let viewer = html::page(&Frames::record(&mut sim, &[0.0]).unwrap());
    (scene, index, viewer)
}

/// The documentation's bytes (both pages) at 600 and 6,000 bars: about linear, and
/// under 120 bytes per bar (a table row per variable took over 2,000).
#[test]
fn documentation_grows_at_most_linearly_with_the_bars() {
    let (_, index_600, viewer_600) = documentation_of_tower(200);
    let (_, index_6000, viewer_6000) = documentation_of_tower(2000);
    let small = (index_600.len() + viewer_600.len()) as f64;
    let large = (index_6000.len() + viewer_6000.len()) as f64;
    println!(
        "600 bars: index {} B, viewer {} B; 6000 bars: index {} B, viewer {} B; ratio {:.2}",
        index_600.len(),
        viewer_600.len(),
        index_6000.len(),
        viewer_6000.len(),
        large / small
    );
    assert!(
        large / small <= 11.0,
        "10× the bars: {:.2}× the bytes",
        large / small
    );
    assert!(
        large / 6000.0 < 120.0,
        "{:.0} bytes per bar",
        large / 6000.0
    );
}

/// The summary row of kind `name` (as shown, e.g. `node[1..6003].x`): its cells.
fn kind_row(html: &str, name: &str) -> Vec<String> {
    let start = pos(html, &format!("<tr class=\"kind\"><td><code>{name}</code>"));
    let end = start + pos(&html[start..], "</tr>");
    html[start..end]
        .split("<td>")
        .skip(1)
        .map(|c| c.trim_end_matches("</td>").to_string())
        .collect()
}

#[test]
fn a_large_structure_gets_a_summary_by_kind_and_the_first_rows() {
    use tensegrity_fmu::fmi::documentation::{FULL_TABLE_VARIABLES, LISTED_PER_KIND};
    let stages = 2000;
    let (scene, html, _) = documentation_of_tower(stages);
    let sim = Simulation::new(Model::new(&scene).unwrap());
    let variables = VariableTable::new(&sim).variables.len();
    assert!(variables > FULL_TABLE_VARIABLES);
    let (nodes, bars, cables) = (3 * (stages + 1), 3 * stages, 3 * (2 * stages + 1));
    assert_eq!(
        (scene.nodes.len(), scene.bars.len(), scene.cables.len()),
        (nodes, bars, cables)
    );
    // name, count, causality, variability, type, unit, start, meaning
    let x = kind_row(&html, &format!("node[1..{nodes}].x"));
    assert_eq!(
        x[1..6],
        [&nodes.to_string(), "Output", "Continuous", "Real", "m"]
    );
    assert_eq!(x[7], "position of node 1 along x");
    let tension = kind_row(&html, &format!("cable[1..{cables}].tension"));
    assert_eq!(tension[1], cables.to_string());
    let mass = kind_row(&html, &format!("bar[1..{bars}].mass"));
    assert_eq!(
        mass[1..7],
        [&bars.to_string(), "Parameter", "Tunable", "Real", "kg", "1"]
    );
    let rest: Vec<f64> = scene
        .cables
        .iter()
        .map(|c| c.rest_length.unwrap())
        .collect();
    let lo = rest.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = rest.iter().copied().fold(0.0, f64::max);
    assert!(lo < hi);
    let rest_row = kind_row(&html, &format!("cable[1..{cables}].rest_length"));
    assert_eq!(rest_row[6], format!("{lo} … {hi}"));
    let inputs = kind_row(&html, &format!("node[{}..{nodes}].fx", nodes - 2));
    assert_eq!(inputs[1..3], ["3", "Input"]);
    assert_eq!(kind_row(&html, "node[1..3].reaction_z")[1], "3");
    // Every variable is counted once.
    let counted: usize = html
        .split("<tr class=\"kind\">")
        .skip(1)
        .map(|r| {
            r.split("<td>")
                .nth(2)
                .unwrap()
                .trim_end_matches("</td>")
                .parse::<usize>()
                .unwrap()
        })
        .sum();
    assert_eq!(counted, variables);
    // The first rows of each kind, and no more.
    for k in 1..=LISTED_PER_KIND {
        assert_eq!(row(&html, &format!("node[{k}].x"))[1], "Output");
        assert_eq!(row(&html, &format!("cable[{k}].rest_length"))[2], "Tunable");
    }
    let beyond = LISTED_PER_KIND + 1;
    for name in [format!("node[{beyond}].x"), format!("bar[{beyond}].mass")] {
        assert!(
            !html.contains(&format!("<tr><td><code>{name}</code>")),
            "{name}"
        );
    }
    assert!(html.matches("<tr").count() < 150);
    // A small structure still lists every variable.
    let small = page(&builtin("tower20").unwrap());
    assert!(small.contains("<tr><td><code>node[61].x</code>"));
    assert!(!small.contains("class=\"kind\""));
}
