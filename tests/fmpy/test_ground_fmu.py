"""Ground contact and support reactions through the FMU (the fmpy twin of tests/ground.rs).

1. The dropped icosahedron of tests/ground.rs (with payloads on its three feet) comes to
   rest on three contacts through the FMU; the contact outputs carry the weight, and the run
   is the CLI's `simulate` run of the same scene.
2. Support reactions balance the weights, scripted loads and force inputs of a structure
   at rest.

Expected values come from the scenes and from statics (W = M g, d = W / (3 k) on three
symmetric contacts), never from recorded outputs. Figures are printed (run with -s).
"""

import subprocess
from pathlib import Path

import numpy as np
import pytest

from effects_scenes import (
    COMM,
    FACE,
    FRICTION,
    G,
    SETTLE,
    SLIP,
    STEP,
    STIFFNESS,
    contact_names,
    dropped_fmu,
    node_names,
    resting,
    settle,
    to_toml,
    total_mass,
)


@pytest.fixture(scope="module")
def dropped(fmus):
    return dropped_fmu(fmus)


# --- 1. the dropped icosahedron ------------------------------------------------------


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


# --- 2. support reactions ------------------------------------------------------------

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


