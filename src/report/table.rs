//! The report's CSV and Markdown text.

use std::fmt::Write;

use super::{Report, RunRecord};
use crate::integrator::Method;
use crate::numbers;

/// The columns of `accuracy.csv`, in order.
pub const COLUMNS: [&str; 10] = [
    "method",
    "setting",
    "correction",
    "status",
    "wall_time_s",
    "max_position_error_m",
    "max_length_error_m",
    "max_orthogonality_error_m2_s",
    "energy_drift_rel",
    "rhs_evaluations",
];

/// The node-position error targets of the recommendation table, m.
pub const TARGETS: [f64; 3] = [1e-3, 1e-6, 1e-9];

/// One line per run; a failed run has status `failed` and empty figures.
pub(crate) fn csv(runs: &[RunRecord]) -> String {
    let mut s = COLUMNS.join(",");
    s.push('\n');
    for r in runs {
        let on = if r.correction { "on" } else { "off" };
        let mut digits = zmij::Buffer::new();
        let mut n = |x: f64| numbers::number(&mut digits, x).to_string();
        let _ = write!(s, "{},{},{on},", r.method.name(), n(r.setting));
        let _ = match &r.result {
            Ok(m) => writeln!(
                s,
                "ok,{},{},{},{},{},{}",
                n(m.wall_time_s),
                n(m.max_position_error_m),
                n(m.max_length_error_m),
                n(m.max_orthogonality_error_m2_s),
                n(m.energy_drift_rel),
                m.rhs_evaluations
            ),
            Err(_) => writeln!(s, "failed,,,,,,"),
        };
    }
    s
}

/// The cheapest run with the correction on whose node-position error is at most
/// `target`, among `methods` (all when empty), with its wall time. Runs that did the very
/// same work (same method, evaluations and error: dopri5 capped by the output interval)
/// count as one computation timed by the fastest of them, represented by the one with the
/// tightest setting.
pub fn recommend<'a>(
    runs: &'a [RunRecord],
    target: f64,
    methods: &[Method],
) -> Option<(&'a RunRecord, f64)> {
    let work = |r: &RunRecord| {
        let m = r.result.as_ref().ok()?;
        Some((
            r.method,
            r.correction,
            m.rhs_evaluations,
            m.max_position_error_m,
        ))
    };
    let pooled = |r: &RunRecord| {
        runs.iter()
            .filter(|x| work(x) == work(r))
            .map(wall)
            .fold(f64::INFINITY, f64::min)
    };
    runs.iter()
        .filter(|r| r.correction && (methods.is_empty() || methods.contains(&r.method)))
        .filter(|r| matches!(&r.result, Ok(m) if m.max_position_error_m <= target))
        .map(|r| (r, pooled(r)))
        .min_by(|a, b| {
            a.1.total_cmp(&b.1)
                .then(a.0.setting.total_cmp(&b.0.setting))
        })
}

/// Seconds to three significant digits: "0.00123", "0.0456", "1.23".
fn secs(x: f64) -> String {
    let digits = if x > 0.0 {
        (2.0 - x.log10().floor()).clamp(0.0, 12.0) as usize
    } else {
        1
    };
    format!("{x:.digits$}")
}

fn wall(r: &RunRecord) -> f64 {
    r.result.as_ref().map_or(f64::INFINITY, |m| m.wall_time_s)
}

/// The printed summary.
pub(crate) fn markdown(report: &Report, load: f64, unconserved: &[&str]) -> String {
    let mut s = String::new();
    let rc = &report.reference;
    let _ = writeln!(s, "### Accuracy report: {}\n", report.scene);
    let excitation = if report.loaded_nodes > 0 {
        format!(
            "the scene as given plus a constant {load} N load along +x on each of its {} force-input nodes",
            report.loaded_nodes
        )
    } else {
        "the scene as given (it has no force inputs to load)".to_string()
    };
    let _ = writeln!(
        s,
        "Excitation: {excitation}; {} s simulated, outputs every {} ms.\n",
        report.horizon,
        report.interval * 1e3
    );
    let _ = writeln!(
        s,
        "Reference: dopri5 at rtol = atol = {:.0e} with the correction on ({} evaluations, {} s). \
         Convergence check: a run at rtol = atol = {:.0e} differs from it by at most {:.1e} m in node \
         position over all output times, so errors well above {:.0e} m are measured reliably.\n",
        rc.tolerance,
        rc.rhs_evaluations,
        secs(rc.wall_time_s),
        rc.check_tolerance,
        rc.max_difference_m,
        rc.max_difference_m
    );
    let _ = writeln!(
        s,
        "Cheapest setting for each error target (least wall time, correction on, max node-position error \
         over the horizon; runs that did identical work share their fastest time):\n"
    );
    let _ = writeln!(
        s,
        "| target (m) | method | setting | wall time (s) | position error (m) | rhs evaluations |"
    );
    let _ = writeln!(s, "|---:|---|---|---:|---:|---:|");
    for target in TARGETS {
        match recommend(&report.runs, target, &[]) {
            Some((r, wall)) => {
                let m = r.result.as_ref().expect("recommended runs succeeded");
                let _ = writeln!(
                    s,
                    "| {target:.0e} | {} | {} | {} | {:.1e} | {} |",
                    r.method.name(),
                    r.setting_label(),
                    secs(wall),
                    m.max_position_error_m,
                    m.rhs_evaluations
                );
            }
            None => {
                let _ = writeln!(s, "| {target:.0e} | none in the sweep | | | | |");
            }
        }
    }
    let _ = writeln!(
        s,
        "\nLeast wall time per method to reach each target (correction on):\n"
    );
    let head: Vec<String> = TARGETS.iter().map(|t| format!("{t:.0e} m")).collect();
    let _ = writeln!(s, "| method | {} |", head.join(" | "));
    let _ = writeln!(s, "|---|{}", "---:|".repeat(TARGETS.len()));
    for method in super::SWEPT {
        let cells: Vec<String> = TARGETS
            .iter()
            .map(|&t| match recommend(&report.runs, t, &[method]) {
                Some((r, wall)) => format!("{} s ({})", secs(wall), r.setting_label()),
                None => "—".to_string(),
            })
            .collect();
        let _ = writeln!(s, "| {} | {} |", method.name(), cells.join(" | "));
    }
    if let Some(note) = capped_note(report) {
        let _ = writeln!(s, "\n{note}");
    }
    let worst = |on: bool| {
        report
            .runs
            .iter()
            .filter(|r| r.correction == on)
            .filter_map(|r| r.result.as_ref().ok().map(|m| (m.max_length_error_m, r)))
            .max_by(|a, b| a.0.total_cmp(&b.0))
    };
    if let (Some((on, _)), Some((off, r))) = (worst(true), worst(false)) {
        let _ = writeln!(
            s,
            "\nBar-length error: at most {on:.1e} m in every run with the correction on; up to \
             {off:.1e} m without it ({} {}). Without the correction, rattle is plain velocity \
             Verlet: its in-step projection is part of the correction.",
            r.method.name(),
            r.setting_label()
        );
    }
    let _ = writeln!(s, "\n{}", energy_note(unconserved));
    if let Some(line) = failed_line(&report.runs) {
        let _ = writeln!(s, "\n{line}");
    }
    for (picture, what) in [
        (&report.work_precision, "work_precision.png: no run"),
        (
            &report.constraint_error,
            "constraint_error.png: neither RK4 run at the figure's step",
        ),
    ] {
        if picture.is_none() {
            let _ = writeln!(s, "\nNot drawn: {what} reached the horizon.");
        }
    }
    s
}

/// What the energy-drift column measures for this scene.
fn energy_note(unconserved: &[&str]) -> String {
    let counted = "Energy drift: E counts kinetic energy, cable strain, gravity, the ground \
                   penalty and the potential of the constant loads";
    if unconserved.is_empty() {
        format!(
            "{counted}; the exact solution conserves it, so the column measures the integrator."
        )
    } else {
        format!(
            "{counted}; it leaves out {}, which change E of the exact solution too, so on this \
             scene the column measures those as well as the integrator.",
            unconserved.join(", ")
        )
    }
}

/// The failed runs folded into one line: how many, which methods and settings, and the
/// first error (each has status `failed` in the CSV).
fn failed_line(runs: &[RunRecord]) -> Option<String> {
    let failed: Vec<&RunRecord> = runs.iter().filter(|r| r.result.is_err()).collect();
    let first = failed.first()?;
    let mut groups: Vec<String> = Vec::new();
    for method in super::SWEPT {
        let mut settings: Vec<String> = Vec::new();
        for r in failed.iter().filter(|r| r.method == method) {
            let label = r.setting_label();
            if !settings.contains(&label) {
                settings.push(label);
            }
        }
        if !settings.is_empty() {
            groups.push(format!("{} {}", method.name(), settings.join(", ")));
        }
    }
    let error = first.result.as_ref().err()?;
    let cut: String = error.chars().take(MAX_ERROR).collect();
    let more = if cut.len() < error.len() { " …" } else { "" };
    Some(format!(
        "Failed: {} of {} runs (status `failed` in the CSV, left out of the tables and \
         pictures): {}. The first, {} {} correction {}: {cut}{more}",
        failed.len(),
        runs.len(),
        groups.join("; "),
        first.method.name(),
        first.setting_label(),
        if first.correction { "on" } else { "off" },
    ))
}

/// Characters of the first failure's message quoted in the summary line.
const MAX_ERROR: usize = 300;

/// A note when several dopri5 tolerances took the very same steps: the output interval,
/// where every advance ends, capped its step.
fn capped_note(report: &Report) -> Option<String> {
    let runs: Vec<(f64, u64)> = report
        .runs
        .iter()
        .filter(|r| r.method == Method::Dopri5 && r.correction)
        .filter_map(|r| Some((r.setting, r.result.as_ref().ok()?.rhs_evaluations)))
        .collect();
    let (_, evals) = runs
        .iter()
        .map(|&(_, e)| (runs.iter().filter(|r| r.1 == e).count(), e))
        .max()?;
    let same: Vec<f64> = runs.iter().filter(|r| r.1 == evals).map(|r| r.0).collect();
    if same.len() < 2 {
        return None;
    }
    let loose = same.iter().copied().fold(0.0, f64::max);
    let tight = same.iter().copied().fold(f64::INFINITY, f64::min);
    Some(format!(
        "Note: dopri5 took identical steps ({evals} evaluations) for every tolerance from \
         {loose:.0e} to {tight:.0e}: its natural step is longer than the {} ms output interval, \
         where every advance ends, so tolerances looser than {tight:.0e} buy nothing at this \
         output interval.",
        report.interval * 1e3
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::Metrics;

    #[test]
    fn a_failed_run_is_a_failed_row_with_empty_figures() {
        let run = RunRecord {
            method: Method::Rk4,
            setting: 1e-3,
            correction: true,
            result: Err("non-finite state".into()),
            length_error_series: Vec::new(),
        };
        let text = csv(&[run]);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], COLUMNS.join(","));
        assert_eq!(lines[1], "rk4,0.001,on,failed,,,,,,");
        assert!(recommend(&[], 1e-3, &[]).is_none());
    }

    #[test]
    fn failed_runs_fold_into_one_line() {
        let run = |method, setting, correction, result: Result<(), &str>| RunRecord {
            method,
            setting,
            correction,
            result: result
                .map(|_| Metrics {
                    wall_time_s: 0.1,
                    max_position_error_m: 1e-6,
                    max_length_error_m: 0.0,
                    max_orthogonality_error_m2_s: 0.0,
                    energy_drift_rel: 0.0,
                    rhs_evaluations: 10,
                })
                .map_err(String::from),
            length_error_series: Vec::new(),
        };
        let runs = [
            run(Method::Rk4, 8e-3, true, Err("blew up at t = 0.1 s")),
            run(Method::Rk4, 8e-3, false, Err("blew up at t = 0.2 s")),
            run(Method::Rk4, 4e-3, true, Err("blew up")),
            run(Method::Rattle, 4e-3, false, Err("blew up")),
            run(Method::Rk4, 2e-3, true, Ok(())),
        ];
        let line = failed_line(&runs).expect("a line");
        assert_eq!(
            line,
            "Failed: 4 of 5 runs (status `failed` in the CSV, left out of the tables and \
             pictures): rk4 h = 8 ms, h = 4 ms; rattle h = 4 ms. The first, rk4 h = 8 ms \
             correction on: blew up at t = 0.1 s"
        );
        assert!(failed_line(&runs[4..]).is_none());
    }
}
