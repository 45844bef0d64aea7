//! The report's two PNG figures, drawn with plotters and the embedded DejaVu Sans font
//! (no system font lookup). Logarithmic axes are drawn as linear axes in log₁₀ of the
//! value with one tick per decade, labelled 10ⁿ.

use std::path::Path;
use std::sync::OnceLock;

use plotters::prelude::*;

use super::{Report, RunRecord};
use crate::integrator::Method;
use crate::partial::{blank_rgb, write_png};

/// DejaVu Sans (see FONT-LICENSE.txt beside this file).
static FONT: &[u8] = include_bytes!("DejaVuSans.ttf");

/// Values below this are drawn at it on logarithmic axes (exact zeros included).
pub(crate) const FLOOR: f64 = 1e-17;

/// A run on the work-precision diagram: the run, its wall time and its error.
type Point<'a> = (&'a RunRecord, f64, f64);

/// `(t, error)` pairs.
type Series = [(f64, f64)];

const SIZE: (u32, u32) = (1100, 750);

/// Added to the upper end of a log₁₀ axis so that its last decade gets a tick.
const EDGE: f64 = 1e-9;

/// Registers the embedded font as "sans-serif" (once); the render pictures use it too.
pub(crate) fn register_font() -> Result<(), String> {
    static DONE: OnceLock<bool> = OnceLock::new();
    let ok = *DONE.get_or_init(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT).is_ok()
    });
    ok.then_some(())
        .ok_or_else(|| "the embedded plot font could not be loaded".to_string())
}

fn colour(method: Method) -> RGBColor {
    match method {
        Method::Rk4 => RGBColor(31, 119, 180),
        Method::Rattle => RGBColor(214, 39, 40),
        Method::Dopri5 => RGBColor(44, 160, 44),
        Method::Sdirk3 => RGBColor(148, 103, 189),
    }
}

/// `10⁻⁶` for −6.
fn decade_label(v: &f64) -> String {
    const SUP: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let e = v.round() as i64;
    let digits: String = e
        .unsigned_abs()
        .to_string()
        .chars()
        .map(|c| SUP[c.to_digit(10).unwrap_or(0) as usize])
        .collect();
    format!("10{}{digits}", if e < 0 { "⁻" } else { "" })
}

/// Whole decades covering `values` (log₁₀, floored at [`FLOOR`]), at least one wide.
fn decades(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .map(|v| v.max(FLOOR).log10())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (-1.0, 0.0);
    }
    let (lo, hi) = (lo.floor(), hi.ceil());
    (lo, if hi > lo { hi } else { lo + 1.0 })
}

fn io<E: std::fmt::Display>(path: &Path) -> impl Fn(E) -> String + '_ {
    move |e| format!("drawing {}: {e}", path.display())
}

/// Light grid lines at 2..9 × 10ⁿ inside the vertical range `[lo, hi]` (log₁₀).
fn minor_decades(lo: f64, hi: f64) -> Vec<f64> {
    let mut out = Vec::new();
    let mut d = lo;
    while d < hi {
        out.extend((2..10).map(|m| d + (m as f64).log10()));
        d += 1.0;
    }
    out
}

/// Node-position error against wall time, log-log, one curve per method (correction on),
/// each point labelled with its setting.
pub(crate) fn work_precision(report: &Report, path: &Path) -> Result<(), String> {
    register_font()?;
    let curves: Vec<(Method, Vec<Point>)> = super::SWEPT
        .into_iter()
        .map(|method| {
            let mut pts: Vec<_> = report
                .runs
                .iter()
                .filter(|r| r.method == method && r.correction)
                .filter_map(|r| {
                    let m = r.result.as_ref().ok()?;
                    Some((r, m.wall_time_s, m.max_position_error_m))
                })
                .collect();
            pts.sort_by_key(|(r, _, _)| r.result.as_ref().map_or(0, |m| m.rhs_evaluations));
            (method, pts)
        })
        .collect();
    let all = || curves.iter().flat_map(|(_, p)| p.iter());
    // Room on the right for the slowest point's label (half a decade).
    let (x0, x1) = decades(all().map(|p| p.1).chain(all().map(|p| p.1 * 3.0)));
    // A decade of headroom above the least accurate run keeps the legend off the curves.
    let (y0, y1) = decades(
        all()
            .map(|p| p.2)
            .chain(all().map(|p| p.2 * 10.0))
            .chain([report.reference.max_difference_m]),
    );
    let mut rgb = blank_rgb(SIZE);
    let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(io(path))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "{}: work-precision, {} s, correction on",
                report.scene, report.horizon
            ),
            ("sans-serif", 30),
        )
        .margin(20)
        .x_label_area_size(70)
        .y_label_area_size(100)
        .build_cartesian_2d((x0..x1 + EDGE).step(1.0), (y0..y1 + EDGE).step(1.0))
        .map_err(io(path))?;
    chart
        .configure_mesh()
        .x_desc("wall time (s)")
        .y_desc("max node-position error vs reference (m)")
        .x_label_formatter(&decade_label)
        .y_label_formatter(&decade_label)
        .x_labels(40)
        .y_labels(40)
        .axis_desc_style(("sans-serif", 24))
        .label_style(("sans-serif", 20))
        .bold_line_style(BLACK.mix(0.25))
        .draw()
        .map_err(io(path))?;
    let light = BLACK.mix(0.08);
    for x in minor_decades(x0, x1) {
        chart
            .draw_series(LineSeries::new([(x, y0), (x, y1)], light))
            .map_err(io(path))?;
    }
    for y in minor_decades(y0, y1) {
        chart
            .draw_series(LineSeries::new([(x0, y), (x1, y)], light))
            .map_err(io(path))?;
    }
    let floor = report.reference.max_difference_m.max(FLOOR).log10();
    chart
        .draw_series(DashedLineSeries::new(
            [(x0, floor), (x1, floor)],
            8,
            6,
            BLACK.mix(0.6).stroke_width(2),
        ))
        .map_err(io(path))?
        .label("reference check (1e-12 vs 1e-11)")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 30, y)], BLACK.mix(0.6).stroke_width(2)));
    for (method, pts) in &curves {
        let c = colour(*method);
        let (labels, xy): (Vec<String>, Vec<(f64, f64)>) = merge_identical(pts)
            .into_iter()
            .map(|(label, w, e)| (label, (w.max(FLOOR).log10(), e.max(FLOOR).log10())))
            .unzip();
        chart
            .draw_series(LineSeries::new(xy.clone(), c.stroke_width(3)))
            .map_err(io(path))?
            .label(format!("{} ({})", method.name(), setting_kind(*method)))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 30, y)], c.stroke_width(3)));
        let font = ("sans-serif", 16).into_font().color(&c);
        // dopri5 usually lies below the fixed-step curves: label it below them.
        let offset = if *method == Method::Dopri5 {
            (9, 4)
        } else {
            (9, -20)
        };
        chart
            .draw_series(xy.iter().zip(labels).map(|(&p, label)| {
                EmptyElement::at(p)
                    + Circle::new((0, 0), 6, c.filled())
                    + Text::new(label, offset, font.clone())
            }))
            .map_err(io(path))?;
    }
    // Curves fall from upper left to lower right: the upper right stays clear.
    draw_legend(&mut chart, SeriesLabelPosition::UpperRight).map_err(io(path))?;
    root.present().map_err(io(path))?;
    drop(chart);
    drop(root);
    write_png(path, &rgb, SIZE)
}

/// The legend box both plots share.
fn draw_legend<'a, DB, CT>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>>
where
    DB: DrawingBackend + 'a,
    CT: CoordTranslate,
{
    chart
        .configure_series_labels()
        .position(position)
        .label_font(("sans-serif", 20))
        .legend_area_size(45)
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK.mix(0.4))
        .draw()
}

fn setting_kind(method: Method) -> &'static str {
    match method {
        Method::Dopri5 => "labels: rtol = atol",
        Method::Rk4 | Method::Rattle | Method::Sdirk3 => "labels: step",
    }
}

/// "8 ms" or "1e-6", next to a point.
fn short_setting(r: &RunRecord) -> String {
    match r.method {
        Method::Dopri5 => format!("{:.0e}", r.setting),
        Method::Rk4 | Method::Rattle | Method::Sdirk3 => {
            format!("{} ms", super::short(r.setting * 1e3))
        }
    }
}

/// One point per group of runs that did the very same work (same evaluations and error,
/// as dopri5 capped by the output interval), at the group's least wall time and labelled
/// with its settings' range, e.g. "1e-3 … 1e-9"; other runs are their own group.
fn merge_identical(pts: &[Point]) -> Vec<(String, f64, f64)> {
    let key = |r: &RunRecord| {
        r.result
            .as_ref()
            .map(|m| (m.rhs_evaluations, m.max_position_error_m))
            .ok()
    };
    let mut out = Vec::new();
    let mut i = 0;
    while i < pts.len() {
        let mut j = i + 1;
        while j < pts.len() && key(pts[j].0) == key(pts[i].0) {
            j += 1;
        }
        let label = if j - i > 1 {
            format!(
                "{} … {}",
                short_setting(pts[i].0),
                short_setting(pts[j - 1].0)
            )
        } else {
            short_setting(pts[i].0)
        };
        let wall = pts[i..j].iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
        out.push((label, wall, pts[i].2));
        i = j;
    }
    out
}

/// Bar-length error against time for RK4 at the scene's step, with and without the
/// correction (the paper's Fig. 4/5); zeros drawn at [`FLOOR`].
pub(crate) fn constraint_error(report: &Report, path: &Path) -> Result<(), String> {
    register_font()?;
    let h = report.constraint_step;
    let find = |on: bool| {
        report
            .runs
            .iter()
            .find(|r| r.method == Method::Rk4 && r.correction == on && r.setting == h)
            .filter(|r| r.result.is_ok())
    };
    // The largest RK4 step without correction, when it is not the scene's.
    let coarsest = report
        .runs
        .iter()
        .filter(|r| r.method == Method::Rk4 && !r.correction && r.result.is_ok())
        .max_by(|a, b| a.setting.total_cmp(&b.setting))
        .filter(|r| r.setting > h);
    let mut series: Vec<(RGBColor, String, &Series)> = Vec::new();
    if let Some(r) = find(true) {
        let label = format!(
            "h = {} ms, correction on (exact zeros drawn at 10⁻¹⁷)",
            h * 1e3
        );
        series.push((RGBColor(31, 119, 180), label, &r.length_error_series));
    }
    if let Some(r) = find(false) {
        let label = format!("h = {} ms, correction off", h * 1e3);
        series.push((RGBColor(214, 39, 40), label, &r.length_error_series));
    }
    if let Some(r) = coarsest {
        let label = format!("h = {} ms, correction off", r.setting * 1e3);
        series.push((RGBColor(255, 127, 14), label, &r.length_error_series));
    }
    let (y0, y1) = decades(
        series
            .iter()
            .flat_map(|(_, _, s)| s.iter().map(|p| p.1))
            .chain([FLOOR, 1e-11]),
    );
    // Headroom above the data for the legend.
    let y1 = y1 + ((y1 - y0) / 4.0).ceil();
    let t1 = report.horizon;
    let mut rgb = blank_rgb(SIZE);
    let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(io(path))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "{}: bar-length constraint error, rk4, with and without correction",
                report.scene
            ),
            ("sans-serif", 26),
        )
        .margin(20)
        .x_label_area_size(70)
        .y_label_area_size(100)
        .build_cartesian_2d(0.0..t1, (y0..y1 + EDGE).step(1.0))
        .map_err(io(path))?;
    chart
        .configure_mesh()
        .x_desc("time (s)")
        .y_desc("max bar-length error |‖b‖ − l| (m)")
        .y_label_formatter(&decade_label)
        .y_labels(40)
        .x_label_formatter(&|t| format!("{}", (t * 1e3).round() / 1e3))
        .max_light_lines(1)
        .axis_desc_style(("sans-serif", 24))
        .label_style(("sans-serif", 20))
        .bold_line_style(BLACK.mix(0.25))
        .light_line_style(BLACK.mix(0.06))
        .draw()
        .map_err(io(path))?;
    for y in minor_decades(y0, y1) {
        chart
            .draw_series(LineSeries::new([(0.0, y), (t1, y)], BLACK.mix(0.08)))
            .map_err(io(path))?;
    }
    let bound = -12.0;
    chart
        .draw_series(DashedLineSeries::new(
            [(0.0, bound), (t1, bound)],
            8,
            6,
            BLACK.mix(0.6).stroke_width(2),
        ))
        .map_err(io(path))?
        .label("10⁻¹² m")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 30, y)], BLACK.mix(0.6).stroke_width(2)));
    for (c, label, s) in series {
        let xy: Vec<(f64, f64)> = s.iter().map(|&(t, e)| (t, e.max(FLOOR).log10())).collect();
        chart
            .draw_series(LineSeries::new(xy, c.stroke_width(3)))
            .map_err(io(path))?
            .label(label)
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 30, y)], c.stroke_width(3)));
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperRight).map_err(io(path))?;
    root.present().map_err(io(path))?;
    drop(chart);
    drop(root);
    write_png(path, &rgb, SIZE)
}
