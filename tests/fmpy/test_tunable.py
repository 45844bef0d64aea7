"""Tunable parameters (issue 10, item 8): set between steps, re-validated, acting from the
next step on with the running state kept; fixed ones stay refused without stopping the run."""

from pathlib import Path

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from effects_scenes import COMM, G, dropped_fmu

SCENES = Path(__file__).resolve().parents[2] / "fmu" / "scenes"


@pytest.fixture(scope="module")
def dropped(fmus):
    return dropped_fmu(fmus)


def run_steps(s, first, last):
    for k in range(first, last):
        s.fmu.doStep(k * COMM, COMM)


TUNED = {
    "gravity.z": -3.0,
    "ground.friction": 0.2,
    "ground.stiffness": 2e4,
    "ground.damping": 40.0,
    "cable[1].damping": 5.0,
    "cable[2].stiffness": 300.0,
    "point_mass[1].mass": 0.5,
    "bar[1].mass": 1.2,
}


@pytest.mark.parametrize("name, value", TUNED.items())
def test_tunable_set_after_initialization_acts_like_set_before(dropped, open_fmu, name, value):
    """Set at t = 0 just after initialization, the value acts exactly as if it had been set
    during initialization (the state at t = 0 is the same): the whole bounce bit for bit."""
    assert dropped.variables[name].variability == "tunable"
    before = open_fmu(dropped, name="before").init(params={name: value})
    after = open_fmu(dropped, name="after").init()
    untouched = open_fmu(dropped, name="untouched").init()
    after.set({name: value})
    assert after.get([name])[0] == value
    for s in (before, after, untouched):
        try:
            run_steps(s, 0, 40)  # through the first impact at about 0.25 s
        except FMICallException:
            raise AssertionError(s.errors())
    assert np.array_equal(after.outputs(), before.outputs())
    assert not np.array_equal(after.outputs(), untouched.outputs()), "the value must act"


def centre_of_mass_velocity(s, scene):
    total, momentum = 0.0, np.zeros(3)
    for bar in scene["bars"]:
        a, b = bar["nodes"]
        va = s.get([f"node[{a}].v{c}" for c in "xyz"])
        vb = s.get([f"node[{b}].v{c}" for c in "xyz"])
        momentum += bar["mass"] * (va + vb) / 2
        total += bar["mass"]
    for p in scene.get("point_masses", []):
        momentum += p["mass"] * s.get([f"node[{p['node']}].v{c}" for c in "xyz"])
        total += p["mass"]
    return momentum / total


def test_gravity_switched_off_mid_flight_stops_the_fall(dropped, open_fmu):
    """Free fall from 0.3 m: no contact before 0.24 s. The centre of mass gains g t until
    gravity is tuned to 0 at 0.05 s, then keeps its velocity (cables are internal)."""
    s = open_fmu(dropped).init()
    run_steps(s, 0, 5)
    v1 = centre_of_mass_velocity(s, dropped.scene)
    assert v1 == pytest.approx([0.0, 0.0, -G * 0.05], abs=1e-12)
    s.set({"gravity.z": 0.0})
    run_steps(s, 5, 15)
    v2 = centre_of_mass_velocity(s, dropped.scene)
    assert np.abs(v2 - v1).max() < 1e-12
    assert np.all(s.get([n for n in dropped.outputs if n.startswith("node[") and n.endswith("contact_force")]) == 0)


def test_invalid_tunable_value_is_refused_and_changes_nothing(dropped, open_fmu):
    s = open_fmu(dropped, name="s").init()
    ref = open_fmu(dropped, name="ref").init()
    run_steps(s, 0, 10)
    run_steps(ref, 0, 10)
    with pytest.raises(FMICallException) as e:
        s.set({"gravity.z": -1.0, "ground.friction": -0.5})  # a valid value first
    assert e.value.status == 3
    assert any("ground.friction = -0.5 rejected" in m for m in s.errors()), s.errors()
    assert s.get(["gravity.z", "ground.friction"]).tolist() == [-G, 0.5]
    run_steps(s, 10, 30)
    run_steps(ref, 10, 30)
    assert np.array_equal(s.outputs(), ref.outputs())


@pytest.mark.parametrize("name, value", [("solver.step_size", 1e-4)])
def test_fixed_parameters_stay_fixed(dropped, open_fmu, name, value):
    s = open_fmu(dropped).init()
    assert dropped.variables[name].variability == "fixed"
    with pytest.raises(FMICallException):
        s.set({name: value})
    assert any(f"{name} is a fixed parameter" in m for m in s.errors())
    with pytest.raises(FMICallException):
        s.fmu.setInteger(s.vrs(["solver.method"]), [2])
    with pytest.raises(FMICallException):
        s.fmu.setBoolean(s.vrs(["solver.correction"]), [0])
    run_steps(s, 0, 3)


def test_tunable_set_mid_run_keeps_the_state_of_an_equilibrium_start(fmus, open_fmu):
    """A scene that starts at its equilibrium is not re-solved when a tunable parameter
    changes mid-run: the running state is kept, so a gravity the structure could not stand
    statically is accepted and acts (before, the set was refused: no stable equilibrium)."""
    head, _, tail = (SCENES / "prism2-elastic.toml").read_text().partition("\n[[")
    text = f'{head}\nstart = "equilibrium"\ngravity = [0.0, 0.0, -9.81]\n\n[[{tail}'
    fmu = fmus.from_toml(text)
    s = open_fmu(fmu).init()
    z0 = s.get(["node[7].z"])[0]
    for k in range(100):
        s.fmu.doStep(k * 1e-3, 1e-3)
    assert abs(s.get(["node[7].z"])[0] - z0) < 1e-9, "it starts at rest"
    s.set({"gravity.z": -4905.0})
    assert s.get(["gravity.z"])[0] == -4905.0
    for k in range(100, 110):
        s.fmu.doStep(k * 1e-3, 1e-3)
    assert s.get(["node[7].z"])[0] < z0 - 1e-3, "the heavier gravity acts from the state kept"
