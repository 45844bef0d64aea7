//! The orthographic camera of the pictures: a direction given by azimuth and elevation,
//! the fit of the projected structure to a pixel rectangle, and the picture's layout
//! (where the structure, the title and the colour bar go).

/// Default azimuth, degrees: the camera 30° counter-clockwise from +x, seen from above z.
pub const DEFAULT_AZIMUTH: f64 = 30.0;
/// Default elevation, degrees above the x–y plane.
pub const DEFAULT_ELEVATION: f64 = 20.0;

/// Orthographic projection of `p` for a camera at `azimuth` (degrees, about +z from +x)
/// and `elevation` (degrees above the x–y plane), looking at the origin with +z up:
/// `(x, y)` on the screen, x to the right and y up, m. At azimuth 0 and elevation 0 the
/// camera looks along −x, so `(x, y) = (p_y, p_z)`.
pub fn project(p: [f64; 3], azimuth: f64, elevation: f64) -> (f64, f64) {
    let (sa, ca) = azimuth.to_radians().sin_cos();
    let (se, ce) = elevation.to_radians().sin_cos();
    let right = [-sa, ca, 0.0];
    let up = [-se * ca, -se * sa, ce];
    (dot(p, right), dot(p, up))
}

/// Distance of `p` towards the camera of [`project`] (larger is nearer), m.
pub fn depth(p: [f64; 3], azimuth: f64, elevation: f64) -> f64 {
    let (sa, ca) = azimuth.to_radians().sin_cos();
    let (se, ce) = elevation.to_radians().sin_cos();
    dot(p, [ce * ca, ce * sa, se])
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Screen metres to pixels: the projected points fitted, centred and with equal scales,
/// into a pixel rectangle (pixel y grows downwards).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fit {
    /// Pixels per metre.
    pub scale: f64,
    /// The screen point drawn at the rectangle's centre, m.
    pub centre: (f64, f64),
    /// The rectangle's centre, pixels.
    pub pixel_centre: (f64, f64),
}

impl Fit {
    /// Fits `points` (screen metres) into `rect = (left, top, right, bottom)` pixels.
    /// A single point or none is drawn at the centre at 100 pixels per metre.
    pub fn new(points: impl IntoIterator<Item = (f64, f64)>, rect: (i32, i32, i32, i32)) -> Self {
        let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for (x, y) in points {
            if x.is_finite() && y.is_finite() {
                (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
            }
        }
        let (w, h) = (f64::from(rect.2 - rect.0), f64::from(rect.3 - rect.1));
        let pixel_centre = (f64::from(rect.0) + w / 2.0, f64::from(rect.1) + h / 2.0);
        if x0 > x1 {
            return Self {
                scale: 100.0,
                centre: (0.0, 0.0),
                pixel_centre,
            };
        }
        let (dx, dy) = (x1 - x0, y1 - y0);
        let scale = match (dx > 0.0, dy > 0.0) {
            (true, true) => (w / dx).min(h / dy),
            (true, false) => w / dx,
            (false, true) => h / dy,
            (false, false) => 100.0,
        };
        Self {
            scale,
            centre: ((x0 + x1) / 2.0, (y0 + y1) / 2.0),
            pixel_centre,
        }
    }

    /// The pixel of a screen point.
    pub fn to_pixel(&self, (x, y): (f64, f64)) -> (i32, i32) {
        let px = self.pixel_centre.0 + (x - self.centre.0) * self.scale;
        let py = self.pixel_centre.1 - (y - self.centre.1) * self.scale;
        (px.round() as i32, py.round() as i32)
    }
}

/// The camera and what to draw besides the structure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Style {
    /// Degrees, see [`project`].
    pub azimuth: f64,
    /// Degrees, see [`project`].
    pub elevation: f64,
    /// Node, bar and cable numbers.
    pub labels: bool,
    /// The scene name and time above the picture.
    pub title: bool,
    /// The tension colour bar on the right.
    pub colour_bar: bool,
}

impl Style {
    /// A full picture (title and colour bar) from the given direction.
    pub fn new(azimuth: f64, elevation: f64, labels: bool) -> Self {
        Self {
            azimuth,
            elevation,
            labels,
            title: true,
            colour_bar: true,
        }
    }
}

pub(super) const TITLE_H: i32 = 44;
pub(super) const BAR_W: i32 = 130;
const MARGIN: i32 = 24;
/// Room below the lowest node for its pin triangle, pixels.
const MARKER: i32 = 14;

/// The pixel rectangle `(left, top, right, bottom)` the structure is fitted into.
pub fn plot_rect(size: (u32, u32), style: &Style) -> (i32, i32, i32, i32) {
    let (w, h) = (size.0 as i32, size.1 as i32);
    let m = if style.title { MARGIN } else { MARGIN / 3 };
    let top = if style.title { TITLE_H } else { 0 } + m;
    let right = w - if style.colour_bar { BAR_W } else { 0 } - m;
    (m, top, right, h - m - MARKER)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projection_axes() {
        let close =
            |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).abs() < 1e-12 && (a.1 - b.1).abs() < 1e-12;
        // Looking along −x: y to the right, z up.
        assert!(close(project([5.0, 2.0, 3.0], 0.0, 0.0), (2.0, 3.0)));
        // Azimuth 90°: looking along −y, x to the left.
        assert!(close(project([2.0, 5.0, 3.0], 90.0, 0.0), (-2.0, 3.0)));
        // From straight above: z vanishes, x is down the screen at azimuth 0.
        assert!(close(project([2.0, 1.0, 7.0], 0.0, 90.0), (1.0, -2.0)));
        assert!((depth([1.0, 0.0, 0.0], 0.0, 0.0) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn fit_fills_the_narrow_side_and_centres() {
        let fit = Fit::new([(0.0, 0.0), (2.0, 1.0)], (0, 0, 400, 400));
        assert_eq!(fit.scale, 200.0);
        assert_eq!(fit.to_pixel((0.0, 0.0)), (0, 300));
        assert_eq!(fit.to_pixel((2.0, 1.0)), (400, 100));
        assert_eq!(fit.to_pixel((1.0, 0.5)), (200, 200));
    }
}
