//! Contact points and forces in a picture: each point a small magenta dot, its force an
//! arrow from it, the run's largest force [`ContactScale::FRACTION`] of the structure's size
//! (projected like the structure), and in the legend a reference arrow with its force.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::super::view::{project, Fit, Style, BAR_W};
use super::super::{ContactScale, Frames};
use super::drawing;

/// Contact dots and force arrows.
pub const CONTACT: RGBColor = RGBColor(200, 20, 160);

/// Longest reference arrow in the legend, pixels.
const LEGEND_ARROW: f64 = 90.0;

/// Draws the contacts of frame `k`, if the run recorded them; `dot` is the dot's radius
/// and `width` the arrows' line width, pixels.
pub(super) fn draw_contacts<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    frames: &Frames,
    k: usize,
    fit: &Fit,
    style: &Style,
    (dot, width): (i32, u32),
) -> Result<(), String> {
    let (Some(scale), Some(contacts)) = (frames.contact_scale(), frames.contacts.get(k)) else {
        return Ok(());
    };
    let err = drawing::<DrawingAreaErrorKind<DB::ErrorType>>("the contacts");
    let px = |p: [f64; 3]| fit.to_pixel(project(p, style.azimuth, style.elevation));
    for c in contacts {
        let from = [c.point.x, c.point.y, c.point.z];
        let tip = c.point + c.force * scale.metres_per_newton;
        arrow(area, px(from), px([tip.x, tip.y, tip.z]), width).map_err(&err)?;
    }
    for c in contacts {
        let at = px([c.point.x, c.point.y, c.point.z]);
        area.draw(&Circle::new(at, dot, CONTACT.filled()))
            .map_err(&err)?;
        area.draw(&Circle::new(at, dot, WHITE.stroke_width(1)))
            .map_err(&err)?;
    }
    Ok(())
}

/// A line from `a` to `b` with a head at `b` (nothing for an arrow under 2 pixels).
fn arrow<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    a: (i32, i32),
    b: (i32, i32),
    width: u32,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (dx, dy) = (f64::from(b.0 - a.0), f64::from(b.1 - a.1));
    let len = dx.hypot(dy);
    if len < 2.0 {
        return Ok(());
    }
    area.draw(&PathElement::new(vec![a, b], CONTACT.stroke_width(width)))?;
    let head = (0.35 * len).min(6.0 + 2.0 * f64::from(width));
    let (ux, uy) = (dx / len, dy / len);
    let (c, s) = (0.94, 0.34); // cos and sin of 20°
    let side = |s: f64| {
        let (rx, ry) = (ux * c - uy * s, uy * c + ux * s);
        (
            b.0 - (head * rx).round() as i32,
            b.1 - (head * ry).round() as i32,
        )
    };
    area.draw(&Polygon::new(vec![b, side(s), side(-s)], CONTACT.filled()))
}

/// A round force for the legend's reference arrow: 1, 2 or 5 times a power of ten, as
/// long as fits in [`LEGEND_ARROW`] pixels at `pixels_per_newton`.
pub fn legend_force(pixels_per_newton: f64) -> f64 {
    let most = LEGEND_ARROW / pixels_per_newton;
    let decade = 10f64.powf(most.log10().floor());
    [5.0, 2.0, 1.0]
        .into_iter()
        .map(|m| m * decade)
        .find(|&f| f <= most * (1.0 + 1e-12))
        .unwrap_or(decade)
}

/// The legend's contact rows below the colour bar, from `y` down: a dot, then a reference
/// arrow with its force ("arrow: 20 N"), or "none" when nothing touched.
pub(super) fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    scale: &ContactScale,
    fit: &Fit,
    (w, y): (i32, i32),
    width: u32,
) -> Result<(), String> {
    let err = drawing::<DrawingAreaErrorKind<DB::ErrorType>>("the contact legend");
    let x0 = w - BAR_W + 20;
    let left = ("sans-serif", 15)
        .into_font()
        .color(&BLACK)
        .pos(Pos::new(HPos::Left, VPos::Center));
    area.draw(&Circle::new((x0 + 5, y), 5, CONTACT.filled()))
        .map_err(&err)?;
    let what = if scale.max_force > 0.0 {
        "contact"
    } else {
        "contact: none"
    };
    area.draw(&Text::new(what, (x0 + 16, y), left.clone()))
        .map_err(&err)?;
    if scale.max_force > 0.0 {
        let per_newton = scale.metres_per_newton * fit.scale;
        let f = legend_force(per_newton);
        let digits = (-f.log10().floor()).max(0.0) as usize;
        let text = format!("arrow: {f:.digits$} N");
        area.draw(&Text::new(text, (x0, y + 26), left))
            .map_err(&err)?;
        let len = (f * per_newton).round() as i32;
        arrow(area, (x0, y + 48), (x0 + len, y + 48), width).map_err(&err)?;
    }
    Ok(())
}
