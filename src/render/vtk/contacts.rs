//! The contacts of one time as VTK XML PolyData, `NAME_vtp/NAME_contacts_0000.vtp`, …:
//! each contact point a vertex, with point data `force` (Float64, 3 components, N: the
//! force on the structure there, friction included; ParaView's Glyph filter draws it as
//! arrows), `magnitude` (Float64, N), `kind` (Int32: 0 terrain, 1 collision, 2 ground),
//! `bar` (Int32, the 1-based bar, 0 for the ground) and `with` (Int32: the 1-based terrain
//! shape, the other bar, or for the ground the 1-based node).

use std::fs::File;

use super::super::Frames;
use super::{data_array, write_poly_data, VtkWriter};
use crate::dynamics::contact_points::ContactKind;

/// The contacts' `.vtp` of time `k`.
pub(super) fn write_contacts(frames: &Frames, k: usize, file: File) -> Result<(), String> {
    let contacts = frames.contacts.get(k).map_or(&[][..], Vec::as_slice);
    let n = contacts.len();
    let points: Vec<f64> = contacts
        .iter()
        .flat_map(|c| c.point.iter().copied())
        .collect();
    let force: Vec<f64> = contacts
        .iter()
        .flat_map(|c| c.force.iter().copied())
        .collect();
    let magnitude: Vec<f64> = contacts.iter().map(|c| c.force.norm()).collect();
    let (mut kind, mut bar, mut with) = (Vec::new(), Vec::new(), Vec::new());
    for c in contacts {
        let (k, b, w) = match c.kind {
            ContactKind::Terrain { bar, shape } => (0, bar + 1, shape + 1),
            ContactKind::Collision { bar, other } => (1, bar + 1, other + 1),
            ContactKind::Ground { node } => (2, 0, node + 1),
        };
        kind.push(k);
        bar.push(b as i32);
        with.push(w as i32);
    }
    let connectivity: Vec<u64> = (0..n as u64).collect();
    let offsets: Vec<u64> = (1..=n as u64).collect();
    let point_data = |xml: &mut VtkWriter| {
        data_array(xml, Some("force"), 3, &force)?;
        data_array(xml, Some("magnitude"), 1, &magnitude)?;
        data_array(xml, Some("kind"), 1, &kind)?;
        data_array(xml, Some("bar"), 1, &bar)?;
        data_array(xml, Some("with"), 1, &with)
    };
    write_poly_data(
        file,
        &points,
        ("Verts", &connectivity, &offsets),
        Some((
            &[("Scalars", "magnitude"), ("Vectors", "force")],
            &point_data,
        )),
        None,
    )
}
