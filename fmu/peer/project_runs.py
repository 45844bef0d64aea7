"""This project's side of the peer comparison: the FMU through fmpy's low-level FMU2Slave
API and the CLI's `simulate`, on the case MuJoCo runs too.

The case is the shipped scene with constant forces on its force-input nodes (tower20 with
1 N along +x on nodes 61–63, as `tensegrity-fmu bench` loads it).
"""

import ctypes
import subprocess
import tempfile
import time
import tomllib
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave, fmi2True

REPO = Path(__file__).resolve().parents[2]
CLI = REPO / "target" / "release" / "tensegrity-fmu"
METHODS = {"rk4": 1, "dopri5": 2, "rattle": 3, "sdirk3": 4}


def build_fmu(scene: str, out: Path) -> Path:
    """Packages a built-in scene (or a scene file) with the CLI."""
    subprocess.run([str(CLI), "build", scene, "-o", str(out)], check=True, capture_output=True)
    return out


@dataclass(frozen=True)
class Solver:
    """The project's solver settings (FMU parameters `solver.*`)."""

    method: str = "rk4"
    step_size: float = 1e-3
    rtol: float = 1e-6
    atol: float = 1e-9

    def label(self) -> str:
        if self.method == "dopri5":
            return f"dopri5 rtol=atol={self.rtol:g}"
        return f"{self.method} h={self.step_size * 1e3:g} ms"


class ProjectFmu:
    """One built FMU: its scene, its parameters' start values and fresh instances of it."""

    def __init__(self, path: Path):
        self.path = Path(path)
        self.md = read_model_description(str(path))
        self.dir = extract(str(path), unzipdir=str(self.path.with_suffix("")) + "_peer")
        with zipfile.ZipFile(path) as z:
            self.scene = tomllib.loads(z.read("resources/scene.toml").decode())
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.starts = {
            v.name: float(v.start)
            for v in self.md.modelVariables
            if v.causality == "parameter" and v.type == "Real"
        }
        n_nodes = len(self.scene["nodes"])
        self.position_names = [f"node[{i}].{a}" for i in range(1, n_nodes + 1) for a in "xyz"]

    def instance(self, solver: Solver, forces: dict) -> FMU2Slave:
        """An initialized instance with the solver settings and constant node forces
        {node: (fx, fy, fz)} (N), at t = 0."""
        fmu = FMU2Slave(
            guid=self.md.guid,
            unzipDirectory=self.dir,
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName="peer",
        )
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.setInteger([self.vr["solver.method"]], [METHODS[solver.method]])
        reals = {"solver.step_size": solver.step_size, "solver.rtol": solver.rtol,
                 "solver.atol": solver.atol}
        for node, f in forces.items():
            reals.update({f"node[{node}].f{a}": f[i] for i, a in enumerate("xyz")})
        fmu.setReal([self.vr[n] for n in reals], list(reals.values()))
        # One fmi2DoStep over a whole 10 s span at 1 ms takes 10,000 internal steps.
        fmu.setInteger([self.vr["solver.max_steps"]], [10_000_000])
        fmu.exitInitializationMode()
        return fmu

    def positions_reader(self, fmu: FMU2Slave):
        """A function returning the node positions (n_nodes × 3, m) now, through
        fmi2GetReal with value references and the buffer allocated once."""
        n = len(self.position_names)
        refs = (ctypes.c_uint * n)(*[self.vr[name] for name in self.position_names])
        values = (ctypes.c_double * n)()
        buffer = np.ctypeslib.as_array(values).reshape(-1, 3)

        def read() -> np.ndarray:
            """A view of the buffer: copy it to keep it past the next read."""
            fmu.fmi2GetReal(fmu.component, refs, n, values)
            return buffer

        return read

    def one_step(self, solver: Solver, forces: dict, span: float) -> float:
        """Wall time (s) of one fmi2DoStep over `span`."""
        fmu = self.instance(solver, forces)
        started = time.perf_counter()
        fmu.fmi2DoStep(fmu.component, 0.0, span, fmi2True)
        wall = time.perf_counter() - started
        fmu.terminate()
        fmu.freeInstance()
        return wall

    def sampled(self, solver: Solver, forces: dict, span: float, interval: float):
        """Steps the FMU every `interval` to `span`, reading every node position at each
        communication point. Returns (wall time s, positions: samples × nodes × 3), with
        the start as the first sample."""
        fmu = self.instance(solver, forces)
        read = self.positions_reader(fmu)
        steps = round(span / interval)
        out = np.empty((steps + 1, len(self.scene["nodes"]), 3))
        do_step, component = fmu.fmi2DoStep, fmu.component
        out[0] = read()  # copies the buffer into the preallocated table
        started = time.perf_counter()
        for k in range(steps):  # fmpy raises on a status above fmi2Warning
            do_step(component, k * interval, interval, fmi2True)
            out[k + 1] = read()
        wall = time.perf_counter() - started
        fmu.terminate()
        fmu.freeInstance()
        return wall, out


def cli_simulate(scene: str, solver: Solver, forces: dict, span: float, interval: float) -> float:
    """Process wall time (s) of `tensegrity-fmu simulate` with the forces as an inputs table;
    its CSV is written to a temporary folder and dropped."""
    names = [f"node[{n}].f{a}" for n in forces for a in "xyz"]
    values = [f[i] for f in forces.values() for i in range(3)]
    with tempfile.TemporaryDirectory(prefix="peer-cli-") as folder:
        inputs = Path(folder, "inputs.csv")
        inputs.write_text("time," + ",".join(names) + "\n0," + ",".join(map(repr, values)) + "\n")
        command = [
            str(CLI), "simulate", scene, "--time", repr(span), "--interval", repr(interval),
            "--method", solver.method, "--step-size", repr(solver.step_size),
            "--inputs", str(inputs), "-o", str(Path(folder, "run.csv")),
        ]
        started = time.perf_counter()
        subprocess.run(command, check=True, capture_output=True)
        return time.perf_counter() - started
