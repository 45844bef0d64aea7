"""The ParaView time series of `render::vtk::write_pvd` read with VTK's own reader.

`cargo test --release --test render_vtk` (run once by the session fixture below) simulates
the built-in `icosahedron` (20 N on a force input) and `prism2-elastic` (at rest), writes
each as `target/render-test/NAME.pvd` + `NAME_vtp/NAME_kkkk.vtp`, and beside them
`NAME_expected.json`: times, positions, velocities, cable tensions and bar forces taken
straight from the simulation (`sim.cable_tension`, `sim.bar_force`, ...), not from the
files. Here the `.pvd` is parsed with xml.etree and every `.vtp` is read with
`vtkXMLPolyDataReader` (the `vtk` wheel, what ParaView itself uses; meshio 5.3.5 reads
`.vtu` but not `.vtp`). The arrays are written in VTK's inline binary format, so values
are compared for exact equality. Independently of the simulation's numbers, the
prestressed scenes at t = 0 must show what their files say: the smallest cable tension is
the scene's `min_tension` (10 N) and every free node is in equilibrium under the member
forces read from the file (tension positive, bars negative in compression).
"""

import json
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader

REPO = Path(__file__).resolve().parents[2]
OUT = REPO / "target" / "render-test"
SCENES = ["icosahedron", "prism2-elastic"]


@pytest.fixture(scope="session")
def series():
    """Writes the series with the Rust test (CI runs it before pytest anyway)."""
    subprocess.run(
        ["cargo", "test", "--release", "--test", "render_vtk"], cwd=REPO, check=True
    )
    return OUT


def expected(name):
    e = json.loads((OUT / f"{name}_expected.json").read_text())
    for key in ("positions", "velocities", "tensions", "bar_forces", "times"):
        e[key] = np.array(e[key], dtype=np.float64)
    return e


def read_pvd(path):
    root = ET.parse(path).getroot()
    assert root.tag == "VTKFile" and root.get("type") == "Collection"
    sets = root.findall("./Collection/DataSet")
    return [(float(d.get("timestep")), path.parent / d.get("file")) for d in sets]


def read_vtp(path):
    reader = vtkXMLPolyDataReader()
    reader.SetFileName(str(path))
    reader.Update()
    assert reader.GetErrorCode() == 0, path
    return reader.GetOutput()


def cell_array(pd, name):
    a = pd.GetCellData().GetArray(name)
    assert a is not None, name
    return vtk_to_numpy(a)


def point_array(pd, name):
    a = pd.GetPointData().GetArray(name)
    assert a is not None, name
    return vtk_to_numpy(a)


@pytest.mark.parametrize("name", SCENES)
def test_pvd_lists_every_time_and_file(series, name):
    e = expected(name)
    listed = read_pvd(series / f"{name}.pvd")
    assert len(listed) == len(e["times"]) > 1
    assert [t for t, _ in listed] == list(e["times"])
    for k, (_, file) in enumerate(listed):
        assert file == series / f"{name}_vtp" / f"{name}_{k:04d}.vtp"
        assert file.is_file()
    assert sorted(p.name for p in (series / f"{name}_vtp").iterdir()) == [
        f.name for _, f in listed
    ]


@pytest.mark.parametrize("name", SCENES)
def test_vtp_points_lines_and_arrays_equal_the_simulation(series, name):
    e = expected(name)
    n, bars, cables = e["n_nodes"], e["bars"], e["cables"]
    nb, nc = len(bars), len(cables)
    for k, (t, file) in enumerate(read_pvd(series / f"{name}.pvd")):
        pd = read_vtp(file)
        assert pd.GetNumberOfPoints() == n
        assert pd.GetNumberOfLines() == nb + nc
        assert pd.GetNumberOfPolys() == pd.GetNumberOfVerts() == 0
        points = vtk_to_numpy(pd.GetPoints().GetData())
        assert points.dtype == np.float64
        np.testing.assert_array_equal(points, e["positions"][k])

        lines = pd.GetLines()
        offsets = vtk_to_numpy(lines.GetOffsetsArray())
        np.testing.assert_array_equal(offsets, 2 * np.arange(nb + nc + 1))
        connectivity = vtk_to_numpy(lines.GetConnectivityArray()).reshape(-1, 2)
        np.testing.assert_array_equal(connectivity, np.array(bars + cables))

        np.testing.assert_array_equal(cell_array(pd, "kind"), [0] * nb + [1] * nc)
        number = list(range(1, nb + 1)) + list(range(1, nc + 1))
        np.testing.assert_array_equal(cell_array(pd, "number"), number)
        tension = cell_array(pd, "tension")
        assert tension.dtype == np.float64
        np.testing.assert_array_equal(tension[nb:], e["tensions"][k])
        np.testing.assert_array_equal(tension[:nb], -e["bar_forces"][k])
        assert pd.GetCellData().GetScalars().GetName() == "tension"

        velocity = point_array(pd, "velocity")
        assert velocity.shape == (n, 3)
        np.testing.assert_array_equal(velocity, e["velocities"][k])
        np.testing.assert_array_equal(point_array(pd, "node"), np.arange(1, n + 1))
        pinned = np.zeros(n, dtype=int)
        pinned[e["pinned"]] = 1
        np.testing.assert_array_equal(point_array(pd, "pinned"), pinned)


@pytest.mark.parametrize("name", SCENES)
def test_first_frame_is_the_prestressed_equilibrium(series, name):
    """From the file alone: min cable tension 10 N and every free node balanced."""
    _, first = read_pvd(series / f"{name}.pvd")[0]
    pd = read_vtp(first)
    x = vtk_to_numpy(pd.GetPoints().GetData())
    ends = vtk_to_numpy(pd.GetLines().GetConnectivityArray()).reshape(-1, 2)
    tension = cell_array(pd, "tension")
    kind = cell_array(pd, "kind")
    assert tension[kind == 1].min() == pytest.approx(10.0, rel=1e-12)
    assert (tension[kind == 0] < 0).all(), "bars are compressed"
    force = np.zeros_like(x)
    for (i, j), s in zip(ends, tension):
        u = (x[j] - x[i]) / np.linalg.norm(x[j] - x[i])
        force[i] += s * u
        force[j] -= s * u
    free = point_array(pd, "pinned") == 0
    assert free.sum() > 0
    assert np.abs(force[free]).max() <= 1e-10 * np.abs(tension).max()


def test_render_from_a_simulate_csv_carries_the_csv_tensions_and_positions(tmp_path):
    """`render --csv` of a `simulate` run: every .vtp holds exactly the CSV's values (the
    CSV's shortest round-trip decimals read back to the same doubles)."""
    cli = REPO / "target" / "release" / "tensegrity-fmu"
    csv_path = tmp_path / "ico.csv"
    subprocess.run(
        [str(cli), "simulate", "icosahedron", "--time", "0.5", "--interval", "0.1", "-o", str(csv_path)],
        check=True, capture_output=True,
    )
    pvd = tmp_path / "ico.pvd"
    subprocess.run(
        [str(cli), "render", "icosahedron", "--csv", str(csv_path), "--fps", "10", "-o", str(pvd)],
        check=True, capture_output=True,
    )
    header = csv_path.read_text().splitlines()[0].replace('"', "").split(",")
    rows = np.loadtxt(csv_path, delimiter=",", skiprows=1)
    col = {n: k for k, n in enumerate(header)}
    cables = sorted(int(n[6:-9]) for n in header if n.startswith("cable[") and n.endswith("].tension"))
    nodes = sorted({int(n[5 : n.index("]")]) for n in header if n.startswith("node[") and n.endswith("].x")})
    listed = read_pvd(pvd)
    assert [t for t, _ in listed] == list(rows[:, 0])  # 0, 0.1, ..., 0.5
    for (t, vtp), row in zip(listed, rows):
        pd = read_vtp(vtp)
        kind, number, tension = (cell_array(pd, a) for a in ("kind", "number", "tension"))
        assert pd.GetNumberOfPoints() == len(nodes) == 12
        assert pd.GetNumberOfLines() == 6 + len(cables) == 30
        file_tensions = dict(zip(number[kind == 1], tension[kind == 1]))
        assert [file_tensions[j] for j in cables] == [row[col[f"cable[{j}].tension"]] for j in cables]
        points = vtk_to_numpy(pd.GetPoints().GetData())
        csv_points = np.array([[row[col[f"node[{i}].{c}"]] for c in "xyz"] for i in nodes])
        assert np.array_equal(points, csv_points)
