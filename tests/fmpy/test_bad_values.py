"""Rejected and clamped values: negative force densities, NaN and infinite inputs, and a
step whose state becomes non-finite; recovery by fmi2Reset and fmi2SetFMUstate (issue 3, items 3 and 5)."""

import ctypes

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from conftest import RK4


@pytest.fixture
def prism2(fmus):
    return fmus.builtin("prism2")


def all_reals(s):
    return [n for n, v in s.file.variables.items() if v.type == "Real"]


# --- inputs --------------------------------------------------------------------------


def test_negative_force_density_is_clamped_with_one_warning(prism2, open_fmu):
    s = open_fmu(prism2).init()
    assert s.get(["cable[7].tension"])[0] > 0
    vr = (ctypes.c_uint * 1)(*s.vrs(["cable[7].force_density"]))
    status = s.fmu.fmi2SetReal(s.fmu.component, vr, 1, (ctypes.c_double * 1)(-2.0))
    assert status == 1  # fmi2Warning
    warned = s.warnings()
    assert len(warned) == 1 and "cable[7].force_density" in warned[0]
    assert s.get(["cable[7].tension"])[0] == 0.0
    s.run(10, 0.001)
    assert s.get(["cable[7].tension"])[0] == 0.0
    s.set({"cable[7].force_density": -5.0})
    assert len(s.warnings()) == 1  # logged once
    # the other cables keep pulling
    assert s.get(["cable[8].tension"])[0] > 0


@pytest.mark.parametrize("bad", [float("nan"), float("inf"), float("-inf")])
def test_non_finite_input_is_an_error_and_reset_recovers(prism2, open_fmu, bad):
    s = open_fmu(prism2)
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.enterInitializationMode()
    fresh = s.get(all_reals(s))
    s.fmu.exitInitializationMode()
    s.run(5, 0.001)
    before = s.get(["node[7].fx", "cable[7].force_density"])
    with pytest.raises(FMICallException):
        s.set({"node[7].fx": 1.0, "cable[7].force_density": bad})
    assert any("finite" in m for m in s.errors())
    # nothing was changed, not even the valid value before the bad one
    assert np.array_equal(s.get(["node[7].fx", "cable[7].force_density"]), before)
    # a refused set is not a failed computation: the run goes on as if it never happened
    s.run(5, 0.001)
    ref = open_fmu(prism2, name="ref").init()
    ref.run(10, 0.001)
    assert np.array_equal(s.outputs(), ref.outputs())
    s.fmu.reset()
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.enterInitializationMode()
    assert np.array_equal(s.get(all_reals(s)), fresh)
    s.fmu.exitInitializationMode()
    s.time = 0.0
    s.run(5, 0.001)


def test_non_finite_input_set_state_recovers_snapshot(prism2, open_fmu):
    s = open_fmu(prism2).init(inputs={"node[8].fz": 3.0})
    s.run(20, 0.001)
    snap = s.fmu.getFMUstate()
    at_snap = s.outputs()
    with pytest.raises(FMICallException):
        s.set({"node[8].fz": float("nan")})
    s.fmu.setFMUstate(snap)
    assert np.array_equal(s.outputs(), at_snap)
    assert s.get(["node[8].fz"])[0] == 3.0
    s.run(10, 0.001)
    ref = open_fmu(prism2, name="ref").init(inputs={"node[8].fz": 3.0})
    ref.run(30, 0.001)
    assert np.array_equal(s.outputs(), ref.outputs())
    s.fmu.freeFMUstate(snap)


@pytest.mark.parametrize("force", [1e8, 1e307])
def test_non_finite_state_is_an_error_and_set_state_recovers(prism2, open_fmu, force):
    """1e307 N overflows in the first internal step; 1e8 N only after a few good ones."""
    s = open_fmu(prism2).init(integers=RK4)
    s.run(10, 0.001)
    snap = s.fmu.getFMUstate()
    good = s.outputs()
    s.set({"node[7].fx": force})
    with pytest.raises(FMICallException):
        s.fmu.doStep(s.time, 0.01)  # ten internal steps
    assert any("fmi2DoStep" in m and "non-finite" in m for m in s.errors())
    t_ok = s.status_time()
    assert 0.01 - 1e-15 <= t_ok < 0.02
    # the state is the last good point, at the time reported as the last successful one
    ref = open_fmu(prism2, name="ref").init(integers=RK4)
    ref.run(10, 0.001)
    ref.set({"node[7].fx": force})
    ref.run(round((t_ok - 0.01) / 0.001), 0.001)
    pos = [i for i, n in enumerate(prism2.outputs) if n.startswith("node[")]
    assert np.array_equal(s.outputs()[pos], ref.outputs()[pos])
    s.fmu.setFMUstate(snap)
    assert np.array_equal(s.outputs(), good)
    assert s.get(["node[7].fx"])[0] == 0.0
    s.run(5, 0.001)
    assert np.all(np.isfinite(s.outputs()))
    s.fmu.freeFMUstate(snap)
