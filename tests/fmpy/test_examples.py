"""fmu/examples/{simulate,controller,lqr_controller}.py on every built-in scene, plus the shipped
icosahedron-dropped (no inputs at all) and an icosahedron with force-density cables.

Each example runs as a user runs it (a subprocess with the FMU's path). Expected values come
from fmpy run independently, from the scene packaged in the FMU, or from physics; user
mistakes must give one line on stderr and exit status 2.
"""

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from fmpy import simulate_fmu

from conftest import BUILTINS, REPO

EXAMPLES = REPO / "fmu" / "examples"
SCENES = BUILTINS + ["icosahedron-dropped"]
NO_INPUTS = "icosahedron-dropped"  # the shipped scene file without force inputs or densities
FLOAT = r"[-+]?\d+\.\d+(?:e[-+]\d+)?"


def run_example(name, *args, timeout=300):
    return subprocess.run([sys.executable, str(EXAMPLES / name), *map(str, args)],
                          capture_output=True, text=True, timeout=timeout)


def one_line_error(res, *words):
    """Exit status 2, one line on stderr naming `words`, no traceback."""
    assert res.returncode == 2, (res.returncode, res.stdout, res.stderr)
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1, res.stderr
    assert "Traceback" not in res.stderr
    for word in words:
        assert word in lines[0], lines[0]
    return lines[0]


@pytest.fixture(scope="module")
def scene_fmus(fmus):
    built = {name: fmus.builtin(name) for name in BUILTINS}
    built[NO_INPUTS] = fmus.from_toml((REPO / "fmu" / "scenes" / f"{NO_INPUTS}.toml").read_text())
    return built


@pytest.fixture(scope="module")
def icosahedron_fd(fmus):
    """The built-in icosahedron with every cable force-density controlled."""
    text = (REPO / "fmu" / "scenes" / "icosahedron.toml").read_text()
    text, n = re.subn(r"^stiffness = 500\.0$", 'control = "force_density"', text, flags=re.M)
    assert n == 24
    return fmus.from_toml(text.replace('name = "icosahedron"', 'name = "icosahedron-fd"', 1))


def first_loaded_node(fmu):
    return fmu.scene.get("force_inputs", [None])[0] if fmu.scene.get("force_inputs") else None


# ---------------------------------------------------------------- simulate.py


@pytest.mark.parametrize("scene", SCENES)
def test_simulate_prints_the_final_state_that_fmpy_computes(scene, scene_fmus, tmp_path):
    fmu = scene_fmus[scene]
    loaded = first_loaded_node(fmu)
    inputs = {f"node[{loaded}].fx": 2.0} if loaded else {}
    png = tmp_path / f"{scene}.png"
    args = [fmu.path, "--stop-time", 0.5, "--plot", png]
    args += [f"--input={k}={v}" for k, v in inputs.items()]
    res = run_example("simulate.py", *args)
    assert res.returncode == 0, res.stderr
    out = res.stdout

    # The same run, read independently with fmpy.
    n_nodes = len(fmu.scene["nodes"])
    names = [f"node[{i}].{a}" for i in range(1, n_nodes + 1) for a in "xyz"]
    cables = [f"cable[{k}].tension" for k in range(1, len(fmu.scene["cables"]) + 1)]
    ref = simulate_fmu(str(fmu.path), stop_time=0.5, start_values=inputs,
                       output=names + cables + ["constraint.length_error"])
    final = np.array([ref[n][-1] for n in names]).reshape(n_nodes, 3)
    start = np.array(fmu.scene["nodes"], dtype=float)
    moved = np.linalg.norm(final - start, axis=1)

    rows = re.findall(rf"^  node\[(\d+)\]\s+({FLOAT})\s+({FLOAT})\s+({FLOAT})\s+({FLOAT})$",
                      out, flags=re.M)
    shown = [int(r[0]) for r in rows]
    if n_nodes <= 12:
        assert shown == list(range(1, n_nodes + 1))
    else:  # the 12 nodes that moved most, in node order
        assert shown == sorted(int(i) + 1 for i in np.argsort(-moved)[:12])
        assert f"the 12 of {n_nodes} nodes that moved most" in out
    for r in rows:
        i = int(r[0]) - 1
        assert np.allclose([float(v) for v in r[1:4]], final[i], atol=1.5e-6), r
        assert float(r[4]) == pytest.approx(moved[i], abs=1.5e-6)
    assert moved.max() > 1e-3  # the load (or gravity) moved something

    tensions = np.array([ref[c][-1] for c in cables])
    m = re.search(rf"min ({FLOAT}) \(cable\[(\d+)\]\), max ({FLOAT}) \(cable\[(\d+)\]\)", out)
    assert m, out
    assert float(m.group(1)) == pytest.approx(tensions.min(), abs=1e-4)
    assert float(m.group(3)) == pytest.approx(tensions.max(), abs=1e-4)
    assert tensions[int(m.group(2)) - 1] == tensions.min()
    assert tensions[int(m.group(4)) - 1] == tensions.max()

    residual = re.search(r"constraint\.length_error: largest (\S+) over the run", out)
    assert float(residual.group(1)) == pytest.approx(np.abs(ref["constraint.length_error"]).max(),
                                                     rel=1e-3, abs=1e-18)
    assert float(residual.group(1)) < 1e-9  # bar lengths held to rounding

    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 20_000


def test_simulate_rejects_an_unknown_input_and_a_bad_stop_time(scene_fmus):
    fmu = scene_fmus["tower20"]
    one_line_error(run_example("simulate.py", fmu.path, "--input", "node[7].fx=1"),
                   "node[7].fx", "not an input of tower20", "node[61].fx")
    one_line_error(run_example("simulate.py", fmu.path, "--input", "node[61].fx"), "NAME=VALUE")
    one_line_error(run_example("simulate.py", fmu.path, "--stop-time", "-1"), "--stop-time")


def test_simulate_passes_on_what_the_fmu_refuses_in_one_line(scene_fmus, tmp_path):
    """A value the FMU refuses, and a picture format matplotlib can't write: the reason on one
    line (the FMU's log goes to stdout), exit status 1, no traceback."""
    fmu = scene_fmus["prism2"]
    res = run_example("simulate.py", fmu.path, "--input", "cable[1].force_density=nan")
    assert res.returncode == 1 and "Traceback" not in res.stderr, res.stderr
    assert res.stderr.strip().splitlines()[-1] == "simulate.py: error: fmi2SetReal failed with status 3 (error)."
    assert "cable[1].force_density = NaN is not a finite number" in res.stdout  # the FMU's log
    res = run_example("simulate.py", fmu.path, "--plot", tmp_path / "run.xyz")
    assert res.returncode == 1 and "Traceback" not in res.stderr, res.stderr
    assert res.stderr.strip().splitlines() == [res.stderr.strip()]
    assert "Format 'xyz' is not supported" in res.stderr
    assert not (tmp_path / "run.xyz").exists()


# ---------------------------------------------------------------- controller.py


@pytest.mark.parametrize("scene", BUILTINS)
def test_controller_brings_its_coordinate_to_the_target(scene, scene_fmus):
    fmu = scene_fmus[scene]
    res = run_example("controller.py", fmu.path, "--stop-time", 2)
    assert res.returncode == 0, res.stderr
    lines = res.stdout.strip().splitlines()
    nodes = np.array(fmu.scene["nodes"], dtype=float)
    density = [k + 1 for k, c in enumerate(fmu.scene["cables"])
               if c.get("control") == "force_density"]
    if density:  # prism2: the length of a force-density cable, 2 % shorter
        m = re.match(r"controlling cable\[(\d+)\] length \(nodes (\d+)-(\d+)\) with "
                     r"cable\[(\d+)\]\.force_density$", lines[0])
        assert m and m.group(1) == m.group(4) and int(m.group(1)) in density, lines[0]
        a, b = fmu.scene["cables"][int(m.group(1)) - 1]["nodes"]
        assert (a, b) == (int(m.group(2)), int(m.group(3)))
        start = np.linalg.norm(nodes[b - 1] - nodes[a - 1])
        target = 0.98 * start
    else:  # the first loaded node's x, 2 cm further
        node = fmu.scene["force_inputs"][0]
        assert lines[0] == f"controlling node[{node}].x with node[{node}].fx"
        start = nodes[node - 1][0]
        target = start + 0.02
    table = np.array([[float(v) for v in line.split()] for line in lines[2:-1]])
    assert table.shape == (21, 4)
    assert np.allclose(table[:, 0], np.arange(21) * 0.1)
    assert table[0, 1] == pytest.approx(start, abs=1e-6)
    assert np.allclose(table[:, 2], target, atol=1e-6)
    error = np.abs(table[:, 1] - target)
    # Over the second second within a few tenths of the start error, at the end within a tenth.
    assert error[10:].max() < 0.3 * error[0] and error[10:].mean() < 0.15 * error[0], error
    assert error[-1] < 0.1 * error[0], error
    if density:
        assert table[:, 3].min() >= 0.0  # a force density never pushes
    m = re.search(rf"({FLOAT}) from the target at the start, ({FLOAT}) at 2 s$", lines[-1])
    assert float(m.group(1)) == pytest.approx(error[0], abs=1e-6)
    assert float(m.group(2)) == pytest.approx(error[-1], abs=1e-6)


def test_controller_on_an_fmu_without_inputs_says_so(scene_fmus):
    fmu = scene_fmus[NO_INPUTS]
    assert not [v for v in fmu.md.modelVariables if v.causality == "input"]
    one_line_error(run_example("controller.py", fmu.path), "has no inputs to control",
                   "force_density", "force_inputs")


# ---------------------------------------------------------------- lqr_controller.py


@pytest.mark.parametrize("scene", SCENES)
def test_lqr_runs_where_there_are_force_densities_and_explains_elsewhere(scene, scene_fmus, cli):
    fmu = scene_fmus[scene]
    has_density = any(n.endswith(".force_density") for n in fmu.vr)
    res = run_example("lqr_controller.py", fmu.path, "--cli", cli, "--stop", 2)
    if not has_density:
        one_line_error(res, "no force-density inputs", "cable[K].force_density")
        return
    assert res.returncode == 0, res.stderr
    n_density = sum(c.get("control") == "force_density" for c in fmu.scene["cables"])
    assert f"LQR on {n_density} force densities" in res.stdout


def lqr_excursion(fmu, cli, law):
    res = run_example("lqr_controller.py", fmu.path, "--cli", cli, "--stop", 8, "--law", law)
    assert res.returncode == 0, res.stderr
    rows = re.findall(rf"^\s*(\d+\.\d+)\s+{FLOAT}\s+{FLOAT}\s+{FLOAT}\s+({FLOAT})\s", res.stdout,
                      flags=re.M)
    return res.stdout, np.array([[float(t), float(d)] for t, d in rows])


def test_lqr_designs_on_another_structures_force_densities(icosahedron_fd, cli):
    """24 force densities of an icosahedron: the pulse on node 4 is absorbed within seconds,
    while with held inputs the structure keeps moving by centimetres."""
    out, rows = lqr_excursion(icosahedron_fd, cli, "lqr")
    assert "LQR on 24 force densities" in out
    rate = float(re.search(rf"decay rate ({FLOAT}) 1/s", out).group(1))
    assert rate > 0.1  # asymptotically stable closed loop
    assert np.allclose(rows[:, 0], np.arange(9))
    peak = rows[:, 1].max()
    assert 1.0 < peak < 100.0, rows  # mm: the 0.5 N s pulse moved node 4, boundedly
    assert rows[-1, 1] < 0.01 * peak, rows  # and the feedback brought it back
    assert float(re.search(rf"smallest force density commanded: ({FLOAT})", out).group(1)) > 0
    _, held = lqr_excursion(icosahedron_fd, cli, "none")
    assert held[-3:, 1].min() > 10.0, held  # mm, without feedback


# ---------------------------------------------------------------- user mistakes


@pytest.mark.parametrize("example", ["simulate.py", "controller.py", "lqr_controller.py"])
def test_user_mistakes_get_one_line(example, tmp_path):
    missing = tmp_path / "missing.fmu"
    one_line_error(run_example(example, missing), str(missing), "no such file")
    text = tmp_path / "notes.fmu"
    text.write_text("not a zip\n")
    one_line_error(run_example(example, text), "is not an FMU")
    one_line_error(run_example(example, missing, "--no-such-option"), "--no-such-option")
    one_line_error(run_example(example), "fmu")  # the FMU argument is required
    assert run_example(example, "--help").returncode == 0
