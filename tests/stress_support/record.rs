//! Result rows of the stress cases, appended to a JSON-lines file and asserted.

use std::fs::{self, OpenOptions};
use std::io::Write;
use std::path::PathBuf;

use super::*;

/// One row of the results table: one (case, method).
#[derive(Debug, Clone)]
pub struct Outcome {
    pub case: String,
    pub method: String,
    pub steps: u64,
    pub max_length_error: f64,
    pub max_orthogonality_error: f64,
    pub energy_drift: Option<f64>,
    /// Largest `|b||ḃ|` seen, m²/s (the round-off scale of the orthogonality error).
    pub speed_scale: f64,
    /// Load-time rejection that was expected (status "rejected" when the checks pass).
    pub rejected: bool,
    pub note: String,
    /// `(passed, what)`: every stated check of the row.
    pub checks: Vec<(bool, String)>,
}

impl Outcome {
    pub fn new(case: &str, method: &str) -> Self {
        Self {
            case: case.to_string(),
            method: method.to_string(),
            steps: 0,
            max_length_error: 0.0,
            max_orthogonality_error: 0.0,
            energy_drift: None,
            speed_scale: 0.0,
            rejected: false,
            note: String::new(),
            checks: Vec::new(),
        }
    }

    /// Takes steps, errors and (if `drift`) the energy drift from a tracker.
    pub fn from_tracker(case: &str, method: &str, t: &Tracker, drift: bool) -> Self {
        let mut o = Self::new(case, method);
        o.steps = t.steps;
        o.max_length_error = t.max_length;
        o.max_orthogonality_error = t.max_orthogonality;
        o.energy_drift = drift.then_some(t.max_drift);
        o.speed_scale = t.speed_scale;
        o.check(t.finite, "finite");
        o
    }

    /// Adds a check; `what` is stated in the note when it fails.
    pub fn check(&mut self, ok: bool, what: impl Into<String>) -> &mut Self {
        self.checks.push((ok, what.into()));
        self
    }

    /// Constraint errors within [`EXACT`] (the correction is on). The orthogonality error
    /// `|b·ḃ|` is held to `EXACT × max(1, |b||ḃ| / (1 m²/s))`: for bars faster than
    /// ~1e3 m/s, 1e-12 m²/s absolute is below double-precision round-off of the product.
    pub fn check_exact(&mut self) -> &mut Self {
        let scale = self.speed_scale.max(1.0);
        if self.max_orthogonality_error > EXACT {
            let limit = sci(EXACT * scale);
            self.note(format!(
                "orthogonality limit {limit} m^2/s (max |b||b'| {})",
                sci(scale)
            ));
        }
        let ok = self.max_length_error <= EXACT && self.max_orthogonality_error <= EXACT * scale;
        self.check(ok, format!("constraint errors <= {EXACT:.0e}"))
    }

    /// For a setting a method cannot meet: either the run stayed sane (no error, energy
    /// drift ≤ 1e-2) or it was refused with a StepError that kept the last good state.
    /// Notes the refusal, and whether states accepted before it broke the constraints.
    pub fn check_sane_or_refused(&mut self, t: &Tracker, time: f64) -> &mut Self {
        let ok = match &t.error {
            Some(_) => t.kept,
            None => t.max_drift <= 1e-2,
        };
        self.check(
            ok,
            "sane (energy drift <= 1e-2) or refused with the state kept",
        );
        if let Some(e) = &t.error {
            self.note(format!("refused at t = {time:.3} s: {e}"));
            if t.max_length > EXACT {
                self.note("states accepted (Ok) before the refusal already broke the constraints");
            }
        }
        self
    }

    pub fn note(&mut self, text: impl AsRef<str>) -> &mut Self {
        if !self.note.is_empty() {
            self.note.push_str("; ");
        }
        self.note.push_str(text.as_ref());
        self
    }

    pub fn passed(&self) -> bool {
        self.checks.iter().all(|(ok, _)| *ok)
    }

    pub fn status(&self) -> &'static str {
        match (self.passed(), self.rejected) {
            (false, _) => "fail",
            (true, true) => "rejected",
            (true, false) => "pass",
        }
    }

    fn json(&self) -> String {
        // The note states every check of the row; failed ones are marked.
        let checks: Vec<String> = self
            .checks
            .iter()
            .map(|(ok, what)| match ok {
                true => what.clone(),
                false => format!("FAILED: {what}"),
            })
            .collect();
        let note = format!("{}; checks: {}", self.note, checks.join(", "));
        let row = serde_json::json!({
            "layer": "library",
            "case": self.case,
            "method": self.method,
            "steps": self.steps,
            "max_length_error": self.max_length_error,
            "max_orthogonality_error": self.max_orthogonality_error,
            "energy_drift": self.energy_drift,
            "status": self.status(),
            "note": note,
        });
        format!("{row}\n")
    }
}

/// The results file: `$STRESS_RESULTS` or `target/stress/results.jsonl`.
pub fn results_path() -> PathBuf {
    match std::env::var_os("STRESS_RESULTS") {
        Some(p) if !p.is_empty() => PathBuf::from(p),
        _ => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/stress/results.jsonl"),
    }
}

/// Appends every row (one `write` call each, so parallel tests never interleave), prints
/// them, then asserts that every check passed.
pub fn report(outcomes: &[Outcome]) {
    let path = results_path();
    if let Some(dir) = path.parent() {
        fs::create_dir_all(dir).expect("create the results folder");
    }
    let mut file = OpenOptions::new()
        .create(true)
        .append(true)
        .open(&path)
        .expect("open the results file");
    for o in outcomes {
        let line = o.json();
        file.write_all(line.as_bytes()).expect("append a row");
        print!("{line}");
    }
    let failed: Vec<String> = outcomes
        .iter()
        .flat_map(|o| {
            o.checks
                .iter()
                .filter(|(ok, _)| !ok)
                .map(move |(_, what)| format!("{} / {}: {what} ({})", o.case, o.method, o.note))
        })
        .collect();
    assert!(failed.is_empty(), "failed checks:\n{}", failed.join("\n"));
}
