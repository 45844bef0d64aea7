//! `documentation/index.html`: the structure and every variable with unit and meaning.

use super::variables::VariableTable;
use crate::model::Model;

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
    let pinned: Vec<String> = scene.fixed.iter().map(|n| n.to_string()).collect();
    h.push_str(&format!(
        "<h2>Structure</h2>\n<ul><li>{} nodes (numbered from 1), pinned: {}</li><li>{} rigid bars</li><li>{} cables ({} force-density controlled)</li><li>scripted loads: {}</li><li>gravity: {}</li><li>internal step {} s, correction {}</li></ul>\n",
        model.n_nodes(),
        if pinned.is_empty() { "none".to_string() } else { pinned.join(", ") },
        model.bars.len(),
        model.cables.len(),
        model.controlled.len(),
        model.loads.len(),
        model.gravity.map_or("none".to_string(), |g| format!("[{}, {}, {}] m/s²", g.x, g.y, g.z)),
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
