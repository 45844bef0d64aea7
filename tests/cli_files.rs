//! Output files are whole or absent: a full disk, a signal, a kill or a planted symlink
//! never leaves a truncated target, never a temporary behind (but a killed run's, removed
//! by the next run), and never writes through a symlink.

use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_tensegrity-fmu");

/// A fresh, empty folder for one test.
fn folder(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tensegrity-files-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// The hidden temporaries in `dir`.
fn temporaries(dir: &Path) -> Vec<String> {
    names(dir)
        .into_iter()
        .filter(|n| n.starts_with('.') && n.contains(".tmp") && n.ends_with(".tensegrity-fmu"))
        .collect()
}

/// Runs the CLI in `dir` with files limited to `max_bytes` (as a full disk would stop
/// them: the write fails with EFBIG, SIGXFSZ being ignored).
fn run_with_file_limit(dir: &Path, args: &[&str], max_bytes: u64) -> Output {
    let mut cmd = Command::new(BIN);
    cmd.args(args).current_dir(dir);
    // SAFETY: only async-signal-safe calls between fork and exec.
    unsafe {
        cmd.pre_exec(move || {
            libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
            let limit = libc::rlimit {
                rlim_cur: max_bytes,
                rlim_max: max_bytes,
            };
            if libc::setrlimit(libc::RLIMIT_FSIZE, &limit) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    cmd.output().unwrap()
}

#[test]
fn a_full_disk_leaves_the_old_file_and_no_temporary() {
    let cases: [(&str, &[&str]); 6] = [
        (
            "out.csv",
            &["simulate", "prism2", "--time", "1", "-o", "out.csv"],
        ),
        (
            "out.png",
            &["render", "prism2", "--at", "0", "-o", "out.png"],
        ),
        (
            "out.gif",
            &["render", "prism2", "--time", "0.2", "-o", "out.gif"],
        ),
        (
            "out.html",
            &["render", "prism2", "--time", "0.2", "-o", "out.html"],
        ),
        ("out.mat", &["linearize", "prism2", "-o", "out.mat"]),
        ("out.json", &["linearize", "prism2", "-o", "out.json"]),
    ];
    for (target, args) in cases {
        let dir = folder(&format!("full-{target}"));
        let old = format!("the old {target}, kept until a new one is whole\n");
        std::fs::write(dir.join(target), &old).unwrap();
        let out = run_with_file_limit(&dir, args, 4096);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{target}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{target}: one line: {stderr}");
        assert!(
            stderr.contains(target) && stderr.contains("File too large"),
            "{target}: names the file and the reason: {stderr}"
        );
        assert_eq!(std::fs::read_to_string(dir.join(target)).unwrap(), old);
        assert_eq!(names(&dir), [target], "{target}: nothing else left");
    }
}

#[test]
fn a_full_disk_during_a_paraview_series_keeps_the_old_series() {
    let dir = folder("full-pvd");
    let made = Command::new(BIN)
        .args(["render", "prism2", "--time", "0.01", "-o", "old.pvd"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(made.status.success());
    std::fs::rename(dir.join("old.pvd"), dir.join("out.pvd")).unwrap();
    std::fs::rename(dir.join("old_vtp"), dir.join("out_vtp")).unwrap();
    let before = names(&dir.join("out_vtp"));
    let pvd = std::fs::read(dir.join("out.pvd")).unwrap();
    // Many small .vtp files: a limit above each one's size stops none, so stop the .pvd
    // side with a run whose every file is larger than the limit.
    let out = run_with_file_limit(
        &dir,
        &["render", "tower20", "--time", "0.02", "-o", "out.pvd"],
        4096,
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("out.pvd") && stderr.contains("File too large"),
        "{stderr}"
    );
    assert_eq!(std::fs::read(dir.join("out.pvd")).unwrap(), pvd);
    assert_eq!(names(&dir.join("out_vtp")), before);
    assert_eq!(names(&dir), ["out.pvd", "out_vtp"]);
}

/// Runs `args` through `sh`, which first plants `links` (name → what it points to) in
/// `dir` and then becomes the CLI (`exec`), so that `$$` is the CLI's process id.
fn run_after_planting(dir: &Path, links: &[(&str, &Path)], args: &[&str]) -> Output {
    let mut script = String::new();
    for (name, to) in links {
        script += &format!("ln -s '{}' \"{name}\" || exit 9\n", to.display());
    }
    script += "exec \"$0\" \"$@\"\n";
    Command::new("sh")
        .arg("-c")
        .arg(script)
        .arg(BIN)
        .args(args)
        .current_dir(dir)
        .env("TMPDIR", dir)
        .output()
        .unwrap()
}

#[test]
fn symlinks_planted_under_temporary_names_are_never_followed() {
    let victims = folder("victims");
    let victim = victims.join("victim.txt");
    let victim_dir = victims.join("victim-folder");
    std::fs::create_dir(&victim_dir).unwrap();
    std::fs::write(victim_dir.join("keep.vtp"), "keep").unwrap();
    let cases: [(&[&str], &[&str]); 5] = [
        (
            &["simulate", "prism2", "--time", "0.1", "-o", "out.csv"],
            &[
                ".out.csv.partial-$$",
                ".out.csv.tmpAAAAAA.tensegrity-fmu",
                ".out.csv.tmp000000.tensegrity-fmu",
            ],
        ),
        (
            &["render", "prism2", "--at", "0", "-o", "out.png"],
            &[
                "out.png",
                ".out.png.partial-$$",
                ".out.png.tmpAAAAAA.tensegrity-fmu",
            ],
        ),
        (
            &["render", "prism2", "--time", "0.1", "-o", "out.gif"],
            &["out.gif", ".out.gif.tmpAAAAAA.tensegrity-fmu"],
        ),
        (
            &["render", "prism2", "--time", "0.01", "-o", "out.pvd"],
            &[".out.pvd.tmp-$$", ".out.pvd.tmpAAAAAA.tensegrity-fmu"],
        ),
        // matrw writes to a path: its private file in $TMPDIR had a predictable name.
        (
            &["linearize", "prism2", "-o", "out.mat"],
            &["tensegrity-fmu-$$-0.mat", ".out.mat.partial-$$"],
        ),
    ];
    for (args, planted) in cases {
        let dir = folder(&format!("links-{}", args[args.len() - 1]));
        std::fs::write(&victim, "not to be written\n").unwrap();
        let links: Vec<(&str, &Path)> = planted.iter().map(|n| (*n, victim.as_path())).collect();
        let mut links = links;
        let vtp_links = [
            ".out_vtp.tmp-$$",
            ".out_vtp.tmpAAAAAA.tensegrity-fmu",
            ".out_vtp.old-$$",
        ];
        if args.contains(&"out.pvd") {
            links.extend(vtp_links.iter().map(|n| (*n, victim_dir.as_path())));
        }
        let out = run_after_planting(&dir, &links, args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{args:?}: {stderr}");
        assert_eq!(
            std::fs::read_to_string(&victim).unwrap(),
            "not to be written\n",
            "{args:?}"
        );
        assert_eq!(names(&victim_dir), ["keep.vtp"], "{args:?}");
        let target = dir.join(args[args.len() - 1]);
        let meta = std::fs::symlink_metadata(&target).unwrap();
        assert!(meta.is_file() && meta.len() > 100, "{args:?}: a new file");
    }
}

/// Starts a long `simulate` of tower20 writing `out.csv` in `dir` and waits until its
/// hidden temporary holds rows.
fn start_long_run(dir: &Path) -> Child {
    start_long_run_of(dir, "out.csv")
}

fn start_long_run_of(dir: &Path, target: &str) -> Child {
    let args = [
        "simulate",
        "tower20",
        "--time",
        "5000",
        "--interval",
        "0.02",
        "-o",
        target,
    ];
    start_writing(dir, &args, target, 100_000)
}

/// Starts the CLI with `args` in `dir` and waits until its hidden temporary for `target`
/// holds more than `min_len` bytes.
fn start_writing(dir: &Path, args: &[&str], target: &str, min_len: u64) -> Child {
    let prefix = format!(".{target}.tmp");
    let mut child = Command::new(BIN)
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        let written = temporaries(dir).iter().any(|n| {
            n.starts_with(&prefix)
                && std::fs::metadata(dir.join(n)).is_ok_and(|m| m.len() >= min_len)
        });
        if written {
            return child;
        }
        if start.elapsed() > Duration::from_secs(120) || child.try_wait().unwrap().is_some() {
            let _ = child.kill();
            panic!(
                "{args:?} never wrote its temporary: {:?}",
                child.wait_with_output()
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn signal(child: &Child, signal: i32) {
    // SAFETY: kill(2) on the process we started, which has not been waited for.
    assert_eq!(unsafe { libc::kill(child.id() as i32, signal) }, 0);
}

/// Sends `sig` to `child`, writing `target` over "old" in `dir`: it ends with 128 + `sig`,
/// leaving the old file and nothing else.
fn assert_signal_keeps_the_old_file(dir: &Path, child: Child, sig: i32, target: &str) {
    signal(&child, sig);
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(128 + sig), "{target}");
    assert_eq!(names(dir), [target], "{target}: no temporary left");
    assert_eq!(std::fs::read_to_string(dir.join(target)).unwrap(), "old\n");
}

#[test]
fn sigterm_and_sighup_remove_the_temporary_and_keep_the_old_file() {
    for (sig, name) in [(libc::SIGTERM, "term"), (libc::SIGHUP, "hup")] {
        let dir = folder(&format!("signal-{name}"));
        std::fs::write(dir.join("out.csv"), "old\n").unwrap();
        let child = start_long_run(&dir);
        assert_signal_keeps_the_old_file(&dir, child, sig, "out.csv");
    }
}

#[test]
fn sigint_outside_simulate_removes_the_temporary_and_keeps_the_old_file() {
    let dir = folder("signal-int-gif");
    std::fs::write(dir.join("out.gif"), "old\n").unwrap();
    let args = [
        "render", "prism2", "--time", "60", "--fps", "50", "-o", "out.gif",
    ];
    let child = start_writing(&dir, &args, "out.gif", 0);
    assert_signal_keeps_the_old_file(&dir, child, libc::SIGINT, "out.gif");
}

#[test]
fn ctrl_c_in_simulate_keeps_a_whole_csv_of_the_rows_so_far() {
    let dir = folder("signal-int-csv");
    std::fs::write(dir.join("out.csv"), "old\n").unwrap();
    let child = start_long_run(&dir);
    signal(&child, libc::SIGINT);
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{stderr}");
    assert_eq!(names(&dir), ["out.csv"]);
    let text = std::fs::read_to_string(dir.join("out.csv")).unwrap();
    let mut lines = text.lines();
    let columns = lines.next().unwrap().split(',').count();
    assert_eq!(columns, 574, "tower20's time and 573 outputs");
    let mut times = Vec::new();
    for line in lines {
        let row: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
        assert_eq!(row.len(), columns, "a whole row: {line:.60}");
        times.push(row[0]);
    }
    // Whatever was on disk when Ctrl-C came (start_long_run waits for 100,000 bytes) stays.
    assert!(
        text.len() >= 100_000 && times.len() > 1,
        "{} bytes, {} rows",
        text.len(),
        times.len()
    );
    assert!(times.windows(2).all(|w| w[1] > w[0]));
    for (k, t) in times.iter().enumerate() {
        assert!((t - k as f64 * 0.02).abs() < 1e-9, "row {k} at t = {t}");
    }
    let last = *times.last().unwrap();
    assert!(last < 5000.0);
    // stderr says where it stopped and what the file holds, as the file shows.
    let said = format!(
        "interrupted at t = {last} s of 5000 s: out.csv holds the {} rows from t = 0 to {last} s",
        times.len()
    );
    assert!(stderr.contains(&said), "{stderr}\nexpected: {said}");
}

#[test]
fn a_killed_runs_temporary_is_removed_by_the_next_run_but_a_live_one_is_not() {
    let dir = folder("kill");
    let live = start_long_run_of(&dir, "live.csv");
    let mut killed = start_long_run_of(&dir, "dead.csv");
    killed.kill().unwrap();
    killed.wait().unwrap();
    let left = temporaries(&dir);
    assert_eq!(left.len(), 2, "{left:?}");
    assert!(left[0].starts_with(".dead.csv.tmp") && left[1].starts_with(".live.csv.tmp"));
    // Another program's hidden temporaries of the same shape are not ours to remove.
    let foreign = [".notes.txt.tmpAb12Cd", ".cache.tmp000000"];
    for name in foreign {
        std::fs::write(dir.join(name), "another program's\n").unwrap();
    }

    let next = Command::new(BIN)
        .args(["simulate", "prism2", "--time", "0.1", "-o", "next.csv"])
        .current_dir(&dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&next.stderr);
    assert!(next.status.success(), "{stderr}");
    assert!(stderr.contains(&left[0]), "says so: {stderr}");
    assert_eq!(temporaries(&dir), [left[1].clone()], "the live one is kept");
    signal(&live, libc::SIGTERM);
    live.wait_with_output().unwrap();
    for name in foreign {
        assert_eq!(
            std::fs::read_to_string(dir.join(name)).unwrap(),
            "another program's\n"
        );
    }
    assert_eq!(names(&dir), [foreign[1], foreign[0], "next.csv"]);
}
