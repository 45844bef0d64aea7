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
//! The arrays are written by the `vtkio` crate in VTK's inline `binary` format
//! (base64 of the little-endian values, no compression), so every double reads back
//! bit for bit. Times in the `.pvd` are written as the shortest decimal that reads back
//! as the same double.
//!
//! Nothing is left half-written: the `.vtp` files go into a temporary folder and the
//! collection into a temporary file beside the target; both are renamed into place only
//! when everything has been written, and removed on failure. An existing `NAME_vtp/`
//! folder is replaced only if it holds nothing but `.vtp` files.

use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use vtkio::model::{
    Attribute, Attributes, ByteOrder, DataArray, DataSet, ElementType, IOBuffer, PolyDataPiece,
    Version, VertexNumbers, Vtk,
};

use super::Frames;

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

    let id = std::process::id();
    let tmp_folder = parent.join(format!(".{folder_name}.tmp-{id}"));
    let tmp_pvd = parent.join(format!(".{stem}.pvd.tmp-{id}"));
    let cleanup = || {
        let _ = fs::remove_dir_all(&tmp_folder);
        let _ = fs::remove_file(&tmp_pvd);
    };
    cleanup();
    let written = write_all(frames, stem, &folder_name, &tmp_folder, &tmp_pvd);
    if let Err(e) = written {
        cleanup();
        return Err(e);
    }

    // Into place: the old folder aside, the new one in, the collection, the old one away.
    let old = parent.join(format!(".{folder_name}.old-{id}"));
    let _ = fs::remove_dir_all(&old);
    let had_old = folder.exists();
    if had_old {
        if let Err(e) = fs::rename(&folder, &old) {
            cleanup();
            return Err(format!("{}: cannot replace: {e}", folder.display()));
        }
    }
    let restore = || {
        if had_old {
            let _ = fs::rename(&old, &folder);
        }
    };
    if let Err(e) = fs::rename(&tmp_folder, &folder) {
        cleanup();
        restore();
        return Err(format!("{}: cannot create: {e}", folder.display()));
    }
    if let Err(e) = fs::rename(&tmp_pvd, path) {
        let _ = fs::remove_dir_all(&folder);
        cleanup();
        restore();
        return Err(format!("{shown}: cannot create: {e}"));
    }
    if had_old {
        let _ = fs::remove_dir_all(&old);
    }
    Ok(())
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
    tmp_pvd: &Path,
) -> Result<(), String> {
    fs::create_dir(tmp_folder).map_err(|e| format!("{}: {e}", tmp_folder.display()))?;
    let digits = frames.len().saturating_sub(1).to_string().len().max(4);
    let names: Vec<String> = (0..frames.len())
        .map(|k| format!("{stem}_{k:0digits$}.vtp"))
        .collect();
    for (k, name) in names.iter().enumerate() {
        let file = tmp_folder.join(name);
        write_vtp(frames, k, &file).map_err(|e| format!("{}: {e}", file.display()))?;
    }
    write_collection(frames, folder_name, &names, tmp_pvd)
        .map_err(|e| format!("{}: {e}", tmp_pvd.display()))
}

/// The `.vtp` of time `k`.
fn write_vtp(frames: &Frames, k: usize, file: &Path) -> Result<(), String> {
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
    let array = |name: &str, elem: ElementType, data: IOBuffer| {
        Attribute::DataArray(DataArray {
            name: name.into(),
            elem,
            data,
        })
    };
    let scalars = ElementType::Scalars {
        num_comp: 1,
        lookup_table: None,
    };
    let piece = PolyDataPiece {
        points: IOBuffer::F64(points),
        lines: Some(VertexNumbers::XML {
            connectivity,
            offsets,
        }),
        data: Attributes {
            point: vec![
                array("velocity", ElementType::Vectors, IOBuffer::F64(velocity)),
                array("node", scalars.clone(), IOBuffer::I32(node)),
                array("pinned", scalars.clone(), IOBuffer::I32(pinned)),
            ],
            // `tension` first: ParaView colours by the first (active) scalars.
            cell: vec![
                array("tension", scalars.clone(), IOBuffer::F64(tension)),
                array("kind", scalars.clone(), IOBuffer::I32(kind)),
                array("number", scalars, IOBuffer::I32(number)),
            ],
        },
        ..Default::default()
    };
    let vtk = Vtk {
        version: Version::new((1, 0)),
        title: String::new(),
        byte_order: ByteOrder::LittleEndian,
        data: DataSet::inline(piece),
        file_path: None,
    };
    let mut out = BufWriter::new(File::create(file).map_err(|e| e.to_string())?);
    vtk.write_xml(&mut out).map_err(|e| e.to_string())?;
    out.flush().map_err(|e| e.to_string())
}

/// The VTK Collection listing one `DataSet` per time, files relative to the `.pvd`.
fn write_collection(
    frames: &Frames,
    folder_name: &str,
    names: &[String],
    file: &Path,
) -> Result<(), String> {
    use quick_xml::escape::escape;
    let mut text = String::with_capacity(200 + 80 * names.len());
    text.push_str("<?xml version=\"1.0\"?>\n");
    text.push_str(
        "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n",
    );
    for (t, name) in frames.times.iter().zip(names) {
        let file = escape(format!("{folder_name}/{name}"));
        text.push_str(&format!(
            "    <DataSet timestep=\"{t}\" group=\"\" part=\"0\" file=\"{file}\"/>\n"
        ));
    }
    text.push_str("  </Collection>\n</VTKFile>\n");
    fs::write(file, text).map_err(|e| e.to_string())
}
