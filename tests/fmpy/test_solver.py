"""Solver settings as FMU parameters: solver.method (Integer), solver.rtol, solver.atol."""

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

METHODS = {"rk4": 1, "dopri5": 2, "rattle": 3, "sdirk3": 4}
TOP = [f"node[{n}].{c}" for n in (7, 8, 9) for c in "xyz"]


def run(open_fmu, fmu, method, comm=1e-3, t_end=0.5, **params):
    s = open_fmu(fmu, name=f"m{method}")
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.enterInitializationMode()
    s.fmu.setInteger(s.vrs(["solver.method"]), [METHODS[method]])
    if params:
        s.set(params)
    s.set({"node[7].fx": 2.0, "node[8].fz": -1.0})
    s.fmu.exitInitializationMode()
    s.run(round(t_end / comm), comm)
    return s


@pytest.mark.parametrize("method", ["dopri5", "rattle", "sdirk3"])
def test_every_method_runs_in_the_fmu_and_agrees_with_rk4(open_fmu, fmus, method):
    fmu = fmus.builtin("prism2-elastic")
    reference = run(open_fmu, fmu, "rk4", **{"solver.step_size": 2.5e-4})
    other = run(open_fmu, fmu, method, **{"solver.rtol": 1e-9, "solver.atol": 1e-9})
    assert other.fmu.getInteger(other.vrs(["solver.method"])) == [METHODS[method]]
    moved = np.abs(reference.get(TOP) - run(open_fmu, fmu, "rk4", t_end=1e-3).get(TOP)).max()
    diff = np.abs(other.get(TOP) - reference.get(TOP)).max()
    # rattle is second order at 1 ms, sdirk3 third; dopri5 runs at 1e-9.
    assert moved > 1e-2
    assert diff < {"rattle": 1e-4, "sdirk3": 1e-5}.get(method, 1e-7), diff
    errors = other.get(["constraint.length_error", "constraint.orthogonality_error"])
    assert errors.max() <= 1e-12


def test_adaptive_method_takes_one_big_communication_step(open_fmu, fmus):
    fmu = fmus.builtin("prism2-elastic")
    params = {"solver.rtol": 1e-10, "solver.atol": 1e-10}
    fine = run(open_fmu, fmu, "dopri5", comm=1e-3, **params)
    big = run(open_fmu, fmu, "dopri5", comm=0.5, **params)
    assert big.time == 0.5
    assert np.abs(big.get(TOP) - fine.get(TOP)).max() < 1e-8


def test_invalid_method_value_is_an_error(open_fmu, fmus):
    s = open_fmu(fmus.builtin("prism2"))
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.enterInitializationMode()
    with pytest.raises(FMICallException):
        s.fmu.setInteger(s.vrs(["solver.method"]), [5])
    assert any("solver.method" in m for m in s.errors())
