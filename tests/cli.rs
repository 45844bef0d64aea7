//! The command line: errors are messages with a failing exit code, never panics.

mod cli_support;
use cli_support::{run, temp};

#[test]
fn build_refuses_a_binary_from_other_sources() {
    let fake = temp("fake.so");
    std::fs::write(&fake, b"not the FMU binary").unwrap();
    let out = temp("x.fmu");
    let (ok, _, err) = run(&[
        "build",
        "--binary",
        fake.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(err.contains("built from other sources"), "{err}");
    assert!(!out.exists(), "nothing is written on failure");
}

#[test]
fn bad_scene_is_reported_with_its_key() {
    let scene = temp("bad.toml");
    std::fs::write(
        &scene,
        "name = \"bad\"\nnodes = [[0,0,0],[1,0,0]]\nfixed = [1]\n[[bars]]\nnodes = [1, 2]\nmass = -1.0\n",
    )
    .unwrap();
    let (ok, _, err) = run(&["simulate", scene.to_str().unwrap(), "--time", "0.01"]);
    assert!(!ok);
    assert!(
        err.contains("bars[1].mass") && err.contains("must be positive"),
        "{err}"
    );
    let (ok, _, err) = run(&["simulate", "no-such-scene"]);
    assert!(!ok);
    assert!(err.contains("no-such-scene"), "{err}");
}

#[test]
fn simulate_writes_fmu_variable_columns() {
    let csv = temp("prism2.csv");
    let (ok, stdout, err) = run(&["simulate", "--time", "0.01", "-o", csv.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(stdout.contains("prism2.csv"));
    let text = std::fs::read_to_string(&csv).unwrap();
    let header = text.lines().next().unwrap();
    assert!(header.starts_with("time,node[1].x,node[1].y,node[1].z,"));
    assert!(header.ends_with("constraint.length_error,constraint.orthogonality_error,energy.total"));
    assert_eq!(text.lines().count(), 12, "header, t = 0 and 10 steps");
}
