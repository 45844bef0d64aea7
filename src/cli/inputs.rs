//! `simulate --inputs FILE.csv`: input signals with the FMU's variable names, applied the
//! way fmpy's `simulate_fmu(..., input=...)` applies them to a co-simulation FMU.
//!
//! fmpy (0.3, `fmpy.simulation.Input`) sets the inputs at each communication point to the
//! table's value at that time and the FMU holds them over the step: linear interpolation
//! between rows, the first row before the table, the last row after it. A time written
//! twice is a step: before it the earlier row applies, from it on the later one, and it is
//! also a communication point (an "input event"), so the step takes effect exactly then.

use std::path::Path;

use tensegrity_fmu::dynamics::Inputs;
use tensegrity_fmu::fmi::variables::{Binding, VariableTable};
use tensegrity_fmu::Simulation;

use fmi2_model_description::Causality;

/// Python's `math.isclose` with its defaults (relative 1e-9, no absolute tolerance), which
/// fmpy uses to compare times.
pub fn isclose(a: f64, b: f64) -> bool {
    a == b || (a - b).abs() <= 1e-9 * a.abs().max(b.abs())
}

/// An input table read from a CSV file.
#[derive(Debug, Clone)]
pub struct InputTable {
    /// Row times, non-decreasing.
    times: Vec<f64>,
    /// One column per input: what it sets, and its values per row.
    columns: Vec<(Target, Vec<f64>)>,
    /// Times written twice (steps), sorted.
    events: Vec<f64>,
}

impl InputTable {
    /// Reads `path`: a header `time,<input names>` and one row per time.
    pub fn read(path: &Path, sim: &Simulation) -> Result<Self, String> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("--inputs {}: cannot read it: {e}", path.display()))?;
        Self::parse(&text, sim).map_err(|e| format!("--inputs {}: {e}", path.display()))
    }

    /// Parses CSV text (see [`InputTable::read`]).
    pub fn parse(text: &str, sim: &Simulation) -> Result<Self, String> {
        let table = VariableTable::new(sim);
        let inputs: Vec<&str> = table
            .variables
            .iter()
            .filter(|v| v.causality == Causality::Input)
            .map(|v| v.name.as_str())
            .collect();
        let known = if inputs.is_empty() {
            format!("scene {} has no inputs", sim.model().scene.name)
        } else {
            format!("the inputs of this scene are {}", inputs.join(", "))
        };
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l.trim()))
            .filter(|(_, l)| !l.is_empty());
        let (_, header) = lines
            .next()
            .ok_or("the file is empty; write a header `time,<input names>` and one row per time")?;
        let names: Vec<&str> = header.split(',').map(clean).collect();
        if names[0] != "time" {
            return Err(format!(
                "the first column must be `time`, got `{}`; write a header `time,<input names>`",
                names[0]
            ));
        }
        let mut columns = Vec::new();
        for (c, &name) in names.iter().enumerate().skip(1) {
            if names[..c].contains(&name) {
                return Err(format!(
                    "column {} `{name}` appears twice in the header; keep one",
                    c + 1
                ));
            }
            let target = match table.by_name(name) {
                Some(v) if v.causality == Causality::Input => {
                    Target::of(v.binding).ok_or_else(|| {
                        format!("column {} `{name}`: --inputs cannot set this input", c + 1)
                    })?
                }
                Some(v) => {
                    return Err(format!(
                        "column {} `{name}` is {} of the FMU, not an input; remove it ({known})",
                        c + 1,
                        causality_name(v.causality)
                    ))
                }
                None => {
                    return Err(format!(
                        "column {} `{name}` is not a variable of scene {}; remove or rename it ({known})",
                        c + 1,
                        sim.model().scene.name
                    ))
                }
            };
            columns.push((target, Vec::new()));
        }
        let mut times: Vec<f64> = Vec::new();
        for (line, row) in lines {
            let fields: Vec<&str> = row.split(',').map(clean).collect();
            if fields.len() != names.len() {
                return Err(format!(
                    "line {line} has {} values but the header has {} columns; give every row one value per column",
                    fields.len(),
                    names.len()
                ));
            }
            for (c, field) in fields.iter().enumerate() {
                let value: f64 = field.parse().map_err(|_| {
                    format!(
                        "line {line}, column `{}`: `{field}` is not a number",
                        names[c]
                    )
                })?;
                if !value.is_finite() {
                    return Err(format!(
                        "line {line}, column `{}`: {field} is not finite; inputs must be finite numbers",
                        names[c]
                    ));
                }
                if c == 0 {
                    if let Some(&last) = times.last() {
                        if value < last {
                            return Err(format!(
                                "line {line}: time {value} is before the previous row's {last}; times must not decrease (write a time twice for a step)"
                            ));
                        }
                    }
                    times.push(value);
                } else {
                    columns[c - 1].1.push(value);
                }
            }
        }
        if times.is_empty() {
            return Err("the file has a header but no rows; add at least one row".into());
        }
        // fmpy: `np.where(np.diff(t) == 0)`, exact equality.
        let mut events: Vec<f64> = times
            .windows(2)
            .filter(|w| w[1] == w[0])
            .map(|w| w[0])
            .collect();
        events.dedup();
        Ok(Self {
            times,
            columns,
            events,
        })
    }

    /// The next step time after `time` (fmpy's `Input.nextEvent`), or infinity.
    pub fn next_event(&self, time: f64) -> f64 {
        self.events
            .iter()
            .copied()
            .find(|&t| t > time && !isclose(t, time))
            .unwrap_or(f64::INFINITY)
    }

    /// Sets the table's value at `time` into `inputs` (fmpy's `Input.interpolate` for
    /// continuous inputs); at a step, the value after it when `after_event`, else before.
    pub fn apply(&self, time: f64, after_event: bool, inputs: &mut Inputs) {
        let t = &self.times;
        let n = t.len();
        // Left insertion index, as `np.searchsorted(t, time)`.
        let i0 = t.partition_point(|&x| x < time);
        let pick = |i: usize, inputs: &mut Inputs| {
            for (target, values) in &self.columns {
                set(inputs, *target, values[i]);
            }
        };
        if n < 2 || i0 == 0 {
            return pick(0, inputs);
        }
        if i0 == n {
            return pick(n - 1, inputs);
        }
        if isclose(time, t[i0]) && i0 < n - 1 && isclose(t[i0], t[i0 + 1]) {
            let mut i = i0;
            if after_event {
                while i < n - 1 && isclose(t[i], t[i + 1]) {
                    i += 1;
                }
            }
            return pick(i, inputs);
        }
        let (t0, t1) = (t[i0 - 1], t[i0]);
        let w0 = (t1 - time) / (t1 - t0);
        let w1 = 1.0 - w0;
        for (target, values) in &self.columns {
            set(inputs, *target, w0 * values[i0 - 1] + w1 * values[i0]);
        }
    }
}

/// What a column sets.
#[derive(Debug, Clone, Copy)]
enum Target {
    ForceDensity(usize),
    RestLength(usize),
    NodeForce(usize, usize),
}

impl Target {
    fn of(binding: Binding) -> Option<Self> {
        match binding {
            Binding::ForceDensity(k) => Some(Self::ForceDensity(k)),
            Binding::ReelInput(k) => Some(Self::RestLength(k)),
            Binding::NodeForce(k, axis) => Some(Self::NodeForce(k, axis)),
            _ => None,
        }
    }
}

fn set(inputs: &mut Inputs, target: Target, value: f64) {
    match target {
        Target::ForceDensity(k) => inputs.force_density[k] = value,
        Target::RestLength(k) => inputs.rest_length[k] = value,
        Target::NodeForce(k, axis) => inputs.node_force[k][axis] = value,
    }
}

/// A header or value cell without surrounding blanks or double quotes.
fn clean(cell: &str) -> &str {
    let cell = cell.trim();
    cell.strip_prefix('"')
        .and_then(|c| c.strip_suffix('"'))
        .unwrap_or(cell)
}

fn causality_name(c: Causality) -> &'static str {
    match c {
        Causality::Parameter => "a parameter",
        Causality::Output => "an output",
        Causality::CalculatedParameter => "a calculated parameter",
        Causality::Local => "a local variable",
        Causality::Independent => "the independent variable",
        Causality::Input => "an input",
    }
}
