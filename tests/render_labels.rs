//! Pictures that read: the labels of `render --labels` never overlap each other or a node
//! (`render::labels`), and cables are drawn over the bars, so a cable crossing a bar shows
//! its colour there (tower20's cables stay visible).

mod cli_support;

use tensegrity_fmu::render::labels::{self, LabelKind, Rect, Request};
use tensegrity_fmu::render::picture::{self, Style, BAR, PNG_SIZE};
use tensegrity_fmu::render::view::{project, DEFAULT_AZIMUTH, DEFAULT_ELEVATION};
use tensegrity_fmu::render::Frames;
use tensegrity_fmu::scene::{builtin, builtin_names};
use tensegrity_fmu::{Model, Scene, Simulation};

fn frames_at(scene: &Scene, t: f64) -> Frames {
    let mut sim = Simulation::new(Model::new(scene).unwrap());
    Frames::record(&mut sim, &[t]).unwrap()
}

fn labelled() -> Style {
    Style::new(DEFAULT_AZIMUTH, DEFAULT_ELEVATION, true)
}

/// The scenes whose labelled pictures are checked: every built-in at its start, and the
/// dropped icosahedron at impact (the labelled picture in docs/render.md).
fn pictures() -> Vec<(String, Frames)> {
    let mut all: Vec<(String, Frames)> = builtin_names()
        .iter()
        .map(|n| (n.to_string(), frames_at(&builtin(n).unwrap(), 0.0)))
        .collect();
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/fmu/scenes/icosahedron-dropped.toml"
    );
    let dropped = Scene::from_name_or_file(path).unwrap();
    all.push((
        "icosahedron-dropped at 0.3 s".into(),
        frames_at(&dropped, 0.3),
    ));
    all
}

#[test]
fn label_boxes_are_pairwise_disjoint_and_off_the_nodes() {
    for (name, frames) in pictures() {
        let style = labelled();
        let fit = picture::fit(&frames, PNG_SIZE, &style);
        let placed = labels::layout(&frames, 0, &fit, &style, PNG_SIZE).unwrap();
        for (i, (a, ra)) in placed.iter().enumerate() {
            for (b, rb) in &placed[i + 1..] {
                assert!(
                    !ra.overlaps(rb),
                    "{name}: {} {ra:?} overlaps {} {rb:?}",
                    a.text,
                    b.text
                );
            }
            assert!(
                ra.x0 >= 0 && ra.y0 >= 0 && ra.x1 < PNG_SIZE.0 as i32 && ra.y1 < PNG_SIZE.1 as i32
            );
            // Near what it labels, and the box as large as the text needs.
            let (cx, cy) = ra.centre();
            let reach = (cx - a.anchor.0).abs().max((cy - a.anchor.1).abs());
            assert!(
                reach <= 3 * (a.size.0.max(a.size.1) / 2 + 3) + 1,
                "{name}: {} is {reach} px off",
                a.text
            );
            assert_eq!((ra.x1 - ra.x0, ra.y1 - ra.y0), a.size);
        }
        // No label covers a node.
        let px = |p: [f64; 3]| fit.to_pixel(project(p, style.azimuth, style.elevation));
        for p in &frames.positions[0] {
            let node = Rect::centred(px(*p), (6, 6));
            for (a, r) in &placed {
                assert!(!r.overlaps(&node), "{name}: {} covers a node", a.text);
            }
        }
        let count = |kind| placed.iter().filter(|(r, _)| r.kind == kind).count();
        let (nodes, bars, cables) = (
            count(LabelKind::Node),
            count(LabelKind::Bar),
            count(LabelKind::Cable),
        );
        println!(
            "{name}: placed {nodes}/{} node, {bars}/{} bar, {cables}/{} cable labels, none overlapping",
            frames.positions[0].len(),
            frames.bars.len(),
            frames.cables.len()
        );
        if !name.starts_with("tower") {
            // The small structures keep every node number.
            assert_eq!(nodes, frames.positions[0].len(), "{name}");
        }
    }
}

#[test]
fn placement_moves_a_label_off_another_and_leaves_out_what_cannot_fit() {
    let request = |text: &str, anchor| Request {
        text: text.into(),
        kind: LabelKind::Cable,
        anchor,
        size: (20, 12),
    };
    let bounds = Rect {
        x0: 0,
        y0: 0,
        x1: 200,
        y1: 200,
    };
    let same = [
        request("c1", (100, 100)),
        request("c2", (100, 100)),
        request("c3", (100, 100)),
    ];
    let spots = labels::place(&same, &[], bounds);
    let spots: Vec<Rect> = spots.into_iter().map(|s| s.expect("room around")).collect();
    assert_eq!(spots[0], Rect::centred((100, 100), (20, 12)));
    for i in 0..3 {
        for j in i + 1..3 {
            assert!(
                !spots[i].overlaps(&spots[j]),
                "{:?} {:?}",
                spots[i],
                spots[j]
            );
        }
    }
    // A picture just big enough for one label: the second is left out.
    let tiny = Rect {
        x0: 0,
        y0: 0,
        x1: 24,
        y1: 14,
    };
    let spots = labels::place(&[request("c1", (12, 7)), request("c2", (12, 7))], &[], tiny);
    assert!(spots[0].is_some() && spots[1].is_none(), "{spots:?}");
    // A blocked box (a node) is avoided.
    let node = Rect::centred((100, 100), (10, 10));
    let spot = labels::place(&[request("c1", (100, 100))], &[node], bounds)[0].unwrap();
    assert!(!spot.overlaps(&node));
}

/// Where the segments a–b and c–d cross, as fractions along each.
fn crossing(a: (f64, f64), b: (f64, f64), c: (f64, f64), d: (f64, f64)) -> Option<(f64, f64)> {
    let (r, s) = ((b.0 - a.0, b.1 - a.1), (d.0 - c.0, d.1 - c.1));
    let den = r.0 * s.1 - r.1 * s.0;
    if den.abs() < 1e-9 {
        return None;
    }
    let q = (c.0 - a.0, c.1 - a.1);
    Some(((q.0 * s.1 - q.1 * s.0) / den, (q.0 * r.1 - q.1 * r.0) / den))
}

/// Distance from `p` to the segment a–b.
fn distance(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let t = (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
    (p.0 - a.0 - t * dx).hypot(p.1 - a.1 - t * dy)
}

/// At every clean crossing of a taut cable over a bar in tower20's picture (no third
/// cable within 4 px), the pixel shows the cable's tension colour, not the bar's.
#[test]
fn cables_show_where_they_cross_bars() {
    for name in ["tower20", "icosahedron"] {
        let frames = frames_at(&builtin(name).unwrap(), 0.0);
        let style = Style::new(DEFAULT_AZIMUTH, DEFAULT_ELEVATION, false);
        let path = cli_support::temp(&format!("{name}-crossings.png"));
        picture::write_png(&frames, 0, &style, &path).unwrap();
        let img = image::open(&path).unwrap().to_rgb8();
        let fit = picture::fit(&frames, PNG_SIZE, &style);
        let pos = &frames.positions[0];
        let px = |n: usize| {
            let (x, y) = fit.to_pixel(project(pos[n], DEFAULT_AZIMUTH, DEFAULT_ELEVATION));
            (f64::from(x), f64::from(y))
        };
        let members: Vec<[usize; 2]> = frames.cables.clone();
        let (mut crossings, mut shown) = (0, 0);
        for (j, &[c0, c1]) in frames.cables.iter().enumerate() {
            let colour = picture::tension_colour(frames.tensions[0][j], frames.max_tension());
            for &[b0, b1] in &frames.bars {
                let Some((s, t)) = crossing(px(c0), px(c1), px(b0), px(b1)) else {
                    continue;
                };
                if !(0.2..0.8).contains(&s) || !(0.2..0.8).contains(&t) {
                    continue;
                }
                let (a, b) = (px(c0), px(c1));
                let at = (a.0 + s * (b.0 - a.0), a.1 + s * (b.1 - a.1));
                let others = members
                    .iter()
                    .filter(|&&m| m != [c0, c1])
                    .filter(|&&[m0, m1]| distance(at, px(m0), px(m1)) < 4.0)
                    .count();
                if others > 0 {
                    continue;
                }
                crossings += 1;
                let (x, y) = (at.0.round() as u32, at.1.round() as u32);
                let near = (x - 1..=x + 1)
                    .flat_map(|x| (y - 1..=y + 1).map(move |y| (x, y)))
                    .filter(|&(x, y)| img.get_pixel(x, y).0 == [colour.0, colour.1, colour.2])
                    .count();
                let bar_at = img.get_pixel(x, y).0 == [BAR.0, BAR.1, BAR.2];
                if near >= 2 && !bar_at {
                    shown += 1;
                }
            }
        }
        println!("{name}: {shown} of {crossings} clean cable-over-bar crossings show the cable");
        assert!(
            crossings >= 2,
            "{name}: too few clean crossings to judge ({crossings})"
        );
        assert_eq!(shown, crossings, "{name}");
    }
}
