//! Reading a run back from a CSV: `tensegrity-fmu simulate`'s (header `time,node[1].x,…`)
//! or fmpy's (`fmpy.util.write_csv`, whose names may be quoted: `"time","node[1].x",…`).
//!
//! Every node position column (`node[i].x/y/z`) must be present; node velocities
//! (`node[i].vx/vy/vz`), cable tensions (`cable[j].tension`) and bar forces
//! (`bar[k].force`) are read when present and are zeros otherwise (a scene whose `outputs`
//! key leaves them out). Other columns are ignored.

use std::collections::HashMap;
use std::path::Path;

use super::Frames;

/// Fills `frames` (topology only, `n` nodes) with the rows of the CSV at `path`.
pub(crate) fn read(mut frames: Frames, n: usize, path: &Path) -> Result<Frames, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("--csv {}: cannot read it: {e}", path.display()))?;
    let at = |line: usize| format!("--csv {}, line {line}", path.display());
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let (_, header) = lines
        .next()
        .ok_or_else(|| format!("--csv {}: the file is empty", path.display()))?;
    let names: Vec<&str> = header.split(',').map(unquote).collect();
    if names.first() != Some(&"time") {
        return Err(format!(
            "{}: the first column must be `time` (got `{}`); pass a CSV written by `tensegrity-fmu simulate` or fmpy",
            at(1),
            names.first().unwrap_or(&"")
        ));
    }
    let index: HashMap<&str, usize> = names.iter().enumerate().map(|(i, n)| (*n, i)).collect();
    let column = |name: &str| index.get(name).copied();
    let mut pos = Vec::with_capacity(3 * n);
    for i in 1..=n {
        for axis in ["x", "y", "z"] {
            let name = format!("node[{i}].{axis}");
            pos.push(column(&name).ok_or_else(|| {
                format!(
                    "--csv {}: no column `{name}`; drawing needs every node position: include \"positions\" in the scene's `outputs` key (or leave the key out) and run it again",
                    path.display()
                )
            })?);
        }
    }
    let optional = |names: Vec<String>| names.iter().map(|s| column(s)).collect::<Vec<_>>();
    let vel = optional(
        (1..=n)
            .flat_map(|i| ["vx", "vy", "vz"].map(|a| format!("node[{i}].{a}")))
            .collect(),
    );
    let ten = optional(
        (1..=frames.cables.len())
            .map(|j| format!("cable[{j}].tension"))
            .collect(),
    );
    let force = optional(
        (1..=frames.bars.len())
            .map(|k| format!("bar[{k}].force"))
            .collect(),
    );
    let mut row = Vec::with_capacity(names.len());
    for (l, line) in lines {
        row.clear();
        for (c, cell) in line.split(',').enumerate() {
            let cell = unquote(cell);
            let v: f64 = cell.parse().map_err(|_| {
                format!(
                    "{}: column `{}`: `{cell}` is not a number",
                    at(l + 1),
                    names.get(c).unwrap_or(&"?")
                )
            })?;
            row.push(v);
        }
        if row.len() != names.len() {
            return Err(format!(
                "{}: {} values for {} columns",
                at(l + 1),
                row.len(),
                names.len()
            ));
        }
        let drawn = pos
            .iter()
            .map(|&c| Some(c))
            .chain(vel.iter().chain(&ten).chain(&force).copied());
        if let Some(c) = std::iter::once(0)
            .chain(drawn.flatten())
            .find(|&c| !row[c].is_finite())
        {
            return Err(format!(
                "{}: column `{}`: {} is not a finite number; a run that diverged cannot be \
                 drawn: keep only the rows before this line, or run the scene again with a smaller step",
                at(l + 1),
                names[c],
                row[c]
            ));
        }
        let t = row[0];
        if let Some(&p) = frames.times.last().filter(|&&p| t <= p) {
            return Err(format!(
                "{}: column `time`: {t} does not come after the previous row's {p}; times must \
                 increase strictly from row to row, as `simulate` writes them",
                at(l + 1)
            ));
        }
        let get = |c: Option<usize>| c.map_or(0.0, |c| row[c]);
        frames.times.push(t);
        frames.positions.push(
            (0..n)
                .map(|i| [row[pos[3 * i]], row[pos[3 * i + 1]], row[pos[3 * i + 2]]])
                .collect(),
        );
        frames.velocities.push(
            (0..n)
                .map(|i| [get(vel[3 * i]), get(vel[3 * i + 1]), get(vel[3 * i + 2])])
                .collect(),
        );
        frames.tensions.push(ten.iter().map(|&c| get(c)).collect());
        frames
            .bar_forces
            .push(force.iter().map(|&c| get(c)).collect());
    }
    if frames.is_empty() {
        return Err(format!(
            "--csv {}: no rows after the header",
            path.display()
        ));
    }
    Ok(frames)
}

/// A cell without surrounding spaces and double quotes.
fn unquote(cell: &str) -> &str {
    let cell = cell.trim();
    cell.strip_prefix('"')
        .and_then(|c| c.strip_suffix('"'))
        .unwrap_or(cell)
}
