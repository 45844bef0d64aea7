//! Errors people meet first: a closed pipe, a misspelt built-in, a wrong value in a scene
//! file, a scene line too long to quote.

mod cli_support;
use cli_support::{run, temp};

use std::process::{Command, Stdio};

/// Runs the CLI with its stdout a pipe whose reader is already gone (as `| head` after
/// it has read its lines).
fn into_closed_pipe(args: &[&str]) -> (std::process::ExitStatus, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_tensegrity-fmu"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the CLI runs");
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    (
        out.status,
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn a_closed_pipe_ends_quietly() {
    for args in [
        &["scene", "prism2"][..],
        &["scene"][..],
        &["bench", "--stages", "2", "--seconds", "0.01"][..],
    ] {
        let (status, err) = into_closed_pipe(args);
        assert!(err.is_empty(), "{args:?}: {err}");
        #[cfg(unix)]
        {
            use std::os::unix::process::ExitStatusExt;
            // Ended by SIGPIPE like `cat`, not by a panic (exit code 101).
            assert!(
                status.success() || status.signal() == Some(13),
                "{args:?}: {status:?}"
            );
        }
        #[cfg(not(unix))]
        assert_ne!(status.code(), Some(101), "{args:?}");
    }
}

#[test]
fn a_misspelt_builtin_suggests_the_nearest() {
    let (ok, _, err) = run(&["scene", "icosahedon"]);
    assert!(!ok);
    assert!(err.contains("did you mean 'icosahedron'?"), "{err}");
    assert!(
        err.contains("prism2, prism2-elastic, icosahedron, tower20"),
        "{err}"
    );
    let (ok, _, err) = run(&["simulate", "towr20"]);
    assert!(!ok);
    assert!(
        err.contains("towr20") && err.contains("no such file") && err.contains("'tower20'?"),
        "{err}"
    );
    // Far from every name: the list, no guess.
    let (ok, _, err) = run(&["build", "my-bridge"]);
    assert!(!ok);
    assert!(
        err.contains("built-ins: prism2") && !err.contains("did you mean"),
        "{err}"
    );
}

/// prism2 as TOML with its second bar's mass replaced by `value`.
fn prism_with_mass(value: &str) -> String {
    let (ok, toml, _) = run(&["scene", "prism2"]);
    assert!(ok);
    let at = toml.match_indices("mass = 1.0").nth(1).unwrap().0;
    format!(
        "{}mass = {value}{}",
        &toml[..at],
        &toml[at + "mass = 1.0".len()..]
    )
}

#[test]
fn scene_errors_name_the_key_path() {
    let path = temp("bad-mass.toml");
    std::fs::write(&path, prism_with_mass("\"x\"")).unwrap();
    let (ok, _, err) = run(&["simulate", path.to_str().unwrap()]);
    assert!(!ok);
    assert!(
        err.contains("bars[2].mass: invalid type: string \"x\", expected f64"),
        "{err}"
    );
    assert!(err.contains("`mass = \"x\"`"), "{err}");
    // The same in JSON.
    let json = r#"{"name": "j", "nodes": [[0,0,0],[1,0,0],[0,1,0]], "fixed": [1],
        "bars": [{"nodes": [1, 2], "mass": 1.0}, {"nodes": [1, 3], "mass": "x"}]}"#;
    let path = temp("bad-mass.json");
    std::fs::write(&path, json).unwrap();
    let (ok, _, err) = run(&["simulate", path.to_str().unwrap()]);
    assert!(!ok);
    assert!(
        err.contains(
            "malformed JSON scene: bars[2].mass: invalid type: string \"x\", expected f64"
        ),
        "{err}"
    );
}

#[test]
fn long_scene_lines_are_cut_in_errors() {
    let long = "y".repeat(10_000);
    for (name, text) in [
        // A syntax error at the end of a 10,000-character line.
        (
            "long-line.toml",
            format!("name = \"p\"\ndescription = \"{long}\" x\n"),
        ),
        // A wrong type whose value is 10,000 characters.
        ("long-value.toml", prism_with_mass(&format!("\"{long}\""))),
    ] {
        let path = temp(name);
        std::fs::write(&path, text).unwrap();
        let (ok, _, err) = run(&["simulate", path.to_str().unwrap()]);
        assert!(!ok);
        assert!(err.len() < 1000, "{name}: {} characters: {err}", err.len());
        assert!(err.contains('…') && err.contains("(line "), "{name}: {err}");
    }
}

#[test]
fn a_bad_tensegrity_simd_value_is_a_one_line_error() {
    let out = Command::new(env!("CARGO_BIN_EXE_tensegrity-fmu"))
        .args(["scene", "prism2"])
        .env("TENSEGRITY_SIMD", "avx512")
        .output()
        .expect("the CLI runs");
    assert!(!out.status.success());
    assert!(out.stdout.is_empty());
    assert_eq!(
        String::from_utf8_lossy(&out.stderr),
        "error: TENSEGRITY_SIMD=avx512 is not a kernel choice: set it to `scalar` or `auto`, \
         or unset it\n"
    );
}
