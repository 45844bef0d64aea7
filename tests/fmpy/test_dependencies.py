"""ModelStructure dependencies (issue 10, item 6): what each output reads at the same instant.

After some doSteps, each input is perturbed with setReal (no doStep) and every output is
read again. An output declared independent of the input must keep exactly its value; the
outputs that physics says must feel the input (its own cable's tension, the energy for a
cable input, a pin's reaction for a force on its node, a bar force at a loaded free node)
must be declared dependent and must move. In Initialization Mode the same holds for the
parameters listed in <InitialUnknowns>.
"""

import numpy as np
import pytest

from conftest import BUILTINS

# Every kind of Known: a reeled cable anchored at a bar-less pinned node (5), a static bar
# (both ends pinned), a controlled and two elastic cables (one damped), a force input, a
# point mass, a scripted sinusoid, gravity and a ground plane under the structure.
ALL_KNOWNS_SCENE = """\
name = "all-knowns"
nodes = [[1.0, 0.0, 0.0], [-0.5, 0.8660254037844386, 0.0], [-0.5, -0.8660254037844386, 0.0], [0.0, 0.0, 1.0], [0.3, 0.0, 2.0]]
fixed = [1, 2, 5]
force_inputs = [4]
gravity = [0.0, 0.0, -9.81]

[[bars]]
nodes = [1, 4]
mass = 1.0

[[bars]]
nodes = [2, 4]
mass = 1.5

[[bars]]
nodes = [3, 4]
mass = 2.0

[[bars]]
nodes = [1, 2]
mass = 1.0

[[cables]]
nodes = [1, 2]
stiffness = 100.0
rest_length = 1.6

[[cables]]
nodes = [2, 3]
control = "force_density"
force_density = 3.25

[[cables]]
nodes = [3, 1]
stiffness = 120.0
rest_length = 1.55
damping = 2.5

[[cables]]
nodes = [4, 5]
control = "rest_length"
stiffness = 200.0
rest_length = 0.9

[[point_masses]]
node = 4
mass = 0.5

[[loads]]
kind = "sinusoidal"
node = 4
amplitude = [1.0, 0.5, 0.0]
frequency = 2.0
phase = 0.3

[ground]
height = 0.9
stiffness = 1000.0
damping = 5.0
friction = 0.4

[solver]
step_size = 0.0002
"""


@pytest.fixture(params=BUILTINS + ["all-knowns"])
def fmu(request, fmus):
    if request.param == "all-knowns":
        return fmus.from_toml(ALL_KNOWNS_SCENE)
    return fmus.builtin(request.param)


def knowns(fmu, section):
    """The Knowns of a ModelStructure section: the inputs for <Outputs>, the inputs and
    parameters (all initial="exact") for <InitialUnknowns>."""
    causalities = {"outputs": ("input",), "initialUnknowns": ("input", "parameter")}[section]
    return [v.name for v in fmu.md.modelVariables if v.causality in causalities]


def declared(fmu, section):
    """{output name: set of Known names} from fmpy's ModelStructure list; an omitted list
    means every Known of the section."""
    every = set(knowns(fmu, section))
    return {
        u.variable.name: every if u.dependencies is None else {d.name for d in u.dependencies}
        for u in getattr(fmu.md, section)
    }


def perturbed(value):
    return value * 1.1 if value != 0 else 1.0


def must_move(fmu, known):
    """(outputs that physics says feel `known`, "all" or "any" of them), with names built
    from the scene, not from the FMU."""
    scene = fmu.scene
    fixed = set(scene.get("fixed", []))
    name, _, field = known.partition("].")
    index = int(name.split("[")[1]) if "[" in name else None
    if known.startswith("cable[") and field in ("force_density", "rest_length", "stiffness"):
        # A pin's reaction moves too, along the axes the cable spans.
        moved = {f"cable[{index}].tension", "energy.total"}
        a, b = scene["cables"][index - 1]["nodes"]
        span = np.subtract(scene["nodes"][b - 1], scene["nodes"][a - 1])
        for n in (a, b):
            if n in fixed:
                moved |= {f"node[{n}].reaction_{c}" for c, d in zip("xyz", span) if abs(d) > 1e-3}
        return moved, "all"
    if known.startswith("node[") and field in ("fx", "fy", "fz"):
        if index in fixed:
            return {f"node[{index}].reaction_{field[1]}"}, "all"
        # A force across a lone bar leaves its λ unchanged: some axis must move one of them.
        bars = [k for k, b in enumerate(scene["bars"], start=1) if index in b["nodes"]]
        return {f"bar[{k}].force" for k in bars}, "any"
    if known.startswith("bar[") and field == "mass" and "gravity" in scene:
        a, b = scene["bars"][index - 1]["nodes"]
        height = np.dot(scene["gravity"], np.add(scene["nodes"][a - 1], scene["nodes"][b - 1]))
        return ({"energy.total"} if abs(height) > 1e-9 else set()), "all"  # weight potential
    if known == "gravity.z":
        return {"energy.total"}, "all"
    return set(), "all"


def check(fmu, slave, knowns, deps):
    outputs = fmu.outputs
    y0 = slave.outputs()
    felt = {}  # "any" groups: what moved over the three axes of a node force
    for known in knowns:
        v = fmu.variables[known]
        if v.type == "Real":
            x0 = float(slave.get([known])[0])
            slave.set({known: perturbed(x0)})
            y1 = slave.outputs()
            slave.set({known: x0})
        else:
            continue
        assert np.array_equal(slave.outputs(), y0), f"{known}: restoring it changed outputs"
        moved = {o for o, a, b in zip(outputs, y0, y1) if a != b}
        for o in outputs:
            if known not in deps[o]:
                assert o not in moved, f"{o} moved when {known} changed but is declared independent"
        group, mode = must_move(fmu, known)
        group = {o for o in group if o in deps}  # outputs the scene publishes
        for o in group:
            assert known in deps[o], f"{o} must depend on {known}"
        if mode == "any":
            felt.setdefault(frozenset(group), set()).update(group & moved)
        else:
            assert group <= moved, f"{sorted(group - moved)} did not move when {known} changed"
    for group, moved in felt.items():
        assert not group or moved, f"none of {sorted(group)} moved under a node force"


def test_outputs_declare_exactly_the_inputs_they_read(fmu, open_fmu):
    deps = declared(fmu, "outputs")
    assert set(deps) == set(fmu.outputs)
    inputs = knowns(fmu, "outputs")
    assert inputs
    for o, ds in deps.items():
        assert all(fmu.variables[d].causality == "input" for d in ds), o
    slave = open_fmu(fmu).init()
    slave.run(20, 1e-3)
    check(fmu, slave, inputs, deps)


def test_state_outputs_depend_on_no_input(fmu):
    deps = declared(fmu, "outputs")
    for o in fmu.outputs:
        if o.startswith("node[") and o.split(".")[1] in ("x", "y", "z", "vx", "vy", "vz"):
            assert deps[o] == set(), o
        if o.startswith("constraint.") or "contact_force" in o or o.startswith("ground.force"):
            assert deps[o] == set(), o


def test_cable_tension_depends_on_its_own_command_only(fmu):
    deps = declared(fmu, "outputs")
    for j, cable in enumerate(fmu.scene.get("cables", []), start=1):
        own = {"force_density": {f"cable[{j}].force_density"},
               "rest_length": {f"cable[{j}].rest_length"}}.get(cable.get("control"), set())
        assert deps[f"cable[{j}].tension"] == own, j


def test_initial_unknowns_declare_the_parameters_they_read(fmu, open_fmu):
    deps = declared(fmu, "initialUnknowns")
    assert set(deps) == set(fmu.outputs)
    every = knowns(fmu, "initialUnknowns")
    for o, ds in deps.items():
        assert all(fmu.variables[d].causality in ("input", "parameter") for d in ds), o
    # A list omitted for its length claims the solver settings too (see test_model_structure).
    listed = {u.variable.name for u in fmu.md.initialUnknowns if u.dependencies is not None}
    solver = {k for k in every if k.startswith("solver.")}
    for o in listed:
        assert not (deps[o] & solver), f"{o} cannot depend on the solver settings"
    slave = open_fmu(fmu)
    slave.fmu.setupExperiment(startTime=0.0)
    slave.fmu.enterInitializationMode()
    check(fmu, slave, every, deps)
    slave.fmu.exitInitializationMode()


def test_dependencies_kind_is_dependent(fmu):
    for u in fmu.md.outputs + fmu.md.initialUnknowns:
        if u.dependencies:
            assert u.dependenciesKind == ["dependent"] * len(u.dependencies), u.variable.name
