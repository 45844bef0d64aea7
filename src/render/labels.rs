//! Where the labels of `render --labels` go: node numbers, then bar and cable names, each
//! placed greedily at the first of several spots around its anchor (the node, or the
//! member's midpoint) where its box overlaps no label placed before it, no node marker and
//! nothing outside the picture. A label that finds no such spot is left out.

use plotters::prelude::*;

use super::view::{plot_rect, project, Fit, Style};
use super::Frames;

/// A label's box in pixels, corners included: `x0 ≤ x ≤ x1`, `y0 ≤ y ≤ y1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rect {
    /// Left.
    pub x0: i32,
    /// Top.
    pub y0: i32,
    /// Right.
    pub x1: i32,
    /// Bottom.
    pub y1: i32,
}

impl Rect {
    /// The box of size `(w, h)` centred on `(x, y)`.
    pub fn centred((x, y): (i32, i32), (w, h): (i32, i32)) -> Self {
        Self {
            x0: x - w / 2,
            y0: y - h / 2,
            x1: x - w / 2 + w,
            y1: y - h / 2 + h,
        }
    }

    /// Whether the two boxes share a pixel.
    pub fn overlaps(&self, other: &Rect) -> bool {
        self.x0 <= other.x1 && other.x0 <= self.x1 && self.y0 <= other.y1 && other.y0 <= self.y1
    }

    /// Whether `other` lies inside this box.
    pub fn contains(&self, other: &Rect) -> bool {
        self.x0 <= other.x0 && other.x1 <= self.x1 && self.y0 <= other.y0 && other.y1 <= self.y1
    }

    /// The centre.
    pub fn centre(&self) -> (i32, i32) {
        ((self.x0 + self.x1) / 2, (self.y0 + self.y1) / 2)
    }
}

/// What a label names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LabelKind {
    /// A node number (`4`).
    Node,
    /// A bar (`b2`).
    Bar,
    /// A cable (`c7`).
    Cable,
}

impl LabelKind {
    /// Font size in pixels.
    pub fn font_size(self) -> f64 {
        match self {
            Self::Node => 15.0,
            Self::Bar => 13.0,
            Self::Cable => 12.0,
        }
    }
}

/// A label to place: its text and size, and the pixel it belongs to.
#[derive(Debug, Clone, PartialEq)]
pub struct Request {
    /// The text.
    pub text: String,
    /// What it names.
    pub kind: LabelKind,
    /// The pixel it labels.
    pub anchor: (i32, i32),
    /// Width and height of its box.
    pub size: (i32, i32),
}

/// Space kept between a label and its anchor, and around a node marker, in pixels.
const GAP: i32 = 3;
/// Half the side of the box kept free around each node.
const NODE_MARK: i32 = 5;

/// Places `requests` in order, each at the first free spot around its anchor: on it, then
/// in eight directions at growing distances; `None` for a label left out. `blocked` boxes
/// (node markers) stay free, and every label stays inside `bounds`.
pub fn place(requests: &[Request], blocked: &[Rect], bounds: Rect) -> Vec<Option<Rect>> {
    let mut placed: Vec<Rect> = Vec::new();
    requests
        .iter()
        .map(|r| {
            let (w, h) = r.size;
            let spot = candidates(r.anchor, (w, h))
                .map(|c| Rect::centred(c, (w, h)))
                .find(|b| {
                    bounds.contains(b)
                        && !blocked.iter().any(|o| o.overlaps(b))
                        && !placed.iter().any(|o| o.overlaps(b))
                })?;
            placed.push(spot);
            Some(spot)
        })
        .collect()
}

/// Centres to try for a box of size `(w, h)` labelling `(x, y)`: on the anchor, then
/// touching it from eight directions (upper right first, where node numbers always went),
/// then the same directions twice and three times as far out.
fn candidates((x, y): (i32, i32), (w, h): (i32, i32)) -> impl Iterator<Item = (i32, i32)> {
    const DIRECTIONS: [(i32, i32); 8] = [
        (1, -1),
        (1, 0),
        (0, -1),
        (1, 1),
        (-1, -1),
        (-1, 0),
        (0, 1),
        (-1, 1),
    ];
    let on = std::iter::once((x, y));
    let around = (1..=3).flat_map(move |ring| {
        DIRECTIONS.iter().map(move |&(dx, dy)| {
            let reach_x = w / 2 + GAP + (ring - 1) * (w / 2 + GAP);
            let reach_y = h / 2 + GAP + (ring - 1) * (h / 2 + GAP);
            (x + dx * reach_x, y + dy * reach_y)
        })
    });
    on.chain(around)
}

/// The labels of frame `k` and their boxes in a picture of `size` drawn with `fit` and
/// `style`: node numbers first, then bars, then cables; labels left out are not listed.
/// Node labels never sit on their node; member labels may cover the middle of their
/// member.
pub fn layout(
    frames: &Frames,
    k: usize,
    fit: &Fit,
    style: &Style,
    size: (u32, u32),
) -> Result<Vec<(Request, Rect)>, String> {
    crate::report::register_font()?;
    let pos = &frames.positions[k];
    let px = |p: [f64; 3]| fit.to_pixel(project(p, style.azimuth, style.elevation));
    let mid = |[a, b]: [usize; 2]| px([0, 1, 2].map(|i| (pos[a][i] + pos[b][i]) / 2.0));
    let request = |text: String, kind: LabelKind, anchor| -> Result<Request, String> {
        let (w, h) = ("sans-serif", kind.font_size())
            .into_font()
            .box_size(&text)
            .map_err(|e| format!("measuring the label {text}: {e}"))?;
        Ok(Request {
            text,
            kind,
            anchor,
            size: (w as i32 + 2, h as i32 + 2),
        })
    };
    let mut requests = Vec::new();
    let mut markers = Vec::new();
    for (i, &p) in pos.iter().enumerate() {
        let at = px(p);
        markers.push(Rect::centred(at, (2 * NODE_MARK, 2 * NODE_MARK)));
        // A node's own label never covers it: it starts from the ring around it.
        requests.push(request(format!("{}", i + 1), LabelKind::Node, at)?);
    }
    for (b, &nodes) in frames.bars.iter().enumerate() {
        requests.push(request(format!("b{}", b + 1), LabelKind::Bar, mid(nodes))?);
    }
    for (j, &nodes) in frames.cables.iter().enumerate() {
        requests.push(request(
            format!("c{}", j + 1),
            LabelKind::Cable,
            mid(nodes),
        )?);
    }
    // The structure's rectangle, with the room around it that the markers leave.
    let (left, top, right, bottom) = plot_rect(size, style);
    let bounds = Rect {
        x0: left - 6,
        y0: top - 6,
        x1: right + 6,
        y1: bottom + 6,
    };
    let spots = place(&requests, &markers, bounds);
    Ok(requests
        .into_iter()
        .zip(spots)
        .filter_map(|(r, spot)| spot.map(|s| (r, s)))
        .collect())
}
