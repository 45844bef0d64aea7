//! `simulate`: rows at the requested times, numbers as people write them, bounded output,
//! and no CSV left behind by a failed run.

mod cli_support;
use cli_support::{run, temp};

use tensegrity_fmu::outputs::number;

/// The CSV's `time` column, as written.
fn times(args: &[&str], name: &str) -> Vec<String> {
    let csv = temp(name);
    let mut all = args.to_vec();
    all.extend(["-o", csv.to_str().unwrap()]);
    let (ok, _, err) = run(&all);
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(&csv).unwrap();
    text.lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap().to_string())
        .collect()
}

#[test]
fn rows_are_at_multiples_of_the_interval_and_at_the_end() {
    let grid = ["0", "0.01", "0.02", "0.03", "0.04", "0.05"];
    // A step that does not divide the interval: the last internal step is shortened.
    let t = times(
        &[
            "simulate",
            "--time",
            "0.05",
            "--interval",
            "0.01",
            "--step-size",
            "0.0003",
        ],
        "a.csv",
    );
    assert_eq!(t, grid);
    // dopri5 with a first step larger than the whole run does not overshoot.
    let t = times(
        &[
            "simulate",
            "--time",
            "0.05",
            "--interval",
            "0.01",
            "--method",
            "dopri5",
        ],
        "b.csv",
    );
    assert_eq!(t, grid);
    let t = times(
        &[
            "simulate",
            "--time",
            "0.05",
            "--interval",
            "0.01",
            "--step-size",
            "0.2",
        ],
        "c.csv",
    );
    assert_eq!(t, grid);
    // --time off the grid ends with a row at --time; 3 · 0.1 is written as 0.3.
    let t = times(
        &["simulate", "--time", "0.025", "--interval", "0.01"],
        "d.csv",
    );
    assert_eq!(t, ["0", "0.01", "0.02", "0.025"]);
    let t = times(&["simulate", "--time", "0.3", "--interval", "0.1"], "e.csv");
    assert_eq!(t, ["0", "0.1", "0.2", "0.3"]);
}

#[test]
fn numbers_are_shortest_round_trip_decimals() {
    let mut d = zmij_buffer();
    let third = 1.0 / 3f64.sqrt();
    for (x, text) in [
        (0.0, "0"),
        (-0.0, "-0"),
        (third, "0.5773502691896258"),
        (-12.5, "-12.5"),
        (100.0, "100"),
        (1e-7, "1e-7"),
        (1.5e20, "1.5e+20"),
        (f64::NAN, "NaN"),
        (f64::INFINITY, "inf"),
        (f64::NEG_INFINITY, "-inf"),
    ] {
        assert_eq!(number(&mut d, x), text);
    }
    // Random bit patterns read back bit-identical, with std's shortest digits.
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    for _ in 0..20_000 {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        let x = f64::from_bits(state);
        if !x.is_finite() {
            continue;
        }
        let text = number(&mut d, x).to_string();
        assert_eq!(
            text.parse::<f64>().unwrap().to_bits(),
            x.to_bits(),
            "{text}"
        );
        // As short as std's shortest (which may pick the other of two equally short).
        let shortest = digits(&format!("{x:e}")).len();
        assert_eq!(digits(&text).len(), shortest, "{x:e} written {text}");
    }
}

fn zmij_buffer() -> zmij::Buffer {
    zmij::Buffer::new()
}

/// Significant digits of a decimal: no sign, point, exponent, leading or trailing zeros.
fn digits(text: &str) -> String {
    let mantissa = text.split(['e', 'E']).next().unwrap();
    let d: String = mantissa.chars().filter(char::is_ascii_digit).collect();
    d.trim_start_matches('0').trim_end_matches('0').to_string()
}

#[test]
fn the_csv_has_plain_numbers() {
    let csv = temp("plain.csv");
    let (ok, _, err) = run(&["simulate", "--time", "0.01", "-o", csv.to_str().unwrap()]);
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let first: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| first[header.iter().position(|h| *h == name).unwrap()];
    // prism2's node 1 is at (1/√3, 0, 0).
    assert_eq!(col("node[1].x"), "0.5773502691896258");
    assert_eq!(col("node[1].y"), "0");
    assert_eq!(col("node[1].z"), "0");
    assert_eq!(col("time"), "0");
    for line in text.lines().skip(1) {
        for cell in line.split(',') {
            let x: f64 = cell.parse().unwrap_or_else(|_| panic!("{cell}"));
            assert_eq!(
                digits(cell).len(),
                digits(&format!("{x:e}")).len(),
                "{cell}"
            );
            // Everyday magnitudes without an exponent (not `5.773502691896258e-1`, `0e0`).
            if x == 0.0 || (1e-5..1e15).contains(&x.abs()) {
                assert!(!cell.contains('e'), "{cell}");
            }
        }
    }
}

#[test]
fn absurd_output_is_refused_before_writing() {
    let csv = temp("huge.csv");
    let (ok, _, err) = run(&[
        "simulate",
        "--time",
        "100000",
        "--interval",
        "0.001",
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(
        err.contains("--interval") && err.contains("--time") && err.contains("100000001 rows"),
        "{err}"
    );
    assert!(!csv.exists());
    // Too many internal steps per row for solver.max_steps.
    let (ok, _, err) = run(&[
        "simulate",
        "--time",
        "1",
        "--interval",
        "1",
        "--step-size",
        "1e-6",
        "--method",
        "rk4",
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(
        err.contains("solver.max_steps") && err.contains("--interval"),
        "{err}"
    );
    assert!(!csv.exists());
}

#[test]
fn a_failed_run_leaves_no_csv_and_keeps_an_old_one() {
    let inputs = temp("blow-up.csv");
    std::fs::write(&inputs, "time,node[7].fx\n0,0\n0.02,0\n0.02,1e300\n").unwrap();
    let csv = temp("kept.csv");
    std::fs::write(&csv, "old contents\n").unwrap();
    let (ok, _, err) = run(&[
        "simulate",
        "--time",
        "0.05",
        "--interval",
        "0.01",
        "--inputs",
        inputs.to_str().unwrap(),
        "--method",
        "rk4",
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(
        err.contains("no CSV written") && err.contains("non-finite"),
        "{err}"
    );
    assert_eq!(std::fs::read_to_string(&csv).unwrap(), "old contents\n");
    let fresh = temp("fresh.csv");
    let (ok, _, _) = run(&[
        "simulate",
        "--time",
        "0.05",
        "--inputs",
        inputs.to_str().unwrap(),
        "-o",
        fresh.to_str().unwrap(),
    ]);
    assert!(!ok);
    let dir = fresh.parent().unwrap();
    let left: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains("fresh"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

#[test]
fn a_step_size_far_below_the_time_scale_is_refused_before_writing() {
    for step in ["1e-12", "1e-300"] {
        let out = temp(&format!("tiny-{step}.csv"));
        let started = std::time::Instant::now();
        let (ok, _, err) = run(&[
            "simulate",
            "prism2-elastic",
            "--time",
            "1",
            "--interval",
            "0.01",
            "--step-size",
            step,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(!ok);
        assert!(
            err.contains("solver.step_size =") && err.contains("fastest time scale"),
            "{err}"
        );
        assert!(!out.exists(), "nothing is written");
        assert!(started.elapsed().as_secs() < 30);
    }
}

#[cfg(target_os = "linux")]
#[test]
fn a_full_disk_stops_the_run_with_the_file_named_and_no_csv_left() {
    use std::os::unix::process::CommandExt;
    let csv = temp("full.csv");
    let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_tensegrity-fmu"));
    // 11 MB of rows, written by the writer thread, into a 1 MB file-size limit.
    command.args([
        "simulate",
        "tower20",
        "--time",
        "1",
        "--interval",
        "0.001",
        "-o",
    ]);
    command.arg(&csv);
    // SAFETY: between fork and exec only async-signal-safe calls: a write past the limit
    // then fails with EFBIG as on a full disk, instead of killing the process (SIGXFSZ).
    unsafe {
        command.pre_exec(|| {
            libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
            let limit = libc::rlimit {
                rlim_cur: 1 << 20,
                rlim_max: 1 << 20,
            };
            if libc::setrlimit(libc::RLIMIT_FSIZE, &limit) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    let out = command.output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert_eq!(
        err.trim_end(),
        format!(
            "error: writing {}: File too large (os error 27)",
            csv.display()
        )
    );
    let left: Vec<_> = std::fs::read_dir(csv.parent().unwrap())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains("full"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}
