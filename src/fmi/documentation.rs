//! `documentation/index.html`: the structure and every variable with unit and meaning.

use fmi2_model_description::Causality;

use super::description::default_communication_step;
use super::variables::kinds::{kinds, pattern, runs};
use super::variables::{BaseType, Binding, Variable, VariableTable};
use crate::analysis::modes::{ModeKind, Spectrum};
use crate::integrator::Method;
use crate::model::{CableLaw, Model};
use crate::sim::Simulation;

/// How many of the lowest natural frequencies the page lists.
pub const LISTED_MODES: usize = 6;

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// `s` as a Python string literal.
fn python_string(s: &str) -> String {
    format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\""))
}

/// `n` followed by the singular or plural noun, e.g. `1 point mass`, `2 point masses`.
pub fn count(n: usize, singular: &str, plural: &str) -> String {
    format!("{n} {}", if n == 1 { singular } else { plural })
}

/// A start value as the importer sees it: Booleans by name, `solver.method` as
/// `1 (rk4)`, Integers without a decimal point.
fn start_text(v: &Variable) -> String {
    let Some(s) = v.start else {
        return String::new();
    };
    match (v.base_type, v.binding) {
        (BaseType::Boolean, _) => (if s != 0.0 { "true" } else { "false" }).to_string(),
        (BaseType::Integer, Binding::Method) => Method::from_fmi_value(s)
            .map_or_else(|| format!("{s}"), |m| format!("{s} ({})", m.name())),
        _ => format!("{s}"),
    }
}

fn variable_table(h: &mut String, title: &str, variables: &[&Variable]) {
    if variables.is_empty() {
        return;
    }
    h.push_str(&format!(
        "<h3>{title}</h3>\n<table><tr><th>name</th><th>causality</th><th>variability</th><th>type</th><th>unit</th><th>start</th><th>meaning</th></tr>\n"
    ));
    for v in variables {
        h.push_str(&format!(
            "<tr><td><code>{}</code></td><td>{:?}</td><td>{:?}</td><td>{:?}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
            escape(&v.name),
            v.causality,
            v.variability,
            v.base_type,
            v.unit.unwrap_or(""),
            start_text(v),
            escape(&v.description)
        ));
    }
    h.push_str("</table>\n");
}

/// Tables list every variable of an FMU with at most this many; a larger one gets a
/// summary by kind and the first [`LISTED_PER_KIND`] rows of each kind, so the page grows
/// with the number of kinds, not of variables.
pub const FULL_TABLE_VARIABLES: usize = 2_000;

/// Rows listed per kind in a summarised table.
pub const LISTED_PER_KIND: usize = 3;

/// A summary row per kind of `variables`, then the first [`LISTED_PER_KIND`] of each kind.
fn summarised_table(h: &mut String, title: &str, variables: &[&Variable]) {
    if variables.is_empty() {
        return;
    }
    let kinds = kinds(variables);
    h.push_str(&format!(
        "<h3>{title}</h3>\n<table><tr><th>variables</th><th>count</th><th>causality</th><th>variability</th><th>type</th><th>unit</th><th>start</th><th>meaning (of the first)</th></tr>\n"
    ));
    for kind in &kinds {
        let v = kind.first;
        let (key, _) = pattern(&v.name);
        let name = match kind.indices.len() {
            0 => v.name.clone(),
            _ => key.replacen("[i]", &format!("[{}]", runs(&kind.indices)), 1),
        };
        let start = match kind.starts {
            Some((lo, hi)) if !kind.same_start => format!("{lo} … {hi}"),
            _ => start_text(v),
        };
        h.push_str(&format!(
            "<tr class=\"kind\"><td><code>{}</code></td><td>{}</td><td>{:?}</td><td>{:?}</td><td>{:?}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
            escape(&name),
            kind.indices.len().max(1),
            v.causality,
            v.variability,
            v.base_type,
            v.unit.unwrap_or(""),
            start,
            escape(&v.description)
        ));
    }
    h.push_str("</table>\n");
    let mut seen = std::collections::HashMap::new();
    let listed: Vec<&Variable> = variables
        .iter()
        .copied()
        .filter(|v| {
            let n = seen.entry(pattern(&v.name).0).or_insert(0usize);
            *n += 1;
            *n <= LISTED_PER_KIND
        })
        .collect();
    variable_table(h, &format!("{title}: the first of each kind"), &listed);
}

/// Escapes `s` and sets its `backquoted` spans as code.
fn escape_code(s: &str) -> String {
    escape(s)
        .split('`')
        .enumerate()
        .map(|(k, part)| {
            if k % 2 == 1 {
                format!("<code>{part}</code>")
            } else {
                part.to_string()
            }
        })
        .collect()
}

/// The HTML page shipped in the FMU, for the simulation at its start state; `fmu_file` is
/// the name the FMU is written as (its usage example opens that file).
pub fn index_html(sim: &Simulation, table: &VariableTable, fmu_file: &str) -> String {
    let model = sim.model();
    let scene = &model.scene;
    let mut h = String::new();
    h.push_str("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">");
    h.push_str(&format!("<title>{}</title>", escape(&scene.name)));
    h.push_str("<style>body{font-family:sans-serif;max-width:60em;margin:auto}td,th{padding:2px 8px;text-align:left}</style></head><body>\n");
    h.push_str(&format!("<h1>{}</h1>\n", escape(&scene.name)));
    if let Some(d) = &scene.description {
        h.push_str(&format!("<p>{}</p>\n", escape(d)));
    }
    usage(&mut h, model, fmu_file);
    h.push_str("<h2>Structure and effects</h2>\n<ul>");
    for line in effect_lines(model) {
        h.push_str(&format!("<li>{}</li>", escape(&line)));
    }
    h.push_str(&format!(
        "<li>{}</li></ul>\n",
        escape(&model.solver.summary())
    ));
    h.push_str(
        "<p>The structure at its start, in an interactive viewer (drag to orbit, wheel to \
         zoom, hover or click to identify a node, bar or cable; \
         <a href=\"structure.html\">open it on its own</a>):</p>\n\
         <iframe src=\"structure.html\" title=\"the structure\" \
         style=\"width:100%;height:34em;border:1px solid #ccc\"></iframe>\n",
    );
    h.push_str("<p>Dynamics: Cheong, Skelton &amp; Cho (2014), non-minimal coordinates with the exact recursive bar-length and orthogonality correction after every internal step. Bar forces are positive in compression.</p>\n");
    natural_frequencies(&mut h, sim);
    h.push_str("<h2>Variables</h2>\n");
    let of = |c: Causality| -> Vec<&Variable> {
        table
            .variables
            .iter()
            .filter(|v| v.causality == c)
            .collect()
    };
    let full = table.variables.len() <= FULL_TABLE_VARIABLES;
    if !full {
        h.push_str(&format!(
            "<p>{} in all, summarised by kind (index ranges, start values from least to \
             greatest, the meaning of the first), then the first {LISTED_PER_KIND} of each \
             kind; <code>modelDescription.xml</code> lists every one.</p>\n",
            count(table.variables.len(), "variable", "variables")
        ));
    }
    let section = |h: &mut String, title: &str, c: Causality| {
        if full {
            variable_table(h, title, &of(c));
        } else {
            summarised_table(h, title, &of(c));
        }
    };
    section(&mut h, "Inputs", Causality::Input);
    section(&mut h, "Outputs", Causality::Output);
    h.push_str("<p>Tunable parameters may be changed between communication steps; fixed ones only before the end of initialization.</p>\n");
    section(&mut h, "Parameters", Causality::Parameter);
    h.push_str("</body></html>\n");
    h
}

/// Most reduced coordinates whose spectrum packaging computes (tower20 has 180: 0.03 s).
const DOCUMENTED_COORDINATES: usize = 600;

/// The lowest natural frequencies about the start state (the spectrum of
/// `tensegrity-fmu modes`), or why there are none: the start state is not at rest.
fn natural_frequencies(h: &mut String, sim: &Simulation) {
    h.push_str("<h2>Natural frequencies</h2>\n");
    let coordinates = 3 * sim.model().coords.r;
    if coordinates > DOCUMENTED_COORDINATES {
        h.push_str(&format!(
            "<p>No natural frequencies are listed: the structure has {coordinates} reduced \
             coordinates, and packaging computes the dense spectrum only up to \
             {DOCUMENTED_COORDINATES} (it costs seconds to minutes beyond); \
             <code>tensegrity-fmu modes</code> lists them.</p>\n"
        ));
        return;
    }
    if let Err(why) = crate::analysis::require_rest(sim, "No natural frequencies are listed") {
        h.push_str(&format!("<p>{}.</p>\n", escape_code(&why)));
        return;
    }
    let y = &sim.state().y;
    let spectrum = Spectrum::new(sim.model(), &sim.inputs, sim.time(), &y[..y.len() / 2]);
    let listed = spectrum.modes.len().min(LISTED_MODES);
    h.push_str(&format!(
        "<p>The {} of the structure about its start state, an equilibrium at rest \
         (linearized in the constrained coordinates, with the geometric stiffness of the \
         prestress; <code>tensegrity-fmu modes</code> lists all {} and \
         <code>tensegrity-fmu linearize</code> writes the state-space model):</p>\n",
        if listed == 1 {
            "lowest mode".to_string()
        } else {
            format!("{listed} lowest modes")
        },
        spectrum.modes.len(),
    ));
    h.push_str("<table><tr><th>mode</th><th>frequency (Hz)</th><th>kind</th></tr>\n");
    for (k, mode) in spectrum.modes.iter().take(listed).enumerate() {
        let kind = match mode.kind {
            ModeKind::Unstable => format!("unstable (grows at {:.4e} 1/s)", mode.growth_rate()),
            kind => kind.name().to_string(),
        };
        h.push_str(&format!(
            "<tr><td>{}</td><td>{:.6}</td><td>{kind}</td></tr>\n",
            k + 1,
            mode.frequency_hz()
        ));
    }
    h.push_str("</table>\n");
}

/// How to run the FMU, and what an importer must know about inputs.
fn usage(h: &mut String, model: &Model, fmu_file: &str) {
    // Text content: quotes stay as they are, so the code reads as written.
    let file = python_string(fmu_file)
        .replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;");
    let step = default_communication_step(model);
    h.push_str("<h2>Usage</h2>\n<p>With <a href=\"https://github.com/CATIA-Systems/FMPy\">fmpy</a>:</p>\n<pre><code>");
    h.push_str(&format!(
        "from fmpy import simulate_fmu\nresult = simulate_fmu({file}, stop_time=1.0, output_interval={step})\nprint(result.dtype.names, result[-1])"
    ));
    h.push_str("</code></pre>\n");
    h.push_str(&format!(
        "<p>Parameters are set with <code>start_values={{\"name\": value}}</code> and inputs with <code>input=</code>. \
         Input values are held constant over each communication step (the FMU does not interpolate inputs); \
         <code>fmi2DoStep</code> integrates the step in internal steps of <code>solver.step_size</code> \
         and the outputs are those at its end. The default experiment reports every {step} s.</p>\n"
    ));
}

/// One line per effect the scene declares, none for an absent one.
fn effect_lines(model: &Model) -> Vec<String> {
    let scene = &model.scene;
    let list = |v: &[usize]| {
        v.iter()
            .map(usize::to_string)
            .collect::<Vec<_>>()
            .join(", ")
    };
    let mut lines = vec![format!(
        "{} (numbered from 1), {}",
        count(model.n_nodes(), "node", "nodes"),
        count(model.bars.len(), "rigid bar", "rigid bars")
    )];
    if !scene.fixed.is_empty() {
        let nodes = if scene.fixed.len() == 1 {
            "node"
        } else {
            "nodes"
        };
        lines.push(format!("pinned {nodes}: {}", list(&scene.fixed)));
    }
    let mut ends = vec![0usize; model.n_nodes()];
    for b in &model.bars {
        ends[b.nodes[0]] += 1;
        ends[b.nodes[1]] += 1;
    }
    let joints = ends.iter().filter(|&&k| k > 1).count();
    if joints > 0 {
        lines.push(format!(
            "{} (nodes shared by bars), class {}",
            count(joints, "class-k joint", "class-k joints"),
            ends.iter().max().copied().unwrap_or(1)
        ));
    }
    let cables_where = |f: fn(&CableLaw) -> bool| model.cables.iter().filter(|c| f(&c.law)).count();
    let elastic = cables_where(|l| matches!(l, CableLaw::Elastic { .. }));
    let damped = model
        .cables
        .iter()
        .filter(|c| {
            matches!(
                c.law,
                CableLaw::Elastic {
                    damping: Some(_),
                    ..
                } | CableLaw::RestLengthControlled {
                    damping: Some(_),
                    ..
                }
            )
        })
        .count();
    if elastic > 0 {
        lines.push(count(elastic, "elastic cable", "elastic cables"));
    }
    if damped > 0 {
        lines.push(format!(
            "{} on the extension rate (while taut)",
            count(damped, "cable with damping", "cables with damping")
        ));
    }
    if !model.controlled.is_empty() {
        lines.push(format!(
            "{} (inputs cable[j].force_density)",
            count(
                model.controlled.len(),
                "force-density controlled cable",
                "force-density controlled cables"
            )
        ));
    }
    if !model.reeled.is_empty() {
        lines.push(format!(
            "{} (inputs cable[j].rest_length)",
            count(
                model.reeled.len(),
                "rest-length controlled cable",
                "rest-length controlled cables"
            )
        ));
    }
    if !scene.force_inputs.is_empty() {
        let nodes = if scene.force_inputs.len() == 1 {
            "node"
        } else {
            "nodes"
        };
        lines.push(format!(
            "force inputs on {nodes} {}",
            list(&scene.force_inputs)
        ));
    }
    if !scene.loads.is_empty() {
        lines.push(format!(
            "{} (parameters load[k].*), evaluated at the internal stage times",
            count(scene.loads.len(), "scripted load", "scripted loads")
        ));
    }
    if let Some(g) = model.gravity {
        lines.push(format!("gravity [{}, {}, {}] m/s²", g.x, g.y, g.z));
    }
    if !scene.point_masses.is_empty() {
        lines.push(format!(
            "{} (parameters point_mass[k].mass)",
            count(scene.point_masses.len(), "point mass", "point masses")
        ));
    }
    if let Some(g) = &model.ground {
        lines.push(format!(
            "ground plane n·x = {} m with n = [{:.4}, {:.4}, {:.4}]: penalty contact (k = {} N/m, c = {} N·s/m) and Coulomb friction μ = {} at {}",
            g.height, g.normal.x, g.normal.y, g.normal.z, g.stiffness, g.damping, g.friction,
            count(g.nodes.len(), "bar-end node", "bar-end nodes")
        ));
    }
    lines
}
