"""The optional effects through the FMU: ground contact, point masses (payloads), gravity and
scripted-load parameters, support reactions (the fmpy twin of tests/ground.rs,
tests/point_masses.rs and tests/effects.rs).

1. A scene with every effect builds an FMU that fmpy validates, with the effect parameters
   and outputs (and their units) in its modelDescription.
2. The dropped icosahedron of tests/ground.rs (with payloads on its three feet) comes to
   rest on three contacts through the FMU; the contact outputs carry the weight, and the run
   is the CLI's `simulate` run of the same scene.
3. The effect parameters act: a stiffer ground, a heavier payload, a weaker gravity, each
   set in initialization mode, change the resting state as statics predicts.
4. Support reactions balance the weights, scripted loads and force inputs of a structure
   at rest.
5. The FMU state mid-bounce resumes bit-identically; invalid effect parameters are errors
   naming the variable, and the instance recovers.

Expected values come from the scenes and from statics (W = M g, d = W / (3 k) on three
symmetric contacts), never from recorded outputs. Figures are printed (run with -s).
"""

import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from conftest import Slave

G = 9.81  # m/s²

# --- scene helpers ---------------------------------------------------------------------


def toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        return repr(float(v))  # shortest round-trip text: the FMU reads the same double
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, (list, tuple, np.ndarray)):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(f"no TOML for {v!r}")


def to_toml(scene: dict) -> str:
    """TOML text of a scene dict: keys, then tables, then arrays of tables."""
    head, tables, arrays = [], [], []
    for key, value in scene.items():
        if isinstance(value, dict):
            tables += ["", f"[{key}]"] + [f"{k} = {toml_value(x)}" for k, x in value.items()]
        elif isinstance(value, list) and value and all(isinstance(x, dict) for x in value):
            for item in value:
                arrays += ["", f"[[{key}]]"] + [f"{k} = {toml_value(x)}" for k, x in item.items()]
        else:
            head.append(f"{key} = {toml_value(value)}")
    return "\n".join(head + arrays + tables) + "\n"


def rotation_between(a, b):
    """The rotation by the smallest angle taking direction a to direction b (Rodrigues)."""
    a = np.asarray(a, float) / np.linalg.norm(a)
    b = np.asarray(b, float) / np.linalg.norm(b)
    axis = np.cross(a, b)
    s, c = np.linalg.norm(axis), float(a @ b)
    k = axis / s
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + s * K + (1 - c) * K @ K


# The dropped icosahedron (tests/ground.rs): 6 bars of 1 kg, prestressed elastic cables,
# no pins, cable face 1-5-9 down, cable damping 30 N·s/m, ground k = 1e4 N/m, c = 100 N·s/m,
# μ = 0.5, rk4. Payloads of 0.25 kg on the three feet (nodes 1, 5, 9) keep the three-fold
# symmetry about the vertical, so each contact carries W/3 at rest. (On the top face,
# nodes 4, 8, 12, they squash the soft icosahedron until nodes 3, 7, 11 touch down too:
# six unequal contacts, measured.)
STIFFNESS = 1e4
CONTACT_DAMPING = 100.0
FRICTION = 0.5
SLIP = 0.01
CABLE_DAMPING = 30.0
PAYLOAD = 0.25
PAYLOAD_NODES = (1, 5, 9)
FACE = (1, 5, 9)
DROP = 0.3  # m, lowest node above the ground
# The FMU's guard bounds the contact rate by the viscous friction μ W w / v_s
# (w = 4 kg⁻¹, the bar end's compliance): 0.5 · 66.2 N · 4 / 0.01 = 1.3e4 s⁻¹, so rk4
# takes h ≤ 2√2 / 1.3e4 = 2.1e-4 s. 0.2 ms, as in tests/ground.rs.
STEP = 2e-4
COMM = 0.01  # s, communication step
# Simulated time of every settling run, s. The base drop is at rest to 4e-8 m/s after 16 s
# (as in tests/ground.rs), but the parameter variations bounce differently: with
# gravity.z = -5 the sum of the contact forces is still 3.6e-5 off the weight at 16 s,
# 7.5e-9 at 30 s (measured). A run takes ~0.3 s of wall time.
SETTLE = 30.0


def dropped_scene(icosahedron: dict) -> dict:
    s = {k: v for k, v in icosahedron.items() if k not in ("fixed", "force_inputs", "solver")}
    s["name"] = "icosahedron-dropped"
    s["description"] = "the built-in icosahedron dropped on a ground (tests/fmpy/test_effects.py)"
    turn = rotation_between([1.0, 1.0, 1.0], [0.0, 0.0, -1.0])
    nodes = np.array(icosahedron["nodes"], float) @ turn.T
    nodes[:, 2] += DROP - nodes[:, 2].min()
    s["nodes"] = [[float(c) for c in p] for p in nodes]
    s["gravity"] = [0.0, 0.0, -G]
    s["cables"] = [dict(c, damping=CABLE_DAMPING) for c in icosahedron["cables"]]
    s["point_masses"] = [{"node": n, "mass": PAYLOAD} for n in PAYLOAD_NODES]
    s["ground"] = {
        "height": 0.0,
        "normal": [0.0, 0.0, 1.0],
        "stiffness": STIFFNESS,
        "damping": CONTACT_DAMPING,
        "friction": FRICTION,
        "slip_velocity": SLIP,
    }
    s["solver"] = {"step_size": STEP, "method": "rk4", "correction": True}
    return s


def total_mass(scene: dict) -> float:
    return sum(b["mass"] for b in scene["bars"]) + sum(p["mass"] for p in scene.get("point_masses", []))


def contact_names(fmu):
    return [n for n in fmu.outputs if n.endswith(".contact_force")]


def node_names(fmu, suffixes):
    n = len(fmu.scene["nodes"])
    return [f"node[{i}].{c}" for i in range(1, n + 1) for c in suffixes]


@pytest.fixture(scope="module")
def dropped(fmus):
    ico = fmus.builtin("icosahedron")
    fmu = fmus.from_toml(to_toml(dropped_scene(ico.scene)))
    assert fmu.scene["ground"]["stiffness"] == STIFFNESS
    return fmu


# --- settling runs, cached per module (SETTLE s of simulated time each) --------------

_runs = {}


def settle(fmu, params=()):
    """Runs the FMU for SETTLE s in doSteps of COMM, parameters set in initialization mode.
    Returns (final outputs by name, every output at every communication point, wall time
    of the doSteps, logged messages); cached per FMU and parameters."""
    key = (str(fmu.path), tuple(params))
    if key not in _runs:
        s = Slave(fmu, name="settle")
        try:
            s.init(params=dict(params))
            vrs = s.vrs(fmu.outputs)
            rows = [s.fmu.getReal(vrs)]
            t0 = time.perf_counter()
            for k in range(round(SETTLE / COMM)):
                s.fmu.doStep(k * COMM, COMM)
                rows.append(s.fmu.getReal(vrs))
            wall = time.perf_counter() - t0
            for name, value in params:
                assert s.get([name])[0] == value, name
            messages = list(s.messages)
        finally:
            s.free()
        _runs[key] = (dict(zip(fmu.outputs, rows[-1])), np.array(rows), wall, messages)
    return _runs[key]


def resting(fmu, final):
    """What a settled run shows: contact forces, ground force, positions, speeds."""
    contact = np.array([final[n] for n in contact_names(fmu)])
    ground = np.array([final[f"ground.force_{c}"] for c in "xyz"])
    z = np.array([final[n] for n in node_names(fmu, "z")])
    v = np.array([final[n] for n in node_names(fmu, ("vx", "vy", "vz"))]).reshape(-1, 3)
    return contact, ground, z, float(np.max(np.linalg.norm(v, axis=1)))


# --- 1. every effect: validation and modelDescription --------------------------------


def everything_scene(base: dict) -> dict:
    """prism2-elastic (pins 1-3, force inputs 7-9, prestress) with every effect: gravity,
    a ground, payloads, the three kinds of scripted load, cable damping, a force-density
    cable (14) and a reeled rest-length cable (15)."""
    s = dict(base)
    s["name"] = "prism2-everything"
    s["description"] = "prism2-elastic with every optional effect (tests/fmpy/test_effects.py)"
    cables = [dict(c) for c in base["cables"]]
    for j, c in enumerate(cables[:13], start=1):
        if j % 2:
            c["damping"] = 2.0
    cables[13] = {"nodes": cables[13]["nodes"], "control": "force_density"}
    cables[14] = dict(cables[14], control="rest_length", damping=1.5)
    s["cables"] = cables
    s["gravity"] = [0.0, 0.0, -G]
    s["point_masses"] = [{"node": 7, "mass": 0.2}, {"node": 9, "mass": 0.3}]
    s["loads"] = [
        {"kind": "constant", "node": 4, "force": [1.0, 0.0, 0.0]},
        {"kind": "sinusoidal", "node": 5, "amplitude": [0.0, 2.0, 0.0], "frequency": 1.5, "phase": 0.3},
        {"kind": "step", "node": 6, "force": [0.0, 0.0, -1.0], "time": 0.05},
    ]
    s["ground"] = {
        "height": -0.05,
        "normal": [0.0, 0.0, 1.0],
        "stiffness": 1e4,
        "damping": 50.0,
        "friction": 0.4,
        "slip_velocity": 0.01,
    }
    # friction rate 0.4 · 63.8 N · 4 kg⁻¹ / 0.01 m/s = 1.0e4 s⁻¹: rk4 needs h ≤ 2.8e-4 s
    s["solver"] = {"step_size": 2.5e-4, "method": "rk4", "correction": True}
    return s


def expected_effect_variables(scene: dict) -> dict:
    """name -> (causality, unit) of every variable, from the scene alone."""
    out = {}
    n = len(scene["nodes"])
    pinned = set(scene.get("fixed", []))
    bar_ends = {e for b in scene["bars"] for e in b["nodes"]}
    for i in range(1, n + 1):
        for c in "xyz":
            out[f"node[{i}].{c}"] = ("output", "m")
            out[f"node[{i}].v{c}"] = ("output", "m/s")
    for j, c in enumerate(scene["cables"], start=1):
        out[f"cable[{j}].tension"] = ("output", "N")
        control = c.get("control")
        if control == "force_density":
            out[f"cable[{j}].force_density"] = ("input", "N/m")
            continue
        out[f"cable[{j}].stiffness"] = ("parameter", "N/m")
        if control == "rest_length":
            out[f"cable[{j}].rest_length"] = ("input", "m")
        else:
            out[f"cable[{j}].rest_length"] = ("parameter", "m")
        if "damping" in c:
            out[f"cable[{j}].damping"] = ("parameter", "N.s/m")
    for k in range(1, len(scene["bars"]) + 1):
        out[f"bar[{k}].force"] = ("output", "N")
        out[f"bar[{k}].mass"] = ("parameter", "kg")
    for i in scene.get("force_inputs", []):
        for c in "xyz":
            out[f"node[{i}].f{c}"] = ("input", "N")
    out["constraint.length_error"] = ("output", "m")
    out["constraint.orthogonality_error"] = ("output", "m2/s")
    out["energy.total"] = ("output", "J")
    for name, unit in [("step_size", "s"), ("correction", None), ("method", None), ("rtol", None), ("atol", None)]:
        out[f"solver.{name}"] = ("parameter", unit)
    # the effects
    if "gravity" in scene:
        for c in "xyz":
            out[f"gravity.{c}"] = ("parameter", "m/s2")
    for k, _ in enumerate(scene.get("point_masses", []), start=1):
        out[f"point_mass[{k}].mass"] = ("parameter", "kg")
    if "ground" in scene:
        for name, unit in [("height", "m"), ("stiffness", "N/m"), ("damping", "N.s/m"),
                           ("friction", None), ("slip_velocity", "m/s")]:
            out[f"ground.{name}"] = ("parameter", unit)
        for i in sorted(bar_ends - pinned):
            out[f"node[{i}].contact_force"] = ("output", "N")
        for c in "xyz":
            out[f"ground.force_{c}"] = ("output", "N")
    for k, load in enumerate(scene.get("loads", []), start=1):
        for c in "xyz":
            out[f"load[{k}].f{c}"] = ("parameter", "N")
        if load["kind"] == "sinusoidal":
            out[f"load[{k}].frequency"] = ("parameter", "Hz")
            out[f"load[{k}].phase"] = ("parameter", "rad")
        if load["kind"] == "step":
            out[f"load[{k}].time"] = ("parameter", "s")
    for i in sorted(pinned):
        for c in "xyz":
            out[f"node[{i}].reaction_{c}"] = ("output", "N")
    return out


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
    expected = expected_effect_variables(scene)
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
    expected = expected_effect_variables(scene)
    want = sorted(n for n, (c, _) in expected.items()
                  if c == "output" and (".contact_force" in n or n.startswith("ground.force_") or ".reaction_" in n))
    assert sorted(fmu.outputs) == want
    assert len(want) == 6 + 3 + 9


# --- 2. the dropped icosahedron ------------------------------------------------------


def test_dropped_icosahedron_comes_to_rest_and_matches_cli(dropped, cli, tmp_path):
    fmu = dropped
    scene = fmu.scene
    mass = total_mass(scene)
    weight = mass * G
    final, rows, wall, messages = settle(fmu)
    assert [m for _, c, m in messages if c != "logEvents"] == []  # the guard accepts 0.2 ms
    contact, ground, z, speed = resting(fmu, final)
    d_static = weight / (3 * STIFFNESS)
    touching = [n for n, f in zip(contact_names(fmu), contact) if f > 0]
    print(
        f"\ndropped icosahedron ({mass} kg, W = {weight:.4f} N) after {SETTLE} s in "
        f"{round(SETTLE / COMM)} doSteps of {COMM} s (rk4 {STEP} s, {wall:.2f} s wall): "
        f"max speed {speed:.2e} m/s; sum of contact forces {contact.sum():.9f} N "
        f"(rel. to W {contact.sum() / weight - 1:.2e}), ground.force = ({ground[0]:.2e}, "
        f"{ground[1]:.2e}, {ground[2]:.9f}) N; contacts {touching}; min z {z.min():.6e} m vs "
        f"-W/(3k) = {-d_static:.6e} m"
    )
    assert speed <= 1e-8
    assert abs(contact.sum() - weight) <= 1e-6 * weight
    assert abs(ground[2] - weight) <= 1e-6 * weight
    assert abs(ground[2] - contact.sum()) <= 1e-9 * weight  # level ground: z is all normal force
    assert np.hypot(ground[0], ground[1]) <= FRICTION * weight * speed / SLIP + 1e-9 * weight
    # three symmetric contacts on the face 1-5-9, each at W/3 and d = W/(3k)
    assert touching == [f"node[{n}].contact_force" for n in FACE]
    for n in FACE:
        assert final[f"node[{n}].contact_force"] == pytest.approx(weight / 3, rel=1e-6)
        assert final[f"node[{n}].z"] == pytest.approx(-d_static, rel=1e-5)
    assert z.min() >= -d_static * (1 + 1e-5)
    assert np.max(rows[:, fmu.outputs.index("constraint.length_error")]) <= 1e-12
    # it bounced: the contact force peaked far above the weight at the impact
    peak = np.max(rows[:, [fmu.outputs.index(n) for n in contact_names(fmu)]].sum(axis=1))
    assert peak > 2 * weight

    # the CLI's `simulate` on the scene the FMU carries, one row per communication point
    out = tmp_path / "dropped.csv"
    subprocess.run(
        [str(cli), "simulate", str(Path(fmu.dir, "resources", "scene.toml")), "--time", str(SETTLE),
         "--interval", str(COMM), "-o", str(out)],
        check=True, capture_output=True,
    )
    csv = np.genfromtxt(out, delimiter=",", names=True, deletechars="", dtype=float)
    assert len(csv) == len(rows)
    times = COMM * np.arange(len(rows))
    assert np.max(np.abs(csv["time"] - times)) <= 1e-12
    worst, worst_name, identical = 0.0, None, 0
    for i, name in enumerate(fmu.outputs):
        diff = np.max(np.abs(rows[:, i] - csv[name]))
        scale = max(1.0, np.max(np.abs(csv[name])))
        identical += bool(np.array_equal(rows[:, i], csv[name]))
        if diff / scale > worst:
            worst, worst_name = diff / scale, name
    print(f"FMU vs CLI simulate: {identical} of {len(fmu.outputs)} outputs bit-identical at "
          f"{len(rows)} points; worst scaled difference {worst:.2e} ({worst_name})")
    assert worst <= 1e-12, worst_name


# --- 3. the effect parameters act ----------------------------------------------------


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


# --- 4. support reactions ------------------------------------------------------------

REACTION_DAMPING = 100.0  # N·s/m on every cable: prism2-elastic settles to 2e-11 W in 30 s
REACTION_SETTLE = 30.0


def test_prestressed_prism_at_rest_has_no_support_reactions(fmus, open_fmu):
    # The self-stress is in equilibrium at every node, pinned ones included.
    fmu = fmus.builtin("prism2")
    s = open_fmu(fmu).init()
    names = [f"node[{i}].reaction_{c}" for i in fmu.scene["fixed"] for c in "xyz"]
    assert len(names) == 9 and all(n in fmu.outputs for n in names)
    r0 = s.get(names)
    s.run(100, 0.001)
    r1 = s.get(names)
    tension = s.get([f"cable[{j}].tension" for j in range(1, 16)]).max()
    print(f"\nprism2 at rest: largest reaction {np.abs(r0).max():.2e} N at t = 0, "
          f"{np.abs(r1).max():.2e} N at 0.1 s (largest tension {tension:.2f} N)")
    assert np.abs(r0).max() <= 1e-12 * tension
    assert np.abs(r1).max() <= 1e-12 * tension


def test_support_reactions_carry_weights_loads_and_inputs_at_rest(fmus, open_fmu):
    base = fmus.builtin("prism2-elastic").scene
    scene = dict(base)
    scene["name"] = "prism2-elastic-reactions"
    scene["gravity"] = [0.0, 0.0, -G]
    scene["cables"] = [dict(c, damping=REACTION_DAMPING) for c in base["cables"]]
    scene["point_masses"] = [{"node": 7, "mass": 0.5}]
    scene["loads"] = [{"kind": "constant", "node": 8, "force": [2.0, -1.0, 3.0]}]
    fmu = fmus.from_toml(to_toml(scene))
    inputs = {"node[9].fx": -1.5, "node[9].fz": 2.0}
    s = open_fmu(fmu).init(inputs=inputs)
    weight = total_mass(scene) * G
    external = np.array([2.0 - 1.5, -1.0, 3.0 + 2.0 - weight])  # loads + inputs + weights
    names = [f"node[{i}].reaction_{c}" for i in scene["fixed"] for c in "xyz"]
    speeds = node_names(fmu, ("vx", "vy", "vz"))
    s.run(round(REACTION_SETTLE / COMM), COMM)
    reactions = s.get(names).reshape(3, 3)
    residual = reactions.sum(axis=0) + external
    speed = np.abs(s.get(speeds)).max()
    print(
        f"\nprism2-elastic under gravity ({total_mass(scene)} kg), a scripted load and an input, "
        f"after {REACTION_SETTLE} s: sum of reactions {reactions.sum(axis=0)} N, "
        f"|sum + loads + inputs + weights| = {np.abs(residual).max():.2e} N "
        f"({np.abs(residual).max() / weight:.2e} W), max velocity {speed:.2e} m/s"
    )
    assert speed <= 1e-6
    # Newton for the whole structure at rest: the pins take what the rest puts on it.
    assert np.abs(residual).max() <= 1e-6 * weight
    # and the pins carry the weight upward, each a share of it
    assert reactions.sum(axis=0)[2] == pytest.approx(weight - 5.0, rel=1e-6)
    assert np.all(reactions[:, 2] > 0)


# --- 5. FMU state with contact; invalid effect parameters ----------------------------

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
    with pytest.raises(FMICallException):
        s.fmu.exitInitializationMode()  # the instance is in the error state
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
