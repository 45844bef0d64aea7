//! The ParaView time series (`render::vtk::write_pvd`) read back here with quick-xml's
//! deserializer and a base64 decoder (VTK's own reader checks them in
//! `tests/fmpy/test_vtk_files.py`): one `.vtp` per recorded time, listed in the `.pvd` with its time; points, lines and
//! every array bit for bit equal to the simulation's values (the arrays are written in
//! VTK's inline binary format, so no digits are lost). Also writes, for
//! `tests/fmpy/test_vtk_files.py`, the series into `target/render-test/` together with a
//! JSON of the values taken straight from the simulation.

use std::fs;
use std::path::{Path, PathBuf};

use base64::engine::general_purpose::STANDARD as BASE64;
use base64::Engine;
use serde::Deserialize;
use tensegrity_fmu::render::terrain::TerrainShape;
use tensegrity_fmu::render::vtk::write_pvd;
use tensegrity_fmu::render::{Frames, GroundPlane};
use tensegrity_fmu::scene::builtin;
use tensegrity_fmu::{Model, Simulation};

/// Where the series are written (kept for the pytest).
fn out_dir() -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/render-test");
    fs::create_dir_all(&dir).unwrap();
    dir
}

/// A run of built-in `name` recorded at `times`, with `force` on the first force-input node.
fn record(name: &str, force: [f64; 3], times: &[f64]) -> Frames {
    let scene = builtin(name).unwrap();
    let mut sim = Simulation::new(Model::new(&scene).unwrap());
    if let Some(f) = sim.inputs.node_force.first_mut() {
        *f = force.into();
    }
    let model = sim.model();
    let n = model.n_nodes();
    let mut frames = Frames {
        name: name.into(),
        bars: model.bars.iter().map(|b| b.nodes).collect(),
        cables: model.cables.iter().map(|c| c.nodes).collect(),
        pinned: (0..n).filter(|&i| model.pinned[i]).collect(),
        point_masses: model
            .scene
            .point_masses
            .iter()
            .map(|p| p.node - 1)
            .collect(),
        ground: model.ground.as_ref().map(|g| GroundPlane {
            normal: g.normal.into(),
            height: g.height,
        }),
        terrain: TerrainShape::all(model.terrain.as_ref()),
        bar_radius: model.bars.iter().map(|b| b.radius).collect(),
        times: vec![],
        positions: vec![],
        velocities: vec![],
        tensions: vec![],
        bar_forces: vec![],
        contacts: vec![],
    };
    let (nb, nc) = (frames.bars.len(), frames.cables.len());
    for &t in times {
        sim.advance_to(t).unwrap();
        sim.refresh();
        frames.times.push(t);
        frames
            .positions
            .push((0..n).map(|i| sim.node_position(i).into()).collect());
        frames
            .velocities
            .push((0..n).map(|i| sim.node_velocity(i).into()).collect());
        frames
            .tensions
            .push((0..nc).map(|j| sim.cable_tension(j)).collect());
        frames
            .bar_forces
            .push((0..nb).map(|b| sim.bar_force(b)).collect());
    }
    frames
}

#[derive(Deserialize)]
struct Pvd {
    #[serde(rename = "@type")]
    kind: String,
    #[serde(rename = "Collection")]
    collection: Collection,
}

#[derive(Deserialize)]
struct Collection {
    #[serde(rename = "DataSet")]
    data_sets: Vec<PvdDataSet>,
}

#[derive(Deserialize)]
struct PvdDataSet {
    #[serde(rename = "@timestep")]
    timestep: String,
    #[serde(rename = "@file")]
    file: String,
    #[serde(rename = "@part")]
    part: String,
}

/// The `.pvd`'s (time, file) pairs of the run (part 0; the terrain is part 1).
fn read_pvd(path: &Path) -> Vec<(f64, PathBuf)> {
    let pvd: Pvd = quick_xml::de::from_str(&fs::read_to_string(path).unwrap()).unwrap();
    assert_eq!(pvd.kind, "Collection");
    let dir = path.parent().unwrap();
    pvd.collection
        .data_sets
        .iter()
        .filter(|d| d.part == "0")
        .map(|d| (d.timestep.parse().unwrap(), dir.join(&d.file)))
        .collect()
}

#[derive(Deserialize)]
struct Vtp {
    #[serde(rename = "@type")]
    kind: String,
    #[serde(rename = "@byte_order")]
    byte_order: String,
    #[serde(rename = "@header_type")]
    header_type: String,
    #[serde(rename = "PolyData")]
    poly_data: PolyData,
}

#[derive(Deserialize)]
struct PolyData {
    #[serde(rename = "Piece")]
    pieces: Vec<Piece>,
}

/// One inline piece: its counts and arrays (a missing `Verts`/`Polys`/`Strips` is empty).
#[derive(Deserialize)]
struct Piece {
    #[serde(rename = "@NumberOfPoints")]
    n_points: usize,
    #[serde(rename = "@NumberOfLines")]
    n_lines: usize,
    #[serde(rename = "@NumberOfVerts")]
    n_verts: usize,
    #[serde(rename = "@NumberOfPolys")]
    n_polys: usize,
    #[serde(rename = "@NumberOfStrips")]
    n_strips: usize,
    #[serde(rename = "PointData")]
    point: Arrays,
    #[serde(rename = "CellData")]
    cell: Arrays,
    #[serde(rename = "Points")]
    points: Arrays,
    #[serde(rename = "Lines")]
    lines: Arrays,
}

#[derive(Deserialize)]
struct Arrays {
    #[serde(rename = "DataArray", default)]
    arrays: Vec<DataArray>,
}

#[derive(Deserialize)]
struct DataArray {
    #[serde(rename = "@type")]
    kind: String,
    #[serde(rename = "@Name", default)]
    name: String,
    #[serde(rename = "@NumberOfComponents")]
    components: usize,
    #[serde(rename = "@format")]
    format: String,
    #[serde(rename = "$text")]
    text: String,
}

impl DataArray {
    /// The values' bytes: base64 of a UInt64 byte count, then the little-endian values.
    fn bytes(&self, kind: &str, size: usize) -> Vec<u8> {
        assert_eq!((self.kind.as_str(), self.format.as_str()), (kind, "binary"));
        let raw = BASE64.decode(self.text.trim()).unwrap();
        let (count, data) = raw.split_at(8);
        let count = u64::from_le_bytes(count.try_into().unwrap()) as usize;
        assert_eq!(count, data.len(), "{}: header counts the bytes", self.name);
        assert_eq!(data.len() % size, 0);
        data.to_vec()
    }
}

/// The single inline piece of a `.vtp`.
fn read_vtp(path: &Path) -> Piece {
    let text = fs::read_to_string(path).unwrap();
    let vtp: Vtp =
        quick_xml::de::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(
        (
            vtp.kind.as_str(),
            vtp.byte_order.as_str(),
            vtp.header_type.as_str()
        ),
        ("PolyData", "LittleEndian", "UInt64")
    );
    let mut pieces = vtp.poly_data.pieces;
    assert_eq!(pieces.len(), 1, "{}", path.display());
    pieces.remove(0)
}

fn array<'a>(attrs: &'a Arrays, name: &str) -> &'a DataArray {
    attrs
        .arrays
        .iter()
        .find(|a| a.name == name)
        .unwrap_or_else(|| panic!("no array {name}"))
}

fn f64s(a: &DataArray) -> Vec<f64> {
    let bytes = a.bytes("Float64", 8);
    bytes
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

fn i32s(a: &DataArray) -> Vec<i32> {
    let bytes = a.bytes("Int32", 4);
    bytes
        .chunks_exact(4)
        .map(|c| i32::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

fn u64s(a: &DataArray) -> Vec<u64> {
    let bytes = a.bytes("UInt64", 8);
    bytes
        .chunks_exact(8)
        .map(|c| u64::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// Checks every file of the series at `pvd` against `frames`, bit for bit.
fn check_series(frames: &Frames, pvd: &Path) {
    let n = frames.n_nodes();
    let (nb, nc) = (frames.bars.len(), frames.cables.len());
    let listed = read_pvd(pvd);
    assert_eq!(listed.len(), frames.len(), "one DataSet per time");
    for (k, (t, file)) in listed.iter().enumerate() {
        assert_eq!(t.to_bits(), frames.times[k].to_bits(), "timestep {k}");
        let name = pvd.file_stem().unwrap().to_str().unwrap();
        assert_eq!(
            file.file_name().unwrap().to_str().unwrap(),
            format!("{name}_{k:04}.vtp")
        );
        let piece = read_vtp(file);
        assert_eq!(piece.n_points, n);
        assert_eq!(piece.n_lines, nb + nc);
        assert_eq!((piece.n_verts, piece.n_polys, piece.n_strips), (0, 0, 0));
        assert_eq!(piece.points.arrays.len(), 1);
        let points = &piece.points.arrays[0];
        assert_eq!(points.components, 3);
        let points = f64s(points);
        let want: Vec<f64> = frames.positions[k].iter().flatten().copied().collect();
        assert_eq!(bits(&points), bits(&want), "points at t = {t}");

        let connectivity = u64s(array(&piece.lines, "connectivity"));
        let offsets = u64s(array(&piece.lines, "offsets"));
        assert_eq!(offsets.len(), nb + nc, "one line per member");
        let want: Vec<u64> = frames
            .bars
            .iter()
            .chain(&frames.cables)
            .flatten()
            .map(|&i| i as u64)
            .collect();
        assert_eq!(connectivity, want, "bars first, then cables");
        assert_eq!(
            offsets,
            (1..=(nb + nc) as u64).map(|m| 2 * m).collect::<Vec<_>>()
        );

        let cell = &piece.cell;
        let kind = i32s(array(cell, "kind"));
        assert_eq!(kind, [vec![0; nb], vec![1; nc]].concat());
        let number = i32s(array(cell, "number"));
        let want: Vec<i32> = (1..=nb as i32).chain(1..=nc as i32).collect();
        assert_eq!(number, want);
        let tension = f64s(array(cell, "tension"));
        assert_eq!(
            bits(&tension[nb..]),
            bits(&frames.tensions[k]),
            "cable tensions at t = {t}"
        );
        let minus_bar_force: Vec<f64> = frames.bar_forces[k].iter().map(|f| -f).collect();
        assert_eq!(
            bits(&tension[..nb]),
            bits(&minus_bar_force),
            "bar tensions (minus the bar force) at t = {t}"
        );

        let point = &piece.point;
        assert_eq!(array(point, "velocity").components, 3);
        let velocity = f64s(array(point, "velocity"));
        let want: Vec<f64> = frames.velocities[k].iter().flatten().copied().collect();
        assert_eq!(bits(&velocity), bits(&want), "velocities at t = {t}");
        assert_eq!(
            i32s(array(point, "node")),
            (1..=n as i32).collect::<Vec<_>>()
        );
        let pinned = i32s(array(point, "pinned"));
        let want: Vec<i32> = (0..n)
            .map(|i| i32::from(frames.pinned.contains(&i)))
            .collect();
        assert_eq!(pinned, want);
    }
}

/// Writes what the pytest compares against: the values straight from the simulation.
fn write_expected(frames: &Frames, path: &Path) {
    let json = serde_json::json!({
        "n_nodes": frames.n_nodes(),
        "bars": frames.bars,
        "cables": frames.cables,
        "pinned": frames.pinned,
        "times": frames.times,
        "positions": frames.positions,
        "velocities": frames.velocities,
        "tensions": frames.tensions,
        "bar_forces": frames.bar_forces,
    });
    fs::write(path, serde_json::to_string(&json).unwrap()).unwrap();
}

fn times(n: usize, dt: f64) -> Vec<f64> {
    (0..=n).map(|k| k as f64 * dt).collect()
}

#[test]
fn icosahedron_under_a_load_reads_back_bit_for_bit() {
    // 20 N along x on node 4 (a force input) moves the structure and changes every tension.
    let frames = record("icosahedron", [20.0, 0.0, 0.0], &times(12, 0.05));
    let (t0, tn) = (&frames.tensions[0], frames.tensions.last().unwrap());
    assert!(t0.iter().all(|&t| t > 0.0), "prestressed: {t0:?}");
    assert!(
        t0.iter().zip(tn).any(|(a, b)| (a - b).abs() > 0.1),
        "the load acts"
    );
    let dir = out_dir();
    let pvd = dir.join("icosahedron.pvd");
    write_pvd(&frames, &pvd).unwrap();
    write_expected(&frames, &dir.join("icosahedron_expected.json"));
    assert!(dir.join("icosahedron_vtp").is_dir());
    check_series(&frames, &pvd);
}

#[test]
fn prism2_elastic_at_rest_reads_back_bit_for_bit() {
    let frames = record("prism2-elastic", [0.0; 3], &times(10, 0.1));
    assert_eq!(
        (frames.bars.len(), frames.cables.len(), frames.n_nodes()),
        (6, 15, 9)
    );
    assert!(!frames.pinned.is_empty());
    let dir = out_dir();
    let pvd = dir.join("prism2-elastic.pvd");
    write_pvd(&frames, &pvd).unwrap();
    write_expected(&frames, &dir.join("prism2-elastic_expected.json"));
    check_series(&frames, &pvd);
}

/// The names of the entries of `dir` (sorted).
fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    v.sort();
    v
}

#[test]
fn a_second_write_replaces_the_series_and_failures_leave_nothing() {
    let dir = out_dir().join("replace");
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    let pvd = dir.join("run.pvd");
    let long = record("prism2-elastic", [0.0; 3], &times(5, 0.1));
    write_pvd(&long, &pvd).unwrap();
    assert_eq!(entries(&dir.join("run_vtp")).len(), 6);

    // A shorter run replaces the whole series: no stale sixth file.
    let short = record("icosahedron", [5.0, 0.0, 0.0], &times(2, 0.1));
    write_pvd(&short, &pvd).unwrap();
    assert_eq!(
        entries(&dir.join("run_vtp")),
        ["run_0000.vtp", "run_0001.vtp", "run_0002.vtp"]
    );
    check_series(&short, &pvd);
    assert_eq!(entries(&dir), ["run.pvd", "run_vtp"], "no temporary left");

    // Inconsistent frames: refused before anything is written; the old series stays.
    let mut broken = long.clone();
    broken.tensions[3].pop();
    let err = write_pvd(&broken, &pvd).unwrap_err();
    assert!(err.contains("inconsistent frames"), "{err}");
    assert_eq!(entries(&dir), ["run.pvd", "run_vtp"]);
    check_series(&short, &pvd);

    // A folder of someone else's files is not replaced.
    fs::write(dir.join("run_vtp/notes.txt"), "mine").unwrap();
    let err = write_pvd(&long, &pvd).unwrap_err();
    assert!(
        err.contains("run_vtp") && err.contains("notes.txt"),
        "{err}"
    );
    assert!(dir.join("run_vtp/notes.txt").is_file());
    check_series(&short, &pvd);

    // Wrong extension, missing folder, unwritable folder: the path and the reason.
    let err = write_pvd(&long, &dir.join("run.vtk")).unwrap_err();
    assert!(err.contains("run.vtk") && err.contains(".pvd"), "{err}");
    let err = write_pvd(&long, &dir.join("nowhere/run.pvd")).unwrap_err();
    assert!(err.contains("nowhere"), "{err}");
    // Files under the temporaries' old predictable names are not in the way, and stay.
    let blocked = dir.join("blocked");
    fs::create_dir(&blocked).unwrap();
    let squatters = [
        format!(".x_vtp.tmp-{}", std::process::id()),
        format!(".x.pvd.tmp-{}", std::process::id()),
    ];
    for squatter in &squatters {
        fs::write(blocked.join(squatter), "not ours").unwrap();
    }
    write_pvd(&long, &blocked.join("x.pvd")).unwrap();
    check_series(&long, &blocked.join("x.pvd"));
    let mut expected = vec![squatters[1].clone(), squatters[0].clone()];
    expected.extend(["x.pvd".to_string(), "x_vtp".to_string()]);
    assert_eq!(entries(&blocked), expected);
}

/// The figures in docs/benchmarks.md: tower20, 10 s at 30 frames per second (301 files).
/// `cargo test --release --test render_vtk -- --nocapture tower20`
#[test]
fn tower20_ten_seconds_at_30_fps() {
    let times: Vec<f64> = (0..=300).map(|k| k as f64 / 30.0).collect();
    let frames = record("tower20", [5.0, 0.0, 0.0], &times);
    let dir = out_dir();
    let pvd = dir.join("tower20.pvd");
    let start = std::time::Instant::now();
    write_pvd(&frames, &pvd).unwrap();
    let seconds = start.elapsed().as_secs_f64();
    let vtp = entries(&dir.join("tower20_vtp"));
    assert_eq!(vtp.len(), 301);
    let sizes: Vec<u64> = vtp
        .iter()
        .map(|f| fs::metadata(dir.join("tower20_vtp").join(f)).unwrap().len())
        .collect();
    let total: u64 = sizes.iter().sum();
    println!(
        "tower20, 10 s at 30 fps: {} nodes, {} bars, {} cables; {} .vtp of {} bytes each, \
         {:.2} MB in all, .pvd {} bytes; written in {seconds:.3} s",
        frames.n_nodes(),
        frames.bars.len(),
        frames.cables.len(),
        vtp.len(),
        sizes[0],
        total as f64 / 1e6,
        fs::metadata(&pvd).unwrap().len(),
    );
    check_series(&frames, &pvd);
}

/// The terrain `.vtp`: its counts, and its cell and point arrays by name.
#[derive(Deserialize)]
struct TerrainVtp {
    #[serde(rename = "PolyData")]
    poly_data: TerrainData,
}

#[derive(Deserialize)]
struct TerrainData {
    #[serde(rename = "Piece")]
    piece: TerrainPiece,
}

#[derive(Deserialize)]
struct TerrainPiece {
    #[serde(rename = "@NumberOfPoints")]
    n_points: usize,
    #[serde(rename = "@NumberOfPolys")]
    n_polys: usize,
    #[serde(rename = "@NumberOfLines")]
    n_lines: usize,
    #[serde(rename = "CellData")]
    cell: Arrays,
    #[serde(rename = "Points")]
    points: Arrays,
    #[serde(rename = "Polys")]
    polys: Arrays,
}

#[test]
fn terrain_is_its_own_polydata_listed_as_part_1() {
    let mut scene = builtin("prism2").unwrap();
    for spec in [
        r#"kind = "box"
center = [1.0, 2.0, -0.5]
size = [2.0, 4.0, 1.0]
stiffness = 1e4"#,
        // 3 rows of 4 heights.
        r#"kind = "heightfield"
origin = [-1.0, -2.0]
spacing = [0.5, 0.25]
heights = [[0.0, 0.1, 0.2, 0.3], [1.0, 1.1, 1.2, 1.3], [2.0, 2.1, 2.2, 2.3]]
stiffness = 1e4"#,
    ] {
        scene.terrain.push(toml::from_str(spec).unwrap());
    }
    let frames = Frames::from_run(&scene, &[0.0, 0.1]).unwrap();
    let pvd = out_dir().join("terrain.pvd");
    write_pvd(&frames, &pvd).unwrap();
    // The run's files as without terrain, and the terrain beside them in the folder.
    check_series(&frames, &pvd);
    let collection = fs::read_to_string(&pvd).unwrap();
    for t in ["0", "0.1"] {
        assert!(collection.contains(&format!(
            "<DataSet timestep=\"{t}\" group=\"\" part=\"1\" file=\"terrain_vtp/terrain_terrain.vtp\"/>"
        )));
    }
    assert_eq!(collection.matches("part=\"0\"").count(), 2);
    let text = fs::read_to_string(out_dir().join("terrain_vtp/terrain_terrain.vtp")).unwrap();
    let piece = quick_xml::de::from_str::<TerrainVtp>(&text)
        .unwrap()
        .poly_data
        .piece;
    // 8 corners and 6 faces of the box, then 12 heights and 3 × 2 quads.
    assert_eq!((piece.n_points, piece.n_polys, piece.n_lines), (20, 12, 0));
    assert_eq!(i32s(array(&piece.cell, "kind")), [[1; 6], [2; 6]].concat());
    assert_eq!(i32s(array(&piece.cell, "shape")), [[1; 6], [2; 6]].concat());
    let points = f64s(&piece.points.arrays[0]);
    let corner = |i: usize| [points[3 * i], points[3 * i + 1], points[3 * i + 2]];
    assert_eq!(corner(0), [0.0, 0.0, -1.0]);
    assert_eq!(corner(7), [2.0, 4.0, 0.0]);
    assert_eq!(corner(8), [-1.0, -2.0, 0.0]);
    assert_eq!(corner(11), [0.5, -2.0, 0.3]);
    assert_eq!(corner(19), [0.5, -1.5, 2.3]);
    let offsets = u64s(array(&piece.polys, "offsets"));
    assert_eq!(offsets, (1..=12).map(|q| 4 * q).collect::<Vec<u64>>());
    let connectivity = u64s(array(&piece.polys, "connectivity"));
    // The box's top (+z) face, then the heightfield's first and last quads.
    assert_eq!(connectivity[4..8], [4, 5, 7, 6]);
    assert_eq!(connectivity[24..28], [8, 9, 13, 12]);
    assert_eq!(connectivity[44..48], [14, 15, 19, 18]);
}
