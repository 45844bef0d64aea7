//! What importers read from the generated modelDescription.xml (issue 10, items 6–9):
//! metadata, the `rad` base unit, the default experiment, Integer solver settings,
//! tunable parameters and ModelStructure dependencies. The XML is parsed with quick-xml.

use std::collections::HashMap;

use quick_xml::events::Event;
use quick_xml::{Reader, XmlVersion};
use tensegrity_fmu::fmi::description::iso8601_utc;
use tensegrity_fmu::fmi::package::{build_fmu, golden_model_description};
use tensegrity_fmu::scene::{builtin, Scene};

/// Elements in document order: name and attributes.
type Element = (String, HashMap<String, String>);

fn elements(xml: &str) -> Vec<Element> {
    let mut reader = Reader::from_str(xml);
    let mut out = Vec::new();
    loop {
        match reader.read_event().expect("well-formed XML") {
            Event::Start(e) | Event::Empty(e) => {
                let attrs = e
                    .attributes()
                    .map(|a| {
                        let a = a.unwrap();
                        let key = a.key.as_ref().to_string();
                        let value = a.normalized_value(XmlVersion::Implicit1_0).unwrap();
                        (key, value.into_owned())
                    })
                    .collect();
                out.push((e.name().as_ref().to_string(), attrs));
            }
            Event::Eof => break,
            _ => {}
        }
    }
    out
}

fn first<'a>(els: &'a [Element], name: &str) -> &'a HashMap<String, String> {
    &els.iter().find(|(n, _)| n == name).unwrap().1
}

/// `(attributes of ScalarVariable, its type element)` by variable name.
fn variables(els: &[Element]) -> HashMap<String, (HashMap<String, String>, Element)> {
    let mut out = HashMap::new();
    for (i, (n, a)) in els.iter().enumerate() {
        if n == "ScalarVariable" {
            out.insert(a["name"].clone(), (a.clone(), els[i + 1].clone()));
        }
    }
    out
}

/// Variable names in ModelVariables order (index i + 1).
fn names(els: &[Element]) -> Vec<String> {
    els.iter()
        .filter(|(n, _)| n == "ScalarVariable")
        .map(|(_, a)| a["name"].clone())
        .collect()
}

/// `{output name: dependency names}` of `<Outputs>` or `<InitialUnknowns>`.
fn dependencies(els: &[Element], list: &str) -> HashMap<String, Vec<String>> {
    let names = names(els);
    let start = els.iter().position(|(n, _)| n == list).unwrap();
    els[start + 1..]
        .iter()
        .take_while(|(n, _)| n == "Unknown")
        .map(|(_, a)| {
            let name = names[a["index"].parse::<usize>().unwrap() - 1].clone();
            let deps = a["dependencies"]
                .split_whitespace()
                .map(|i| names[i.parse::<usize>().unwrap() - 1].clone())
                .collect();
            (name, deps)
        })
        .collect()
}

fn golden(name: &str) -> Vec<Element> {
    elements(&golden_model_description(&builtin(name).unwrap()).unwrap())
}

/// prism2-elastic with a sinusoidal load, gravity, a point mass and a ground plane.
fn every_effect(step_size: f64) -> Scene {
    let mut text = builtin("prism2-elastic").unwrap().to_toml_string();
    text = text.replacen(
        "[[bars]]",
        "gravity = [0.0, 0.0, -9.81]\n\n[[loads]]\nkind = \"sinusoidal\"\nnode = 7\namplitude = [1.0, 0.0, 0.0]\nfrequency = 2.0\nphase = 0.5\n\n[[point_masses]]\nnode = 8\nmass = 0.25\n\n[ground]\nheight = -1.0\nstiffness = 1000.0\n\n[[bars]]",
        1,
    );
    let mut scene = Scene::from_toml_str(&text).unwrap();
    scene.solver.step_size = step_size;
    scene
}

#[test]
fn root_names_version_license_tool_and_date() {
    let els = golden("prism2");
    let root = first(&els, "fmiModelDescription");
    assert_eq!(root["version"], "0.1.0");
    assert_eq!(root["license"], "MIT OR Apache-2.0");
    assert_eq!(root["author"], "the tensegrity-fmu developers");
    assert!(root["copyright"].contains("the tensegrity-fmu developers"));
    // The golden text holds placeholders for what varies from build to build.
    assert_eq!(root["generationTool"], "tensegrity-fmu 0.1.0 (git 0000000)");
    assert_eq!(root["generationDateAndTime"], "1970-01-01T00:00:00Z");
}

#[test]
fn iso8601_dates_in_utc() {
    assert_eq!(iso8601_utc(0), "1970-01-01T00:00:00Z");
    // A hostile SOURCE_DATE_EPOCH is clamped instead of panicking.
    assert_eq!(iso8601_utc(i64::MAX), "9999-12-31T23:59:59Z");
    assert_eq!(iso8601_utc(-5), "1970-01-01T00:00:00Z");
    // `date -u -d @951782400`, a leap day, and `date -u -d @1700000000`.
    assert_eq!(iso8601_utc(951_782_400), "2000-02-29T00:00:00Z");
    assert_eq!(iso8601_utc(1_700_000_000), "2023-11-14T22:13:20Z");
    assert_eq!(iso8601_utc(4_107_542_399), "2100-02-28T23:59:59Z");
}

#[test]
fn packaged_fmu_names_the_commit_and_source_date_epoch() {
    let dir = std::env::temp_dir().join(format!("tensegrity-md-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // build_fmu only checks that the binary carries this build's id.
    let binary = dir.join("binary.so");
    std::fs::write(&binary, tensegrity_fmu::fmi::BUILD_ID).unwrap();
    let out = dir.join("prism2.fmu");
    // This is the only test in this file that reads the environment.
    std::env::set_var("SOURCE_DATE_EPOCH", "1700000000");
    build_fmu(&builtin("prism2").unwrap(), &binary, &out).unwrap();
    std::env::remove_var("SOURCE_DATE_EPOCH");
    let mut zip = zip::ZipArchive::new(std::fs::File::open(&out).unwrap()).unwrap();
    let mut xml = String::new();
    std::io::Read::read_to_string(&mut zip.by_name("modelDescription.xml").unwrap(), &mut xml)
        .unwrap();
    let els = elements(&xml);
    let root = first(&els, "fmiModelDescription");
    assert_eq!(root["generationDateAndTime"], "2023-11-14T22:13:20Z");
    let git = std::process::Command::new("git")
        .args(["rev-parse", "--short", "HEAD"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    let commit = String::from_utf8(git.stdout).unwrap().trim().to_string();
    let tool = &root["generationTool"];
    assert!(
        tool.starts_with(&format!("tensegrity-fmu 0.1.0 (git {commit}")),
        "{tool} does not name HEAD {commit}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn rad_has_its_base_unit() {
    let xml = golden_model_description(&every_effect(1e-3)).unwrap();
    assert!(
        xml.contains("<Unit name=\"rad\">\n      <BaseUnit rad=\"1\"/>\n    </Unit>"),
        "{xml}"
    );
    let els = elements(&xml);
    assert_eq!(variables(&els)["load[1].phase"].1 .1["unit"], "rad");
}

#[test]
fn default_experiment_reports_every_10_ms_or_ten_internal_steps() {
    let els = golden("prism2");
    let exp = first(&els, "DefaultExperiment");
    assert_eq!(exp["startTime"], "0");
    assert_eq!(exp["stopTime"], "1");
    assert_eq!(exp["stepSize"], "0.01");
    let els = elements(&golden_model_description(&every_effect(0.005)).unwrap());
    assert_eq!(first(&els, "DefaultExperiment")["stepSize"], "0.05");
}

#[test]
fn solver_method_and_max_steps_are_integers() {
    let els = golden("prism2");
    assert!(els.iter().all(|(n, _)| n != "TypeDefinitions"));
    let vars = variables(&els);
    let (method, (kind, t)) = &vars["solver.method"];
    assert_eq!(kind, "Integer");
    assert_eq!(
        (t["start"].as_str(), t["min"].as_str(), t["max"].as_str()),
        ("2", "1", "4")
    );
    assert!(method["description"].contains("1 = rk4, 2 = dopri5"));
    let (steps, (kind, t)) = &vars["solver.max_steps"];
    assert_eq!(kind, "Integer");
    assert_eq!((t["start"].as_str(), t["min"].as_str()), ("100000", "1"));
    assert_eq!(steps["causality"], "parameter");
    assert!(steps["description"].contains("fmi2DoStep"));
}

#[test]
fn tunable_and_fixed_parameters() {
    let els = elements(&golden_model_description(&every_effect(1e-3)).unwrap());
    let vars = variables(&els);
    let fixed = [
        "solver.step_size",
        "solver.method",
        "solver.correction",
        "solver.locate_events",
    ];
    let mut tunable = vec![
        "solver.max_steps".to_string(),
        "solver.rtol".into(),
        "solver.atol".into(),
        "point_mass[1].mass".into(),
        "load[1].fx".into(),
        "load[1].fy".into(),
        "load[1].fz".into(),
        "load[1].frequency".into(),
        "load[1].phase".into(),
    ];
    for field in [
        "height",
        "stiffness",
        "damping",
        "friction",
        "slip_velocity",
    ] {
        tunable.push(format!("ground.{field}"));
    }
    for axis in ["x", "y", "z"] {
        tunable.push(format!("gravity.{axis}"));
    }
    for k in 1..=6 {
        tunable.push(format!("bar[{k}].mass"));
    }
    for j in 1..=15 {
        tunable.push(format!("cable[{j}].stiffness"));
        tunable.push(format!("cable[{j}].rest_length"));
    }
    let parameters: Vec<&String> = vars
        .iter()
        .filter(|(_, (a, _))| a["causality"] == "parameter")
        .map(|(n, _)| n)
        .collect();
    assert_eq!(parameters.len(), fixed.len() + tunable.len());
    for name in fixed {
        assert_eq!(vars[name].0["variability"], "fixed", "{name}");
    }
    for name in &tunable {
        let (a, _) = &vars[name];
        assert_eq!(a["variability"], "tunable", "{name}");
        assert_eq!(a["initial"], "exact", "{name}");
    }
}

#[test]
fn outputs_depend_on_the_inputs_they_read() {
    let els = golden("prism2");
    let deps = dependencies(&els, "Outputs");
    // All 15 cables are controlled; nodes 7–9 have force inputs.
    assert!(deps["node[7].x"].is_empty() && deps["node[9].vz"].is_empty());
    assert!(deps["constraint.length_error"].is_empty());
    assert_eq!(deps["cable[4].tension"], ["cable[4].force_density"]);
    let energy = &deps["energy.total"];
    assert_eq!(energy.len(), 15);
    assert!(energy.iter().all(|d| d.ends_with(".force_density")));
    let unknowns = els.iter().filter(|(n, _)| n == "Unknown");
    for (_, a) in unknowns {
        let n = a["dependencies"].split_whitespace().count();
        match a.get("dependenciesKind") {
            Some(kinds) => assert_eq!(kinds.split(' ').collect::<Vec<_>>(), vec!["dependent"; n]),
            None => assert_eq!(n, 0),
        }
    }
}

#[test]
fn initial_unknowns_add_the_parameters_they_read() {
    let els = golden("prism2-elastic");
    let outputs = dependencies(&els, "Outputs");
    let initial = dependencies(&els, "InitialUnknowns");
    assert_eq!(outputs.len(), initial.len());
    // An elastic cable's tension reads its own law, never an input.
    assert!(outputs["cable[3].tension"].is_empty());
    assert_eq!(
        initial["cable[3].tension"],
        ["cable[3].stiffness", "cable[3].rest_length"]
    );
    assert!(initial["node[4].z"].is_empty());
    // Energy: every mass (kinetic) and every cable law, never a solver setting.
    let energy = &initial["energy.total"];
    assert_eq!(energy.iter().filter(|d| d.ends_with(".mass")).count(), 6);
    assert_eq!(
        energy.iter().filter(|d| d.starts_with("cable[")).count(),
        30
    );
    assert!(energy.iter().all(|d| !d.starts_with("solver.")));
}
