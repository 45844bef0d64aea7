"""The shipped FMUs under libcosim (DNV's Open Simulation Platform master, via libcosimpy).

libcosim runs the same binary as fmpy, so with the same communication points and the same
inputs both must agree to round-off. libcosim counts time in integer nanoseconds and calls
doStep(t / 1e9, (t + h) / 1e9 - t / 1e9); the fmpy runs here pass exactly those doubles.
libcosim ignores Enumeration variables; `solver.method` is an Integer, so it sees every
variable.
"""

import numpy as np
import pytest
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
from libcosimpy.CosimManipulator import CosimManipulator
from libcosimpy.CosimObserver import CosimObserver
from libcosimpy.CosimSlave import CosimLocalSlave

from conftest import BUILTINS

log_output_level(CosimLogLevel.ERROR)

MS = 1_000_000  # ns


def observed(fmu):
    """Node positions, cable tensions and the energy: what the comparisons look at."""
    nodes = [n for n in fmu.outputs if n.startswith("node[") and n[-2:] in (".x", ".y", ".z")]
    tensions = [n for n in fmu.outputs if n.endswith(".tension")]
    return nodes, tensions, ["energy.total"]


def push(fmu, fx=5.0, fz=-5.0):
    """A force on the scene's first force-input node, so that something moves."""
    node = fmu.scene["force_inputs"][0]
    return {f"node[{node}].fx": fx, f"node[{node}].fz": fz}


class Cosim:
    """A libcosim execution at a fixed step of `step_ns`, with a last-value observer."""

    def __init__(self, step_ns):
        self.step_ns = step_ns
        self.execution = CosimExecution.from_step_size(step_ns)
        self.observer = CosimObserver.create_last_value()
        assert self.execution.add_observer(self.observer)
        self.slaves = []  # CosimLocalSlave objects must outlive the execution's use of them
        self.refs = {}

    def add(self, fmu, name, initial=None):
        slave = CosimLocalSlave(fmu_path=str(fmu.path), instance_name=name)
        self.slaves.append(slave)
        index = self.execution.add_local_slave(slave)
        assert index >= 0, f"libcosim did not load {fmu.path}"
        refs = {v.name.decode(): v.reference for v in self.execution.slave_variables(index)}
        # libcosim reads the same modelDescription: same names, same value references
        assert all(refs[n] == fmu.vr[n] for n in refs)
        assert set(refs) == set(fmu.vr), "libcosim sees every variable, solver.method too"
        self.refs[index] = refs
        for name_, value in (initial or {}).items():
            assert self.execution.real_initial_value(index, refs[name_], value)
        return index

    def get(self, index, names):
        return np.array(self.observer.last_real_values(index, [self.refs[index][n] for n in names]))

    def run(self, n, names, index=0, each=None):
        """n communication steps; the observed values of slave `index` (or of each slave in a
        list) after each step, as (n, len(names)) arrays."""
        indices = index if isinstance(index, list) else [index]
        rows = {i: [] for i in indices}
        for k in range(n):
            if each:
                each(k)
            assert self.execution.step(), self.execution.status()
            for i in indices:
                rows[i].append(self.get(i, names))
        assert self.execution.status().current_time == n * self.step_ns
        out = [np.array(rows[i]) for i in indices]
        return out if isinstance(index, list) else out[0]


def cosim_step(k, step_ns):
    """libcosim's doStep arguments for step k (cosim::to_double_time_point/duration)."""
    t, t1 = k * step_ns / 1e9, (k + 1) * step_ns / 1e9
    return t, t1 - t


def fmpy_run(slave, n, step_ns, names, each=None):
    """The fmpy counterpart of Cosim.run, at libcosim's communication points."""
    rows = []
    for k in range(n):
        if each:
            each(k)
        slave.fmu.doStep(*cosim_step(k, step_ns))
        rows.append(slave.get(names))
    return np.array(rows)


def assert_agree(fmu, a, b, names):
    nodes, tensions, energy = observed(fmu)
    col = {n: i for i, n in enumerate(names)}
    for group, tol, unit in ((nodes, 1e-12, "m"), (tensions, 1e-10, "N"), (energy, 1e-10, "J")):
        idx = [col[n] for n in group]
        err = np.max(np.abs(a[:, idx] - b[:, idx])) if idx else 0.0
        assert err <= tol, f"libcosim vs fmpy: {group[0]}… differ by {err:.3g} {unit}"


@pytest.mark.parametrize("name", BUILTINS)
def test_libcosim_matches_fmpy_on_the_builtins(fmus, open_fmu, name):
    fmu = fmus.builtin(name)
    names = sum(observed(fmu), [])
    inputs = push(fmu)
    n, step_ns = (100, 2 * MS) if name == "tower20" else (200, MS)
    cosim = Cosim(step_ns)
    cosim.add(fmu, "structure", initial=inputs)
    via_cosim = cosim.run(n, names)
    s = open_fmu(fmu).init(inputs=inputs)
    via_fmpy = fmpy_run(s, n, step_ns, names)
    assert_agree(fmu, via_cosim, via_fmpy, names)
    # not a comparison of two structures at rest: the pushed node moved
    node = fmu.scene["force_inputs"][0]
    x = names.index(f"node[{node}].x")
    assert abs(via_cosim[-1, x] - fmu.scene["nodes"][node - 1][0]) > 1e-5
    print(f"{name}: {n} steps of {step_ns / MS:g} ms, max |Δ| {np.max(np.abs(via_cosim - via_fmpy)):.3g}")


def test_libcosim_parameter_sets_the_stiffness(fmus, open_fmu):
    """A Real parameter given to libcosim as an initial value: doubling the stiffness of a
    cable between free nodes doubles its tension at the start (same stretch) and breaks the
    prestressed equilibrium; fmpy with the same value agrees."""
    fmu = fmus.builtin("prism2-elastic")
    names = sum(observed(fmu), [])
    fixed = set(fmu.scene["fixed"])
    j = next(j for j, c in enumerate(fmu.scene["cables"], 1) if not fixed & set(c["nodes"]))
    param = f"cable[{j}].stiffness"
    k = float(fmu.variables[param].start)
    runs = {}
    for stiffness in (k, 2 * k):
        cosim = Cosim(MS)
        cosim.add(fmu, "elastic", initial={param: stiffness})
        runs[stiffness] = cosim.run(50, names)
        s = open_fmu(fmu, name=f"k{stiffness}").init(params={param: stiffness})
        assert_agree(fmu, runs[stiffness], fmpy_run(s, 50, MS, names), names)
    t = names.index(f"cable[{j}].tension")
    # after 1 ms the nodes have barely moved: the tension is still about twice the prestress
    assert runs[2 * k][0, t] / runs[k][0, t] == pytest.approx(2.0, rel=1e-3)
    # the default stiffness keeps the prestressed equilibrium; the doubled one does not
    nodes = [names.index(n) for n in observed(fmu)[0]]
    assert np.max(np.abs(runs[k][-1, nodes] - runs[k][0, nodes])) <= 1e-10
    assert np.max(np.abs(runs[2 * k][-1, nodes] - runs[k][-1, nodes])) > 1e-5


def test_libcosim_input_set_mid_run_acts_from_the_next_step(fmus, open_fmu):
    """An override manipulator sets a force input at step 50; fmpy sets it at the same point."""
    fmu = fmus.builtin("prism2")
    names = sum(observed(fmu), [])
    node = fmu.scene["force_inputs"][0]
    fz = f"node[{node}].fz"
    cosim = Cosim(MS)
    index = cosim.add(fmu, "prism")
    override = CosimManipulator.create_override()
    assert cosim.execution.add_manipulator(override)

    def on_cosim(k):
        if k == 50:
            assert override.slave_real_values(index, [cosim.refs[index][fz]], [-20.0])

    via_cosim = cosim.run(150, names, each=on_cosim)
    s = open_fmu(fmu).init()

    def on_fmpy(k):
        if k == 50:
            s.set({fz: -20.0})

    via_fmpy = fmpy_run(s, 150, MS, names, each=on_fmpy)
    assert_agree(fmu, via_cosim, via_fmpy, names)
    z = names.index(f"node[{node}].z")
    z0 = fmu.scene["nodes"][node - 1][2]
    assert np.max(np.abs(via_cosim[:50, z] - z0)) <= 1e-10, "at rest before the input is set"
    assert via_cosim[-1, z] < z0 - 1e-4, "the downward force moves the node down"


def test_two_prisms_coupled_through_libcosim(fmus, open_fmu):
    """The tension of a cable between free nodes of prism a drives prism b's force input on
    its first force-input node (a libcosim connection); a is pushed so the tension varies. libcosim's fixed-step algorithm steps both
    from the same inputs and then transfers outputs to inputs; fmpy does the same by hand."""
    fmu = fmus.builtin("prism2")
    names = sum(observed(fmu), [])
    node = fmu.scene["force_inputs"][0]
    fixed = set(fmu.scene["fixed"])
    j = next(j for j, c in enumerate(fmu.scene["cables"], 1) if not fixed & set(c["nodes"]))
    source, target = f"cable[{j}].tension", f"node[{node}].fx"
    pushed = push(fmu, fx=0.0, fz=-10.0)
    cosim = Cosim(MS)
    a = cosim.add(fmu, "a", initial=pushed)
    b = cosim.add(fmu, "b")
    cosim.execution.connect_real_variables(a, cosim.refs[a][source], b, cosim.refs[b][target])
    n = 200
    rows_a, rows_b = cosim.run(n, names, index=[a, b])
    via_cosim = {"a": rows_a, "b": rows_b}

    sa = open_fmu(fmu, name="a").init(inputs=pushed)
    sb = open_fmu(fmu, name="b").init()
    sb.set({target: sa.get([source])[0]})
    rows = {"a": [], "b": []}
    for k in range(n):
        sa.fmu.doStep(*cosim_step(k, MS))
        sb.fmu.doStep(*cosim_step(k, MS))
        sb.set({target: sa.get([source])[0]})
        rows["a"].append(sa.get(names))
        rows["b"].append(sb.get(names))
    for key in "ab":
        assert_agree(fmu, via_cosim[key], np.array(rows[key]), names)
    # b moves only through the connection: its node is pushed along x by a's tension
    x = names.index(f"node[{node}].x")
    tension = via_cosim["a"][:, names.index(source)]
    assert np.ptp(tension) > 1e-3, "a's tension varies"
    assert abs(via_cosim["b"][-1, x] - fmu.scene["nodes"][node - 1][0]) > 1e-4
