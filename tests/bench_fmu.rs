//! `tensegrity-fmu bench fmu`: one row per tower size, whose counts and sizes are those of
//! the FMU `build` writes for that tower; bar counts that are no tower's are refused.

use std::process::Command;

use tensegrity_fmu::fmi::package::golden_model_description;
use tensegrity_fmu::fmi::variables::VariableTable;
use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::scene::tower_with_rest_lengths;
use tensegrity_fmu::{Model, Simulation};

fn bench(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_tensegrity-fmu"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["bench", "fmu"])
        .args(args)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn inputs_keeps_the_three_top_forces() {
    let (ok, stdout, stderr) = bench(&["--bars", "6", "--inputs"]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("force inputs on the top ring"), "{stdout}");
    let row = stdout.lines().find(|l| l.starts_with("| 6 |")).unwrap();
    let mut scene = tower_with_rest_lengths(2, "tower6");
    scene.solver.method = Method::Rk4;
    let sim = Simulation::new(Model::new(&scene).unwrap());
    let variables = VariableTable::new(&sim).variables.len();
    assert_eq!(row.split('|').nth(2).unwrap().trim(), variables.to_string());
    assert_eq!(scene.force_inputs.len(), 3);
}

#[test]
fn one_row_per_size_with_the_fmus_counts() {
    let (ok, stdout, stderr) = bench(&["--bars", "6,60"]);
    assert!(ok, "{stderr}");
    let rows: Vec<Vec<&str>> = stdout
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| bars"))
        .map(|l| l.trim_matches('|').split('|').map(str::trim).collect())
        .collect();
    assert_eq!(rows.len(), 2, "{stdout}");
    let mut xml_mb = Vec::new();
    for (row, bars) in rows.iter().zip([6usize, 60]) {
        assert_eq!(row[0], bars.to_string());
        let mut scene = tower_with_rest_lengths(bars / 3, &format!("tower{bars}"));
        scene.force_inputs.clear();
        scene.solver.method = Method::Rk4;
        scene.solver.step_size = 1e-3;
        let sim = Simulation::new(Model::new(&scene).unwrap());
        assert_eq!(row[1], VariableTable::new(&sim).variables.len().to_string());
        let number = |k: usize| row[k].split(' ').next().unwrap().parse::<f64>().unwrap();
        // modelDescription.xml as `golden` writes it (only the GUID, commit and date differ)
        let xml = golden_model_description(&scene).unwrap().len() as f64 / 1e6;
        assert!(
            (number(2) - xml).abs() <= 0.006,
            "{} MB, not {xml} MB",
            number(2)
        );
        assert!(number(3) > 1.0, "the .fmu holds the 3.8 MB binary: {row:?}");
        // build, read, initialize, two doSteps
        assert!((4..=8).all(|k| number(k) >= 0.0), "{row:?}");
        assert!(row[8].ends_with("(step 0.01 s)"), "{row:?}");
        xml_mb.push(number(2));
    }
    assert!(xml_mb[1] > 5.0 * xml_mb[0], "{xml_mb:?}");
}

#[test]
fn bar_counts_must_be_towers() {
    let (ok, _, stderr) = bench(&["--bars", "60,61"]);
    assert!(!ok);
    assert!(
        stderr.contains("--bars 61: a tower has 3 bars per stage"),
        "{stderr}"
    );
    let (ok, _, stderr) = bench(&["--bars", "60", "--python", "/nonexistent/python"]);
    assert!(!ok);
    assert!(
        stderr.contains("--python /nonexistent/python: no such program"),
        "{stderr}"
    );
}
