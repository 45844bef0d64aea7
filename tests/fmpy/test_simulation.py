"""fmpy as a co-simulation master, and the dynamics seen through the FMU's variables (issue 3)."""

import subprocess

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.fmi1 import FMICallException

from conftest import RK4

from conftest import cable_length

POSITIONS = lambda fmu: [n for n in fmu.outputs if n.startswith("node[") and n[-2] == "."]  # noqa: E731


def constant_input(stop, **values):
    """A structured array holding each input constant from 0 to `stop`."""
    dtype = [("time", np.float64)] + [(name, np.float64) for name in values]
    return np.array([(0.0, *values.values()), (stop, *values.values())], dtype=dtype)


def with_velocities(scene_text, velocities):
    """The scene with initial node velocities (the CLI's `simulate` then has something to do)."""
    rows = ", ".join("[" + ", ".join(repr(float(c)) for c in v) + "]" for v in velocities)
    head, sep, tail = scene_text.partition("\n[[bars]]")
    return f'{head}\nvelocities = [{rows}]\n{sep.lstrip(chr(10))}{tail}'.replace(
        'name = "', 'name = "moving-', 1
    )


def test_simulate_fmu_default_experiment_holds_at_rest(fmus):
    fmu = fmus.builtin("prism2")
    res = simulate_fmu(str(fmu.path))
    de = fmu.md.defaultExperiment
    assert res["time"][0] == float(de.startTime)
    assert res["time"][-1] == pytest.approx(float(de.stopTime))
    assert len(res) > 100
    for name in POSITIONS(fmu):
        assert np.max(np.abs(res[name] - res[name][0])) <= 1e-10, name
    # the prestress: every cable is in tension, the smallest at the scene's min_tension
    tensions = np.array([res[f"cable[{j}].tension"][0] for j in range(1, 16)])
    assert tensions.min() == pytest.approx(fmu.scene["prestress"]["min_tension"], rel=1e-9)


def test_force_density_start_values_give_the_initial_tensions(fmus, open_fmu):
    fmu = fmus.builtin("prism2")
    s = open_fmu(fmu).init()
    for j, cable in enumerate(fmu.scene["cables"], start=1):
        assert cable["control"] == "force_density"
        start = float(fmu.variables[f"cable[{j}].force_density"].start)
        assert s.get([f"cable[{j}].force_density"])[0] == start
        # tension = force density x length, the length from the scene's start geometry
        a, b = (np.array(fmu.scene["nodes"][n - 1]) for n in cable["nodes"])
        assert s.get([f"cable[{j}].tension"])[0] == pytest.approx(start * np.linalg.norm(b - a), rel=1e-12)


def run_cli_csv(cli, scene, stop, tmp_path, interval):
    out = tmp_path / "cli.csv"
    subprocess.run(
        [str(cli), "simulate", scene, "--time", str(stop), "--interval", repr(interval), "-o", str(out)],
        check=True,
        capture_output=True,
    )
    return np.genfromtxt(out, delimiter=",", names=True, deletechars="", dtype=float)


@pytest.mark.parametrize("scene", ["prism2", "tower20", "moving-prism2-elastic"])
def test_simulate_fmu_reproduces_cli_simulate_csv(fmus, cli, tmp_path, scene):
    if scene.startswith("moving-"):
        base = fmus.builtin("prism2-elastic")
        n = len(base.scene["nodes"])
        v = [[0.0, 0.0, 0.0]] * 3 + [[0.01 * (i % 3), -0.02, 0.005 * i] for i in range(3, n)]
        text = with_velocities(base.scene_text, v)
        fmu = fmus.from_toml(text)
        path = tmp_path / "moving.toml"
        path.write_text(text)
        scene_arg, stop = str(path), 0.5
    else:
        fmu, scene_arg, stop = fmus.builtin(scene), scene, 1.0
    step = float(fmu.md.defaultExperiment.stepSize)
    csv = run_cli_csv(cli, scene_arg, stop, tmp_path, step)
    res = simulate_fmu(str(fmu.path), stop_time=stop, output_interval=step)
    assert len(res) == len(csv)
    assert np.max(np.abs(res["time"] - csv["time"])) <= 1e-12
    moved = 0.0
    for name in fmu.outputs:
        assert np.max(np.abs(res[name] - csv[name])) <= 1e-12 * max(1.0, np.max(np.abs(csv[name]))), name
        moved = max(moved, np.ptp(csv[name]))
    if scene.startswith("moving-"):
        assert moved > 1e-3  # the comparison was not between two structures at rest


def test_constant_force_input_moves_node_and_keeps_lengths(fmus):
    fmu = fmus.builtin("prism2-elastic")
    res = simulate_fmu(
        str(fmu.path),
        stop_time=1.0,
        output_interval=0.01,
        input=constant_input(1.0, **{"node[7].fx": 5.0}),
    )
    dx = res["node[7].x"] - res["node[7].x"][0]
    assert np.max(np.abs(dx)) > 1e-3
    assert dx[5] > 0  # early on the node follows the force
    assert np.max(res["constraint.length_error"]) <= 1e-12
    assert np.max(res["constraint.orthogonality_error"]) <= 1e-9


def test_constraints_hold_over_10s_and_drift_without_correction(fmus):
    fmu = fmus.builtin("prism2-elastic")
    force = constant_input(10.0, **{"node[7].fx": 5.0, "node[8].fz": -3.0})
    common = dict(stop_time=10.0, output_interval=0.05, input=force)
    on = simulate_fmu(str(fmu.path), **common)
    off = simulate_fmu(str(fmu.path), start_values={"solver.correction": False}, **common)
    assert np.max(on["constraint.length_error"]) <= 1e-12
    assert np.max(on["constraint.orthogonality_error"]) <= 1e-9
    assert off["constraint.length_error"][-1] > 1e-10
    assert off["constraint.length_error"][-1] > 100 * max(on["constraint.length_error"][-1], 1e-15)


def test_raising_one_force_density_shortens_that_cable(fmus, open_fmu):
    fmu = fmus.builtin("prism2")
    name = "cable[7].force_density"
    start = float(fmu.variables[name].start)
    assert start > 0
    base = open_fmu(fmu, name="base").init()
    raised = open_fmu(fmu, name="raised").init(inputs={name: 1.5 * start})
    l0 = cable_length(base, fmu.scene, 7)
    base.run(200, 0.001)
    raised.run(200, 0.001)
    assert cable_length(base, fmu.scene, 7) == pytest.approx(l0, abs=1e-9)
    assert cable_length(raised, fmu.scene, 7) < l0 - 1e-4
    # the tension output is force density times the length from the node outputs
    t = raised.get(["cable[7].tension"])[0]
    assert t == pytest.approx(1.5 * start * cable_length(raised, fmu.scene, 7), rel=1e-12)


@pytest.mark.parametrize("axis, sign", [("x", 1.0), ("y", -1.0), ("z", 1.0)])
def test_external_force_moves_top_node_in_its_direction(fmus, open_fmu, axis, sign):
    fmu = fmus.builtin("prism2")
    node = fmu.scene["force_inputs"][1]
    coords = [f"node[{node}].{c}" for c in "xyz"]
    base = open_fmu(fmu, name="base").init()
    pushed = open_fmu(fmu, name="pushed").init(inputs={f"node[{node}].f{axis}": sign * 10.0})
    base.run(50, 0.001)
    pushed.run(50, 0.001)
    d = pushed.get(coords) - base.get(coords)
    direction = np.array([c == axis for c in "xyz"], float) * sign
    assert d @ direction > 1e-4
    assert d @ direction > 0.5 * np.linalg.norm(d)


# --- parameters ----------------------------------------------------------------------


def test_bar_mass_set_in_initialization_changes_dynamics(fmus, open_fmu):
    fmu = fmus.builtin("prism2")
    force = {"node[7].fx": 10.0}
    default = open_fmu(fmu, name="default").init(inputs=force)
    same = open_fmu(fmu, name="same").init(params={"bar[4].mass": 1.0}, inputs=force)
    heavy = open_fmu(fmu, name="heavy").init(params={"bar[4].mass": 4.0}, inputs=force)
    assert heavy.get(["bar[4].mass"])[0] == 4.0
    for s in (default, same, heavy):
        s.run(30, 0.001)
    pos = POSITIONS(fmu)
    assert np.array_equal(same.get(pos), default.get(pos))  # rebuilt model, same values
    # node 7 sits on bar 4: four times the mass, less displacement under the same force
    x0 = fmu.scene["nodes"][6][0]
    assert 0 < heavy.get(["node[7].x"])[0] - x0 < default.get(["node[7].x"])[0] - x0


def test_cable_stiffness_set_in_initialization_scales_tension(fmus, open_fmu):
    fmu = fmus.builtin("prism2-elastic")
    k = float(fmu.variables["cable[7].stiffness"].start)
    default = open_fmu(fmu, name="default").init()
    stiff = open_fmu(fmu, name="stiff").init(params={"cable[7].stiffness": 2 * k})
    t0 = default.get(["cable[7].tension"])[0]
    # same geometry and rest length: tension = stiffness * (length - rest length)
    assert stiff.get(["cable[7].tension"])[0] == pytest.approx(2 * t0, rel=1e-12)
    default.run(100, 0.001)
    stiff.run(100, 0.001)
    pos = POSITIONS(fmu)
    assert np.max(np.abs(default.get(pos) - np.array([c for n in fmu.scene["nodes"] for c in n]))) < 1e-10
    assert np.max(np.abs(stiff.get(pos) - default.get(pos))) > 1e-4


@pytest.mark.parametrize(
    "scene, name, bad",
    [
        ("prism2", "bar[1].mass", -1.0),
        ("prism2", "bar[2].mass", 0.0),
        ("prism2-elastic", "cable[7].stiffness", -500.0),
        ("prism2", "solver.step_size", -0.001),
    ],
)
def test_invalid_parameter_is_an_error_and_reset_recovers(fmus, open_fmu, scene, name, bad):
    fmu = fmus.builtin(scene)
    s = open_fmu(fmu)
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.enterInitializationMode()
    with pytest.raises(FMICallException):
        s.set({name: bad})
    assert any(name in m for m in s.errors())
    assert s.get([name])[0] == float(fmu.variables[name].start)
    # refused, so nothing changed: initialization goes on with the start value
    s.fmu.exitInitializationMode()
    s.run(5, 0.001)
    plain = open_fmu(fmu, name="plain").init()
    plain.run(5, 0.001)
    assert np.array_equal(s.outputs(), plain.outputs())
    s.fmu.reset()
    s.init(inputs={"node[7].fx": 1.0})
    s.run(20, 0.001)
    ref = open_fmu(fmu, name="ref").init(inputs={"node[7].fx": 1.0})
    ref.run(20, 0.001)
    assert np.array_equal(s.outputs(), ref.outputs())


def test_correction_parameter_false_gives_larger_length_error(fmus, open_fmu):
    fmu = fmus.builtin("prism2-elastic")
    force = {"node[7].fx": 5.0, "node[9].fy": -4.0}
    on = open_fmu(fmu, name="on").init(inputs=force)
    off = open_fmu(fmu, name="off").init(booleans={"solver.correction": False}, inputs=force)
    assert off.fmu.getBoolean(off.vrs(["solver.correction"])) == [0]
    on.run(1000, 0.01)
    off.run(1000, 0.01)
    e_on = on.get(["constraint.length_error"])[0]
    e_off = off.get(["constraint.length_error"])[0]
    assert e_on <= 1e-12
    assert e_off > 1e-10 and e_off > 100 * max(e_on, 1e-15)


def test_step_size_parameter_sets_the_internal_step(fmus, open_fmu):
    fmu = fmus.builtin("prism2-elastic")
    force = {"node[7].fx": 20.0}
    coarse = open_fmu(fmu, name="coarse").init(params={"solver.step_size": 0.002}, inputs=force, integers=RK4)
    fine = open_fmu(fmu, name="fine").init(inputs=force, integers=RK4)
    # with a 2 ms internal step, one 2 ms communication step is exactly two 1 ms ones
    # of the default only if the parameter was ignored
    coarse.run(10, 0.002)
    fine.run(10, 0.002)
    pos = POSITIONS(fmu)
    diff = np.max(np.abs(coarse.get(pos) - fine.get(pos)))
    assert 0 < diff < 1e-6
    again = open_fmu(fmu, name="again").init(params={"solver.step_size": 0.002}, inputs=force, integers=RK4)
    for k in range(20):
        again.fmu.doStep(k * 0.001, 0.001)  # 1 ms communication steps: shortened internal steps
    assert np.max(np.abs(again.get(pos) - fine.get(pos))) <= 1e-12
