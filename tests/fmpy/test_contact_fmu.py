"""Terrain contact and bar–bar collisions through the FMU (the fmpy twin of tests/terrain.rs
and tests/collisions.rs).

1. The icosahedron dropped onto a box step runs in the FMU as in the CLI's `simulate`.
2. A bar across two boxes, with the boxes' stiffness set as an FMU parameter, rests at the
   depth that stiffness gives (box top + radius − m g / (4 k)).
3. Two crossed bars rest on each other at the depth `collisions.stiffness` gives.
4. The FMU state, saved while bars touch the terrain and each other, restores to the same
   bits, in the same instance and, serialized, in another.

Expected values come from statics and from uninterrupted runs, never from recorded outputs.
"""

import subprocess
from pathlib import Path

import numpy as np
import pytest

from conftest import RK4

REPO = Path(__file__).resolve().parents[2]
G = 9.81

BAR_ON_BOXES = """name = "bar_on_boxes"
nodes = [[-1.0, 0.0, 0.6], [1.0, 0.0, 0.6]]
bars = [{ nodes = [1, 2], mass = 2.0, radius = 0.05 }]
gravity = [0.0, 0.0, -9.81]
[[terrain]]
kind = "box"
center = [-0.6, 0.0, 0.25]
size = [0.4, 1.0, 0.5]
stiffness = 1e5
damping = 400.0
friction = 0.5
[[terrain]]
kind = "box"
center = [0.6, 0.0, 0.25]
size = [0.4, 1.0, 0.5]
stiffness = 1e5
damping = 400.0
friction = 0.5
"""

# A pinned bar along x, and a free one leaning on it with its far end (past its centre of
# mass) on the plane under both.
CROSSED = """name = "crossed"
nodes = [[-1.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, -0.3, 0.2057142857142857], [0.0, 0.7, 0.02]]
fixed = [1, 2]
bars = [{ nodes = [1, 2], mass = 1.0, radius = 0.03 }, { nodes = [3, 4], mass = 1.5, radius = 0.02 }]
gravity = [0.0, 0.0, -9.81]
collisions = { stiffness = 2e5, damping = 300.0, friction = 0.5 }
[[terrain]]
kind = "plane"
point = [0.0, 0.0, 0.0]
stiffness = 1e5
damping = 300.0
friction = 0.5
"""


def test_the_step_scene_runs_in_the_fmu_as_in_simulate(fmus, open_fmu, cli, tmp_path):
    fmu = fmus.from_toml((REPO / "fmu" / "scenes" / "icosahedron-step.toml").read_text())
    # rk4 at a fixed 0.1 ms, in the FMU and on the command line.
    s = open_fmu(fmu).init(integers=RK4, params={"solver.step_size": 1e-4})
    rows = [s.outputs()]
    for k in range(60):
        s.fmu.doStep(0.01 * k, 0.01)
        rows.append(s.outputs())
    rows = np.array(rows)
    touched = rows[:, fmu.outputs.index("terrain[2].contacts")]
    assert touched.max() >= 1, "it lands on the step"
    out = tmp_path / "step.csv"
    subprocess.run(
        [str(cli), "simulate", str(Path(fmu.dir, "resources", "scene.toml")), "--time", "0.6",
         "--interval", "0.01", "--method", "rk4", "--step-size", "1e-4", "-o", str(out)],
        check=True, capture_output=True,
    )
    csv = np.genfromtxt(out, delimiter=",", names=True, deletechars="", dtype=float)
    assert len(csv) == len(rows)
    for i, name in enumerate(fmu.outputs):
        scale = max(1.0, np.max(np.abs(csv[name])))
        assert np.max(np.abs(rows[:, i] - csv[name])) <= 1e-12 * scale, name


def test_box_stiffness_set_as_a_parameter_sets_the_resting_depth(fmus, open_fmu):
    fmu = fmus.from_toml(BAR_ON_BOXES)
    assert fmu.variables["terrain[1].stiffness"].unit == "N/m"
    assert fmu.variables["terrain[2].contacts"].unit == "1"
    assert fmu.variables["bar[1].radius"].start == "0.05"
    k = 4e5
    s = open_fmu(fmu).init(params={"terrain[1].stiffness": k, "terrain[2].stiffness": k})
    s.run(300, 0.01)
    z = s.get(["node[1].z", "node[2].z"])
    expected = 0.5 + 0.05 - 2.0 * G / (4 * k)
    print(f"resting z {z} vs {expected}")
    assert np.max(np.abs(z - expected)) <= 1e-7
    assert s.get(["terrain[1].contacts", "terrain[2].contacts"]).tolist() == [2.0, 2.0]
    assert s.get(["terrain[1].force_z"])[0] == pytest.approx(G, rel=1e-6)


def test_crossed_bars_rest_at_the_depth_the_collision_stiffness_gives(fmus, open_fmu):
    text = CROSSED.replace("[0.0, -0.3, 0.2057142857142857], [0.0, 0.7, 0.02]", "[0.0, -0.5, 0.15], [0.0, 0.5, 0.15]").replace(
        "[[terrain]]\nkind = \"plane\"\npoint = [0.0, 0.0, 0.0]", "[[terrain]]\nkind = \"plane\"\npoint = [0.0, 0.0, -5.0]"
    )
    fmu = fmus.from_toml(text)
    k = 5e5
    s = open_fmu(fmu).init(params={"collisions.stiffness": k})
    s.run(200, 0.01)
    z = s.get(["node[3].z", "node[4].z"])
    expected = 0.1 + 0.05 - 1.5 * G / k
    print(f"resting z {z} vs {expected}")
    assert np.max(np.abs(z - expected)) <= 1e-8
    assert s.get(["collisions.contacts"])[0] == 1.0
    assert s.get(["collisions.max_penetration"])[0] == pytest.approx(1.5 * G / k, rel=1e-6)


def test_state_saved_while_touching_restores_bit_identically(fmus, open_fmu):
    fmu = fmus.from_toml(CROSSED)
    # A fixed step, so that the runs' communication points need not be the same floats.
    fixed = dict(integers=RK4, params={"solver.step_size": 1e-4})
    s = open_fmu(fmu).init(**fixed)
    s.run(25, 0.01)
    touching = s.get(["collisions.contacts", "terrain[1].contacts"])
    assert touching[0] >= 1 and touching[1] >= 1, touching
    state = s.fmu.getFMUstate()
    blob = s.fmu.serializeFMUstate(state)
    s.run(25, 0.01)
    first = s.outputs()
    s.fmu.setFMUstate(state)
    s.time = 0.25
    s.run(25, 0.01)
    assert np.array_equal(s.outputs(), first)
    other = open_fmu(fmu, name="other").init(**fixed)
    other.fmu.setFMUstate(other.fmu.deSerializeFMUstate(blob))
    other.time = 0.25
    other.run(25, 0.01)
    assert np.array_equal(other.outputs(), first)
    reference = open_fmu(fmu, name="reference").init(**fixed)
    reference.run(50, 0.01)
    assert np.array_equal(reference.outputs(), first)
