//! `render` to PNG: the structure is drawn where the projection puts it (bar colour at
//! every bar midpoint, each cable's tension colour at its midpoint), slack cables differ
//! from taut ones, every built FMU carries a `model.png` icon, and the error cases.

mod cli_support;

use cli_support::{run, temp};
use image::RgbImage;
use tensegrity_fmu::render::picture::{self, Style, BAR, PNG_SIZE, SLACK};
use tensegrity_fmu::render::view::{project, DEFAULT_AZIMUTH, DEFAULT_ELEVATION};
use tensegrity_fmu::render::Frames;
use tensegrity_fmu::scene::builtin;
use tensegrity_fmu::{Model, Simulation};

fn read_png(path: &std::path::Path) -> RgbImage {
    image::open(path).expect("a PNG").to_rgb8()
}

/// Pixels of `colour` within `r` pixels of `(x, y)`.
fn hits(img: &RgbImage, (x, y): (i32, i32), r: i32, colour: [u8; 3]) -> usize {
    let mut n = 0;
    for dy in -r..=r {
        for dx in -r..=r {
            let (px, py) = (x + dx, y + dy);
            if px >= 0 && py >= 0 && (px as u32) < img.width() && (py as u32) < img.height() {
                n += usize::from(img.get_pixel(px as u32, py as u32).0 == colour);
            }
        }
    }
    n
}

fn rgb(c: plotters::style::RGBColor) -> [u8; 3] {
    [c.0, c.1, c.2]
}

/// Pixel positions along the middle third of a segment, one per pixel of length.
fn middle_third(a: (i32, i32), b: (i32, i32)) -> Vec<(i32, i32)> {
    let len = f64::from((b.0 - a.0).abs().max((b.1 - a.1).abs())).max(1.0);
    let n = len as i32;
    (n / 3..=2 * n / 3)
        .map(|i| {
            let f = f64::from(i) / len;
            (
                (f64::from(a.0) + f * f64::from(b.0 - a.0)).round() as i32,
                (f64::from(a.1) + f * f64::from(b.1 - a.1)).round() as i32,
            )
        })
        .collect()
}

/// Distance in pixels from `p` to the segment `a`–`b`.
fn distance(p: (i32, i32), a: (i32, i32), b: (i32, i32)) -> f64 {
    let f = |q: (i32, i32)| (f64::from(q.0), f64::from(q.1));
    let (p, a, b) = (f(p), f(a), f(b));
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p.0 - a.0 - t * dx).hypot(p.1 - a.1 - t * dy)
}

struct Drawn {
    frames: Frames,
    px: Box<dyn Fn([f64; 3]) -> (i32, i32)>,
}

/// Where the picture of frame 0 of `frames` puts each point (default camera, full picture).
fn drawn(frames: Frames) -> Drawn {
    let style = Style::new(DEFAULT_AZIMUTH, DEFAULT_ELEVATION, false);
    let fit = picture::fit(&frames, PNG_SIZE, &style);
    Drawn {
        frames,
        px: Box::new(move |p| fit.to_pixel(project(p, DEFAULT_AZIMUTH, DEFAULT_ELEVATION))),
    }
}

impl Drawn {
    fn ends(&self, [a, b]: [usize; 2]) -> ((i32, i32), (i32, i32)) {
        let pos = &self.frames.positions[0];
        ((self.px)(pos[a]), (self.px)(pos[b]))
    }

    /// Cables whose middle third stays clear of every bar (bars are drawn over cables).
    fn clear_cables(&self) -> Vec<usize> {
        (0..self.frames.cables.len())
            .filter(|&j| {
                let (a, b) = self.ends(self.frames.cables[j]);
                middle_third(a, b).iter().all(|&p| {
                    self.frames.bars.iter().all(|&bar| {
                        let (c, d) = self.ends(bar);
                        distance(p, c, d) > 8.0
                    })
                })
            })
            .collect()
    }
}

#[test]
fn png_has_bars_and_tension_coloured_cables_where_projected() {
    let out = temp("prism2.png");
    let (ok, stdout, stderr) = run(&["render", "prism2", "-o", out.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    assert_eq!(stdout.trim(), out.to_str().unwrap());
    let img = read_png(&out);
    assert_eq!(img.dimensions(), PNG_SIZE);
    let frames = Frames::from_run(&builtin("prism2").unwrap(), &[0.0]).unwrap();
    let d = drawn(frames);
    let bar = rgb(BAR);
    for (k, &nodes) in d.frames.bars.iter().enumerate() {
        let (a, b) = d.ends(nodes);
        let mid = ((a.0 + b.0) / 2, (a.1 + b.1) / 2);
        assert!(
            hits(&img, mid, 1, bar) >= 3,
            "bar {} not drawn at {mid:?}",
            k + 1
        );
    }
    let max = d.frames.max_tension();
    assert!(
        max > 10.0,
        "prism2 is prestressed to at least 10 N, got max {max}"
    );
    let clear = d.clear_cables();
    assert!(
        clear.len() >= 6,
        "only {} cables clear of bars",
        clear.len()
    );
    for &j in &clear {
        let t = d.frames.tensions[0][j];
        let colour = rgb(picture::tension_colour(t, max));
        let (a, b) = d.ends(d.frames.cables[j]);
        let mid = ((a.0 + b.0) / 2, (a.1 + b.1) / 2);
        assert!(
            hits(&img, mid, 2, colour) >= 2,
            "cable {} ({t} N) not drawn in {colour:?} at {mid:?}",
            j + 1
        );
    }
    // Not blank: a good share of coloured pixels, and a title above the structure.
    let inked = img.pixels().filter(|p| p.0 != [255, 255, 255]).count();
    assert!(inked > 10_000, "{inked} inked pixels");
    let title = (0..40u32)
        .flat_map(|y| (0..PNG_SIZE.0).map(move |x| (x, y)))
        .filter(|&(x, y)| img.get_pixel(x, y).0 != [255, 255, 255])
        .count();
    assert!(
        title > 200,
        "no title: {title} inked pixels in the top band"
    );
}

#[test]
fn a_slack_cable_is_drawn_grey_and_dashed_a_taut_one_in_colour() {
    let scene = builtin("prism2").unwrap();
    let mut sim = Simulation::new(Model::new(&scene).unwrap());
    let taut = drawn(Frames::record(&mut sim, &[0.0]).unwrap());
    let j = taut.clear_cables()[0];
    let controlled = &sim.model().controlled;
    let input = controlled
        .iter()
        .position(|&c| c == j)
        .expect("prism2's cables are all controlled");
    let mut sim = Simulation::new(Model::new(&scene).unwrap());
    sim.inputs.force_density[input] = 0.0;
    let slack = drawn(Frames::record(&mut sim, &[0.0]).unwrap());
    assert_eq!(slack.frames.tensions[0][j], 0.0);
    assert!(taut.frames.tensions[0][j] > 0.0);
    let style = Style::new(DEFAULT_AZIMUTH, DEFAULT_ELEVATION, false);
    let count = |d: &Drawn, name: &str, colour: [u8; 3]| {
        let path = temp(name);
        picture::write_png(&d.frames, 0, &style, &path).unwrap();
        let img = read_png(&path);
        let (a, b) = d.ends(d.frames.cables[j]);
        middle_third(a, b)
            .iter()
            .filter(|&&p| hits(&img, p, 1, colour) > 0)
            .count()
    };
    let max = taut.frames.max_tension();
    let coloured = rgb(picture::tension_colour(taut.frames.tensions[0][j], max));
    let grey = rgb(SLACK);
    let (taut_grey, taut_colour) = (
        count(&taut, "taut-g.png", grey),
        count(&taut, "taut-c.png", coloured),
    );
    let (slack_grey, slack_colour) = (
        count(&slack, "slack-g.png", grey),
        count(&slack, "slack-c.png", coloured),
    );
    let along = middle_third(
        taut.ends(taut.frames.cables[j]).0,
        taut.ends(taut.frames.cables[j]).1,
    )
    .len();
    println!(
        "cable {}: taut {taut_colour}/{along} coloured, slack {slack_grey}/{along} grey",
        j + 1
    );
    assert_eq!(taut_grey, 0);
    assert!(taut_colour * 10 >= along * 9);
    assert_eq!(slack_colour, 0);
    // Dashed: grey along part of it, not all of it.
    assert!(
        slack_grey * 4 >= along && slack_grey < along,
        "{slack_grey} of {along}"
    );
}

#[test]
fn every_built_fmu_carries_a_model_png_icon() {
    for name in ["prism2", "prism2-elastic", "icosahedron", "tower20"] {
        let fmu = temp(&format!("{name}.fmu"));
        let (ok, _, stderr) = run(&["build", name, "-o", fmu.to_str().unwrap()]);
        assert!(ok, "{name}: {stderr}");
        let mut zip = zip::ZipArchive::new(std::fs::File::open(&fmu).unwrap()).unwrap();
        let mut png = Vec::new();
        std::io::Read::read_to_end(&mut zip.by_name("model.png").expect("model.png"), &mut png)
            .unwrap();
        let img = image::load_from_memory(&png).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), picture::ICON_SIZE, "{name}");
        let bar = img.pixels().filter(|p| p.0 == rgb(BAR)).count();
        assert!(bar > 300, "{name}: {bar} bar pixels in model.png");
        // the documentation shows the structure in the interactive viewer
        let read = |zip: &mut zip::ZipArchive<std::fs::File>, entry: &str| {
            let mut text = String::new();
            std::io::Read::read_to_string(&mut zip.by_name(entry).expect(entry), &mut text)
                .unwrap();
            text
        };
        let index = read(&mut zip, "documentation/index.html");
        assert!(index.contains("<iframe src=\"structure.html\""), "{name}");
        let viewer = read(&mut zip, "documentation/structure.html");
        assert!(viewer.contains(&format!("<title>{name}")), "{name}");
        let model = tensegrity_fmu::Model::new(&builtin(name).unwrap()).unwrap();
        let nodes = format!("\"n_nodes\":{}", model.n_nodes());
        assert!(
            viewer.contains(&nodes),
            "{name}: the embedded run has every node"
        );
    }
}

fn render_err(args: &[&str]) -> String {
    let (ok, _, stderr) = run(args);
    assert!(!ok, "{args:?} succeeded");
    stderr
}

#[test]
fn render_errors_name_the_option_and_the_fix() {
    let out = temp("e.jpg");
    let e = render_err(&["render", "prism2", "-o", out.to_str().unwrap()]);
    assert!(
        e.contains(".png, .gif, .html, .pvd") && e.contains("-o"),
        "{e}"
    );
    let png = temp("e.png");
    let png = png.to_str().unwrap();
    let e = render_err(&["render", "prism2", "-o", png, "--time", "1", "--at", "2"]);
    assert!(e.contains("--at 2") && e.contains("0 to 1 s"), "{e}");
    let e = render_err(&["render", "prism2", "-o", png, "--at", "-0.5"]);
    assert!(
        e.contains("--at -0.5") && e.contains("outside the run"),
        "{e}"
    );
    let gif = temp("e.gif");
    let e = render_err(&[
        "render",
        "prism2",
        "-o",
        gif.to_str().unwrap(),
        "--fps",
        "0",
    ]);
    assert!(e.contains("--fps") && e.contains("--fps 10"), "{e}");
    let e = render_err(&["render", "prism2", "-o", gif.to_str().unwrap(), "--at", "1"]);
    assert!(e.contains("--at is for still pictures"), "{e}");
    let e = render_err(&["render", "prism2", "-o", png, "--azimuth", "nan"]);
    assert!(e.contains("--azimuth"), "{e}");
    assert!(!std::path::Path::new(png).exists() && !gif.exists());
}

#[test]
fn html_and_paraview_outputs_come_from_the_same_run() {
    let html = temp("run.html");
    let (ok, _, stderr) = run(&[
        "render",
        "prism2",
        "--time",
        "1",
        "--fps",
        "10",
        "-o",
        html.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(page.contains("<title>prism2"), "the page names the scene");
    assert!(!page.contains("https://") && !page.contains("http://"));
    let pvd = temp("run.pvd");
    let (ok, _, stderr) = run(&[
        "render",
        "prism2",
        "--time",
        "1",
        "--fps",
        "10",
        "-o",
        pvd.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let collection = std::fs::read_to_string(&pvd).unwrap();
    // one data set per frame: t = 0, 0.1, …, 1
    assert_eq!(collection.matches("<DataSet ").count(), 11, "{collection}");
    assert!(collection.contains("timestep=\"1\""), "{collection}");
}

#[test]
fn pins_point_masses_and_the_ground_are_marked() {
    // prism2: pinned nodes 1–3 get triangles; no ground.
    let out = temp("pins.png");
    let (ok, _, stderr) = run(&["render", "prism2", "-o", out.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    let img = read_png(&out);
    let d = drawn(Frames::from_run(&builtin("prism2").unwrap(), &[0.0]).unwrap());
    assert_eq!(d.frames.pinned, [0, 1, 2]);
    for &i in &d.frames.pinned {
        let (x, y) = (d.px)(d.frames.positions[0][i]);
        // The triangle hangs below its node.
        assert!(
            hits(&img, (x, y + 12), 3, rgb(picture::PIN)) > 10,
            "pin {}",
            i + 1
        );
    }
    let ground = rgb(picture::GROUND_FILL);
    assert_eq!(img.pixels().filter(|p| p.0 == ground).count(), 0);
    // A dropped icosahedron with a payload on node 2 over a ground plane.
    let mut text = tensegrity_fmu::Model::new(&builtin("icosahedron").unwrap())
        .unwrap()
        .explicit_scene()
        .to_toml_string()
        .replace("fixed = [1, 5, 9]", "gravity = [0.0, 0.0, -9.81]");
    text.push_str(
        "\n[[point_masses]]\nnode = 2\nmass = 0.5\n\n[ground]\nheight = -0.8\nstiffness = 1e4\n",
    );
    let scene_path = temp("dropped.toml");
    std::fs::write(&scene_path, &text).unwrap();
    let out = temp("dropped.png");
    let (ok, _, stderr) = run(&[
        "render",
        scene_path.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let img = read_png(&out);
    let scene = tensegrity_fmu::Scene::from_name_or_file(scene_path.to_str().unwrap()).unwrap();
    let d = drawn(Frames::from_run(&scene, &[0.0]).unwrap());
    assert!(d.frames.pinned.is_empty());
    assert_eq!(d.frames.point_masses, [1]);
    let mass = (d.px)(d.frames.positions[0][1]);
    assert!(
        hits(&img, mass, 5, rgb(BAR)) > 60,
        "no filled circle at node 2"
    );
    // The ground quad's centre lies under the structure's centre, on the plane.
    let quad = picture::ground_quad(&d.frames).unwrap();
    assert!(quad.iter().all(|p| (p[2] + 0.8).abs() < 1e-12));
    let centre = [0, 1, 2].map(|i| quad.iter().map(|p| p[i]).sum::<f64>() / 4.0);
    let nodes = &d.frames.positions[0];
    for i in 0..2 {
        let mean = nodes.iter().map(|p| p[i]).sum::<f64>() / nodes.len() as f64;
        assert!((centre[i] - mean).abs() < 1e-12);
    }
    let filled = img.pixels().filter(|p| p.0 == ground).count();
    assert!(filled > 20_000, "{filled} ground pixels");
    // Near each corner of the quad (out beyond the structure) the picture shows ground.
    for corner in quad {
        let inside = [0, 1, 2].map(|i| centre[i] + 0.9 * (corner[i] - centre[i]));
        assert!(hits(&img, (d.px)(inside), 3, ground) > 0, "{corner:?}");
    }
}

/// prism2 (pinned, at rest) with `terrain` (TOML tables, `{z0}` replaced by the lowest
/// node's height less 0.25 m), its bars of radius `radius`.
fn prism2_on(terrain: &[&str], radius: f64) -> tensegrity_fmu::Scene {
    let mut scene = builtin("prism2").unwrap();
    let nodes = Frames::from_run(&scene, &[0.0])
        .unwrap()
        .positions
        .remove(0);
    let z0 = nodes.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min);
    for t in terrain {
        let text = t.replace("{z0}", &(z0 - 0.25).to_string());
        scene.terrain.push(toml::from_str(&text).unwrap());
    }
    scene.bars.iter_mut().for_each(|b| b.radius = radius);
    scene
}

/// The PNG of frame 0 of `scene`, and where it puts points.
fn picture_of(scene: &tensegrity_fmu::Scene, name: &str) -> (RgbImage, Drawn) {
    let frames = Frames::from_run(scene, &[0.0]).unwrap();
    let out = temp(name);
    let style = Style::new(DEFAULT_AZIMUTH, DEFAULT_ELEVATION, false);
    picture::write_png(&frames, 0, &style, &out).unwrap();
    (read_png(&out), drawn(frames))
}

#[test]
fn a_box_under_the_structure_is_drawn_shaded_where_projected() {
    // A 0.4 m high block under the whole prism, its top 5 cm below the lowest node.
    let block = r#"kind = "box"
center = [0.0, 0.0, {z0}]
size = [2.0, 2.0, 0.4]
stiffness = 1e4"#;
    let scene = prism2_on(&[block], 0.0);
    let (img, d) = picture_of(&scene, "box.png");
    let [x, y, z] = match &d.frames.terrain[..] {
        [tensegrity_fmu::render::terrain::TerrainShape::Box(m)] => {
            assert_eq!((m.points.len(), m.quads.len()), (8, 6));
            m.points.iter().fold([f64::NEG_INFINITY; 3], |a, p| {
                [a[0].max(p[0]), a[1].max(p[1]), a[2].max(p[2])]
            })
        }
        other => panic!("one box, got {other:?}"),
    };
    // The camera (azimuth 30°) sees the +x and +y sides, each lit its own shade.
    let (east, north) = (
        picture::terrain_shade(picture::BOX_COLOUR, [1.0, 0.0, 0.0]),
        picture::terrain_shade(picture::BOX_COLOUR, [0.0, 1.0, 0.0]),
    );
    assert_ne!(east, north);
    let east_mid = (d.px)([x, 0.0, z - 0.2]);
    let north_mid = (d.px)([0.0, y, z - 0.2]);
    assert!(
        hits(&img, east_mid, 3, rgb(east)) >= 40,
        "+x side at {east_mid:?}"
    );
    assert!(
        hits(&img, north_mid, 3, rgb(north)) >= 40,
        "+y side at {north_mid:?}"
    );
    // The top, lit most, shows around the structure.
    let top = rgb(picture::terrain_shade(picture::BOX_COLOUR, [0.0, 0.0, 1.0]));
    assert!(img.pixels().filter(|p| p.0 == top).count() > 5_000);
    // Without the box the same spots show no box colour.
    let (plain, _) = picture_of(&builtin("prism2").unwrap(), "no-box.png");
    assert_eq!(plain.pixels().filter(|p| p.0 == rgb(east)).count(), 0);
    // The structure stays on top: every bar midpoint is bar-coloured.
    for &nodes in &d.frames.bars {
        let (a, b) = d.ends(nodes);
        let mid = ((a.0 + b.0) / 2, (a.1 + b.1) / 2);
        assert!(hits(&img, mid, 1, rgb(BAR)) >= 3, "bar at {mid:?}");
    }
}

#[test]
fn a_heightfield_is_drawn_as_its_shaded_quads() {
    // 3 rows of 4 heights sloping up along x, spanning the structure and more.
    let field = r#"kind = "heightfield"
origin = [-2.0, -2.0]
spacing = [1.3333333333333333, 2.0]
heights = [[-0.3, -0.2, -0.1, 0.0], [-0.3, -0.2, -0.1, 0.0], [-0.3, -0.2, -0.1, 0.0]]
stiffness = 1e4"#;
    let scene = prism2_on(&[field], 0.0);
    let (img, d) = picture_of(&scene, "heightfield.png");
    let mesh = d.frames.terrain_meshes().remove(0);
    assert_eq!((mesh.points.len(), mesh.quads.len()), (12, 6));
    // Every quad has the same slope, so one shade; it fills much of the picture.
    let n = tensegrity_fmu::render::terrain::quad_normal(&mesh, mesh.quads[0]);
    assert!((n[0] + 0.0749).abs() < 1e-3 && n[2] > 0.99, "{n:?}");
    let shade = rgb(picture::terrain_shade(picture::HEIGHTFIELD_COLOUR, n));
    let filled = img.pixels().filter(|p| p.0 == shade).count();
    assert!(filled > 50_000, "{filled} heightfield pixels");
    // At the middle of each quad in the picture and clear of the structure, the field shows.
    let rect = picture::plot_rect(PNG_SIZE, &Style::new(30.0, 20.0, false));
    let members: Vec<_> = d
        .frames
        .bars
        .iter()
        .chain(&d.frames.cables)
        .map(|&m| d.ends(m))
        .collect();
    let mut seen = 0;
    for q in &mesh.quads {
        let c = [0, 1, 2].map(|i| q.iter().map(|&k| mesh.points[k][i]).sum::<f64>() / 4.0);
        let p = (d.px)(c);
        let inside = p.0 > rect.0 + 5 && p.0 < rect.2 - 5 && p.1 > rect.1 + 5 && p.1 < rect.3 - 5;
        if inside && members.iter().all(|&(a, b)| distance(p, a, b) > 30.0) {
            assert!(hits(&img, p, 3, shade) >= 40, "quad middle {c:?} at {p:?}");
            seen += 1;
        }
    }
    assert!(seen >= 1, "{seen} quad middles in the picture");
}

#[test]
fn bars_with_a_radius_are_drawn_thicker() {
    let count = |img: &RgbImage| img.pixels().filter(|p| p.0 == rgb(BAR)).count();
    let (thin, _) = picture_of(&builtin("prism2").unwrap(), "radius-0.png");
    let (thick, d) = picture_of(&prism2_on(&[], 0.04), "radius-4cm.png");
    assert_eq!(d.frames.bar_radius, [0.04; 6]);
    let (a, b) = (count(&thin), count(&thick));
    assert!(b > 2 * a, "{a} bar pixels without a radius, {b} with 4 cm");
}
