//! The interactive HTML page of a simulated run (`render::html::page`): it embeds the run
//! with the right counts and values, loads nothing from outside, and a hostile scene name
//! cannot leave its script element. Writes `target/render-test/prism2.html` (read by
//! tests/fmpy/test_html_viewer.py in headless Chromium) and `tower20.html` (10 s at 30 fps,
//! whose size and generation time are printed).

use std::path::PathBuf;
use std::time::Instant;

use nalgebra::Vector3;
use tensegrity_fmu::render::html::{page, DATA_ELEMENT_ID};
use tensegrity_fmu::render::terrain::TerrainShape;
use tensegrity_fmu::render::{Frames, GroundPlane};
use tensegrity_fmu::scene::{builtin, GroundSpec, PointMassSpec};
use tensegrity_fmu::{Model, Scene, Simulation};

fn out_dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/render-test");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Simulates `scene` for `duration` s, recording `fps` frames per second (and t = 0);
/// `drive(sim, t)` sets the inputs before the run reaches each frame time.
fn record(
    scene: &Scene,
    duration: f64,
    fps: f64,
    mut drive: impl FnMut(&mut Simulation, f64),
) -> Frames {
    let model = Model::new(scene).expect("scene builds");
    let mut sim = Simulation::new(model);
    let m = sim.model();
    let mut frames = Frames {
        name: scene.name.clone(),
        bars: m.bars.iter().map(|b| b.nodes).collect(),
        cables: m.cables.iter().map(|c| c.nodes).collect(),
        pinned: (0..m.n_nodes()).filter(|&i| m.pinned[i]).collect(),
        point_masses: scene.point_masses.iter().map(|p| p.node - 1).collect(),
        ground: m.ground.as_ref().map(|g| GroundPlane {
            normal: g.normal.into(),
            height: g.height,
        }),
        terrain: TerrainShape::all(m.terrain.as_ref()),
        bar_radius: m.bars.iter().map(|b| b.radius).collect(),
        times: vec![],
        positions: vec![],
        velocities: vec![],
        tensions: vec![],
        bar_forces: vec![],
        contacts: vec![],
    };
    let n = (duration * fps).round() as usize;
    for k in 0..=n {
        let t = k as f64 / fps;
        if k > 0 {
            sim.advance_to(t).expect("run steps");
        }
        drive(&mut sim, t);
        sim.refresh();
        let m = sim.model();
        let p3 = |v: Vector3<f64>| [v.x, v.y, v.z];
        frames.times.push(t);
        frames
            .positions
            .push((0..m.n_nodes()).map(|i| p3(sim.node_position(i))).collect());
        frames
            .velocities
            .push((0..m.n_nodes()).map(|i| p3(sim.node_velocity(i))).collect());
        frames
            .tensions
            .push((0..m.cables.len()).map(|j| sim.cable_tension(j)).collect());
        frames
            .bar_forces
            .push((0..m.bars.len()).map(|b| sim.bar_force(b)).collect());
    }
    frames
}

/// The JSON in the page's data element.
fn embedded(page: &str) -> serde_json::Value {
    let open = format!("<script type=\"application/json\" id=\"{DATA_ELEMENT_ID}\">");
    let start = page.find(&open).expect("data element") + open.len();
    let len = page[start..].find("</script>").expect("closed");
    serde_json::from_str(&page[start..start + len]).expect("valid JSON")
}

/// The little-endian 4-byte words of the base64 text `d[key]`.
fn words(d: &serde_json::Value, key: &str) -> Vec<[u8; 4]> {
    use base64::Engine;
    let text = d[key].as_str().unwrap_or_else(|| panic!("{key}: not text"));
    let bytes = base64::engine::general_purpose::STANDARD
        .decode(text)
        .unwrap();
    assert_eq!(bytes.len() % 4, 0, "{key}");
    bytes.chunks(4).map(|w| [w[0], w[1], w[2], w[3]]).collect()
}

/// The `f32` array `d[key]`.
fn floats(d: &serde_json::Value, key: &str) -> Vec<f32> {
    words(d, key).into_iter().map(f32::from_le_bytes).collect()
}

/// The `u32` array `d[key]`.
fn indices(d: &serde_json::Value, key: &str) -> Vec<u32> {
    words(d, key).into_iter().map(u32::from_le_bytes).collect()
}

/// prism2 with a ground plane under it, a point mass on node 8, a sideways sinusoidal push on
/// node 7 (its force input) and cable 13's force density cut to 0 for 1 s ≤ t < 1.5 s (slack).
fn prism2_frames() -> Frames {
    let mut scene = builtin("prism2").unwrap();
    scene.ground = Some(GroundSpec {
        height: -0.05,
        normal: [0.0, 0.0, 1.0],
        stiffness: 1e4,
        damping: 100.0,
        friction: 0.0,
        slip_velocity: 0.01,
    });
    scene
        .point_masses
        .push(PointMassSpec { node: 8, mass: 0.5 });
    let model = Model::new(&scene).unwrap();
    let slack = 12; // cable 13
    let input = model.controlled.iter().position(|&j| j == slack).unwrap();
    let start = model.controlled_start[input];
    record(&scene, 3.0, 30.0, |sim, t| {
        let f = 6.0 * (2.0 * std::f64::consts::PI * 0.8 * t).sin();
        sim.inputs.node_force[0] = Vector3::new(f, 0.5 * f, 0.0);
        sim.inputs.force_density[input] = if (1.0..1.5).contains(&t) { 0.0 } else { start };
    })
}

#[test]
fn prism2_page_embeds_the_run() {
    let frames = prism2_frames();
    let html = page(&frames);
    let path = out_dir().join("prism2.html");
    std::fs::write(&path, &html).unwrap();

    let d = embedded(&html);
    assert_eq!(d["name"], "prism2");
    assert_eq!(d["n_nodes"], 9);
    let bars = indices(&d, "bars");
    assert_eq!(bars.len(), 2 * 6);
    assert_eq!(indices(&d, "cables").len(), 2 * 15);
    assert_eq!(bars[..2], [0, 3]);
    assert_eq!(d["pinned"], serde_json::json!([0, 1, 2]));
    assert_eq!(d["point_masses"], serde_json::json!([7]));
    assert_eq!(d["ground"]["height"], -0.05);
    assert_eq!(d["ground"]["normal"], serde_json::json!([0.0, 0.0, 1.0]));
    let times = d["times"].as_array().unwrap();
    assert_eq!(times.len(), 91);
    assert_eq!(times[90], 3.0);
    let positions = floats(&d, "positions");
    assert_eq!(positions.len(), 91 * 27);
    assert_eq!(floats(&d, "velocities").len(), 91 * 27);
    let tensions = floats(&d, "tensions");
    assert_eq!(tensions.len(), 91 * 15);
    assert_eq!(floats(&d, "bar_forces").len(), 91 * 6);
    // Values as recorded (to f32 precision): node 7 at the last frame; cable 13 slack at
    // t = 1.2 s (frame 36) only.
    let last = &frames.positions[90][6];
    for c in 0..3 {
        let got = f64::from(positions[90 * 27 + 3 * 6 + c]);
        assert!(
            (got - last[c]).abs() <= 1e-6 * (1.0 + last[c].abs()),
            "{got} vs {}",
            last[c]
        );
    }
    assert_eq!(frames.tensions[36][12], 0.0);
    assert_eq!(tensions[36 * 15 + 12], 0.0);
    assert!(tensions[90 * 15 + 12] > 1.0, "taut again at the end");
    assert!(tensions[12] > 1.0, "taut at the start");
    // The structure moves: the top node is elsewhere at the end.
    let moved = (0..3).map(|c| (frames.positions[90][6][c] - frames.positions[0][6][c]).powi(2));
    assert!(moved.sum::<f64>().sqrt() > 0.01);

    for needle in ["http://", "https://", "src=", "<link", "@import", "url("] {
        assert!(!html.contains(needle), "page contains {needle:?}");
    }
    assert!(html.contains("<title>prism2 · tensegrity-fmu</title>"));
    assert_eq!(html.matches("<script").count(), 2);
}

#[test]
fn hostile_scene_name_stays_text() {
    let mut frames = prism2_frames();
    frames.name = "</script><script>alert(1)</script>".to_string();
    let html = page(&frames);
    assert_eq!(
        html.matches("<script").count(),
        2,
        "only the page's own scripts"
    );
    assert_eq!(html.matches("</script>").count(), 2);
    assert!(!html.contains("<script>alert(1)"));
    assert!(html.contains("&lt;/script&gt;&lt;script&gt;alert(1)&lt;/script&gt;"));
    assert_eq!(embedded(&html)["name"], frames.name);
    std::fs::write(out_dir().join("hostile.html"), &html).unwrap();
}

#[test]
fn run_without_frames_still_makes_a_page() {
    let mut frames = prism2_frames();
    frames.name = "empty".to_string();
    frames.times.clear();
    frames.positions.clear();
    frames.velocities.clear();
    frames.tensions.clear();
    frames.bar_forces.clear();
    let html = page(&frames);
    let d = embedded(&html);
    assert_eq!(d["n_nodes"], 0);
    assert_eq!(d["times"], serde_json::json!([]));
    assert_eq!(indices(&d, "bars").len(), 2 * 6);
    assert!(floats(&d, "positions").is_empty());
    std::fs::write(out_dir().join("empty.html"), &html).unwrap();
}

#[test]
fn tower20_ten_seconds_at_30_fps() {
    let scene = builtin("tower20").unwrap();
    let started = Instant::now();
    let frames = record(&scene, 10.0, 30.0, |sim, t| {
        let f = 8.0 * (2.0 * std::f64::consts::PI * 0.5 * t).sin();
        sim.inputs.node_force[0] = Vector3::new(f, 0.0, 0.0);
    });
    let simulated = started.elapsed();
    let started = Instant::now();
    let html = page(&frames);
    let generated = started.elapsed();
    std::fs::write(out_dir().join("tower20.html"), &html).unwrap();
    println!(
        "tower20, 10 s at 30 fps: {} frames, {} nodes, page {} bytes ({:.2} MB), generated in {:.3} s (simulation {:.2} s)",
        frames.len(),
        frames.n_nodes(),
        html.len(),
        html.len() as f64 / 1e6,
        generated.as_secs_f64(),
        simulated.as_secs_f64()
    );
    let d = embedded(&html);
    assert_eq!(d["times"].as_array().unwrap().len(), 301);
    assert_eq!(indices(&d, "bars").len(), 2 * 60);
    assert_eq!(indices(&d, "cables").len(), 2 * frames.cables.len());
    assert_eq!(d["n_nodes"], frames.n_nodes());
}

/// The bar counts of the large structure pages: `VIEWER_BARS` (comma-separated multiples of
/// 3), by default 6,000; tests/fmpy/test_html_viewer.py reads the same variable.
fn large_bar_counts() -> Vec<usize> {
    std::env::var("VIEWER_BARS")
        .unwrap_or_else(|_| "6000".into())
        .split(',')
        .map(|b| {
            b.trim()
                .parse()
                .expect("VIEWER_BARS: comma-separated bar counts")
        })
        .collect()
}

/// The structure page `build` puts in an FMU (one frame, at the start) for towers of
/// [`large_bar_counts`] bars, written as `target/render-test/tower<bars>.html`: about 85
/// bytes per bar.
#[test]
fn large_tower_structure_pages() {
    for bars in large_bar_counts() {
        assert_eq!(
            bars % 3,
            0,
            "VIEWER_BARS: multiples of 3 (a stage has 3 bars)"
        );
        let scene =
            tensegrity_fmu::scene::tower_with_rest_lengths(bars / 3, &format!("tower{bars}"));
        let started = Instant::now();
        let mut sim = Simulation::new(Model::new(&scene).unwrap());
        let frames = Frames::record(&mut sim, &[0.0]).unwrap();
        let html = page(&frames);
        println!(
            "{bars} bars: page {} bytes ({:.1} per bar), made in {:.2} s",
            html.len(),
            html.len() as f64 / bars as f64,
            started.elapsed().as_secs_f64()
        );
        let d = embedded(&html);
        assert_eq!(indices(&d, "bars").len(), 2 * bars);
        assert_eq!(floats(&d, "positions").len(), 3 * scene.nodes.len());
        assert!(html.len() < 100 * bars, "{} bytes", html.len());
        std::fs::write(out_dir().join(format!("tower{bars}.html")), &html).unwrap();
    }
}

#[test]
fn page_holds_the_terrain_shapes_and_bar_radii() {
    let mut scene = builtin("prism2").unwrap();
    for spec in [
        r#"kind = "plane"
point = [0.0, 0.0, -0.5]
normal = [0.0, 0.0, 2.0]
stiffness = 1e4"#,
        r#"kind = "box"
center = [1.0, 2.0, -0.5]
size = [2.0, 4.0, 1.0]
yaw = 90.0
stiffness = 1e4"#,
        r#"kind = "heightfield"
origin = [-1.0, -2.0]
spacing = [0.5, 0.25]
heights = [[0.0, 0.1, 0.2, 0.3], [1.0, 1.1, 1.2, 1.3], [2.0, 2.1, 2.2, 2.3]]
stiffness = 1e4"#,
    ] {
        scene.terrain.push(toml::from_str(spec).unwrap());
    }
    scene.bars[2].radius = 0.03;
    let frames = Frames::from_run(&scene, &[0.0]).unwrap();
    let html = page(&frames);
    std::fs::write(out_dir().join("terrain.html"), &html).unwrap();
    let d = embedded(&html);
    let terrain = d["terrain"].as_array().unwrap();
    assert_eq!(terrain.len(), 3);
    assert_eq!(terrain[0]["kind"], "plane");
    assert_eq!(terrain[0]["normal"], serde_json::json!([0.0, 0.0, 1.0]));
    assert_eq!(terrain[0]["height"], -0.5);
    assert_eq!(terrain[1]["kind"], "box");
    let corners = terrain[1]["points"].as_array().unwrap();
    assert_eq!(corners.len(), 8);
    assert_eq!(terrain[1]["quads"].as_array().unwrap().len(), 6);
    // Yawed 90°: the 2 m edge now runs along y, the 4 m one along x.
    let corner = |i: usize| -> Vec<f64> {
        corners[i]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| (v.as_f64().unwrap() * 1e9).round() / 1e9)
            .collect()
    };
    assert_eq!(corner(0), [3.0, 1.0, -1.0]);
    assert_eq!(corner(7), [-1.0, 3.0, 0.0]);
    assert_eq!(terrain[2]["kind"], "heightfield");
    assert_eq!(terrain[2]["points"].as_array().unwrap().len(), 12);
    assert_eq!(
        terrain[2]["points"][11],
        serde_json::json!([0.5, -1.5, 2.3])
    );
    assert_eq!(terrain[2]["quads"][5], serde_json::json!([6, 7, 11, 10]));
    assert_eq!(
        d["bar_radius"],
        serde_json::json!([0.0, 0.0, 0.03, 0.0, 0.0, 0.0])
    );
    // The viewer reads them: a legend row per kind, drawn faces.
    for needle in [
        "terrain box",
        "terrain heightfield",
        "terrain plane",
        "drawFaces",
    ] {
        assert!(html.contains(needle), "{needle}");
    }
    // Without terrain or radii the page says so plainly.
    let plain = embedded(&page(
        &Frames::from_run(&builtin("prism2").unwrap(), &[0.0]).unwrap(),
    ));
    assert_eq!(plain["terrain"], serde_json::json!([]));
    assert!(plain["bar_radius"].is_null());
}
