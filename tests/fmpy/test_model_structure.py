"""ModelStructure in its short form, checked against dependencies measured on the FMU.

Each Known is perturbed alone and every output is read again: in Initialization Mode for
<InitialUnknowns> (Knowns: inputs and parameters, all initial="exact"), and at a
communication point after some doSteps for <Outputs> (Knowns: inputs). What moved is the
row's measured dependency set. A listed row must name exactly that set (save two cases,
named where they are checked: loads on a pin, and the axes of a pin's reaction). An
omitted list means "every Known": in <Outputs> it is allowed only when the row reads
every input; in <InitialUnknowns>, also when the row reads every input and more
parameters than a short list holds, since parameters are never connected, so no false
loop can arise.

The scene is a tower whose three bar columns are chains joined at their nodes, so a bar
force reads the cables and masses of its whole column: dense rows (omitted) next to
sparse ones (a cable tension reads its own cable only) and rows that read none. One
force input on the top of the first column makes that column read every input, the
others none. Gravity makes every mass weigh.
"""

import math

import numpy as np
import pytest

DENSE_ROW = 64  # the most parameters an <InitialUnknowns> row reading every input lists
STAGES = 8


def tower_toml():
    """A STAGES-stage tower (tower_scene's layout, moved off the z axis), cables at 98% of
    their lengths."""
    radius, h = 1 / math.sqrt(3), 0.5 + math.sqrt(3) / 6
    node = lambda ring, i: 3 * ring + i + 1  # noqa: E731
    nodes = []
    for ring in range(STAGES + 1):
        for i in range(3):
            a = math.radians(ring * 150 + i * 120)
            # Off the axis, so that the weight's potential feels gravity.x and .y too.
            nodes.append([0.3 + radius * math.cos(a), 0.2 + radius * math.sin(a), ring * h])
    lines = [
        'name = "dense-column-tower"',
        f"nodes = {nodes}",
        "fixed = [1, 2, 3]",
        f"force_inputs = [{node(STAGES, 0)}]",
        "gravity = [0.0, 0.0, -9.81]",
    ]
    for k in range(STAGES):
        for i in range(3):
            lines += ["[[bars]]", f"nodes = [{node(k, i)}, {node(k + 1, i)}]", "mass = 1.0"]
    pairs = [(node(r, i), node(r, (i + 1) % 3)) for r in range(STAGES + 1) for i in range(3)]
    pairs += [(node(k, i), node(k + 1, (i + 2) % 3)) for k in range(STAGES) for i in range(3)]
    for a, b in pairs:
        rest = 0.98 * math.dist(nodes[a - 1], nodes[b - 1])
        lines += ["[[cables]]", f"nodes = [{a}, {b}]", "stiffness = 500.0", f"rest_length = {rest!r}"]
    return "\n".join(lines) + "\n"


@pytest.fixture(scope="module")
def tower(fmus):
    return fmus.from_toml(tower_toml())


def names(fmu, causalities):
    return [v.name for v in fmu.md.modelVariables if v.causality in causalities]


def measured(fmu, slave, knowns):
    """({output: Knowns that move it by more than rounding}, {output: Knowns that move it at
    all}), each Known changed alone at the slave's current state."""
    outputs = fmu.outputs
    y0 = slave.outputs()
    felt = {o: set() for o in outputs}
    stirred = {o: set() for o in outputs}
    for known in knowns:
        if fmu.variables[known].type != "Real":
            continue  # the Integer and Boolean settings are the solver's: read by no output
        x0 = float(slave.get([known])[0])
        slave.set({known: x0 * 1.1 if x0 != 0 else 1.0})
        y1 = slave.outputs()
        slave.set({known: x0})
        assert np.array_equal(slave.outputs(), y0), f"{known}: restoring it changed outputs"
        for o, a, b in zip(outputs, y0, y1):
            if a != b:
                stirred[o].add(known)
            if abs(a - b) > 1e-9 * max(1.0, abs(a)):
                felt[o].add(known)
    return felt, stirred


def on_pins(fmu):
    """Knowns of the cables with an end on a pin. Their load there goes into the pin, so a
    bar force feels it only through rounding (1e-14 N); a listed row still names them, as
    one that does not must keep every bit."""
    pins = set(fmu.scene["fixed"])
    return {
        f"cable[{j}].{field}"
        for j, c in enumerate(fmu.scene["cables"], start=1)
        if pins & set(c["nodes"])
        for field in ("stiffness", "rest_length")
    }


def blind_axes(output, felt):
    """What a pin's reaction lists for all three axes but feels along some: a load
    straight on the pin (a horizontal cable between two pins lifts no pin)."""
    node, _, field = output.partition(".reaction_")
    if not field:
        return set()
    return set().union(*(felt.get(f"{node}.reaction_{axis}", set()) for axis in "xyz"))


def compare(fmu, unknowns, measures, inputs, knowns, dense_allowed):
    """Every row against what moves it; returns the omitted rows. A listed row names every
    Known that moves it at all, and no other than those felt beyond rounding, save loads
    on the pins."""
    felt, stirred = measures
    omitted = set()
    for u in unknowns:
        o, truth = u.variable.name, felt[u.variable.name]
        if u.dependencies is not None:
            listed = {d.name for d in u.dependencies}
            assert stirred[o] <= listed, (o, sorted(stirred[o] - listed))
            pinned = on_pins(fmu) if o.startswith("bar[") else set()
            spare = listed - truth - pinned - blind_axes(o, felt)
            assert not spare, (o, sorted(spare))
            continue
        omitted.add(o)
        assert u.dependenciesKind is None, o
        assert truth & set(inputs) == set(inputs), f"{o}: omitted but misses an input"
        if truth != set(knowns):
            read = len(truth - set(inputs))
            assert dense_allowed and read > DENSE_ROW, f"{o}: omitted, reads {read} parameters"
    return omitted


def test_initial_unknowns_match_what_moves_in_initialization_mode(tower, open_fmu):
    inputs = names(tower, ("input",))
    knowns = names(tower, ("input", "parameter"))
    slave = open_fmu(tower)
    slave.fmu.setupExperiment(startTime=0.0)
    slave.fmu.enterInitializationMode()
    moved = measured(tower, slave, knowns)
    slave.fmu.exitInitializationMode()
    omitted = compare(tower, tower.md.initialUnknowns, moved, inputs, knowns, dense_allowed=True)
    felt = moved[0]
    # Both forms occur: the first column's bar forces are omitted, the other columns' listed.
    first_column = {f"bar[{3 * k + 1}].force" for k in range(STAGES)}
    assert first_column <= omitted
    assert not {f"bar[{3 * k + 2}].force" for k in range(STAGES)} & omitted
    assert all(len(felt[f"bar[{3 * k + 2}].force"]) > DENSE_ROW for k in range(STAGES))
    assert felt["cable[1].tension"] == {"cable[1].stiffness", "cable[1].rest_length"}


def test_outputs_match_what_moves_at_a_communication_point(tower, open_fmu):
    inputs = names(tower, ("input",))
    slave = open_fmu(tower).init()
    slave.run(20, 1e-3)
    moved = measured(tower, slave, inputs)
    omitted = compare(tower, tower.md.outputs, moved, inputs, inputs, dense_allowed=False)
    # The first column reads the force at its top; the rest, including the state, none.
    assert {f"bar[{3 * k + 1}].force" for k in range(STAGES)} <= omitted
    listed = {u.variable.name: u.dependencies for u in tower.md.outputs}
    assert listed["bar[2].force"] == [] and listed["node[1].x"] == []
