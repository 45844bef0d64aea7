//! `bench` (the scaling table) measures every height in interleaved rounds and prints, per
//! row, the median ratio to linear with the rounds' range. This checks the table, not the
//! timings: the figures vary with the machine's load.

use std::process::Command;

#[test]
fn bench_prints_the_median_ratio_and_the_rounds_range() {
    let out = Command::new(env!("CARGO_BIN_EXE_tensegrity-fmu"))
        .args([
            "bench",
            "--stages",
            "2,4",
            "--seconds",
            "0.001",
            "--rounds",
            "3",
        ])
        .output()
        .expect("the CLI runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let row = |stages: &str| -> Vec<String> {
        let prefix = format!("| {stages} |");
        let line = stdout
            .lines()
            .find(|l| l.starts_with(&prefix))
            .unwrap_or_else(|| panic!("no row for {stages} stages in:\n{stdout}"));
        line.trim_matches('|')
            .split('|')
            .map(|cell| cell.trim().to_string())
            .collect()
    };
    let number = |cell: &str| -> f64 { cell.parse().unwrap_or_else(|_| panic!("{cell}")) };
    let smallest = row("2");
    assert_eq!(smallest.len(), 7, "{smallest:?}");
    assert_eq!(smallest[1], "6", "bars");
    assert_eq!((&*smallest[5], &*smallest[6]), ("1.00", "1.00–1.00"));
    let taller = row("4");
    assert_eq!(taller[1], "12", "bars");
    let (us, per_bar) = (number(&taller[3]), number(&taller[4]));
    assert!(
        (per_bar - us / 12.0).abs() <= 0.0005 + 0.05 / 12.0,
        "{taller:?}"
    );
    let (low, high) = taller[6].split_once('–').expect("a range");
    let (low, median, high) = (number(low), number(&taller[5]), number(high));
    assert!(low > 0.0 && low <= median && median <= high, "{taller:?}");
}
