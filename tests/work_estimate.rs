//! A run's work is predicted before it starts: runs past 1e7 internal steps are refused
//! without `--force`, naming the element that sets the time scale and the remedies; the
//! built-in scenes are not refused and their predicted step counts are within 3× of the
//! counts they take; long runs show a progress bar with an ETA on stderr.

mod cli_support;
use cli_support::{run, temp};

use std::process::Command;

use tensegrity_fmu::scene::{extreme_scenes, Scene};
use tensegrity_fmu::{analysis, Simulation};

/// Writes `scene` as TOML into this test's temporary folder.
fn scene_file(scene: &Scene) -> String {
    let path = temp(&format!("{}.toml", scene.name));
    std::fs::write(&path, scene.to_toml_string()).unwrap();
    path.to_str().unwrap().to_owned()
}

/// The shipped scene files, fmu/scenes/*.toml.
fn shipped() -> Vec<String> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fmu/scenes");
    let mut files: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .map(|p| p.to_str().unwrap().to_owned())
        .collect();
    files.sort();
    assert!(files.len() >= 5, "{files:?}");
    files
}

#[test]
fn every_extreme_scene_is_refused_up_front_naming_its_element() {
    for extreme in extreme_scenes() {
        let file = scene_file(&extreme.scene);
        let csv = temp(&format!("{}.csv", extreme.scene.name));
        let started = std::time::Instant::now();
        let (ok, out, err) = run(&["simulate", &file, "-o", csv.to_str().unwrap()]);
        println!(
            "{} ({:.3} s): {err}",
            extreme.scene.name,
            started.elapsed().as_secs_f64()
        );
        assert!(!ok && out.is_empty(), "{err}");
        assert_eq!(err.lines().count(), 1, "one line: {err}");
        assert!(
            err.starts_with("error: simulate refused, no CSV written: this run would take about "),
            "{err}"
        );
        assert!(
            err.contains(extreme.key),
            "{} not named: {err}",
            extreme.key
        );
        for remedy in ["solver.method = \"sdirk3\"", "a softer element", "--force"] {
            assert!(err.contains(remedy), "{remedy}: {err}");
        }
        // The estimate it gives is past the limit.
        let at = err.find("about ").unwrap() + "about ".len();
        let steps: f64 = err[at..].split(' ').next().unwrap().parse().unwrap();
        assert!(steps > 1e7, "{err}");
        assert!(!csv.exists());
    }
}

#[test]
fn the_shipped_scenes_are_not_refused() {
    for file in shipped() {
        let csv = temp("shipped.csv");
        let (ok, _, err) = run(&["simulate", &file, "-o", csv.to_str().unwrap()]);
        assert!(ok, "{file}: {err}");
        assert!(!err.contains("refused"), "{file}: {err}");
    }
}

/// Predicted against taken internal steps (accepted and rejected) for a run to `stop`
/// with a row every `interval`, as `simulate` advances.
fn predicted_and_taken(scene: &Scene, stop: f64, interval: f64) -> (f64, u64) {
    let mut sim = Simulation::new(analysis::load(scene).unwrap());
    let predicted = sim.predict_work(stop, interval).steps;
    let rows = (stop / interval).round() as u64;
    for k in 1..=rows {
        sim.advance_to(k as f64 * interval).unwrap();
    }
    let stats = sim.stats();
    (predicted, stats.steps + stats.rejected)
}

#[test]
fn the_shipped_scenes_take_within_3x_of_the_predicted_steps() {
    for file in shipped() {
        let scene = Scene::from_name_or_file(&file).unwrap();
        let step = scene.solver.step_size;
        // simulate's default rows (every step), and rows far apart, where dopri5 picks
        // its own steps.
        for (stop, interval) in [(1.0, step), (1.0, 0.1), (2.0, 2.0)] {
            let (predicted, taken) = predicted_and_taken(&scene, stop, interval);
            let ratio = predicted / taken as f64;
            println!(
                "{} to {stop} s, rows every {interval} s: predicted {predicted}, took {taken} \
                 ({ratio:.2})",
                scene.name
            );
            assert!((1.0 / 3.0..=3.0).contains(&ratio), "{file}: {ratio}");
        }
    }
}

#[test]
fn force_runs_a_refused_scene() {
    // The damped cable's rate bounds dopri5's step from below: a short run is predicted
    // past 1e7 steps while it takes far fewer.
    let scene = extreme_scenes()
        .into_iter()
        .find(|e| e.scene.name == "huge-damping")
        .unwrap()
        .scene;
    let file = scene_file(&scene);
    let csv = temp("forced.csv");
    let args = ["simulate", &file, "--time", "1e-5", "--interval", "1e-5"];
    let out = ["-o", csv.to_str().unwrap()];
    let (ok, _, err) = run(&[&args[..], &out].concat());
    assert!(!ok && err.contains("cables[7].damping"), "{err}");
    assert!(!csv.exists());
    let (ok, _, err) = run(&[&args[..], &out, &["--force"]].concat());
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(text.lines().count(), 3, "header and rows at 0 and 1e-5 s");
}

#[test]
fn render_is_refused_too() {
    let scene = extreme_scenes().remove(1).scene;
    assert_eq!(scene.name, "heavy-gravity");
    let gif = temp("heavy.gif");
    let (ok, _, err) = run(&["render", &scene_file(&scene), "-o", gif.to_str().unwrap()]);
    assert!(!ok, "{err}");
    assert!(
        err.starts_with("error: render refused, nothing drawn: "),
        "{err}"
    );
    assert!(err.contains("the gravity, |gravity| = 1e15 m/s²"), "{err}");
    assert!(!gif.exists());
}

/// `simulate` with `TENSEGRITY_FMU_PROGRESS` set to `setting` (unset for `None`):
/// (stdout, stderr).
fn with_progress(setting: Option<&str>) -> (String, String) {
    let csv = temp(&format!("progress-{}.csv", setting.unwrap_or("auto")));
    let mut command = Command::new(env!("CARGO_BIN_EXE_tensegrity-fmu"));
    command.args(["simulate", "tower20", "--time", "0.5", "-o"]);
    command.arg(&csv).env_remove("TENSEGRITY_FMU_PROGRESS");
    if let Some(s) = setting {
        command.env("TENSEGRITY_FMU_PROGRESS", s);
    }
    let out = command.output().unwrap();
    assert!(out.status.success());
    let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    (text(&out.stdout), text(&out.stderr))
}

#[test]
fn the_progress_bar_goes_to_stderr_only() {
    let (out, err) = with_progress(Some("always"));
    println!("{err:?}");
    assert_eq!(out.lines().count(), 1, "only the CSV's path: {out}");
    assert!(err.contains("% of 0.5 s simulated"), "{err:?}");
    assert!(err.contains("elapsed, ETA "), "{err:?}");
    // Not a terminal, and a short run: no bar by default.
    let (_, err) = with_progress(None);
    assert!(!err.contains("ETA"), "{err:?}");
}

#[test]
fn a_fixed_step_run_past_the_limit_names_the_step() {
    // 2 s at 1e-7 s: exactly 2e7 rk4 steps.
    let csv = temp("fixed.csv");
    let args = [
        "simulate",
        "prism2-elastic",
        "--method",
        "rk4",
        "--step-size",
        "1e-7",
    ];
    let rows = [
        "--time",
        "2",
        "--interval",
        "0.005",
        "-o",
        csv.to_str().unwrap(),
    ];
    let (ok, _, err) = run(&[&args[..], &rows].concat());
    println!("{err}");
    assert!(!ok);
    assert!(
        err.contains("about 2.00e7 internal steps")
            && err.contains("rk4 takes fixed steps of solver.step_size = 0.0000001 s"),
        "{err}"
    );
    assert!(err.contains("--force"), "{err}");
    assert!(!csv.exists());
}
