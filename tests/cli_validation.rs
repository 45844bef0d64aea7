//! Data a user hands in: a CSV to draw that diverged or whose times stand still, a scene
//! named outside ASCII, and a bug (a panic), which must read as one line, not a backtrace.

mod cli_support;
use cli_support::{run, temp};

use std::path::Path;
use std::process::Command;

/// A CSV of prism2 from `simulate`, as lines.
fn prism2_csv(name: &str) -> Vec<String> {
    let csv = temp(name);
    let (ok, _, err) = run(&[
        "simulate",
        "prism2",
        "--time",
        "0.05",
        "--interval",
        "0.01",
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    std::fs::read_to_string(&csv)
        .unwrap()
        .lines()
        .map(String::from)
        .collect()
}

/// `render --csv` of `lines`: (success, stderr); no picture may appear on failure.
fn render_csv(name: &str, lines: &[String]) -> (bool, String) {
    let csv = temp(name);
    std::fs::write(&csv, lines.join("\n") + "\n").unwrap();
    let png = temp(&format!("{name}.png"));
    let (ok, _, err) = run(&[
        "render",
        "prism2",
        "--csv",
        csv.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(ok, png.exists(), "{err}");
    (ok, err)
}

/// Sets cell `column` of line `line` (0 = the header) to `value`.
fn set(lines: &mut [String], line: usize, column: usize, value: &str) {
    let mut cells: Vec<&str> = lines[line].split(',').collect();
    cells[column] = value;
    lines[line] = cells.join(",");
}

#[test]
fn render_csv_refuses_non_finite_values_naming_line_and_column() {
    let lines = prism2_csv("finite.csv");
    assert!(
        render_csv("finite-ok.csv", &lines).0,
        "the CSV as written draws"
    );
    let header: Vec<&str> = lines[0].split(',').collect();
    let x4 = header.iter().position(|&c| c == "node[4].x").unwrap();
    let tension = header
        .iter()
        .position(|&c| c == "cable[2].tension")
        .unwrap();
    for (column, value, line) in [
        (x4, "NaN", 3),
        (x4, "inf", 2),
        (tension, "-inf", 5),
        (0, "NaN", 1),
    ] {
        let mut bad = lines.clone();
        set(&mut bad, line, column, value);
        let (ok, err) = render_csv("finite-bad.csv", &bad);
        assert!(!ok);
        assert_eq!(err.lines().count(), 1, "{err}");
        let expected = format!(
            "line {}: column `{}`: {} is not a finite number",
            line + 1,
            header[column],
            value.parse::<f64>().unwrap()
        );
        assert!(err.contains(&expected), "{err}\nexpected: {expected}");
    }
}

#[test]
fn render_csv_refuses_times_that_do_not_increase_strictly() {
    let lines = prism2_csv("times.csv");
    let mut zeros = lines.clone();
    for line in 1..zeros.len() {
        set(&mut zeros, line, 0, "0");
    }
    let mut back = lines.clone();
    set(&mut back, 4, 0, "0.015");
    let mut repeated = lines.clone();
    set(&mut repeated, 3, 0, "0.01");
    for (bad, line, t, previous) in [
        (zeros, 3, "0", "0"),
        (back, 5, "0.015", "0.02"),
        (repeated, 4, "0.01", "0.01"),
    ] {
        let (ok, err) = render_csv("times-bad.csv", &bad);
        assert!(!ok);
        assert_eq!(err.lines().count(), 1, "{err}");
        let expected = format!(
            "line {line}: column `time`: {t} does not come after the previous row's {previous}"
        );
        assert!(err.contains(&expected), "{err}\nexpected: {expected}");
    }
}

const NAME: &str = "Prisme à ressorts — 張力";

/// prism2 renamed [`NAME`], as a scene file in its own folder.
fn unicode_scene(folder: &str) -> (std::path::PathBuf, std::path::PathBuf) {
    let dir = temp(folder);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let (ok, toml, _) = run(&["scene", "prism2"]);
    assert!(ok);
    let renamed = toml.replacen("name = \"prism2\"", &format!("name = \"{NAME}\""), 1);
    assert_ne!(renamed, toml);
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, renamed).unwrap();
    (dir, scene)
}

fn run_in(dir: &Path, args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_tensegrity-fmu"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    (out.status.success(), err)
}

#[test]
fn a_scene_named_outside_ascii_writes_every_format() {
    let (dir, scene) = unicode_scene("unicode");
    let scene = scene.to_str().unwrap();
    // The default output is named after the scene.
    let (ok, err) = run_in(&dir, &["simulate", scene, "--time", "0.05"]);
    assert!(ok, "{err}");
    let csv = std::fs::read_to_string(dir.join(format!("{NAME}.csv"))).unwrap();
    assert_eq!(csv.lines().count(), 52, "a header and 51 rows");
    for out in ["a.png", "a.gif", "a.html", "a.pvd"] {
        let (ok, err) = run_in(&dir, &["render", scene, "--time", "0.02", "-o", out]);
        assert!(ok, "{out}: {err}");
    }
    let html = std::fs::read_to_string(dir.join("a.html")).unwrap();
    assert!(html.contains(NAME), "the page names the scene");
    for out in ["a.json", "a.npz", "a.mat"] {
        let (ok, err) = run_in(&dir, &["linearize", scene, "-o", out]);
        assert!(ok, "{out}: {err}");
    }
    let json = std::fs::read_to_string(dir.join("a.json")).unwrap();
    assert!(json.contains(&format!("\"scene\": \"{NAME}\"")));
    let mat = matrw::load_matfile(dir.join("a.mat").to_str().unwrap()).unwrap();
    let text: String = mat["scene"].to_vec::<char>().unwrap().into_iter().collect();
    assert_eq!(text, "Prisme ? ressorts ? ??", "MAT text is ASCII");
    let (ok, err) = run_in(&dir, &["modes", scene, "-o", "shapes.csv"]);
    assert!(ok, "{err}");
    let (ok, err) = run_in(&dir, &["build", scene, "-o", "a.fmu"]);
    assert!(ok, "{err}");
    let fmu = zip::ZipArchive::new(std::fs::File::open(dir.join("a.fmu")).unwrap()).unwrap();
    assert!(fmu.len() > 3);
    let mut made: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    made.sort();
    let expected = [
        format!("{NAME}.csv"),
        "a.fmu".into(),
        "a.gif".into(),
        "a.html".into(),
        "a.json".into(),
        "a.mat".into(),
        "a.npz".into(),
        "a.png".into(),
        "a.pvd".into(),
        "a_vtp".into(),
        "scene.toml".into(),
        "shapes.csv".into(),
    ];
    let mut expected = expected.to_vec();
    expected.sort();
    assert_eq!(made, expected);
}

#[test]
fn a_panic_is_one_line_that_calls_it_a_bug_and_leaves_no_temporary() {
    let dir = temp("panic");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("out.csv"), "old\n").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_tensegrity-fmu"))
        .args(["simulate", "prism2", "-o", "out.csv"])
        .current_dir(&dir)
        .env("TENSEGRITY_FMU_TEST_PANIC", "1")
        .env("RUST_BACKTRACE", "1")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(101));
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with("error: internal error, a bug in tensegrity-fmu")
            && err.contains("deliberate panic")
            && err.contains("src/cli/simulate.rs:")
            && err.contains("please report it"),
        "{err}"
    );
    assert!(
        !err.contains("backtrace") && !err.contains("panicked"),
        "{err}"
    );
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert_eq!(left.len(), 1, "only out.csv");
    assert_eq!(
        std::fs::read_to_string(dir.join("out.csv")).unwrap(),
        "old\n"
    );
}
