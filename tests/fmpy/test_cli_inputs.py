"""`tensegrity-fmu simulate --inputs FILE.csv` against fmpy running the built FMU with the
same input table (`fmpy.simulate_fmu(..., input=...)`): the CSV's rows must match fmpy's
results at the output times, for every input kind (node forces, a force-density cable, a
reeled rest-length cable), ramps (interpolated at the communication points, held over the
step) and steps (a time written twice, between two output times).

Expected values come from fmpy driving the FMU, never from the CLI itself.
"""

import csv
import subprocess

import numpy as np
import pytest
from fmpy import simulate_fmu

from effects_scenes import everything_scene, to_toml

STOP = 0.1
INTERVAL = 0.01
STEP = 0.00023  # does not divide the interval: the last internal step is shortened

# Ramps between rows off the output grid, a step at 0.023 (between two output times) and
# one at 0.06 (on an output time), rows before and after the run.
INPUT_CSV = """time,node[7].fx,node[8].fy,cable[14].force_density,cable[15].rest_length
-1,0,0,20,0.9
0.005,0,0,20,0.9
0.023,2.5,0,20,0.9
0.023,2.5,-3,35,0.9
0.047,-1,-3,35,0.85
0.06,-1,-3,35,0.85
0.06,4,1,10,0.8
0.2,4,1,10,0.8
"""


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    names, values = rows[0], np.array(rows[1:], dtype=float)
    return names, values


def structured(path):
    names, values = read_csv(path)
    return np.array([tuple(r) for r in values], dtype=[(n, np.double) for n in names])


@pytest.fixture(scope="module")
def case(cli, fmus, tmp_path_factory):
    root = tmp_path_factory.mktemp("cli_inputs")
    text = to_toml(everything_scene(fmus.builtin("prism2-elastic").scene))
    scene = root / "everything.toml"
    scene.write_text(text)
    inputs = root / "inputs.csv"
    inputs.write_text(INPUT_CSV)
    out = root / "cli.csv"
    plain = root / "plain.csv"
    common = [str(cli), "simulate", str(scene), "--time", str(STOP), "--interval", str(INTERVAL)]
    common += ["--step-size", str(STEP)]
    subprocess.run(common + ["--inputs", str(inputs), "-o", str(out)], check=True, capture_output=True)
    subprocess.run(common + ["-o", str(plain)], check=True, capture_output=True)
    fmu = fmus.from_toml(text)
    ref = simulate_fmu(
        str(fmu.path),
        stop_time=STOP,
        output_interval=INTERVAL,
        input=structured(inputs),
        start_values={"solver.step_size": STEP},
        output=fmu.outputs,
    )
    return read_csv(out), read_csv(plain), ref


def test_rows_are_at_the_output_times(case):
    (names, values), _, _ = case
    assert names[0] == "time"
    np.testing.assert_array_equal(values[:, 0], [k * INTERVAL for k in range(10)] + [STOP])


def test_cli_matches_fmpy_at_every_output_time(case):
    (names, values), _, ref = case
    # fmpy also records a row at each input step (0.023): pick its rows at our times.
    for row in values:
        t = row[0]
        hits = np.flatnonzero(np.isclose(ref["time"], t, rtol=1e-12, atol=1e-15))
        assert len(hits) == 1, f"fmpy has no single row at t = {t}: {ref['time']}"
        expected = ref[hits[0]]
        # Same communication points, input values and internal steps: the same doubles.
        for name, value in zip(names[1:], row[1:]):
            assert value == expected[name], (t, name, value, expected[name])


def test_the_inputs_act(case):
    (names, values), (plain_names, plain), _ = case
    assert names == plain_names
    moved = np.abs(values[:, 1:] - plain[:, 1:]).max(axis=0)
    # Node 7 is pushed along x, node 8 along y; cable 14's tension follows its input.
    for name in ["node[7].x", "node[8].y", "cable[14].tension", "cable[15].tension"]:
        assert moved[names.index(name) - 1] > 1e-4, name
    # At t = 0 the positions are the scene's, and cable 14 pulls with the table's 20 N/m.
    np.testing.assert_array_equal(values[0, 1:4], plain[0, 1:4])


def test_force_density_from_the_table_at_t0(case, fmus):
    (names, values), _, _ = case
    a, b = fmus.builtin("prism2-elastic").scene["cables"][13]["nodes"]
    pa = np.array([values[0, names.index(f"node[{a}].{c}")] for c in "xyz"])
    pb = np.array([values[0, names.index(f"node[{b}].{c}")] for c in "xyz"])
    tension = values[0, names.index("cable[14].tension")]
    assert tension == pytest.approx(20.0 * np.linalg.norm(pb - pa), rel=1e-12)

