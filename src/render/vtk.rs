//! A run as a ParaView time series: `NAME.pvd`, a VTK Collection with one `DataSet` per
//! recorded time, and beside it the folder `NAME_vtp/` holding one VTK XML PolyData file
//! per time, `NAME_vtp/NAME_0000.vtp`, `NAME_0001.vtp`, … (four digits, more when there
//! are more than 10,000 times). Open the `.pvd` in ParaView and play it.
//!
//! Each `.vtp` holds:
//! - Points: the node positions, m (Float64).
//! - Lines: one two-point line per member, bars first (in bar order), then cables.
//! - Cell data `kind` (Int32): 0 = bar, 1 = cable; `number` (Int32): the 1-based bar or
//!   cable number; `tension` (Float64, N): the member's axial force, tension positive,
//!   i.e. the cable tension for cables (0 when slack) and minus the bar force for bars
//!   (bars in compression are negative), so one colour map shows both.
//! - Point data `velocity` (Float64, 3 components, m/s), `node` (Int32, 1-based node
//!   number) and `pinned` (Int32, 1 for a pinned node, else 0).
//!
//! Terrain, where the scene has some, is one more PolyData file in the folder,
//! `NAME_vtp/NAME_terrain.vtp`, listed in the collection as part 1 of every time so that
//! ParaView opens it with the run: each shape's quads as polygons (a box's 8 corners and 6
//! faces, a heightfield's grid, subsampled past 3000 quads, a plane as one quad over the
//! structure's extent over the run), with cell data `shape` (Int32, the 1-based terrain
//! number) and `kind` (Int32: 0 plane, 1 box, 2 heightfield).
//!
//! A run recorded with its contacts adds `NAME_vtp/NAME_contacts_0000.vtp`, … per time,
//! the last part of each time: the contact points as vertices with their `force` (see
//! [`contacts`]).
//!
//! The XML is written with quick-xml's `Writer`; the arrays in VTK's inline `binary`
//! format (`header_type="UInt64"`: base64 of the byte count followed by the little-endian
//! values, no compression), so every double reads back bit for bit. Times in the `.pvd` are written as the shortest decimal that reads back
//! as the same double.
//!
//! Nothing is left half-written: the `.vtp` files go into a hidden temporary folder and the
//! collection into a hidden temporary file beside the target (see [`crate::partial`]); both
//! are renamed into place only when everything has been written, and removed on failure.
//! An existing `NAME_vtp/` folder is replaced only if it holds nothing but `.vtp` files.

use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::partial::{commit_folder_and_file, Partial, PartialDir};

use base64::engine::general_purpose::STANDARD as BASE64;
use base64::Engine;
use quick_xml::events::{BytesDecl, BytesText, Event};
use quick_xml::Writer;

use super::terrain::TerrainShape;
use super::Frames;

mod contacts;

/// Writes `frames` as the ParaView time series `path` (which must end in `.pvd`) plus the
/// folder `NAME_vtp/` beside it (see the module documentation for what each file holds).
/// Errors name the path and the reason; on error nothing new is left behind and any
/// earlier series at the same place is kept.
pub fn write_pvd(frames: &Frames, path: &Path) -> Result<(), String> {
    check(frames)?;
    let shown = path.display();
    if path.extension().and_then(|e| e.to_str()) != Some("pvd") {
        return Err(format!("{shown}: a ParaView time series must end in .pvd"));
    }
    let stem = path
        .file_stem()
        .and_then(|s| s.to_str())
        .filter(|s| !s.is_empty())
        .ok_or_else(|| format!("{shown}: the file name must be UTF-8 before .pvd"))?;
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !parent.is_dir() {
        return Err(format!("{shown}: no folder {}", parent.display()));
    }
    let folder_name = format!("{stem}_vtp");
    let folder = parent.join(&folder_name);
    if path.is_dir() {
        return Err(format!("{shown}: is a folder"));
    }
    if folder.exists() {
        replaceable(&folder)?;
    }

    let tmp_folder = PartialDir::create(&folder)?;
    let (tmp_pvd, pvd) = Partial::create(path)?;
    write_all(frames, stem, &folder_name, tmp_folder.path(), pvd)
        .map_err(|e| format!("cannot write {shown}: {e}"))?;
    commit_folder_and_file(tmp_folder, tmp_pvd)
}

/// The frames are consistent: every time has a position and velocity per node, a tension
/// per cable and a force per bar, members name existing nodes, and times are finite.
fn check(frames: &Frames) -> Result<(), String> {
    let n = frames.n_nodes();
    let k = frames.len();
    if k == 0 {
        return Err("nothing to write: no recorded time".into());
    }
    if frames.positions.len() != k
        || frames.velocities.len() != k
        || frames.tensions.len() != k
        || frames.bar_forces.len() != k
    {
        return Err(format!(
            "inconsistent frames: {k} times but {} positions, {} velocities, {} tensions, {} bar forces",
            frames.positions.len(),
            frames.velocities.len(),
            frames.tensions.len(),
            frames.bar_forces.len()
        ));
    }
    for (i, t) in frames.times.iter().enumerate() {
        if !t.is_finite() {
            return Err(format!("time {} is {t}", i + 1));
        }
        let sizes = (
            frames.positions[i].len(),
            frames.velocities[i].len(),
            frames.tensions[i].len(),
            frames.bar_forces[i].len(),
        );
        if sizes != (n, n, frames.cables.len(), frames.bars.len()) {
            return Err(format!(
                "inconsistent frames at t = {t}: {} positions, {} velocities, {} tensions, {} bar forces for {n} nodes, {} cables, {} bars",
                sizes.0, sizes.1, sizes.2, sizes.3, frames.cables.len(), frames.bars.len()
            ));
        }
    }
    let members = frames.bars.iter().map(|m| ("bar", m));
    let members = members.chain(frames.cables.iter().map(|m| ("cable", m)));
    let mut count = [0usize; 2];
    for (what, m) in members {
        let c = &mut count[usize::from(what == "cable")];
        *c += 1;
        if m[0] >= n || m[1] >= n {
            return Err(format!(
                "{what} {c} joins nodes {} and {} but there are {n} nodes",
                m[0] + 1,
                m[1] + 1
            ));
        }
    }
    if let Some(p) = frames.pinned.iter().find(|&&p| p >= n) {
        return Err(format!("pinned node {} but there are {n} nodes", p + 1));
    }
    Ok(())
}

/// An existing `NAME_vtp/` may be replaced only if it holds nothing but `.vtp` files.
fn replaceable(folder: &Path) -> Result<(), String> {
    let shown = folder.display();
    if !folder.is_dir() {
        return Err(format!("{shown}: exists and is not a folder"));
    }
    let entries = fs::read_dir(folder).map_err(|e| format!("{shown}: {e}"))?;
    for entry in entries {
        let entry = entry.map_err(|e| format!("{shown}: {e}"))?;
        let p = entry.path();
        if !(p.is_file() && p.extension().is_some_and(|e| e == "vtp")) {
            return Err(format!(
                "{shown}: holds {} besides .vtp files; not replacing it",
                p.display()
            ));
        }
    }
    Ok(())
}

/// Writes every `.vtp` into `tmp_folder` and the collection into `tmp_pvd`.
fn write_all(
    frames: &Frames,
    stem: &str,
    folder_name: &str,
    tmp_folder: &Path,
    pvd: File,
) -> Result<(), String> {
    let digits = frames.len().saturating_sub(1).to_string().len().max(4);
    let names: Vec<String> = (0..frames.len())
        .map(|k| format!("{stem}_{k:0digits$}.vtp"))
        .collect();
    // A new file in a new private folder: nothing planted there to follow.
    let create = |name: &str, write: &dyn Fn(File) -> Result<(), String>| {
        fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(tmp_folder.join(name))
            .map_err(|e| e.to_string())
            .and_then(write)
            .map_err(|e| format!("{name}: {e}"))
    };
    for (k, name) in names.iter().enumerate() {
        create(name, &|out| write_vtp(frames, k, out))?;
    }
    let mut parts: Vec<Vec<String>> = names.into_iter().map(|n| vec![n]).collect();
    if !frames.terrain.is_empty() {
        let name = format!("{stem}_terrain.vtp");
        create(&name, &|out| write_terrain(frames, out))?;
        parts.iter_mut().for_each(|p| p.push(name.clone()));
    }
    if !frames.contacts.is_empty() {
        for (k, p) in parts.iter_mut().enumerate() {
            let name = format!("{stem}_contacts_{k:0digits$}.vtp");
            create(&name, &|out| contacts::write_contacts(frames, k, out))?;
            p.push(name);
        }
    }
    write_collection(frames, folder_name, &parts, pvd)
}

/// A number type of a VTK `DataArray`: its `type` name and its little-endian bytes.
trait Element: Copy {
    const VTK_TYPE: &'static str;
    fn append_le(self, out: &mut Vec<u8>);
}

impl Element for f64 {
    const VTK_TYPE: &'static str = "Float64";
    fn append_le(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
}

impl Element for i32 {
    const VTK_TYPE: &'static str = "Int32";
    fn append_le(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
}

impl Element for u64 {
    const VTK_TYPE: &'static str = "UInt64";
    fn append_le(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
}

/// Writes `<DataArray>` with `values` inline in VTK's binary format: base64 of the UInt64
/// byte count followed by the values (the file's `header_type`).
fn data_array<W: Write, T: Element>(
    xml: &mut Writer<W>,
    name: Option<&str>,
    components: usize,
    values: &[T],
) -> std::io::Result<()> {
    let size = std::mem::size_of_val(values);
    let mut bytes = Vec::with_capacity(8 + size);
    bytes.extend_from_slice(&(size as u64).to_le_bytes());
    for &v in values {
        v.append_le(&mut bytes);
    }
    let components = components.to_string();
    let mut element = xml
        .create_element("DataArray")
        .with_attribute(("type", T::VTK_TYPE));
    if let Some(name) = name {
        element = element.with_attribute(("Name", name));
    }
    element
        .with_attributes([
            ("NumberOfComponents", components.as_str()),
            ("format", "binary"),
        ])
        .write_text_content(BytesText::new(&BASE64.encode(bytes)))?;
    Ok(())
}

/// A `VTKFile` of `kind` in `file`, its content written by `body`.
fn write_vtk_file(
    file: File,
    kind: &str,
    version: &str,
    header_type: Option<&str>,
    body: impl FnOnce(&mut Writer<BufWriter<File>>) -> std::io::Result<()>,
) -> Result<(), String> {
    let out = BufWriter::new(file);
    let mut xml = Writer::new_with_indent(out, b' ', 2);
    xml.write_event(Event::Decl(BytesDecl::new("1.0", None, None)))
        .map_err(|e| e.to_string())?;
    let mut root = xml
        .create_element("VTKFile")
        .with_attributes([("type", kind), ("version", version)])
        .with_attribute(("byte_order", "LittleEndian"));
    if let Some(header_type) = header_type {
        root = root.with_attribute(("header_type", header_type));
    }
    root.write_inner_content(body).map_err(|e| e.to_string())?;
    let mut out = xml.into_inner();
    out.write_all(b"\n")
        .and_then(|()| out.flush())
        .map_err(|e| e.to_string())
}

/// The XML writer of a VTK file.
type VtkWriter = Writer<BufWriter<File>>;

/// Point or cell data: the element's attributes and what writes its arrays.
type Section<'a> = Option<(
    &'a [(&'a str, &'a str)],
    &'a dyn Fn(&mut VtkWriter) -> std::io::Result<()>,
)>;

/// A `.vtp` of one PolyData piece: `points` (3 values each), cells of one kind (`Verts`,
/// `Lines` or `Polys`, with their connectivity and offsets), and the point and cell data.
fn write_poly_data(
    file: File,
    points: &[f64],
    (cells, connectivity, offsets): (&str, &[u64], &[u64]),
    point_data: Section,
    cell_data: Section,
) -> Result<(), String> {
    let (n_points, n_cells) = ((points.len() / 3).to_string(), offsets.len().to_string());
    let count = |kind: &str| if kind == cells { n_cells.as_str() } else { "0" };
    write_vtk_file(file, "PolyData", "1.0", Some("UInt64"), |xml| {
        xml.create_element("PolyData").write_inner_content(|xml| {
            xml.create_element("Piece")
                .with_attributes([
                    ("NumberOfPoints", n_points.as_str()),
                    ("NumberOfVerts", count("Verts")),
                    ("NumberOfLines", count("Lines")),
                    ("NumberOfStrips", "0"),
                    ("NumberOfPolys", count("Polys")),
                ])
                .write_inner_content(|xml| {
                    for (tag, section) in [("PointData", point_data), ("CellData", cell_data)] {
                        if let Some((attributes, arrays)) = section {
                            xml.create_element(tag)
                                .with_attributes(attributes.iter().copied())
                                .write_inner_content(|xml| arrays(xml))?;
                        }
                    }
                    xml.create_element("Points")
                        .write_inner_content(|xml| data_array(xml, None, 3, points))?;
                    xml.create_element(cells).write_inner_content(|xml| {
                        data_array(xml, Some("connectivity"), 1, connectivity)?;
                        data_array(xml, Some("offsets"), 1, offsets)
                    })?;
                    Ok(())
                })?;
            Ok(())
        })?;
        Ok(())
    })
}

/// The `.vtp` of time `k`.
fn write_vtp(frames: &Frames, k: usize, file: File) -> Result<(), String> {
    let n = frames.n_nodes();
    let (nb, nc) = (frames.bars.len(), frames.cables.len());
    let points: Vec<f64> = frames.positions[k].iter().flatten().copied().collect();
    let velocity: Vec<f64> = frames.velocities[k].iter().flatten().copied().collect();
    let members = frames.bars.iter().chain(&frames.cables);
    let connectivity: Vec<u64> = members.flatten().map(|&i| i as u64).collect();
    let offsets: Vec<u64> = (1..=(nb + nc) as u64).map(|m| 2 * m).collect();
    let kind: Vec<i32> = (0..nb).map(|_| 0).chain((0..nc).map(|_| 1)).collect();
    let number: Vec<i32> = (1..=nb).chain(1..=nc).map(|i| i as i32).collect();
    let tension: Vec<f64> = frames.bar_forces[k]
        .iter()
        .map(|f| -f)
        .chain(frames.tensions[k].iter().copied())
        .collect();
    let node: Vec<i32> = (1..=n).map(|i| i as i32).collect();
    let mut pinned = vec![0i32; n];
    for &p in &frames.pinned {
        pinned[p] = 1;
    }
    let point_data = |xml: &mut VtkWriter| {
        data_array(xml, Some("velocity"), 3, &velocity)?;
        data_array(xml, Some("node"), 1, &node)?;
        data_array(xml, Some("pinned"), 1, &pinned)
    };
    let cell_data = |xml: &mut VtkWriter| {
        data_array(xml, Some("tension"), 1, &tension)?;
        data_array(xml, Some("kind"), 1, &kind)?;
        data_array(xml, Some("number"), 1, &number)
    };
    write_poly_data(
        file,
        &points,
        ("Lines", &connectivity, &offsets),
        Some((&[("Scalars", "node"), ("Vectors", "velocity")], &point_data)),
        // `tension` is the active scalars: ParaView colours by it.
        Some((&[("Scalars", "tension")], &cell_data)),
    )
}

/// The terrain's `.vtp`: every shape's quads as polygons.
fn write_terrain(frames: &Frames, file: File) -> Result<(), String> {
    let (mut points, mut connectivity, mut offsets) = (Vec::<f64>::new(), Vec::new(), Vec::new());
    let (mut shape, mut kind) = (Vec::<i32>::new(), Vec::<i32>::new());
    for (number, (t, mesh)) in frames
        .terrain
        .iter()
        .zip(frames.terrain_meshes())
        .enumerate()
    {
        let first = (points.len() / 3) as u64;
        points.extend(mesh.points.iter().flatten());
        for q in &mesh.quads {
            connectivity.extend(q.iter().map(|&i| first + i as u64));
            offsets.push(connectivity.len() as u64);
            shape.push(number as i32 + 1);
            kind.push(match t {
                TerrainShape::Plane { .. } => 0,
                TerrainShape::Box(_) => 1,
                TerrainShape::Heightfield(_) => 2,
            });
        }
    }
    let cell_data = |xml: &mut VtkWriter| {
        data_array(xml, Some("kind"), 1, &kind)?;
        data_array(xml, Some("shape"), 1, &shape)
    };
    write_poly_data(
        file,
        &points,
        ("Polys", &connectivity, &offsets),
        None,
        Some((&[("Scalars", "kind")], &cell_data)),
    )
}

/// The VTK Collection listing one `DataSet` per time and part, files relative to the
/// `.pvd`: `parts[k]` are time k's files, part 0 the run's, then the terrain's and the
/// contacts' where there are.
fn write_collection(
    frames: &Frames,
    folder_name: &str,
    parts: &[Vec<String>],
    file: File,
) -> Result<(), String> {
    write_vtk_file(file, "Collection", "0.1", None, |xml| {
        xml.create_element("Collection")
            .write_inner_content(|xml| {
                for (t, files) in frames.times.iter().zip(parts) {
                    let time = t.to_string();
                    for (part, name) in files.iter().enumerate() {
                        let (part, path) = (part.to_string(), format!("{folder_name}/{name}"));
                        xml.create_element("DataSet")
                            .with_attributes([
                                ("timestep", time.as_str()),
                                ("group", ""),
                                ("part", part.as_str()),
                                ("file", path.as_str()),
                            ])
                            .write_empty()?;
                    }
                }
                Ok(())
            })?;
        Ok(())
    })
}
