//! `bench effects` runs its three cases and reports each one's pipeline. This checks the
//! table, not the timings: the figures vary with the machine's load.

use std::process::Command;

/// The optional effects: none may appear in the base case's pipeline.
const OPTIONAL: [&str; 7] = [
    "Gravity",
    "DampedCables",
    "ForceDensityCables",
    "ReeledCables",
    "NodeForces",
    "ScriptedLoads",
    "GroundContact",
];

#[test]
fn bench_effects_prints_three_cases_and_their_pipelines() {
    let out = Command::new(env!("CARGO_BIN_EXE_tensegrity-fmu"))
        .args(["bench", "effects", "--seconds", "0.001", "--repeats", "1"])
        .output()
        .expect("the CLI runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let row = |case: &str| -> Vec<String> {
        let prefix = format!("| {case} |");
        let line = stdout
            .lines()
            .find(|l| l.starts_with(&prefix))
            .unwrap_or_else(|| panic!("no row for {case} in:\n{stdout}"));
        line.trim_matches('|')
            .split('|')
            .map(|cell| cell.trim().to_string())
            .collect()
    };
    let mut base_us = f64::NAN;
    for case in ["base", "declared-zero", "active"] {
        let cells = row(case);
        assert_eq!(cells.len(), 7, "{cells:?}");
        let number = |k: usize| -> f64 {
            cells[k]
                .parse()
                .unwrap_or_else(|_| panic!("{case}: column {k} is not a number: {cells:?}"))
        };
        let (us, ratio, steps, forces) = (number(1), number(2), number(3), number(4));
        for (what, v) in [
            ("µs/step", us),
            ("ratio", ratio),
            ("steps", steps),
            ("force stage µs/eval", forces),
        ] {
            assert!(v.is_finite() && v > 0.0, "{case}: {what} = {v}");
        }
        if case == "base" {
            base_us = us;
            assert_eq!(cells[2], "1.00");
        } else {
            // The printed ratio is the printed times' ratio (to their rounding).
            assert!(
                (ratio - us / base_us).abs() < 0.01 + 0.1 / base_us,
                "{cells:?}"
            );
        }
        let displacement = number(5);
        let pipeline = &cells[6];
        assert!(pipeline.contains("JointsAndPins"), "{case}: {pipeline}");
        if case == "base" {
            assert!(pipeline.contains("ElasticCables"), "{pipeline}");
            for effect in OPTIONAL {
                assert!(!pipeline.contains(effect), "base has {effect}: {pipeline}");
            }
            assert!(displacement < 1e-9, "base moved {displacement} m");
        } else {
            for effect in OPTIONAL {
                assert!(
                    pipeline.contains(effect),
                    "{case} lacks {effect}: {pipeline}"
                );
            }
        }
        match case {
            // Declared at zero, the effects change nothing: the tower stays at equilibrium.
            "declared-zero" => assert!(displacement < 1e-9, "moved {displacement} m"),
            "active" => assert!(displacement > 1e-3, "moved only {displacement} m"),
            _ => {}
        }
    }
}
