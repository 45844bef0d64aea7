//! Terrain faces in a picture: their light shading, the part of the terrain the view is
//! fitted to, clipping to the plot, and which members a face hides.
//!
//! The structure is drawn over the terrain, except the pieces of members that lie behind a
//! face (beyond its plane, seen from the camera, and inside its picture): those are drawn
//! faintly, so that a bar behind a step reads as hidden and still shows.

use plotters::style::RGBColor;

use super::terrain::{dot, quad_normal, TerrainShape};
use super::view::{depth, project};
use super::Frames;

/// Base colours of the terrain kinds before shading.
pub const PLANE_COLOUR: RGBColor = RGBColor(226, 222, 205);
/// See [`PLANE_COLOUR`].
pub const BOX_COLOUR: RGBColor = RGBColor(200, 162, 118);
/// See [`PLANE_COLOUR`].
pub const HEIGHTFIELD_COLOUR: RGBColor = RGBColor(142, 180, 122);

/// Where the light comes from (fixed in the world, so a face's colour does not depend on
/// the camera): above, a little from +x and +y.
const LIGHT: [f64; 3] = [0.398, 0.221, 0.890];

/// The base colour of a kind (see [`TerrainShape::kind`]).
pub fn base_colour(kind: &str) -> RGBColor {
    match kind {
        "box" => BOX_COLOUR,
        "heightfield" => HEIGHTFIELD_COLOUR,
        _ => PLANE_COLOUR,
    }
}

/// The colour of a face of `base` with outward unit `normal`: 60 % ambient, 40 % lit.
pub fn shade(base: RGBColor, normal: [f64; 3]) -> RGBColor {
    scale(base, 0.6 + 0.4 * dot(normal, LIGHT).max(0.0))
}

/// `c` darkened by `f` (at most 1).
pub fn scale(c: RGBColor, f: f64) -> RGBColor {
    let s = |v: u8| (f64::from(v) * f).round().clamp(0.0, 255.0) as u8;
    RGBColor(s(c.0), s(c.1), s(c.2))
}

/// One face as drawn.
#[derive(Debug, Clone)]
pub struct Face {
    /// Corners, m.
    pub corners: Vec<[f64; 3]>,
    /// Outward unit normal.
    pub normal: [f64; 3],
    /// Shaded fill.
    pub fill: RGBColor,
    /// The shape's kind.
    pub kind: &'static str,
}

/// Every terrain face seen from the camera, in drawing order: planes first (floors under
/// everything), then heightfield quads far before near with each box's near faces (those
/// turned away are left out) drawn after the quads it may hide and before the quads that
/// lie in front of one of those faces' planes.
pub fn faces(frames: &Frames, azimuth: f64, elevation: f64) -> Vec<Face> {
    let view = toward_camera(azimuth, elevation);
    let (mut planes, mut quads, mut boxes) = (Vec::new(), Vec::new(), Vec::new());
    for (shape, mesh) in frames.terrain.iter().zip(frames.terrain_meshes()) {
        let kind = shape.kind();
        let mut near = Vec::new();
        for &q in &mesh.quads {
            let normal = quad_normal(&mesh, q);
            let face = Face {
                corners: q.iter().map(|&k| mesh.points[k]).collect(),
                normal,
                fill: shade(base_colour(kind), normal),
                kind,
            };
            match shape {
                TerrainShape::Plane { .. } => planes.push(face),
                TerrainShape::Heightfield(_) => quads.push(face),
                TerrainShape::Box(_) if dot(normal, view) > 0.0 => near.push(face),
                TerrainShape::Box(_) => {}
            }
        }
        if !near.is_empty() {
            boxes.push(near);
        }
    }
    let key = |f: &Face| depth(centroid(&f.corners), azimuth, elevation);
    quads.sort_by(|a, b| key(a).total_cmp(&key(b)));
    let box_key = |b: &Vec<Face>| b.iter().map(key).sum::<f64>() / b.len() as f64;
    boxes.sort_by(|a, b| box_key(a).total_cmp(&box_key(b)));
    // Layer of a quad: 1 + the last box (far to near) with a near face it lies in front of.
    let layer = |q: &Face| {
        let c = centroid(&q.corners);
        boxes
            .iter()
            .rposition(|b| b.iter().any(|f| ahead(f, c) > 0.0))
            .map_or(0, |i| i + 1)
    };
    let layers: Vec<usize> = quads.iter().map(layer).collect();
    let mut out = planes;
    let mut boxes = boxes.into_iter();
    for l in 0..=layers.iter().copied().max().unwrap_or(0).max(boxes.len()) {
        let here = quads.iter().zip(&layers).filter(|(_, &m)| m == l);
        out.extend(here.map(|(q, _)| q.clone()));
        out.extend(boxes.next().into_iter().flatten());
    }
    out
}

/// How far `p` lies on the outer side of the face's plane, m.
fn ahead(face: &Face, p: [f64; 3]) -> f64 {
    let c = face.corners[0];
    dot(face.normal, [p[0] - c[0], p[1] - c[1], p[2] - c[2]])
}

/// Unit vector from the scene towards the camera.
fn toward_camera(azimuth: f64, elevation: f64) -> [f64; 3] {
    let (sa, ca) = azimuth.to_radians().sin_cos();
    let (se, ce) = elevation.to_radians().sin_cos();
    [ce * ca, ce * sa, se]
}

fn centroid(points: &[[f64; 3]]) -> [f64; 3] {
    let n = points.len().max(1) as f64;
    [0, 1, 2].map(|i| points.iter().map(|p| p[i]).sum::<f64>() / n)
}

/// The terrain points the view is fitted to: the structure's neighbourhood (its extent
/// over the run widened by a quarter) holds them, so that a field of a hundred metres
/// does not shrink a one-metre robot to a dot. Box corners are pulled into it.
pub fn fit_points(frames: &Frames) -> Vec<[f64; 3]> {
    let nodes: Vec<[f64; 3]> = frames.positions.iter().flatten().copied().collect();
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in nodes.iter().filter(|p| p.iter().all(|v| v.is_finite())) {
        for i in 0..2 {
            (lo[i], hi[i]) = (lo[i].min(p[i]), hi[i].max(p[i]));
        }
    }
    if lo[0] > hi[0] {
        return Vec::new();
    }
    let widen = ((hi[0] - lo[0]).max(hi[1] - lo[1]) * 0.25).max(0.25);
    let (lo, hi) = (lo.map(|v| v - widen), hi.map(|v| v + widen));
    let inside = |p: &[f64; 3]| (0..2).all(|i| p[i] >= lo[i] && p[i] <= hi[i]);
    let mut out = Vec::new();
    for (shape, mesh) in frames.terrain.iter().zip(frames.terrain_meshes()) {
        match shape {
            TerrainShape::Plane { .. } => out.extend(mesh.points),
            TerrainShape::Heightfield(_) => out.extend(mesh.points.into_iter().filter(inside)),
            TerrainShape::Box(_) => {
                let touches = (0..2).all(|i| {
                    let along = mesh.points.iter().map(|p| p[i]);
                    along.clone().fold(f64::INFINITY, f64::min) <= hi[i]
                        && along.fold(f64::NEG_INFINITY, f64::max) >= lo[i]
                });
                if touches {
                    let pull =
                        |p: [f64; 3]| [p[0].clamp(lo[0], hi[0]), p[1].clamp(lo[1], hi[1]), p[2]];
                    out.extend(mesh.points.into_iter().map(pull));
                }
            }
        }
    }
    out
}

/// Members are judged in this many equal pieces, so that a bar lying over a step's edge is
/// hidden only beyond it.
pub const PIECES: usize = 8;

/// For members given by their end points, which pieces of each are hidden (bit `i` for
/// piece `i` of [`PIECES`] from the first end). A face hides a piece whose middle lies
/// farther than `tol` m beyond the face's plane, as seen from the camera, and inside the
/// face's picture (so a bar resting on a face is not behind it).
pub fn occlusion(
    faces: &[Face],
    members: &[([f64; 3], [f64; 3])],
    azimuth: f64,
    elevation: f64,
    tol: f64,
) -> Vec<u32> {
    let view = toward_camera(azimuth, elevation);
    let pictures: Vec<Vec<(f64, f64)>> = faces
        .iter()
        .map(|f| {
            f.corners
                .iter()
                .map(|&p| project(p, azimuth, elevation))
                .collect()
        })
        .collect();
    let boxes: Vec<[f64; 4]> = pictures.iter().map(|p| bounds(p)).collect();
    let mut hidden = vec![0u32; members.len()];
    for (m, &(a, b)) in members.iter().enumerate() {
        let middles: Vec<[f64; 3]> = (0..PIECES)
            .map(|i| {
                let f = (i as f64 + 0.5) / PIECES as f64;
                [0, 1, 2].map(|c| a[c] + f * (b[c] - a[c]))
            })
            .collect();
        let seen: Vec<(f64, f64)> = middles
            .iter()
            .map(|&p| project(p, azimuth, elevation))
            .collect();
        let mb = bounds(&seen);
        for (f, face) in faces.iter().enumerate() {
            let fb = boxes[f];
            if mb[0] > fb[2] || mb[2] < fb[0] || mb[1] > fb[3] || mb[3] < fb[1] {
                continue;
            }
            let side = dot(face.normal, view).signum();
            let c = face.corners[0];
            for (i, (p, &q)) in middles.iter().zip(&seen).enumerate() {
                let d = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
                if dot(face.normal, d) * side < -tol && inside(q, &pictures[f]) {
                    hidden[m] |= 1 << i;
                }
            }
        }
    }
    hidden
}

/// The stretches `(from, to)` (fractions of the member's length) of the pieces whose
/// bit in `mask` equals `behind`, neighbours joined.
pub fn stretches(mask: u32, behind: bool) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::new();
    for i in 0..PIECES {
        if (mask >> i & 1 == 1) != behind {
            continue;
        }
        let (s0, s1) = (i as f64 / PIECES as f64, (i + 1) as f64 / PIECES as f64);
        match out.last_mut() {
            Some(last) if last.1 == s0 => last.1 = s1,
            _ => out.push((s0, s1)),
        }
    }
    out
}

/// `[x0, y0, x1, y1]` of points.
fn bounds(points: &[(f64, f64)]) -> [f64; 4] {
    points.iter().fold(
        [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ],
        |b, &(x, y)| [b[0].min(x), b[1].min(y), b[2].max(x), b[3].max(y)],
    )
}

/// Whether `q` lies inside the polygon (even-odd rule).
fn inside(q: (f64, f64), polygon: &[(f64, f64)]) -> bool {
    let mut odd = false;
    for k in 0..polygon.len() {
        let (p, r) = (polygon[k], polygon[(k + 1) % polygon.len()]);
        if (p.1 > q.1) != (r.1 > q.1) && q.0 < p.0 + (q.1 - p.1) / (r.1 - p.1) * (r.0 - p.0) {
            odd = !odd;
        }
    }
    odd
}

/// The polygon `points` (pixels) clipped to the rectangle `(left, top, right, bottom)`.
pub fn clip(points: &[(f64, f64)], rect: (i32, i32, i32, i32)) -> Vec<(i32, i32)> {
    let (l, t, r, b) = (
        f64::from(rect.0),
        f64::from(rect.1),
        f64::from(rect.2),
        f64::from(rect.3),
    );
    // Sutherland–Hodgman: one edge of the rectangle at a time, `inside(p) ≥ 0` kept.
    let edges: [&dyn Fn((f64, f64)) -> f64; 4] =
        [&|p| p.0 - l, &|p| r - p.0, &|p| p.1 - t, &|p| b - p.1];
    let mut poly = points.to_vec();
    for inside in edges {
        let mut out = Vec::with_capacity(poly.len() + 2);
        for k in 0..poly.len() {
            let (p, q) = (poly[k], poly[(k + 1) % poly.len()]);
            let (dp, dq) = (inside(p), inside(q));
            if dp >= 0.0 {
                out.push(p);
            }
            if (dp >= 0.0) != (dq >= 0.0) {
                let s = dp / (dp - dq);
                out.push((p.0 + s * (q.0 - p.0), p.1 + s * (q.1 - p.1)));
            }
        }
        poly = out;
        if poly.is_empty() {
            break;
        }
    }
    poly.iter()
        .map(|p| (p.0.round() as i32, p.1.round() as i32))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clip_to_rectangle() {
        let square = [(-10.0, -10.0), (10.0, -10.0), (10.0, 10.0), (-10.0, 10.0)];
        let mut c = clip(&square, (0, 0, 5, 5));
        c.sort();
        c.dedup();
        assert_eq!(c, [(0, 0), (0, 5), (5, 0), (5, 5)]);
        assert!(clip(&square, (20, 20, 30, 30)).is_empty());
    }

    #[test]
    fn stretches_join_neighbours() {
        assert_eq!(stretches(0, false), [(0.0, 1.0)]);
        assert!(stretches(0, true).is_empty());
        assert_eq!(stretches(0b1100_0001, true), [(0.0, 0.125), (0.75, 1.0)]);
        assert_eq!(stretches(0b1100_0001, false), [(0.125, 0.75)]);
    }

    #[test]
    fn tops_are_lit_more_than_sides() {
        let top = shade(BOX_COLOUR, [0.0, 0.0, 1.0]);
        let away = shade(BOX_COLOUR, [-1.0, 0.0, 0.0]);
        assert!(top.0 > away.0 && away == scale(BOX_COLOUR, 0.6));
    }
}
