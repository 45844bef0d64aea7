//! Still pictures (PNG) of a recorded run, drawn with plotters: an orthographic view fitted
//! to the structure over the whole run, bars as thick dark lines, cables over them coloured
//! by tension (slack ones light grey and dashed) with a colour bar, pinned nodes as
//! triangles, point masses as filled circles, the ground plane as a grid, and a title.
//! [`draw_frame`] is shared with the GIF animation and the FMU icon.

use std::path::Path;

use image::ImageEncoder;
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::labels::{self, LabelKind};
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
    Fit::new(
        nodes.chain(ground).map(|p| project(p, az, el)),
        plot_rect(size, style),
    )
}

/// The corners of the ground quad drawn under the structure: the structure's extent over
/// the run projected onto the plane, widened by a quarter (at least 0.5 m across).
pub fn ground_quad(frames: &Frames) -> Option<[[f64; 3]; 4]> {
    let g = frames.ground.as_ref()?;
    let n = g.normal;
    let a = if n[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let e1 = unit(cross(n, a));
    let e2 = cross(n, e1);
    let pts: Vec<[f64; 3]> = frames.positions.iter().flatten().copied().collect();
    let count = pts.len().max(1) as f64;
    let mut c = [0.0; 3];
    for p in &pts {
        (0..3).for_each(|i| c[i] += p[i] / count);
    }
    let off = dot(c, n) - g.height;
    let c = [c[0] - off * n[0], c[1] - off * n[1], c[2] - off * n[2]];
    let r = pts
        .iter()
        .map(|p| {
            let d = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
            dot(d, e1).abs().max(dot(d, e2).abs())
        })
        .fold(0.25_f64, f64::max)
        * 1.25;
    let at = |s: f64, t: f64| [0, 1, 2].map(|i| c[i] + r * (s * e1[i] + t * e2[i]));
    Some([at(-1.0, -1.0), at(1.0, -1.0), at(1.0, 1.0), at(-1.0, 1.0)])
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = dot(a, a).sqrt();
    a.map(|x| x / n)
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
    // Bars under cables, so that cables crossing in front of or behind a bar stay
    // visible (a tower's cables run over its bars); within each, far before near.
    let mut bars: Vec<usize> = (0..frames.bars.len()).collect();
    bars.sort_by(|&a, &b| {
        depth(mid(frames.bars[a]), az, el).total_cmp(&depth(mid(frames.bars[b]), az, el))
    });
    for &b in &bars {
        let [p, q] = frames.bars[b];
        area.draw(&PathElement::new(
            vec![px(pos[p]), px(pos[q])],
            BAR.stroke_width(thick),
        ))
        .map_err(&err)?;
    }
    let mut cables: Vec<usize> = (0..frames.cables.len()).collect();
    cables.sort_by(|&a, &b| {
        depth(mid(frames.cables[a]), az, el).total_cmp(&depth(mid(frames.cables[b]), az, el))
    });
    let tensions = &frames.tensions[k];
    for &j in &cables {
        let [a, b] = frames.cables[j];
        let ends = [px(pos[a]), px(pos[b])];
        let t = tensions[j];
        if is_slack(t, max_tension) {
            let dash = (4 * thin) as i32;
            area.draw(&DashedPathElement::new(
                ends,
                dash,
                dash,
                SLACK.stroke_width(thin),
            ))
            .map_err(&err)?;
        } else {
            let c = tension_colour(t, max_tension);
            area.draw(&PathElement::new(ends.to_vec(), c.stroke_width(thin)))
                .map_err(&err)?;
        }
    }
    for &i in &frames.pinned {
        let (x, y) = px(pos[i]);
        let tri = vec![(x, y), (x - r, y + 2 * r), (x + r, y + 2 * r)];
        area.draw(&Polygon::new(tri, PIN.filled())).map_err(&err)?;
    }
    for &i in &frames.point_masses {
        area.draw(&Circle::new(px(pos[i]), r, BAR.filled()))
            .map_err(&err)?;
        area.draw(&Circle::new(px(pos[i]), r, WHITE.stroke_width(1)))
            .map_err(&err)?;
    }
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
