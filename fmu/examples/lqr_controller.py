"""LQR state feedback on all force densities of prism2, stepped through fmpy's FMU2Slave API.

Scene prism2 (the default FMU): 15 force-density controlled cables, nodes 1-3 pinned, force
inputs on nodes 7-9. The controller is designed on the linear model that
`tensegrity-fmu linearize` writes about the FMU's start state (an equilibrium at rest):

    x' = A x + B u,  y = C x + D u,

with states x the modal amplitudes `mode[k]` and rates `mode[k].rate`, inputs u and outputs y
the FMU's variable names. The gain K minimizes the integral of

    |node displacements|² / (1 cm)² + |node velocities|² / (10 cm/s)² + |Δγ|² / (2 N/m)²

over the 15 force densities γ (the displacements and velocities of the free nodes 4-9 through
the rows of C; scipy.linalg.solve_continuous_are). At every communication step the modal state
is estimated from the measured node positions and velocities (least squares through the same
rows of C) and the command is γ = γ₀ − K x̂, clamped to [0.1 γ₀, 3 γ₀] so every cable stays
taut. A force pulse on node[7].fx (10 N for 50 ms at t = 0.5 s) disturbs the structure.

The 12 cables that can move a free node span only 10 of the 12 modal force directions about
this equilibrium, so two directions are reached only through the stiffness coupling: the
slowest closed-loop mode decays at about 0.34 1/s (time constant 3 s) whatever the weights.
Over 20 s node 7 still returns to within a few hundredths of a millimetre of its start.

The old PD law on cable 14 alone (controller.py) is run with the same disturbance by `--law pd`:
it drifts away, while the LQR brings node 7 back to its start.

    .venv/bin/python fmu/examples/lqr_controller.py [prism2.fmu] [--model model.json]
        [--stop 20] [--step 0.001] [--pulse 20] [--law lqr|pd|none]

Without a .fmu the script builds prism2 with the CLI (target/release/tensegrity-fmu, or
`tensegrity-fmu` on the PATH, or --cli); without --model it linearizes the scene packaged in
the FMU (resources/scene.toml), so model and FMU always match.
"""

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import scipy.linalg
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import controller as pd_example  # noqa: E402  (the old PD law, for the comparison)

REPO = HERE.parents[1]
WATCHED = 7  # the node whose excursion is reported
FREE_NODES = range(4, 10)  # nodes 4-9 (1-3 are pinned)
POSITIONS = [f"node[{n}].{a}" for n in FREE_NODES for a in "xyz"]
VELOCITIES = [f"node[{n}].v{a}" for n in FREE_NODES for a in "xyz"]

# LQR weights: the scale of each quantity that costs as much as the others.
DISPLACEMENT_SCALE = 0.01  # m
VELOCITY_SCALE = 0.1  # m/s
DENSITY_SCALE = 2.0  # N/m
# Clamp of the command, relative to the equilibrium force density of each cable.
DENSITY_BOUNDS = (0.1, 3.0)


def find_cli(cli=None):
    """The tensegrity-fmu executable: the given one, the repository's release build, or PATH."""
    if cli:
        return str(cli)
    built = REPO / "target" / "release" / "tensegrity-fmu"
    if built.is_file():
        return str(built)
    found = shutil.which("tensegrity-fmu")
    if not found:
        sys.exit("tensegrity-fmu not found: build it (cargo build --release) or pass --cli")
    return found


def linearize(scene, cli, out):
    """Runs `tensegrity-fmu linearize SCENE -o out` and returns the model as a dict."""
    subprocess.run(
        [cli, "linearize", str(scene), "-o", str(out)],
        check=True,
        stdout=subprocess.DEVNULL,
    )
    return json.loads(Path(out).read_text())


class LinearModel:
    """The JSON of `tensegrity-fmu linearize` as numpy arrays, indexed by name."""

    def __init__(self, data):
        self.data = data
        self.states = data["states"]
        self.inputs = data["inputs"]
        self.outputs = data["outputs"]
        self.A = np.array(data["A"])
        self.B = np.array(data["B"])
        self.C = np.array(data["C"])
        self.u0 = dict(zip(self.inputs, data["input_values"]))
        self.y0 = dict(zip(self.outputs, data["output_values"]))
        self.m = len(self.states) // 2  # modes: x = (amplitudes, rates)

    def input_columns(self, names):
        return self.B[:, [self.inputs.index(n) for n in names]]

    def output_rows(self, names):
        return self.C[[self.outputs.index(n) for n in names], :]


class LqrLaw:
    """u = clamp(γ₀ − K x̂), x̂ from the node positions and velocities by least squares."""

    def __init__(self, lin: LinearModel):
        m = lin.m
        self.commanded = [n for n in lin.inputs if n.endswith(".force_density")]
        self.measured = POSITIONS + VELOCITIES
        self.u0 = np.array([lin.u0[n] for n in self.commanded])
        self.y0 = np.array([lin.y0[n] for n in POSITIONS])
        cp = lin.output_rows(POSITIONS)
        cv = lin.output_rows(VELOCITIES)
        # Positions depend on the amplitudes only, velocities on the rates only.
        assert np.allclose(cp[:, m:], 0) and np.allclose(cv[:, :m], 0)
        self.position_pinv = np.linalg.pinv(cp[:, :m])
        self.velocity_pinv = np.linalg.pinv(cv[:, m:])
        b = lin.input_columns(self.commanded)
        q = cp.T @ cp / DISPLACEMENT_SCALE**2 + cv.T @ cv / VELOCITY_SCALE**2
        r = np.eye(len(self.commanded)) / DENSITY_SCALE**2
        p = scipy.linalg.solve_continuous_are(lin.A, b, q, r)
        self.K = np.linalg.solve(r, b.T @ p)
        self.closed_loop = np.linalg.eigvals(lin.A - b @ self.K)
        self.lower = DENSITY_BOUNDS[0] * self.u0
        self.upper = DENSITY_BOUNDS[1] * self.u0

    def estimate(self, measured):
        n = len(POSITIONS)
        amplitudes = self.position_pinv @ (measured[:n] - self.y0)
        rates = self.velocity_pinv @ measured[n:]
        return np.concatenate([amplitudes, rates])

    def __call__(self, _t, measured):
        u = self.u0 - self.K @ self.estimate(measured)
        return np.clip(u, self.lower, self.upper)


class PdLaw:
    """The PD law of controller.py on cable 14 alone (the other 14 densities held)."""

    def __init__(self, start):
        self.commanded = [pd_example.CABLE]
        self.measured = [f"node[{WATCHED}].x", f"node[{WATCHED}].vx"]
        self.q0 = start[pd_example.CABLE]
        self.u0 = np.array([self.q0])

    def __call__(self, _t, measured):
        x, vx = measured
        return np.array([pd_example.pd_command(self.q0, x, vx)])


class OpenLoop:
    """Every input held at its start value."""

    commanded = []
    measured = []
    u0 = np.array([])

    def __call__(self, _t, _measured):
        return np.array([])


def run(fmu_path, law, stop=20.0, step=1e-3, pulse=10.0, pulse_start=0.5, pulse_width=0.05,
        report_every=1.0, out=sys.stdout):
    """Steps the FMU to `stop` with `law` at communication step `step`, a force of `pulse` N
    on node[7].fx from `pulse_start` for `pulse_width` s. Returns times, node 7's positions,
    and the smallest force density commanded."""
    md = read_model_description(str(fmu_path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzipdir = extract(str(fmu_path))
    fmu = FMU2Slave(
        guid=md.guid,
        unzipDirectory=unzipdir,
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="lqr",
    )
    watch = [vr[f"node[{WATCHED}].{a}"] for a in "xyz"]
    measured_vr = [vr[n] for n in law.measured]
    commanded_vr = [vr[n] for n in law.commanded]
    force_vr = [vr[f"node[{WATCHED}].fx"]]
    n_steps = round(stop / step)
    every = max(1, round(report_every / step))
    times = np.arange(n_steps + 1) * step
    node = np.empty((n_steps + 1, 3))
    lowest = np.inf
    try:
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0, stopTime=stop)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        if out:
            print(f"{'t [s]':>6} {'node[7].x [m]':>14} {'node[7].y [m]':>14} "
                  f"{'node[7].z [m]':>14} {'|Δ| [mm]':>10} {'max |Δγ| [N/m]':>15}", file=out)
        for k, t in enumerate(times):
            node[k] = fmu.getReal(watch)
            u = law(t, np.array(fmu.getReal(measured_vr)) if measured_vr else None)
            if len(u):
                lowest = min(lowest, float(u.min()))
            if out and k % every == 0:
                d = 1e3 * np.linalg.norm(node[k] - node[0])
                low = f"{abs(u - law.u0).max():15.3f}" if len(u) else f"{'-':>15}"
                print(f"{t:6.2f} {node[k][0]:14.6f} {node[k][1]:14.6f} {node[k][2]:14.6f} "
                      f"{d:10.3f} {low}", file=out)
            if k == n_steps:
                break
            if len(u):
                fmu.setReal(commanded_vr, list(u))
            force = pulse if pulse_start <= t + 1e-9 < pulse_start + pulse_width else 0.0
            fmu.setReal(force_vr, [force])
            fmu.doStep(currentCommunicationPoint=t, communicationStepSize=step)
        fmu.terminate()
    finally:
        fmu.freeInstance()
        shutil.rmtree(unzipdir, ignore_errors=True)
    return times, node, lowest


def excursion(times, node, after=0.0):
    """Node 7's largest distance from its start position (after time `after`) and its final
    distance, in m."""
    d = np.linalg.norm(node - node[0], axis=1)
    return float(d[times >= after].max()), float(d[-1])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("fmu", nargs="?", help="prism2.fmu (built with the CLI if omitted)")
    ap.add_argument("--model", help="a linear model from `tensegrity-fmu linearize` (.json)")
    ap.add_argument("--cli", help="the tensegrity-fmu executable")
    ap.add_argument("--stop", type=float, default=20.0, help="stop time, s (default 20)")
    ap.add_argument("--step", type=float, default=1e-3, help="communication step, s")
    ap.add_argument("--pulse", type=float, default=10.0,
                    help="force on node[7].fx for 50 ms from t = 0.5 s, N (default 10)")
    ap.add_argument("--law", choices=["lqr", "pd", "none"], default="lqr")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        fmu_path = args.fmu
        if fmu_path is None:
            fmu_path = tmp / "prism2.fmu"
            subprocess.run([find_cli(args.cli), "build", "prism2", "-o", str(fmu_path)],
                           check=True, stdout=subprocess.DEVNULL)
        md = read_model_description(str(fmu_path))
        start = {v.name: float(v.start) for v in md.modelVariables if v.causality == "input"}
        if args.law == "lqr":
            if args.model:
                data = json.loads(Path(args.model).read_text())
            else:
                scene = extract(str(fmu_path), unzipdir=str(tmp / "fmu"))
                data = linearize(Path(scene, "resources", "scene.toml"), find_cli(args.cli),
                                 tmp / "model.json")
            lin = LinearModel(data)
            law = LqrLaw(lin)
            slowest = -law.closed_loop.real.max()
            print(f"LQR on {len(law.commanded)} force densities, {lin.m} modes; slowest "
                  f"closed-loop decay rate {slowest:.3f} 1/s; |K| max {abs(law.K).max():.1f}")
        elif args.law == "pd":
            law = PdLaw(start)
            print(f"PD law of controller.py on {pd_example.CABLE}")
        else:
            law = OpenLoop()
            print("open loop: every input held")
        times, node, lowest = run(fmu_path, law, args.stop, args.step, args.pulse)
    peak, final = excursion(times, node)
    print(f"node 7: largest excursion {1e3 * peak:.3f} mm, final offset {1e3 * final:.3f} mm "
          f"(after {args.stop:g} s, step {args.step:g} s, {args.pulse:g} N pulse)")
    if np.isfinite(lowest):
        print(f"smallest force density commanded: {lowest:.3f} N/m")
    return times, node, lowest


if __name__ == "__main__":
    main()
