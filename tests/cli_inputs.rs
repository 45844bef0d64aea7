//! `simulate --inputs FILE.csv`: a bad table is a message naming the column or line and the
//! fix, and nothing is written. (The values are compared with fmpy in
//! tests/fmpy/test_cli_inputs.py.)

mod cli_support;
use cli_support::temp;

use std::process::Command;

/// Runs prism2 with `table` as its input CSV; returns success, stderr and the CSV if any.
fn simulate(name: &str, table: &str) -> (bool, String, Option<String>) {
    let inputs = temp(&format!("{name}.in.csv"));
    std::fs::write(&inputs, table).unwrap();
    let csv = temp(&format!("{name}.out.csv"));
    let out = Command::new(env!("CARGO_BIN_EXE_tensegrity-fmu"))
        .args([
            "simulate",
            "--time",
            "0.02",
            "--interval",
            "0.01",
            "--inputs",
        ])
        .arg(&inputs)
        .arg("-o")
        .arg(&csv)
        .output()
        .expect("the CLI runs");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!err.contains("panicked"), "{err}");
    (
        out.status.success(),
        err,
        std::fs::read_to_string(&csv).ok(),
    )
}

fn refused(name: &str, table: &str, expected: &[&str]) {
    let (ok, err, csv) = simulate(name, table);
    assert!(!ok, "{name}: accepted");
    assert!(csv.is_none(), "{name}: a CSV was written");
    assert!(err.contains("--inputs"), "{name}: {err}");
    for part in expected {
        assert!(err.contains(part), "{name}: `{part}` missing from {err}");
    }
}

#[test]
fn unknown_column_names_the_inputs() {
    refused(
        "unknown",
        "time,node[7].fx,node[99].fx\n0,1,2\n",
        &[
            "column 3 `node[99].fx`",
            "not a variable",
            "node[7].fx, node[7].fy",
        ],
    );
}

#[test]
fn non_input_columns_are_refused() {
    refused(
        "output",
        "time,node[7].x\n0,1\n",
        &["`node[7].x` is an output", "not an input"],
    );
    refused(
        "parameter",
        "time,solver.step_size\n0,0.001\n",
        &["`solver.step_size` is a parameter", "not an input"],
    );
    refused(
        "first",
        "t,node[7].fx\n0,1\n",
        &["first column must be `time`, got `t`"],
    );
    refused(
        "twice",
        "time,node[7].fx,node[7].fx\n0,1,1\n",
        &["`node[7].fx` appears twice"],
    );
}

#[test]
fn bad_values_name_line_and_column() {
    refused(
        "nan",
        "time,node[7].fx\n0,1\n0.01,NaN\n",
        &["line 3, column `node[7].fx`", "not finite"],
    );
    refused(
        "inf",
        "time,node[7].fx\n0,inf\n",
        &["line 2, column `node[7].fx`", "not finite"],
    );
    refused(
        "text",
        "time,node[7].fx\n0,heavy\n",
        &["line 2, column `node[7].fx`", "`heavy` is not a number"],
    );
    refused(
        "short",
        "time,node[7].fx,node[7].fy\n0,1\n",
        &["line 2 has 2 values but the header has 3 columns"],
    );
    refused("empty", "time,node[7].fx\n", &["no rows"]);
}

#[test]
fn time_must_not_decrease() {
    refused(
        "backwards",
        "time,node[7].fx\n0,0\n0.02,1\n0.01,2\n",
        &[
            "line 4",
            "time 0.01 is before the previous row's 0.02",
            "write a time twice for a step",
        ],
    );
}

#[test]
fn a_good_table_drives_the_inputs() {
    // A step to 3 N at 0.01 s: controlled-cable tensions are unchanged, but node 7 moves.
    let (ok, err, csv) = simulate("good", "time,node[7].fx\n0,0\n0.005,0\n0.005,3\n1,3\n");
    assert!(ok, "{err}");
    let (_, _, plain) = simulate("good-plain", "time,node[7].fy\n0,0\n");
    let col = |text: &str| -> Vec<f64> {
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let c = header.iter().position(|h| *h == "node[7].x").unwrap();
        lines
            .map(|l| l.split(',').nth(c).unwrap().parse().unwrap())
            .collect()
    };
    let driven = col(&csv.unwrap());
    let still = col(&plain.unwrap());
    assert_eq!(driven[0], still[0]);
    assert!(driven[2] - still[2] > 1e-6, "{driven:?} vs {still:?}");
}
