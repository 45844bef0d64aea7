"""The optional effects through the FMU: gravity, point masses (payloads), ground contact and
scripted-load parameters (the fmpy twin of tests/point_masses.rs and tests/effects.rs; the
dropped icosahedron and the support reactions are in test_ground_fmu.py).

1. A scene with every effect builds an FMU that fmpy validates, with the effect parameters
   and outputs (and their units) in its modelDescription.
2. The effect parameters act: a stiffer ground, a heavier payload, a weaker gravity, each
   set in initialization mode, change the resting state of the dropped icosahedron as
   statics predicts.
3. The FMU state mid-bounce resumes bit-identically; invalid effect parameters are errors
   naming the variable, and the instance recovers.

Expected values come from the scenes and from statics (W = M g, d = W / (3 k) on three
symmetric contacts), never from recorded outputs. Figures are printed (run with -s).
"""

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from effects_scenes import (
    COMM,
    FACE,
    G,
    PAYLOAD,
    STIFFNESS,
    contact_names,
    dropped_fmu,
    everything_scene,
    expected_variables,
    resting,
    settle,
    to_toml,
    total_mass,
)


@pytest.fixture(scope="module")
def dropped(fmus):
    return dropped_fmu(fmus)


# --- 1. every effect: validation and modelDescription --------------------------------

# SI base-unit exponents (kg, m, s) of the units the effects add.
EFFECT_UNITS = {
    "m/s2": (0, 1, -2),
    "N.s/m": (1, 0, -1),
    "Hz": (0, 0, -1),
    "rad": (0, 0, 0),
    "N": (1, 1, -2),
    "N/m": (1, 0, -2),
    "kg": (1, 0, 0),
    "m": (0, 1, 0),
    "m/s": (0, 1, -1),
    "s": (0, 0, 1),
}


def test_scene_with_every_effect_validates_and_declares_its_variables(fmus):
    text = to_toml(everything_scene(fmus.builtin("prism2-elastic").scene))
    fmu = fmus.from_toml(text)
    scene = fmu.scene
    assert validate_fmu(str(fmu.path)) == []
    md = read_model_description(str(fmu.path))
    variables = {v.name: v for v in md.modelVariables}
    expected = expected_variables(scene)
    assert set(variables) == set(expected), (
        f"missing {sorted(set(expected) - set(variables))}, extra {sorted(set(variables) - set(expected))}"
    )
    for name, (causality, unit) in expected.items():
        v = variables[name]
        assert (v.causality, v.unit) == (causality, unit), name
    # start values of the effect parameters are the scene's
    ground = scene["ground"]
    for key in ("height", "stiffness", "damping", "friction", "slip_velocity"):
        assert float(variables[f"ground.{key}"].start) == ground[key], key
    assert [float(variables[f"gravity.{c}"].start) for c in "xyz"] == scene["gravity"]
    assert [float(variables[f"point_mass[{k}].mass"].start) for k in (1, 2)] == [0.2, 0.3]
    assert [float(variables[f"load[2].{f}"].start) for f in ("fy", "frequency", "phase")] == [2.0, 1.5, 0.3]
    assert float(variables["load[3].time"].start) == 0.05
    assert float(variables["load[3].fz"].start) == -1.0
    # contact points are the free bar ends only; reactions only at the pins
    assert sorted(int(n[5:-15]) for n in variables if n.endswith(".contact_force")) == [4, 5, 6, 7, 8, 9]
    assert sorted({int(n[5:n.index("]")]) for n in variables if ".reaction_" in n}) == [1, 2, 3]
    # every unit used is declared with its SI base units
    declared = {u.name: u.baseUnit for u in md.unitDefinitions}
    used = {v.unit for v in md.modelVariables if v.unit}
    assert used <= set(declared), used - set(declared)
    for name, (kg, m, s) in EFFECT_UNITS.items():
        b = declared[name]
        assert (b.kg, b.m, b.s, b.A, b.K, b.mol, b.cd) == (kg, m, s, 0, 0, 0, 0), name
    # and it runs: 0.2 s through fmpy's own master, past the step load's switch-on
    res = simulate_fmu(str(fmu.path), stop_time=0.2, output_interval=0.01)
    for name in fmu.outputs:
        assert np.all(np.isfinite(res[name])), name
    assert np.max(res["constraint.length_error"]) <= 1e-12
    assert np.all(res["ground.force_z"] == 0.0)  # the ground is 5 cm below the pinned ring


def test_output_groups_contact_and_reactions_select_only_those(fmus):
    scene = everything_scene(fmus.builtin("prism2-elastic").scene)
    scene["name"] = "prism2-everything-forces"
    scene["outputs"] = ["contact", "reactions"]
    fmu = fmus.from_toml(to_toml(scene))
    assert validate_fmu(str(fmu.path)) == []
    expected = expected_variables(scene)
    want = sorted(n for n, (c, _) in expected.items()
                  if c == "output" and (".contact_force" in n or n.startswith("ground.force_") or ".reaction_" in n))
    assert sorted(fmu.outputs) == want
    assert len(want) == 6 + 3 + 9


# --- 2. the effect parameters act ----------------------------------------------------


def test_ground_payload_and_gravity_parameters_change_the_resting_state(dropped):
    fmu = dropped
    mass = total_mass(fmu.scene)
    assert fmu.variables["point_mass[1].mass"].start is not None
    assert float(fmu.variables["point_mass[1].mass"].start) == PAYLOAD
    base, *_ = settle(fmu)
    stiff, *_ = settle(fmu, (("ground.stiffness", 2 * STIFFNESS),))
    heavy, *_ = settle(fmu, (("point_mass[1].mass", 2 * PAYLOAD),))
    light_g = 5.0
    weak, *_ = settle(fmu, (("gravity.z", -light_g),))

    def penetrations(final):
        return np.array([-final[f"node[{n}].z"] for n in FACE])

    def load(final):
        return sum(final[n] for n in contact_names(fmu))

    d1, d2 = penetrations(base), penetrations(stiff)
    w = mass * G
    extra = PAYLOAD * G  # point_mass[1] doubled from PAYLOAD
    print(
        f"\nresting penetrations: k = {STIFFNESS:g} N/m {d1.mean():.6e} m (W/3k = {w / (3 * STIFFNESS):.6e}), "
        f"k = {2 * STIFFNESS:g} N/m {d2.mean():.6e} m (ratio {d2.mean() / d1.mean():.9f}); "
        f"sum of contact forces: base {load(base):.9f} N, point_mass[1] x2 {load(heavy):.9f} N "
        f"(change {load(heavy) - load(base):.9f} vs p g = {extra:.9f}), gravity.z = -{light_g} "
        f"{load(weak):.9f} N (M g' = {mass * light_g:.9f})"
    )
    heavy_feet = [heavy[f"node[{n}].contact_force"] for n in FACE]
    print(
        f"point_mass[1] x2: contact forces on nodes {FACE} {np.round(heavy_feet, 6)} N, max speed "
        f"{resting(fmu, heavy)[3]:.1e} m/s (base {resting(fmu, base)[3]:.1e}; the unequal feet settle "
        f"more slowly, but the weight is carried)"
    )
    # a ground twice as stiff: same load on each contact, half the penetration
    assert load(stiff) == pytest.approx(w, rel=1e-6)
    assert d2 == pytest.approx(w / (6 * STIFFNESS), rel=1e-5)
    assert d2 == pytest.approx(d1 / 2, rel=1e-5)
    # a heavier payload on node 1: the ground carries p g more
    assert load(heavy) == pytest.approx(w + extra, rel=1e-6)
    assert heavy["ground.force_z"] == pytest.approx(w + extra, rel=1e-6)
    assert load(heavy) - load(base) == pytest.approx(extra, abs=1e-6 * w)
    assert heavy_feet[0] > max(heavy_feet[1:])  # the payload's foot carries most
    # weaker gravity: the weight and the penetrations scale with it
    assert load(weak) == pytest.approx(mass * light_g, rel=1e-6)
    assert weak["ground.force_z"] == pytest.approx(mass * light_g, rel=1e-6)
    assert penetrations(weak) == pytest.approx(mass * light_g / (3 * STIFFNESS), rel=1e-5)


# --- 3. FMU state with contact; invalid effect parameters ----------------------------

MID_BOUNCE = 27  # doSteps of COMM: the first impact is at √(2 DROP / g) = 0.247 s


def run_steps(s, first, last):
    for k in range(first, last):
        s.fmu.doStep(k * COMM, COMM)


def test_state_mid_bounce_resumes_bit_identically(dropped, open_fmu):
    fmu = dropped
    contacts = contact_names(fmu)
    ref = open_fmu(fmu, name="ref").init()
    run_steps(ref, 0, 60)
    s = open_fmu(fmu, name="s").init()
    run_steps(s, 0, MID_BOUNCE)
    at_state = s.outputs()
    touching = s.get(contacts)
    vz = s.get([f"node[{n}].vz" for n in FACE])
    print(f"\nsnapshot at {MID_BOUNCE * COMM:.2f} s: contact forces {touching[touching > 0].round(2)} N, "
          f"face node vz {vz.round(3)} m/s")
    assert touching.sum() > 0 and np.any(np.abs(vz) > 1e-2)  # in contact and still moving
    state = s.fmu.getFMUstate()
    blob = s.fmu.serializeFMUstate(state)
    run_steps(s, MID_BOUNCE, 60)
    assert np.array_equal(s.outputs(), ref.outputs())
    # set back, on the same instance, any number of times
    s.fmu.setFMUstate(state)
    assert np.array_equal(s.outputs(), at_state)
    run_steps(s, MID_BOUNCE, 60)
    assert np.array_equal(s.outputs(), ref.outputs())
    s.fmu.freeFMUstate(state)
    # deserialized into another instance that has run elsewhere
    other = open_fmu(fmu, name="other").init()
    run_steps(other, 0, 5)
    restored = other.fmu.deSerializeFMUstate(blob)
    other.fmu.setFMUstate(restored)
    assert np.array_equal(other.outputs(), at_state)
    run_steps(other, MID_BOUNCE, 60)
    assert np.array_equal(other.outputs(), ref.outputs())
    other.fmu.freeFMUstate(restored)


def test_state_carries_effect_parameters(dropped, open_fmu):
    fmu = dropped
    params = {"ground.stiffness": 2 * STIFFNESS, "point_mass[1].mass": 2 * PAYLOAD, "gravity.z": -8.0}
    source = open_fmu(fmu, name="source").init(params=params)
    run_steps(source, 0, MID_BOUNCE)
    blob = source.fmu.serializeFMUstate(source.fmu.getFMUstate())
    plain = open_fmu(fmu, name="plain").init()
    plain.fmu.setFMUstate(plain.fmu.deSerializeFMUstate(blob))
    assert plain.get(list(params)).tolist() == list(params.values())
    run_steps(source, MID_BOUNCE, 60)
    run_steps(plain, MID_BOUNCE, 60)
    assert np.array_equal(plain.outputs(), source.outputs())
    unchanged = open_fmu(fmu, name="unchanged").init()
    run_steps(unchanged, 0, 60)
    assert not np.array_equal(plain.outputs(), unchanged.outputs())


@pytest.mark.parametrize(
    "name, bad",
    [
        ("ground.stiffness", -1.0),
        ("ground.stiffness", 0.0),
        ("ground.damping", -5.0),
        ("ground.friction", -0.5),
        ("ground.slip_velocity", 0.0),
        ("point_mass[1].mass", float("nan")),
        ("point_mass[2].mass", -0.1),
        ("gravity.z", float("inf")),
    ],
)
def test_invalid_effect_parameter_is_an_error_and_the_instance_recovers(dropped, open_fmu, name, bad):
    fmu = dropped
    start = float(fmu.variables[name].start)
    ref = open_fmu(fmu, name="ref").init()
    run_steps(ref, 0, 30)  # through the first impact
    s = open_fmu(fmu, name="s")
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.enterInitializationMode()
    early = s.fmu.getFMUstate()
    with pytest.raises(FMICallException) as e:
        s.set({"ground.height": 0.001, name: bad})  # a valid value first
    assert e.value.status == 3  # fmi2Error
    named = [m for m in s.errors() if name in m]
    assert named, s.errors()
    print(f"\n{name} = {bad}: {named[0]}")
    assert s.get([name, "ground.height"]).tolist() == [start, 0.0]  # nothing was applied
    # a refused set leaves the instance as it was: initialization goes on
    s.fmu.exitInitializationMode()
    run_steps(s, 0, 30)
    assert np.array_equal(s.outputs(), ref.outputs())
    # recovery 1: the state saved in initialization mode
    s.fmu.setFMUstate(early)
    s.fmu.exitInitializationMode()
    run_steps(s, 0, 30)
    assert np.array_equal(s.outputs(), ref.outputs())
    s.fmu.freeFMUstate(early)
    # recovery 2: fmi2Reset, then a valid value of the same parameter is accepted
    s.fmu.reset()
    s.init(params={name: start})
    run_steps(s, 0, 30)
    assert np.array_equal(s.outputs(), ref.outputs())
