"""LQR state feedback on every force density of an FMU, stepped through fmpy's FMU2Slave API.

Works on any FMU that the project builds whose scene has force-density controlled cables
(`control = "force_density"`, such as the built-in prism2); an FMU without `cable[K].force_density`
inputs gets a one-line explanation (exit status 2). The controller is designed on the linear
model that `tensegrity-fmu linearize` writes about the FMU's start state (an equilibrium at
rest), from the scene packaged in the FMU (resources/scene.toml), so model and FMU match:

    x' = A x + B u,  y = C x + D u,

with states x the modal amplitudes `mode[k]` and rates `mode[k].rate`, inputs u and outputs y
the FMU's variable names. The gain K minimizes the integral of

    |node displacements|² / (1 cm)² + |node velocities|² / (10 cm/s)² + |Δγ|² / (2 N/m)²

over the force densities γ (the displacements and velocities of the free nodes, those without
pin reactions, through the rows of C; scipy.linalg.solve_continuous_are). At every
communication step the modal state is estimated from the measured node positions and
velocities (least squares through the same rows of C) and the command is γ = γ₀ − K x̂,
clamped to [0.1 γ₀, 3 γ₀] so every cable stays taut. A force pulse on the first loaded node
(10 N along x for 50 ms at t = 0.5 s) disturbs the structure; `--law none` holds every input
for comparison.

On prism2 the 12 cables that can move a free node span only 10 of the 12 modal force
directions about its equilibrium, so two directions are reached only through the stiffness
coupling: the slowest closed-loop mode decays at about 0.34 1/s (time constant 3 s) whatever
the weights. Over 20 s node 7 still returns to within a few hundredths of a millimetre of its
start; held inputs leave it swinging by centimetres.

    .venv/bin/python fmu/examples/lqr_controller.py prism2.fmu [--model model.json]
        [--stop 20] [--step 0.001] [--pulse 10] [--law lqr|none] [--cli PATH]
"""

import json
import shutil
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

import numpy as np
from fmpy import extract
from fmpy.fmi2 import FMU2Slave

from fmu_variables import FmuVariables, Parser, check_fmu, fail, run_main

REPO = Path(__file__).resolve().parents[2]

# LQR weights: the scale of each quantity that costs as much as the others.
DISPLACEMENT_SCALE = 0.01  # m
VELOCITY_SCALE = 0.1  # m/s
DENSITY_SCALE = 2.0  # N/m
# Clamp of the command, relative to the equilibrium force density of each cable.
DENSITY_BOUNDS = (0.1, 3.0)


def find_cli(cli=None):
    """The tensegrity-fmu executable: the given one, the repository's release build, or PATH."""
    if cli:
        if not Path(cli).is_file():
            fail(f"--cli {cli}: no such file")
        return str(cli)
    built = REPO / "target" / "release" / "tensegrity-fmu"
    if built.is_file():
        return str(built)
    found = shutil.which("tensegrity-fmu")
    if not found:
        fail("tensegrity-fmu not found: build it (cargo build --release) or pass --cli PATH")
    return found


def linearize(scene, cli, out):
    """Runs `tensegrity-fmu linearize SCENE -o out` and returns the model as a dict."""
    res = subprocess.run([cli, "linearize", str(scene), "-o", str(out)],
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if res.returncode != 0:
        lines = res.stderr.strip().splitlines() or ["no message"]
        fail(f"tensegrity-fmu linearize failed: {lines[-1]}")
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
    """u = clamp(γ₀ − K x̂), x̂ from the free nodes' positions and velocities by least squares."""

    def __init__(self, lin: LinearModel, free_nodes):
        import scipy.linalg  # only the design needs scipy

        m = lin.m
        self.positions = [n for node in free_nodes for n in FmuVariables.position(node)]
        velocities = [n for node in free_nodes for n in FmuVariables.velocity(node)]
        self.commanded = [n for n in lin.inputs if n.endswith(".force_density")]
        self.measured = self.positions + velocities
        self.u0 = np.array([lin.u0[n] for n in self.commanded])
        self.y0 = np.array([lin.y0[n] for n in self.positions])
        cp = lin.output_rows(self.positions)
        cv = lin.output_rows(velocities)
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
        n = len(self.positions)
        amplitudes = self.position_pinv @ (measured[:n] - self.y0)
        rates = self.velocity_pinv @ measured[n:]
        return np.concatenate([amplitudes, rates])

    def __call__(self, _t, measured):
        u = self.u0 - self.K @ self.estimate(measured)
        return np.clip(u, self.lower, self.upper)


class OpenLoop:
    """Every input held at its start value."""

    commanded = []
    measured = []
    u0 = np.array([])

    def __call__(self, _t, _measured):
        return np.array([])


def watched_node(fmu: FmuVariables):
    """The node that the pulse pushes and whose excursion is reported: the first loaded node,
    else the highest free one."""
    if fmu.force_input_nodes:
        return fmu.force_input_nodes[0]
    return max(fmu.free, key=lambda n: fmu.start.get(f"node[{n}].z", 0.0))


def run(fmu_path, law, stop=20.0, step=1e-3, pulse=10.0, pulse_start=0.5, pulse_width=0.05,
        report_every=1.0, out=sys.stdout):
    """Steps the FMU to `stop` with `law` at communication step `step`, a force of `pulse` N
    along x on the watched node from `pulse_start` for `pulse_width` s (when the FMU has force
    inputs). Returns times, the watched node's positions, and the smallest force density
    commanded."""
    fmu = FmuVariables(check_fmu(fmu_path))
    md, vr = fmu.md, fmu.vr
    node_id = watched_node(fmu)
    unzipdir = extract(str(fmu_path))
    slave = FMU2Slave(
        guid=md.guid,
        unzipDirectory=unzipdir,
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="lqr",
    )
    watch = [vr[n] for n in fmu.position(node_id)]
    measured_vr = [vr[n] for n in law.measured]
    commanded_vr = [vr[n] for n in law.commanded]
    force_vr = [vr[f"node[{node_id}].fx"]] if node_id in fmu.force_input_nodes else []
    n_steps = round(stop / step)
    every = max(1, round(report_every / step))
    times = np.arange(n_steps + 1) * step
    node = np.empty((n_steps + 1, 3))
    lowest = np.inf
    try:
        slave.instantiate()
        slave.setupExperiment(startTime=0.0, stopTime=stop)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        if out:
            label = f"node[{node_id}]"
            print(f"{'t [s]':>6} {label + '.x [m]':>14} {label + '.y [m]':>14} "
                  f"{label + '.z [m]':>14} {'|Δ| [mm]':>10} {'max |Δγ| [N/m]':>15}", file=out)
        for k, t in enumerate(times):
            node[k] = slave.getReal(watch)
            u = law(t, np.array(slave.getReal(measured_vr)) if measured_vr else None)
            if len(u):
                lowest = min(lowest, float(u.min()))
            if out and k % every == 0:
                d = 1e3 * np.linalg.norm(node[k] - node[0])
                change = f"{abs(u - law.u0).max():15.3f}" if len(u) else f"{'-':>15}"
                print(f"{t:6.2f} {node[k][0]:14.6f} {node[k][1]:14.6f} {node[k][2]:14.6f} "
                      f"{d:10.3f} {change}", file=out)
            if k == n_steps:
                break
            if len(u):
                slave.setReal(commanded_vr, list(u))
            if force_vr:
                force = pulse if pulse_start <= t + 1e-9 < pulse_start + pulse_width else 0.0
                slave.setReal(force_vr, [force])
            slave.doStep(currentCommunicationPoint=t, communicationStepSize=step)
        slave.terminate()
    finally:
        slave.freeInstance()
        shutil.rmtree(unzipdir, ignore_errors=True)
    return times, node, lowest


def excursion(times, node, after=0.0):
    """The watched node's largest distance from its start position (after time `after`) and
    its final distance, in m."""
    d = np.linalg.norm(node - node[0], axis=1)
    return float(d[times >= after].max()), float(d[-1])


def design(fmu_path, fmu, model=None, cli=None):
    """The LQR law on the FMU's force densities, designed on `model` (a linearize JSON) or on
    the linearization of the scene packaged in the FMU."""
    try:
        import scipy.linalg  # noqa: F401  (the Riccati solver; not in the quickstart's .venv)
    except ImportError:
        fail("the LQR design needs scipy: .venv/bin/pip install -r tests/requirements.txt "
             "(or bash tests/setup.sh)")
    if model:
        try:
            data = json.loads(Path(model).read_text())
        except (OSError, ValueError) as exc:
            fail(f"--model {model}: not a linear model from `tensegrity-fmu linearize` ({exc})")
    else:
        with tempfile.TemporaryDirectory() as tmp, zipfile.ZipFile(fmu_path) as archive:
            if "resources/scene.toml" not in archive.namelist():
                fail(f"{fmu_path} has no resources/scene.toml: pass --model from "
                     "`tensegrity-fmu linearize SCENE -o model.json`")
            scene = Path(tmp, "scene.toml")
            scene.write_bytes(archive.read("resources/scene.toml"))
            data = linearize(scene, find_cli(cli), Path(tmp, "model.json"))
    lin = LinearModel(data)
    missing = [n for n in fmu.force_density_inputs if n not in lin.inputs]
    if missing:
        fail(f"--model: {missing[0]} is an input of the FMU but not of the linear model; "
             "linearize the FMU's own scene")
    return lin, LqrLaw(lin, fmu.free)


def main(argv=None):
    ap = Parser(description=__doc__.splitlines()[0])
    ap.add_argument("fmu", help="an FMU built by tensegrity-fmu with force-density cables")
    ap.add_argument("--model", help="a linear model from `tensegrity-fmu linearize` (.json)")
    ap.add_argument("--cli", help="the tensegrity-fmu executable")
    ap.add_argument("--stop", type=float, default=20.0, help="stop time, s (default 20)")
    ap.add_argument("--step", type=float, default=1e-3, help="communication step, s")
    ap.add_argument("--pulse", type=float, default=10.0,
                    help="force along x on the first loaded node for 50 ms from t = 0.5 s, N")
    ap.add_argument("--law", choices=["lqr", "none"], default="lqr")
    args = ap.parse_args(argv)
    for option in ("stop", "step"):
        value = getattr(args, option)
        if not (np.isfinite(value) and value > 0):
            fail(f"--{option} {value:g}: must be a positive number of seconds")
    fmu = FmuVariables(check_fmu(args.fmu))
    if not fmu.force_density_inputs:
        fail(f"{args.fmu} has no force-density inputs (cable[K].force_density), the LQR's "
             "actuators: build a scene whose cables have control = \"force_density\", e.g. prism2")
    if args.law == "lqr":
        lin, law = design(args.fmu, fmu, args.model, args.cli)
        slowest = -law.closed_loop.real.max()
        print(f"LQR on {len(law.commanded)} force densities, {lin.m} modes; slowest "
              f"closed-loop decay rate {slowest:.3f} 1/s; |K| max {abs(law.K).max():.1f}")
    else:
        law = OpenLoop()
        print("open loop: every input held")
    times, node, lowest = run(args.fmu, law, args.stop, args.step, args.pulse)
    peak, final = excursion(times, node)
    print(f"node {watched_node(fmu)}: largest excursion {1e3 * peak:.3f} mm, final offset "
          f"{1e3 * final:.3f} mm (after {args.stop:g} s, step {args.step:g} s, "
          f"{args.pulse:g} N pulse)")
    if np.isfinite(lowest):
        print(f"smallest force density commanded: {lowest:.3f} N/m")
    return times, node, lowest


if __name__ == "__main__":
    run_main(main)
