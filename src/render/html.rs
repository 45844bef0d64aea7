//! One self-contained interactive HTML page of a run: a canvas viewer written for this
//! page (`viewer.js`, `viewer.css`, inlined) and the run embedded as JSON with base64
//! typed arrays. The page loads
//! nothing at view time: no network, no external script, style or font.

use base64::engine::general_purpose::STANDARD as BASE64;
use base64::Engine;
use serde::Serialize;

use super::terrain::TerrainShape;
use super::{Frames, GroundPlane};

const VIEWER_JS: &str = include_str!("viewer.js");
const VIEWER_CSS: &str = include_str!("viewer.css");

/// The id of the `<script type="application/json">` element holding the run.
pub const DATA_ELEMENT_ID: &str = "run-data";

/// The run as the page's script reads it. The bulk is binary, base64 of little-endian
/// arrays (a browser decodes them into typed arrays at once, and they take about 5.3 bytes
/// per number against 10 or more as JSON text): node pairs as `u32`, per-frame values
/// flattened over frames as `f32` (about 7 significant digits: far below a pixel; NaN
/// where not finite). Times stay JSON `f64`, so the clock shows them exactly.
#[derive(Serialize)]
struct PageData<'a> {
    name: &'a str,
    n_nodes: usize,
    /// `u32`: bar `b` joins nodes `[2 b]` and `[2 b + 1]` (0-based).
    bars: String,
    /// `u32`: cable `j` joins nodes `[2 j]` and `[2 j + 1]`.
    cables: String,
    pinned: &'a [usize],
    point_masses: &'a [usize],
    ground: Option<&'a GroundPlane>,
    /// Planes as normal and height, boxes and heightfields as points and quads.
    terrain: &'a [TerrainShape],
    /// Bar radii, m; absent when every bar is a line.
    bar_radius: Option<&'a [f64]>,
    times: &'a [f64],
    /// `f32`: `[(k n_nodes + i) 3 + c]`, node `i` at frame `k`, m.
    positions: String,
    /// `f32`, as positions, m/s.
    velocities: String,
    /// `f32`: `[k n_cables + j]`, N.
    tensions: String,
    /// `f32`: `[k n_bars + b]`, N, compression positive.
    bar_forces: String,
    /// The contact points and forces, where the run recorded them.
    contacts: Option<ContactData>,
}

/// Every frame's contacts: frame k's are `counts[k]` points after those of the frames
/// before it.
#[derive(Serialize)]
struct ContactData {
    /// `u32`: contacts per frame.
    counts: String,
    /// `f32`: `[3 m + c]`, contact m's point, m.
    points: String,
    /// `f32`: as points, the force on the structure there, N.
    forces: String,
    /// The largest force over the run, N.
    max_force: f64,
    /// Arrow length per newton, m/N.
    metres_per_newton: f64,
}

fn contact_data(frames: &Frames) -> Option<ContactData> {
    let scale = frames.contact_scale()?;
    let all = frames.contacts.iter().flatten();
    let counts: Vec<u8> = frames
        .contacts
        .iter()
        .flat_map(|c| u32::try_from(c.len()).unwrap_or(u32::MAX).to_le_bytes())
        .collect();
    Some(ContactData {
        counts: BASE64.encode(counts),
        points: f32_base64(all.clone().flat_map(|c| c.point.as_slice())),
        forces: f32_base64(all.flat_map(|c| c.force.as_slice())),
        max_force: scale.max_force,
        metres_per_newton: scale.metres_per_newton,
    })
}

/// Base64 of `values` as little-endian `f32`.
fn f32_base64<'a>(values: impl Iterator<Item = &'a f64>) -> String {
    let bytes: Vec<u8> = values.flat_map(|&v| (v as f32).to_le_bytes()).collect();
    BASE64.encode(bytes)
}

/// Base64 of the node pairs as little-endian `u32`.
fn pairs_base64(pairs: &[[usize; 2]]) -> String {
    let bytes: Vec<u8> = pairs
        .iter()
        .flatten()
        .flat_map(|&n| u32::try_from(n).unwrap_or(u32::MAX).to_le_bytes())
        .collect();
    BASE64.encode(bytes)
}

/// The run as JSON that is safe inside a `<script>` element: every `<` (which JSON allows
/// only inside strings) is written `\u003c`, so no `</script>` or `<!--` can appear; the
/// line and paragraph separators are escaped too.
pub fn embedded_json(frames: &Frames) -> String {
    let data = PageData {
        name: &frames.name,
        n_nodes: frames.n_nodes(),
        bars: pairs_base64(&frames.bars),
        cables: pairs_base64(&frames.cables),
        pinned: &frames.pinned,
        point_masses: &frames.point_masses,
        ground: frames.ground.as_ref(),
        terrain: &frames.terrain,
        bar_radius: Some(frames.bar_radius.as_slice()).filter(|r| r.iter().any(|&r| r > 0.0)),
        times: &frames.times,
        positions: f32_base64(frames.positions.iter().flatten().flatten()),
        velocities: f32_base64(frames.velocities.iter().flatten().flatten()),
        tensions: f32_base64(frames.tensions.iter().flatten()),
        bar_forces: f32_base64(frames.bar_forces.iter().flatten()),
        contacts: contact_data(frames),
    };
    let json = serde_json::to_string(&data).expect("plain data serializes");
    json.replace('<', "\\u003c")
        .replace('\u{2028}', "\\u2028")
        .replace('\u{2029}', "\\u2029")
}

/// Text escaped for HTML element content and attribute values.
fn escape_html(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            _ => out.push(c),
        }
    }
    out
}

/// One self-contained HTML page showing the run: orbit (drag), zoom (wheel), pan
/// (shift-drag), play/pause and a time slider; bars thick, cables coloured by tension with
/// a legend (slack cables dashed grey), pinned nodes and point masses marked, the ground
/// plane drawn when present, and hover or click to identify a node, bar or cable by its
/// 1-based number. The page's script exposes `window.viewer` for scripted checks.
pub fn page(frames: &Frames) -> String {
    let json = embedded_json(frames);
    let name = escape_html(&frames.name);
    let mut html = String::with_capacity(json.len() + VIEWER_JS.len() + VIEWER_CSS.len() + 4096);
    html.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    html.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
    html.push_str(&format!("<title>{name} · tensegrity-fmu</title>\n"));
    html.push_str("<style>\n");
    html.push_str(VIEWER_CSS);
    html.push_str("</style>\n</head>\n<body>\n");
    html.push_str(&format!(
        "<header><h1 id=\"scene-name\">{name}</h1><span id=\"summary\"></span></header>\n"
    ));
    html.push_str(concat!(
        "<main id=\"stage\">\n",
        "<canvas id=\"view\" tabindex=\"0\" aria-label=\"3-D view of the structure\"></canvas>\n",
        "<div id=\"tooltip\" hidden></div>\n",
        "<aside id=\"legend\"></aside>\n",
        "<div id=\"help\">drag: orbit · shift-drag: pan · wheel: zoom · double-click: reset · ",
        "space: play/pause · ←/→: step</div>\n",
        "</main>\n",
        "<footer id=\"controls\">\n",
        "<button id=\"play\" type=\"button\">Play</button>\n",
        "<input id=\"time\" type=\"range\" min=\"0\" max=\"0\" step=\"1\" value=\"0\" ",
        "aria-label=\"time\">\n",
        "<output id=\"clock\">t = 0 s</output>\n",
        "<label>speed <select id=\"speed\">",
        "<option value=\"0.1\">0.1×</option><option value=\"0.25\">0.25×</option>",
        "<option value=\"0.5\">0.5×</option><option value=\"1\" selected>1×</option>",
        "<option value=\"2\">2×</option></select></label>\n",
        "<span id=\"status\">hover or click a node, bar or cable</span>\n",
        "</footer>\n",
    ));
    html.push_str(&format!(
        "<script type=\"application/json\" id=\"{DATA_ELEMENT_ID}\">{json}</script>\n"
    ));
    html.push_str("<script>\n");
    html.push_str(VIEWER_JS);
    html.push_str("</script>\n</body>\n</html>\n");
    html
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tiny(name: &str) -> Frames {
        Frames {
            name: name.to_string(),
            bars: vec![[0, 1]],
            cables: vec![[1, 2], [2, 0]],
            pinned: vec![0],
            point_masses: vec![1],
            ground: Some(GroundPlane {
                normal: [0.0, 0.0, 1.0],
                height: -0.5,
            }),
            terrain: Vec::new(),
            bar_radius: vec![0.0],
            times: vec![0.0, 0.1],
            positions: vec![
                vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
                vec![[0.0, 0.0, 0.0], [1.0, 0.25, 0.0], [0.0, 1.0, 0.5]],
            ],
            velocities: vec![vec![[0.0; 3]; 3]; 2],
            tensions: vec![vec![3.0, 0.0], vec![f64::NAN, 2.5]],
            bar_forces: vec![vec![1.0], vec![-1.5]],
            contacts: Vec::new(),
        }
    }

    fn data(page: &str) -> serde_json::Value {
        let open = format!("<script type=\"application/json\" id=\"{DATA_ELEMENT_ID}\">");
        let start = page.find(&open).expect("data element") + open.len();
        let len = page[start..].find("</script>").expect("closed");
        serde_json::from_str(&page[start..start + len]).expect("valid JSON")
    }

    #[test]
    fn escapes_script_end_in_the_name() {
        let evil = "</script><script>alert(1)</script><!-- & \u{2028}";
        let page = page(&tiny(evil));
        // Exactly the page's own two scripts, opened and closed once each.
        assert_eq!(page.matches("<script").count(), 2);
        assert_eq!(page.matches("</script>").count(), 2);
        assert!(!page.contains("<script>alert"));
        assert!(!page.contains("<!--"));
        assert!(page.contains("<title>&lt;/script&gt;&lt;script&gt;alert(1)"));
        // The name reads back exactly from the embedded JSON.
        assert_eq!(data(&page)["name"], evil);
    }

    /// The little-endian 4-byte words of the base64 string `d[key]`.
    fn words(d: &serde_json::Value, key: &str) -> Vec<[u8; 4]> {
        let bytes = BASE64
            .decode(d[key].as_str().expect("base64 text"))
            .unwrap();
        assert_eq!(bytes.len() % 4, 0, "{key}");
        bytes.chunks(4).map(|w| [w[0], w[1], w[2], w[3]]).collect()
    }

    #[test]
    fn embeds_the_run() {
        let page = page(&tiny("tiny"));
        let d = data(&page);
        let floats =
            |key| -> Vec<f32> { words(&d, key).into_iter().map(f32::from_le_bytes).collect() };
        let nodes =
            |key| -> Vec<u32> { words(&d, key).into_iter().map(u32::from_le_bytes).collect() };
        assert_eq!(d["n_nodes"], 3);
        assert_eq!(nodes("bars"), [0, 1]);
        assert_eq!(nodes("cables"), [1, 2, 2, 0]);
        assert_eq!(d["pinned"], serde_json::json!([0]));
        assert_eq!(d["point_masses"], serde_json::json!([1]));
        assert_eq!(d["ground"]["height"], -0.5);
        assert_eq!(d["times"], serde_json::json!([0.0, 0.1]));
        let positions = floats("positions");
        assert_eq!(positions.len(), 2 * 9);
        assert_eq!(
            positions[9..],
            [0.0, 0.0, 0.0, 1.0, 0.25, 0.0, 0.0, 1.0, 0.5]
        );
        assert_eq!(floats("velocities"), [0.0; 18]);
        let tensions = floats("tensions");
        assert_eq!(tensions[..2], [3.0, 0.0]);
        assert!(tensions[2].is_nan() && tensions[3] == 2.5);
        assert_eq!(floats("bar_forces"), [1.0, -1.5]);
        assert!(page.contains("<h1 id=\"scene-name\">tiny</h1>"));
    }

    #[test]
    fn loads_nothing_from_outside() {
        let page = page(&tiny("tiny"));
        for needle in [
            "http://", "https://", "//cdn", "src=", "<link", "@import", "url(",
        ] {
            assert!(!page.contains(needle), "page contains {needle:?}");
        }
    }
}
