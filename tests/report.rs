//! The accuracy report on prism2: its CSV has the promised columns and finite values, the
//! errors fall with cost on each method's curve, the correction holds the constraints, and
//! both figures are real PNGs. Wall times are not asserted.

use std::path::PathBuf;

use tensegrity_fmu::integrator::Method;
use tensegrity_fmu::report::{self, Options, COLUMNS};
use tensegrity_fmu::scene::builtin;
use tensegrity_fmu::{Model, Simulation};

struct Row {
    method: String,
    setting: f64,
    correction: bool,
    status: String,
    /// wall time, position, length, orthogonality, energy drift, evaluations.
    figures: Option<[f64; 6]>,
}

fn parse(csv: &str) -> (Vec<String>, Vec<Row>) {
    let mut lines = csv.lines();
    let header = lines
        .next()
        .expect("a header")
        .split(',')
        .map(String::from)
        .collect();
    let rows = lines
        .map(|line| {
            let cells: Vec<&str> = line.split(',').collect();
            assert_eq!(cells.len(), COLUMNS.len(), "row {line}");
            let number = |s: &str| -> f64 {
                let x: f64 = s
                    .parse()
                    .unwrap_or_else(|_| panic!("not a number: {s:?} in {line}"));
                assert!(x.is_finite(), "non-finite value in {line}");
                x
            };
            let figures = match cells[3] {
                "ok" => {
                    let v: Vec<f64> = cells[4..].iter().map(|s| number(s)).collect();
                    Some(v.try_into().expect("six figures"))
                }
                "failed" => {
                    assert!(cells[4..].iter().all(|s| s.is_empty()), "failed row {line}");
                    None
                }
                other => panic!("unknown status {other}"),
            };
            Row {
                method: cells[0].to_string(),
                setting: number(cells[1]),
                correction: match cells[2] {
                    "on" => true,
                    "off" => false,
                    other => panic!("correction {other}"),
                },
                status: cells[3].to_string(),
                figures,
            }
        })
        .collect();
    (header, rows)
}

fn assert_png(path: &PathBuf) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(
        bytes.starts_with(b"\x89PNG\r\n\x1a\n"),
        "{} is not a PNG",
        path.display()
    );
    assert!(
        bytes.len() > 10_000,
        "{} has only {} bytes",
        path.display(),
        bytes.len()
    );
}

#[test]
fn prism2_accuracy_report() {
    let dir = std::env::temp_dir().join(format!("tensegrity-report-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let scene = builtin("prism2").unwrap();
    let r = report::accuracy(&scene, &Options::default(), &dir).expect("the report runs");
    println!("{}", r.markdown);
    assert!(r.markdown.contains("Convergence check"));
    assert!(r.markdown.contains("| target (m) |"));
    let reference = r.reference.max_difference_m;
    assert!(
        reference.is_finite() && reference < 1e-9,
        "reference check {reference}"
    );

    let (header, rows) = parse(&std::fs::read_to_string(&r.csv).unwrap());
    assert_eq!(header, COLUMNS);
    assert_eq!(rows.len(), r.runs.len(), "a row per run");
    for method in ["rk4", "rattle", "sdirk3", "dopri5"] {
        for on in [true, false] {
            let n = rows
                .iter()
                .filter(|x| x.method == method && x.correction == on)
                .count();
            assert!(n >= 4, "{method} correction {on}: {n} runs");
        }
    }
    for row in rows.iter().filter(|x| x.correction) {
        assert_eq!(row.status, "ok", "{} {} failed", row.method, row.setting);
        let [_, _, length, ..] = row.figures.unwrap();
        assert!(
            length <= 1e-12,
            "{} {}: length error {length}",
            row.method,
            row.setting
        );
    }

    // Each curve, by cost: errors fall while they are well above the reference's own
    // error; near it, a factor 2 of noise is allowed.
    for method in ["rk4", "rattle", "sdirk3", "dopri5"] {
        let mut curve: Vec<[f64; 6]> = rows
            .iter()
            .filter(|x| x.method == method && x.correction)
            .map(|x| x.figures.unwrap())
            .collect();
        curve.sort_by(|a, b| a[5].total_cmp(&b[5]));
        let errors: Vec<f64> = curve.iter().map(|f| f[1]).collect();
        let shown: Vec<String> = errors.iter().map(|e| format!("{e:.2e}")).collect();
        println!("{method}: errors by cost {shown:?}");
        for w in curve.windows(2) {
            let (cheap, dear) = (w[0][1], w[1][1]);
            if cheap > 100.0 * reference {
                assert!(
                    dear <= cheap,
                    "{method}: error rose from {cheap:e} to {dear:e}"
                );
            } else {
                assert!(
                    dear <= 2.0 * cheap,
                    "{method}: error rose from {cheap:e} to {dear:e}"
                );
            }
        }
        assert!(
            errors.last() < errors.first(),
            "{method}: no gain from cost"
        );
    }

    // Without the correction, RK4 at its largest step leaves the constraints.
    let coarsest = rows
        .iter()
        .filter(|x| x.method == "rk4" && !x.correction)
        .max_by(|a, b| a.setting.total_cmp(&b.setting))
        .unwrap();
    let [_, _, length, ..] = coarsest.figures.expect("rk4 without correction ran");
    println!(
        "rk4 h = {} s without correction: length error {length:e} m",
        coarsest.setting
    );
    assert!(length > 1e-12, "length error {length}");

    assert_png(r.work_precision.as_ref().expect("drawn"));
    assert_png(r.constraint_error.as_ref().expect("drawn"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A short report with one step per fixed-step method and one dopri5 tolerance.
fn short_report(scene: &tensegrity_fmu::scene::Scene, name: &str) -> report::Report {
    let dir = std::env::temp_dir().join(format!("tensegrity-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let options = Options {
        horizon: 0.2,
        fixed_steps: 2,
        dopri5_tols: vec![1e-6],
        min_repeats: 1,
        min_timing_s: 0.0,
        ..Options::default()
    };
    let r = report::accuracy(scene, &options, &dir).expect("the report runs");
    let _ = std::fs::remove_dir_all(&dir);
    r
}

/// Steel-stiff cables (κ = 1e6 N/m, 100 N prestress): rk4's sweep starts at the largest
/// step that divides the 10 ms output interval and is stable for this scene: that step
/// runs, the next larger one is refused by the stability guard, and no run fails.
#[test]
fn fixed_step_sweeps_start_at_the_scenes_stability_limit() {
    let mut scene = builtin("prism2-elastic").unwrap();
    for c in &mut scene.cables {
        c.stiffness = Some(1e6);
    }
    scene.prestress = Some(tensegrity_fmu::scene::PrestressSpec { min_tension: 100.0 });
    let r = short_report(&scene, "limit");
    let first = |m: Method| {
        r.runs
            .iter()
            .filter(|x| x.method == m)
            .map(|x| x.setting)
            .fold(0.0, f64::max)
    };
    let h = first(Method::Rk4);
    let parts = (0.01 / h).round();
    assert!((0.01 / parts - h).abs() < 1e-15, "{h} divides the interval");
    assert!(parts > 1.0, "the 10 ms interval is above rk4's limit here");
    let refused = |h: f64| {
        let mut s = scene.clone();
        s.solver.method = Method::Rk4;
        s.solver.step_size = h;
        Simulation::new(Model::new(&s).unwrap()).stability_problem()
    };
    assert_eq!(refused(h), None, "h = {h} s is stable");
    let larger = 0.01 / (parts - 1.0);
    assert!(refused(larger).is_some(), "h = {larger} s is refused");
    assert!(r.runs.iter().all(|x| x.result.is_ok()), "{}", r.markdown);
    // sdirk3, stable at any step, starts at the output interval.
    assert_eq!(first(Method::Sdirk3), 0.01);
    assert!(!r.markdown.contains("Failed:"), "{}", r.markdown);
    println!("rk4 starts at h = {h} s (10 ms / {parts})");
}

/// The energy column says which terms its E leaves out: none for a conservative scene,
/// cable damping and the scripted loads' work where a scene has them.
#[test]
fn energy_column_names_what_it_leaves_out() {
    let plain = short_report(&builtin("prism2").unwrap(), "plain");
    assert!(
        plain.markdown.contains("the exact solution conserves it"),
        "{}",
        plain.markdown
    );
    let mut damped = builtin("prism2-elastic").unwrap();
    damped.cables[0].damping = Some(2.0);
    damped.loads = vec![tensegrity_fmu::scene::LoadSpec::Sinusoidal {
        node: 7,
        amplitude: [1.0, 0.0, 0.0],
        frequency: 1.0,
        phase: 0.0,
    }];
    let r = short_report(&damped, "damped");
    assert!(
        r.markdown
            .contains("it leaves out cable damping losses, the work of the scripted loads"),
        "{}",
        r.markdown
    );
}

#[test]
fn sampling_between_steps_does_not_count_as_the_methods_work() {
    // The report refreshes at each output to sample; a step right after a refresh could
    // take it as its first stage, which would hide a quarter of rk4's work at a step as
    // long as the output interval. Every step must evaluate its start itself.
    let r = short_report(&builtin("prism2").unwrap(), "sampling");
    let mut checked = 0;
    for run in r
        .runs
        .iter()
        .filter(|x| x.method == Method::Rk4 && x.correction)
    {
        let m = run.result.as_ref().expect("rk4 runs");
        let steps = (r.horizon / run.setting).round() as u64;
        println!(
            "rk4 h = {}: {} evaluations, {steps} steps",
            run.setting, m.rhs_evaluations
        );
        // The first step may take the evaluation that ends the stability check, which
        // runs inside the timed advance (its power iteration is not counted either).
        assert!(
            m.rhs_evaluations + 1 >= 4 * steps,
            "h = {}: {} evaluations for {steps} steps",
            run.setting,
            m.rhs_evaluations
        );
        checked += 1;
    }
    assert!(checked >= 2, "{checked} rk4 runs");
}
