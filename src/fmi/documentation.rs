//! `documentation/index.html`: the structure and every variable with unit and meaning.

use super::variables::VariableTable;
use crate::model::{CableLaw, Model};

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The HTML page shipped in the FMU.
pub fn index_html(model: &Model, table: &VariableTable) -> String {
    let scene = &model.scene;
    let mut h = String::new();
    h.push_str("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">");
    h.push_str(&format!("<title>{}</title>", escape(&scene.name)));
    h.push_str("<style>body{font-family:sans-serif;max-width:60em;margin:auto}td,th{padding:2px 8px;text-align:left}</style></head><body>\n");
    h.push_str(&format!("<h1>{}</h1>\n", escape(&scene.name)));
    if let Some(d) = &scene.description {
        h.push_str(&format!("<p>{}</p>\n", escape(d)));
    }
    h.push_str("<h2>Structure and effects</h2>\n<ul>");
    for line in effect_lines(model) {
        h.push_str(&format!("<li>{}</li>", escape(&line)));
    }
    h.push_str(&format!(
        "<li>internal step {} s, correction {}</li></ul>\n",
        model.solver.step_size,
        if model.solver.correction { "on" } else { "off" },
    ));
    h.push_str("<p>Dynamics: Cheong, Skelton &amp; Cho (2014), non-minimal coordinates with the exact recursive bar-length and orthogonality correction after every internal step. Bar forces are positive in compression.</p>\n");
    h.push_str("<h2>Variables</h2>\n<table><tr><th>name</th><th>causality</th><th>unit</th><th>start</th><th>meaning</th></tr>\n");
    for v in &table.variables {
        h.push_str(&format!(
            "<tr><td><code>{}</code></td><td>{:?}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
            escape(&v.name),
            v.causality,
            v.unit.unwrap_or(""),
            v.start.map_or(String::new(), |s| s.to_string()),
            escape(&v.description)
        ));
    }
    h.push_str("</table>\n</body></html>\n");
    h
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
        "{} nodes (numbered from 1), {} rigid bars",
        model.n_nodes(),
        model.bars.len()
    )];
    if !scene.fixed.is_empty() {
        lines.push(format!("pinned nodes: {}", list(&scene.fixed)));
    }
    let mut ends = vec![0usize; model.n_nodes()];
    for b in &model.bars {
        ends[b.nodes[0]] += 1;
        ends[b.nodes[1]] += 1;
    }
    let joints = ends.iter().filter(|&&k| k > 1).count();
    if joints > 0 {
        lines.push(format!(
            "{joints} class-k joints (nodes shared by bars), class {}",
            ends.iter().max().copied().unwrap_or(1)
        ));
    }
    let count = |f: fn(&CableLaw) -> bool| model.cables.iter().filter(|c| f(&c.law)).count();
    let elastic = count(|l| matches!(l, CableLaw::Elastic { .. }));
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
        lines.push(format!("{elastic} elastic cables"));
    }
    if damped > 0 {
        lines.push(format!(
            "{damped} cables with damping on the extension rate (while taut)"
        ));
    }
    if !model.controlled.is_empty() {
        lines.push(format!(
            "{} force-density controlled cables (inputs cable[j].force_density)",
            model.controlled.len()
        ));
    }
    if !model.reeled.is_empty() {
        lines.push(format!(
            "{} rest-length controlled cables (inputs cable[j].rest_length)",
            model.reeled.len()
        ));
    }
    if !scene.force_inputs.is_empty() {
        lines.push(format!(
            "force inputs on nodes {}",
            list(&scene.force_inputs)
        ));
    }
    if !scene.loads.is_empty() {
        lines.push(format!(
            "{} scripted loads (parameters load[k].*), evaluated at the internal stage times",
            scene.loads.len()
        ));
    }
    if let Some(g) = model.gravity {
        lines.push(format!("gravity [{}, {}, {}] m/s²", g.x, g.y, g.z));
    }
    if !scene.point_masses.is_empty() {
        lines.push(format!(
            "{} point masses (parameters point_mass[k].mass)",
            scene.point_masses.len()
        ));
    }
    if let Some(g) = &model.ground {
        lines.push(format!(
            "ground plane n·x = {} m with n = [{:.4}, {:.4}, {:.4}]: penalty contact (k = {} N/m, c = {} N·s/m) and Coulomb friction μ = {} at {} bar-end nodes",
            g.height, g.normal.x, g.normal.y, g.normal.z, g.stiffness, g.damping, g.friction, g.nodes.len()
        ));
    }
    lines
}
