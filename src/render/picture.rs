//! Still pictures (PNG) of a recorded run, drawn with plotters: an orthographic view fitted
//! to the structure over the whole run, bars as thick dark lines, cables over them coloured
//! by tension (slack ones light grey and dashed) with a colour bar, pinned nodes as
//! triangles, point masses as filled circles, the ground plane as a grid, and a title;
//! the contacts, where the run recorded them ([`contacts`]). [`draw_frame`] is shared with
//! the GIF animation and the FMU icon.

pub mod contacts;

use std::path::Path;

use image::ImageEncoder;
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::faces::{self, Face};
pub use super::faces::{shade as terrain_shade, BOX_COLOUR, HEIGHTFIELD_COLOUR, PLANE_COLOUR};
use super::labels::{self, LabelKind};
use super::terrain::plane_quad;
use super::view::{depth, project, Fit, BAR_W, TITLE_H};
pub use super::view::{plot_rect, Style};
use super::Frames;
use crate::partial;

/// Bars.
pub const BAR: RGBColor = RGBColor(35, 35, 35);
/// Slack cables (tension 0), drawn dashed.
pub const SLACK: RGBColor = RGBColor(175, 175, 175);
/// Pinned-node triangles.
pub const PIN: RGBColor = RGBColor(120, 50, 160);
/// The ground plane (filled) and its grid.
pub const GROUND_FILL: RGBColor = RGBColor(236, 234, 222);
const GROUND_GRID: RGBColor = RGBColor(196, 192, 172);

/// Tension colour map from 0 (blue) to the run's largest tension (red).
const STOPS: [(f64, [u8; 3]); 4] = [
    (0.0, [40, 110, 200]),
    (0.35, [0, 165, 140]),
    (0.7, [240, 160, 20]),
    (1.0, [210, 25, 30]),
];

/// The colour of a taut cable with tension `t` on a map from 0 to `max` N.
pub fn tension_colour(t: f64, max: f64) -> RGBColor {
    let x = if max > 0.0 {
        (t / max).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = if x.is_nan() { 0.0 } else { x };
    let k = STOPS.iter().position(|s| s.0 >= x).unwrap_or(3).max(1);
    let ((xa, a), (xb, b)) = (STOPS[k - 1], STOPS[k]);
    let f = (x - xa) / (xb - xa);
    let mix = |i: usize| (f64::from(a[i]) + f * (f64::from(b[i]) - f64::from(a[i]))).round() as u8;
    RGBColor(mix(0), mix(1), mix(2))
}

/// A cable is drawn slack when its tension is at most this fraction of the largest.
const SLACK_FRACTION: f64 = 1e-9;

/// Whether cable tension `t` is drawn as slack in a run whose largest tension is `max`.
pub fn is_slack(t: f64, max: f64) -> bool {
    !(t > SLACK_FRACTION * max && t > 0.0)
}

/// Size of a PNG picture, pixels.
pub const PNG_SIZE: (u32, u32) = (900, 760);

/// The fit of the whole run (every node at every time, and the ground quad) into a
/// picture of `size` pixels: the same for every frame of an animation.
pub fn fit(frames: &Frames, size: (u32, u32), style: &Style) -> Fit {
    let (az, el) = (style.azimuth, style.elevation);
    let nodes = frames.positions.iter().flatten().copied();
    let ground = ground_quad(frames).into_iter().flatten();
    let terrain = faces::fit_points(frames);
    Fit::new(
        nodes
            .chain(ground)
            .chain(terrain)
            .map(|p| project(p, az, el)),
        plot_rect(size, style),
    )
}

/// The corners of the ground quad drawn under the structure: the structure's extent over
/// the run projected onto the plane, widened by a quarter (at least 0.5 m across).
pub fn ground_quad(frames: &Frames) -> Option<[[f64; 3]; 4]> {
    let g = frames.ground.as_ref()?;
    let points: Vec<[f64; 3]> = frames.positions.iter().flatten().copied().collect();
    Some(plane_quad(g.normal, g.height, &points))
}

/// Errors of plotters as messages.
pub(crate) fn drawing<E: std::fmt::Display>(what: &str) -> impl Fn(E) -> String + '_ {
    move |e| format!("drawing {what}: {e}")
}

/// Draws frame `k` of `frames` on `area` (already cleared), fitted with `fit`; colours
/// span 0 to `max_tension`.
pub fn draw_frame<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    frames: &Frames,
    k: usize,
    fit: &Fit,
    max_tension: f64,
    style: &Style,
) -> Result<(), String> {
    if k >= frames.len() {
        return Err(format!(
            "no frame {k} to draw: the run has {} recorded times",
            frames.len()
        ));
    }
    crate::report::register_font()?;
    let err = drawing::<DrawingAreaErrorKind<DB::ErrorType>>("the picture");
    let (az, el) = (style.azimuth, style.elevation);
    let pos = &frames.positions[k];
    let px = |p: [f64; 3]| fit.to_pixel(project(p, az, el));
    let mid = |[a, b]: [usize; 2]| [0, 1, 2].map(|i| (pos[a][i] + pos[b][i]) / 2.0);
    let (thin, thick, r) = if style.title { (2, 6, 10) } else { (1, 3, 5) };
    if let Some(quad) = ground_quad(frames) {
        let corners: Vec<_> = quad.iter().map(|&p| px(p)).collect();
        area.draw(&Polygon::new(corners, GROUND_FILL.filled()))
            .map_err(&err)?;
        let lines = 8;
        for s in 0..=lines {
            let f = s as f64 / lines as f64;
            let lerp = |a: [f64; 3], b: [f64; 3]| [0, 1, 2].map(|i| a[i] + f * (b[i] - a[i]));
            for (a, b) in [
                (lerp(quad[0], quad[1]), lerp(quad[3], quad[2])),
                (lerp(quad[0], quad[3]), lerp(quad[1], quad[2])),
            ] {
                area.draw(&PathElement::new(vec![px(a), px(b)], GROUND_GRID))
                    .map_err(&err)?;
            }
        }
    }
    let faces = faces::faces(frames, az, el);
    let members: Vec<[usize; 2]> = frames.bars.iter().chain(&frames.cables).copied().collect();
    let ends: Vec<_> = members.iter().map(|&[a, b]| (pos[a], pos[b])).collect();
    let hidden = faces::occlusion(&faces, &ends, az, el, occlusion_tolerance(frames, k));
    let plot = plot_rect(area.dim_in_pixel(), style);
    for face in &faces {
        draw_face(area, face, &px, plot)?;
    }
    let scale = fit.scale;
    let draw_members = |behind: bool| -> Result<(), String> {
        // Behind the terrain, faint.
        let ink = |c: RGBColor| c.mix(if behind { 0.3 } else { 1.0 });
        // The stretches of member `m` on this side of the terrain, as pixel segments.
        let pieces = |m: usize| {
            let [a, b] = members[m];
            let at = |s: f64| px([0, 1, 2].map(|i| pos[a][i] + s * (pos[b][i] - pos[a][i])));
            let spans = faces::stretches(hidden[m], behind);
            spans
                .into_iter()
                .map(|(s0, s1)| vec![at(s0), at(s1)])
                .collect::<Vec<_>>()
        };
        // Bars under cables, so that cables crossing in front of or behind a bar stay
        // visible (a tower's cables run over its bars); within each, far before near.
        let nb = frames.bars.len();
        let depth_of = |m: usize| depth(mid(members[m]), az, el);
        let mut bars: Vec<usize> = (0..nb).collect();
        bars.sort_by(|&a, &b| depth_of(a).total_cmp(&depth_of(b)));
        for &b in &bars {
            // A bar with a radius looks as thick as it is, where that is thicker.
            let r = frames.bar_radius.get(b).copied().unwrap_or(0.0);
            let width = thick.max((2.0 * r * scale).round().min(80.0) as u32);
            for line in pieces(b) {
                area.draw(&PathElement::new(line, ink(BAR).stroke_width(width)))
                    .map_err(&err)?;
            }
        }
        let mut cables: Vec<usize> = (0..frames.cables.len()).collect();
        cables.sort_by(|&a, &b| depth_of(nb + a).total_cmp(&depth_of(nb + b)));
        let tensions = &frames.tensions[k];
        for &j in &cables {
            let t = tensions[j];
            for line in pieces(nb + j) {
                if is_slack(t, max_tension) {
                    let dash = (4 * thin) as i32;
                    area.draw(&DashedPathElement::new(
                        line,
                        dash,
                        dash,
                        ink(SLACK).stroke_width(thin),
                    ))
                    .map_err(&err)?;
                } else {
                    let c = tension_colour(t, max_tension);
                    area.draw(&PathElement::new(line, ink(c).stroke_width(thin)))
                        .map_err(&err)?;
                }
            }
        }
        Ok(())
    };
    draw_members(true)?;
    draw_members(false)?;
    // Markers of nodes behind the terrain are faint too.
    let marked: Vec<_> = frames
        .pinned
        .iter()
        .chain(&frames.point_masses)
        .map(|&i| (pos[i], pos[i]))
        .collect();
    let behind = faces::occlusion(&faces, &marked, az, el, occlusion_tolerance(frames, k));
    let ink = |n: usize| if behind[n] != 0 { 0.3 } else { 1.0 };
    for (n, &i) in frames.pinned.iter().enumerate() {
        let (x, y) = px(pos[i]);
        let tri = vec![(x, y), (x - r, y + 2 * r), (x + r, y + 2 * r)];
        area.draw(&Polygon::new(tri, PIN.mix(ink(n)).filled()))
            .map_err(&err)?;
    }
    for (n, &i) in frames.point_masses.iter().enumerate() {
        let a = ink(frames.pinned.len() + n);
        area.draw(&Circle::new(px(pos[i]), r, BAR.mix(a).filled()))
            .map_err(&err)?;
        area.draw(&Circle::new(px(pos[i]), r, WHITE.mix(a).stroke_width(1)))
            .map_err(&err)?;
    }
    contacts::draw_contacts(area, frames, k, fit, style, (r / 2, thin + 1))?;
    if style.labels {
        draw_labels(area, frames, k, fit, style)?;
    }
    let (w, _) = area.dim_in_pixel();
    if style.title {
        let title = format!("{} — t = {:.3} s", frames.name, frames.times[k]);
        let font = ("sans-serif", 24).into_font().color(&BLACK);
        let font = font.pos(Pos::new(HPos::Center, VPos::Center));
        area.draw(&Text::new(title, (w as i32 / 2, TITLE_H / 2 + 6), font))
            .map_err(&err)?;
    }
    if style.colour_bar {
        draw_colour_bar(area, max_tension, thin, w as i32)?;
        if let Some(scale) = frames.contact_scale() {
            let y = TITLE_H + 360 + 70;
            contacts::draw_legend(area, &scale, fit, (w as i32, y), thin)?;
        }
    }
    Ok(())
}

/// How far behind a face a member's middle must lie to count as hidden, m: a bar resting
/// on the terrain, or pressed a little into it, stays in front.
fn occlusion_tolerance(frames: &Frames, k: usize) -> f64 {
    let pos = &frames.positions[k];
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in pos {
        for i in 0..3 {
            (lo[i], hi[i]) = (lo[i].min(p[i]), hi[i].max(p[i]));
        }
    }
    let size = (0..3).map(|i| hi[i] - lo[i]).fold(0.0, f64::max);
    let radius = frames.bar_radius.iter().copied().fold(0.0, f64::max);
    0.02 * size + 2.0 * radius
}

/// One terrain face, clipped to the plot.
fn draw_face<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    face: &Face,
    px: &impl Fn([f64; 3]) -> (i32, i32),
    plot: (i32, i32, i32, i32),
) -> Result<(), String> {
    let err = drawing::<DrawingAreaErrorKind<DB::ErrorType>>("the terrain");
    let corners: Vec<(f64, f64)> = face
        .corners
        .iter()
        .map(|&p| {
            let (x, y) = px(p);
            (f64::from(x), f64::from(y))
        })
        .collect();
    let poly = faces::clip(&corners, plot);
    if poly.len() < 3 {
        return Ok(());
    }
    area.draw(&Polygon::new(poly.clone(), face.fill.filled()))
        .map_err(&err)?;
    let edge = faces::scale(face.fill, if face.kind == "box" { 0.6 } else { 0.88 });
    let mut outline = poly;
    outline.push(outline[0]);
    area.draw(&PathElement::new(outline, edge)).map_err(&err)?;
    if face.kind == "plane" {
        // A grid, as on the ground, so that the plane reads as a floor.
        let q = &face.corners;
        for s in 1..8 {
            let f = f64::from(s) / 8.0;
            let lerp = |a: [f64; 3], b: [f64; 3]| [0, 1, 2].map(|i| a[i] + f * (b[i] - a[i]));
            for (a, b) in [
                (lerp(q[0], q[1]), lerp(q[3], q[2])),
                (lerp(q[0], q[3]), lerp(q[1], q[2])),
            ] {
                area.draw(&PathElement::new(vec![px(a), px(b)], edge))
                    .map_err(&err)?;
            }
        }
    }
    Ok(())
}

fn draw_labels<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    frames: &Frames,
    k: usize,
    fit: &Fit,
    style: &Style,
) -> Result<(), String> {
    let err = drawing::<DrawingAreaErrorKind<DB::ErrorType>>("the labels");
    let centred = Pos::new(HPos::Center, VPos::Center);
    let background = WHITE.mix(0.75).filled();
    for (label, rect) in labels::layout(frames, k, fit, style, area.dim_in_pixel())? {
        let colour = match label.kind {
            LabelKind::Node => RGBColor(0, 0, 150),
            LabelKind::Bar => BAR,
            LabelKind::Cable => RGBColor(90, 90, 90),
        };
        let font = ("sans-serif", label.kind.font_size())
            .into_font()
            .color(&colour)
            .pos(centred);
        area.draw(&Rectangle::new(
            [(rect.x0, rect.y0), (rect.x1, rect.y1)],
            background,
        ))
        .map_err(&err)?;
        area.draw(&Text::new(label.text, rect.centre(), font))
            .map_err(&err)?;
    }
    Ok(())
}

/// A tension with few digits for the colour bar.
fn newtons(t: f64) -> String {
    if t == 0.0 {
        "0".into()
    } else if t >= 100.0 {
        format!("{t:.0}")
    } else if t >= 1.0 {
        format!("{t:.1}")
    } else {
        format!("{t:.3}")
    }
}

fn draw_colour_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    max: f64,
    thin: u32,
    w: i32,
) -> Result<(), String> {
    let err = drawing::<DrawingAreaErrorKind<DB::ErrorType>>("the colour bar");
    let (x0, x1) = (w - BAR_W + 20, w - BAR_W + 44);
    let (top, bottom) = (TITLE_H + 60, TITLE_H + 360);
    let font = ("sans-serif", 15).into_font().color(&BLACK);
    area.draw(&Text::new("tension, N", (x0 - 8, top - 36), font.clone()))
        .map_err(&err)?;
    if max > 0.0 {
        for y in top..=bottom {
            let t = max * f64::from(bottom - y) / f64::from(bottom - top);
            let c = tension_colour(t, max);
            area.draw(&PathElement::new(vec![(x0, y), (x1, y)], c))
                .map_err(&err)?;
        }
        let left = font.pos(Pos::new(HPos::Left, VPos::Center));
        for f in [0.0, 0.5, 1.0] {
            let y = bottom - (f * f64::from(bottom - top)).round() as i32;
            area.draw(&PathElement::new(vec![(x1, y), (x1 + 5, y)], BLACK))
                .map_err(&err)?;
            area.draw(&Text::new(newtons(f * max), (x1 + 8, y), left.clone()))
                .map_err(&err)?;
        }
    } else {
        area.draw(&Text::new("none", (x0, top + 10), font.clone()))
            .map_err(&err)?;
    }
    let y = bottom + 34;
    area.draw(&DashedPathElement::new(
        [(x0, y), (x1 + 6, y)],
        4 * thin as i32,
        4 * thin as i32,
        SLACK.stroke_width(thin.max(2)),
    ))
    .map_err(&err)?;
    let left = font.pos(Pos::new(HPos::Left, VPos::Center));
    area.draw(&Text::new("slack", (x1 + 12, y), left))
        .map_err(&err)?;
    Ok(())
}

/// Writes frame `k` of `frames` as a PNG of [`PNG_SIZE`].
pub fn write_png(frames: &Frames, k: usize, style: &Style, path: &Path) -> Result<(), String> {
    let what = path.display().to_string();
    let fit = fit(frames, PNG_SIZE, style);
    let mut rgb = partial::blank_rgb(PNG_SIZE);
    {
        let root = BitMapBackend::with_buffer(&mut rgb, PNG_SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(drawing(&what))?;
        draw_frame(&root, frames, k, &fit, frames.max_tension(), style)?;
        root.present().map_err(drawing(&what))?;
    }
    partial::write_png(path, &rgb, PNG_SIZE)
}

/// Size of the FMU icon `model.png`, pixels.
pub const ICON_SIZE: (u32, u32) = (256, 256);

/// The FMU icon: frame 0 of `frames`, the structure only (no title, colour bar or
/// labels), as PNG bytes of [`ICON_SIZE`].
pub fn icon_png(frames: &Frames) -> Result<Vec<u8>, String> {
    let style = Style {
        title: false,
        colour_bar: false,
        ..Style::new(
            super::view::DEFAULT_AZIMUTH,
            super::view::DEFAULT_ELEVATION,
            false,
        )
    };
    let (w, h) = ICON_SIZE;
    let mut rgb = partial::blank_rgb(ICON_SIZE);
    {
        let fit = fit(frames, ICON_SIZE, &style);
        let root = BitMapBackend::with_buffer(&mut rgb, ICON_SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(drawing("model.png"))?;
        draw_frame(&root, frames, 0, &fit, frames.max_tension(), &style)?;
        root.present().map_err(drawing("model.png"))?;
    }
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(&rgb, w, h, image::ColorType::Rgb8)
        .map_err(drawing("model.png"))?;
    Ok(png)
}
