"""Shared scenes and helpers of the effects tests (test_effects.py, test_ground_fmu.py):
a TOML writer for scene dicts, the dropped icosahedron of tests/ground.rs and the
prism2-elastic scene with every effect, the variables a scene calls for, and the cached
settling runs of the dropped icosahedron.

Expected values come from the scenes and from statics (W = M g, d = W / (3 k) on three
symmetric contacts), never from recorded outputs.
"""

import time

import numpy as np

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


def dropped_fmu(fmus):
    """The dropped icosahedron, built from the built-in one."""
    ico = fmus.builtin("icosahedron")
    fmu = fmus.from_toml(to_toml(dropped_scene(ico.scene)))
    assert fmu.scene["ground"]["stiffness"] == STIFFNESS
    return fmu


# --- settling runs, cached per session (SETTLE s of simulated time each) -------------

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


# --- the scene with every effect -----------------------------------------------------


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


# --- the variables a scene calls for (test_model_description.py, test_effects.py) ------


def expected_variables(scene):
    """name -> (causality, unit) of every variable, from the scene alone: the variables of
    issue 3, then the effects' parameters and outputs (gravity, payloads, ground contact,
    scripted loads) when the scene has them."""
    out = {}
    n_nodes = len(scene["nodes"])
    for i in range(1, n_nodes + 1):
        for c in "xyz":
            out[f"node[{i}].{c}"] = ("output", "m")
            out[f"node[{i}].v{c}"] = ("output", "m/s")
    for j, cable in enumerate(scene.get("cables", []), start=1):
        out[f"cable[{j}].tension"] = ("output", "N")
        if cable.get("control") == "force_density":
            out[f"cable[{j}].force_density"] = ("input", "N/m")
        else:
            out[f"cable[{j}].stiffness"] = ("parameter", "N/m")
            if cable.get("control") == "rest_length":
                out[f"cable[{j}].rest_length"] = ("input", "m")
            else:
                out[f"cable[{j}].rest_length"] = ("parameter", "m")
            if "damping" in cable:
                out[f"cable[{j}].damping"] = ("parameter", "N.s/m")
    for k in range(1, len(scene["bars"]) + 1):
        out[f"bar[{k}].force"] = ("output", "N")
        out[f"bar[{k}].mass"] = ("parameter", "kg")
    for i in scene.get("force_inputs", []):
        for c in "xyz":
            out[f"node[{i}].f{c}"] = ("input", "N")
    for i in scene.get("fixed", []):
        for c in "xyz":
            out[f"node[{i}].reaction_{c}"] = ("output", "N")
    out["constraint.length_error"] = ("output", "m")
    out["constraint.orthogonality_error"] = ("output", "m2/s")
    out["energy.total"] = ("output", "J")
    out["solver.step_size"] = ("parameter", "s")
    out["solver.correction"] = ("parameter", None)
    out["solver.locate_events"] = ("parameter", None)
    out["solver.method"] = ("parameter", None)
    out["solver.max_steps"] = ("parameter", None)
    out["solver.rtol"] = ("parameter", None)
    out["solver.atol"] = ("parameter", None)
    # the effects
    if "gravity" in scene:
        for c in "xyz":
            out[f"gravity.{c}"] = ("parameter", "m/s2")
    for k, _ in enumerate(scene.get("point_masses", []), start=1):
        out[f"point_mass[{k}].mass"] = ("parameter", "kg")
    if "ground" in scene:
        pinned = set(scene.get("fixed", []))
        bar_ends = {e for b in scene["bars"] for e in b["nodes"]}
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
    return out
