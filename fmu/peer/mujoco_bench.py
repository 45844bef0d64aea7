"""Peer benchmark: this project against MuJoCo on tower20 (issue 14, item 4).

    .venv/bin/python fmu/peer/mujoco_bench.py [--repeats 5] [--span 2.0]

Both engines run the identical case: the shipped tower20 (60 bars, 123 elastic cables,
prestressed, bottom ring pinned, no gravity) with 1 N along +x on its top nodes 61–63 (the
load `tensegrity-fmu bench` puts on it). The MuJoCo model is written from the scene the
FMU ships and the FMU's parameters (`mujoco_model.py`). Prints
1. what 10 s at 1 ms costs: the CLI, the FMU in one fmi2DoStep, the FMU stepped at 1 ms
   reading every node position after each step, MuJoCo implicitfast and RK4
   (`mujoco.rollout`; the bars as free bodies joined by connect equalities, and as a tree
   of ball joints), best of interleaved repeats in this process, and the ratios;
2. a work-precision table over a shorter span: each engine's error in node positions
   against the project's tight dopri5 run and against its own tightest run, and the least
   wall time that reaches 1e-3, 1e-5 and 1e-7 m.
Needs `cargo build --release --workspace` (and fmu/build-binary.sh) first.
"""

import argparse
import os
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
from mujoco import rollout

sys.path.insert(0, str(Path(__file__).resolve().parent))
import mujoco_model  # noqa: E402
from mujoco_model import MujocoSettings, Structure  # noqa: E402
from project_runs import ProjectFmu, Solver, build_fmu, cli_simulate  # noqa: E402

SCENE = "tower20"
TOP_LOAD = (1.0, 0.0, 0.0)  # N on each force-input node, as `tensegrity-fmu bench` applies
TIMING_SPAN, TIMING_STEP = 10.0, 1e-3
SAMPLE_INTERVAL = 0.01  # s between the positions compared in the work-precision sweep
TARGETS = (1e-3, 1e-5, 1e-7)  # m
# The bars as free bodies held by connect equalities (the general mapping), and as a tree
# of ball joints (exact joints; a tower's bars form one, so it needs no equalities).
JOINTS = ("equality", "tree")


def mujoco_name(integrator: str, joints: str) -> str:
    return f"MuJoCo {integrator}" + (", ball-joint tree" if joints == "tree" else "")


@dataclass
class Case:
    """Everything both engines need, built once."""

    fmu: ProjectFmu
    structure: Structure
    forces: dict

    def mujoco_model(self, integrator: str, timestep: float, joints: str) -> mujoco.MjModel:
        settings = MujocoSettings(timestep=timestep, integrator=integrator, joints=joints)
        return mujoco_model.build(self.structure, settings)


def prepare(folder: Path) -> Case:
    fmu = ProjectFmu(build_fmu(SCENE, folder / f"{SCENE}.fmu"))
    structure = Structure(fmu.scene, fmu.starts)
    forces = {node: TOP_LOAD for node in fmu.scene["force_inputs"]}
    return Case(fmu, structure, forces)


def mujoco_rollout(case: Case, model: mujoco.MjModel, span: float):
    """(wall time s, states after each step) of one rollout from the start over `span`."""
    data = mujoco.MjData(model)
    start = mujoco_model.initial_state(model)[None]
    control = mujoco_model.controls(case.structure, case.forces)[None, None, :]
    steps = round(span / model.opt.timestep)
    states = np.empty((1, steps, start.shape[1]))
    started = time.perf_counter()
    rollout.rollout(model, data, start, control, nstep=steps, state=states)
    return time.perf_counter() - started, states[0]


def mujoco_positions(case: Case, model: mujoco.MjModel, span: float, interval: float):
    """(wall time s, node positions at every `interval`: samples × nodes × 3)."""
    wall, states = mujoco_rollout(case, model, span)
    reader = mujoco_model.NodeReader(model, case.structure)
    every = round(interval / model.opt.timestep)
    samples = [mujoco_model.initial_state(model)] + list(states[every - 1 :: every])
    return wall, np.array([reader.positions(s) for s in samples])


# --- 1. cost of 10 s at 1 ms ------------------------------------------------------------


def timing_runs(case: Case):
    """name -> a function returning the wall time (s) of 10 s of tower20 at 1 ms."""
    rk4 = Solver("rk4", step_size=TIMING_STEP)
    span = TIMING_SPAN
    runs = {
        "project CLI `simulate` (rk4)": lambda: cli_wall(case, rk4),
        "project FMU, one fmi2DoStep of 10 s (rk4)": lambda: case.fmu.one_step(rk4, case.forces, span),
        "project FMU, 1 ms doSteps + getReal of 189 positions (rk4)": lambda: case.fmu.sampled(
            rk4, case.forces, span, TIMING_STEP
        )[0],
    }
    for joints in JOINTS:
        for integrator in ("implicitfast", "RK4"):
            model = case.mujoco_model(integrator, TIMING_STEP, joints)
            runs[f"{mujoco_name(integrator, joints)} (rollout)"] = (
                lambda model=model: mujoco_rollout(case, model, span)[0]
            )
    return runs


def cli_wall(case: Case, solver: Solver) -> float:
    """The CLI's time stepping: a 10 s run's process wall time less a one-step run's (start-up,
    scene loading and the prestress solve). Rows only at 0 and 10 s."""
    full = cli_simulate(SCENE, solver, case.forces, TIMING_SPAN, TIMING_SPAN)
    startup = cli_simulate(SCENE, solver, case.forces, solver.step_size, solver.step_size)
    return full - startup


def best_interleaved(runs: dict, repeats: int) -> dict:
    best = {name: float("inf") for name in runs}
    for _ in range(repeats):
        for name, run in runs.items():
            best[name] = min(best[name], run())
    return best


def print_timing(best: dict, repeats: int):
    steps = round(TIMING_SPAN / TIMING_STEP)
    print(f"## tower20, {TIMING_SPAN:g} s at {TIMING_STEP * 1e3:g} ms ({steps} steps), "
          f"1 N +x on nodes 61-63; best of {repeats} interleaved repeats\n")
    print("| run | wall (s) | µs/step |")
    print("|---|---:|---:|")
    for name, wall in best.items():
        print(f"| {name} | {wall:.4f} | {wall / steps * 1e6:.1f} |")
    project = [n for n in best if n.startswith("project")]
    peers = [n for n in best if n.startswith("MuJoCo")]
    print("\nMuJoCo / project (wall-time ratio; above 1: the project is faster)\n")
    print("| MuJoCo \\ project | " + " | ".join(["CLI", "FMU one doStep", "FMU 1 ms + getReal"]) + " |")
    print("|---|" + "---:|" * len(project))
    for peer in peers:
        ratios = " | ".join(f"{best[peer] / best[p]:.1f}" for p in project)
        print(f"| {peer} | {ratios} |")
    print("\nCLI: process wall time of the 10 s run less that of a one-step run "
          "(start-up, scene load, prestress solve); FMU and MuJoCo: the stepping alone "
          "(instantiation and model compilation excluded). A step is 4 evaluations for the "
          "project's rk4 (plus its exact correction) and MuJoCo's RK4, 1 for implicitfast. "
          "MuJoCo's rollout keeps the full state of every step.")


def print_mujoco_profile(case: Case, steps: int = 2000, repeats: int = 3):
    """Where a MuJoCo implicitfast step goes: MuJoCo's own timers over mj_step calls, from
    the fastest of a few interleaved repeats."""
    parts = {
        "step": mujoco.mjtTimer.mjTIMER_STEP,
        "position (kinematics, tendon Jacobians, constraint rows)": mujoco.mjtTimer.mjTIMER_POSITION,
        "velocity": mujoco.mjtTimer.mjTIMER_VELOCITY,
        "constraint solver": mujoco.mjtTimer.mjTIMER_CONSTRAINT,
        "integration (advance)": mujoco.mjtTimer.mjTIMER_ADVANCE,
    }
    models = {joints: case.mujoco_model("implicitfast", TIMING_STEP, joints) for joints in JOINTS}
    best = {}
    for _ in range(repeats):
        for joints, model in models.items():
            data = mujoco.MjData(model)
            data.ctrl[:] = mujoco_model.controls(case.structure, case.forces)
            for _ in range(steps):
                mujoco.mj_step(model, data)
            times = [data.timer[t].duration / data.timer[t].number * 1e6 for t in parts.values()]
            if joints not in best or times[0] < best[joints][0]:
                best[joints] = times
    print(f"\nWhere MuJoCo's implicitfast step goes (its timers, µs per step, {steps} mj_step "
          f"calls from Python, fastest of {repeats}):\n")
    print("| model | nv | equalities | " + " | ".join(parts) + " |")
    print("|---|---:|---:|" + "---:|" * len(parts))
    for joints, model in models.items():
        cells = " | ".join(f"{t:.1f}" for t in best[joints])
        print(f"| {mujoco_name('implicitfast', joints)} | {model.nv} | {model.neq} | {cells} |")


# --- 2. work-precision ----------------------------------------------------------------


@dataclass
class Run:
    engine: str
    setting: str
    wall: float
    positions: np.ndarray


def max_error(a: np.ndarray, b: np.ndarray) -> float:
    """Largest node distance over nodes and sample times, m."""
    return float(np.linalg.norm(a - b, axis=2).max())


def project_sweep(case: Case, span: float, repeats: int) -> list:
    solvers = [Solver("rk4", step_size=h) for h in (10e-3, 5e-3, 2.5e-3, 1.25e-3, 0.625e-3)]
    solvers += [Solver("dopri5", rtol=tol, atol=tol) for tol in (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)]
    runs = []
    for solver in solvers:
        walls, positions = zip(
            *(case.fmu.sampled(solver, case.forces, span, SAMPLE_INTERVAL) for _ in range(repeats))
        )
        runs.append(Run(f"project {solver.method}", solver.label(), min(walls), positions[0]))
    return runs


# Steps that divide the sampling interval. Above 1 ms MuJoCo raises the equality model's
# time constant to 2 steps (its `refsafe`), so those runs are of slightly softer joints.
MUJOCO_STEPS = (5e-3, 2e-3, 1e-3, 0.5e-3, 0.25e-3, 0.125e-3, 0.0625e-3)
# MuJoCo runs longer than this many steps are timed once: they are far from any best.
REPEATED_STEPS = 4000


def mujoco_sweep(case: Case, span: float, repeats: int, joints: str) -> list:
    """implicitfast then RK4 runs at each step size; the last (RK4, smallest h) is the
    tightest."""
    runs = []
    for integrator in ("implicitfast", "RK4"):
        for h in MUJOCO_STEPS:
            model = case.mujoco_model(integrator, h, joints)
            count = repeats if span / h <= REPEATED_STEPS else 1
            walls, positions = zip(
                *(mujoco_positions(case, model, span, SAMPLE_INTERVAL) for _ in range(count))
            )
            name = mujoco_name(integrator, joints)
            runs.append(Run(name, f"h={h * 1e3:g} ms", min(walls), positions[0]))
    return runs


@dataclass
class Row:
    run: Run
    vs_project: float  # m, against the project's dopri5 1e-11
    vs_own: float  # m, against the engine's own tightest run
    is_own_ref: bool


def least_wall(candidates: list, target: float) -> str:
    """The fastest of the (run, error) pairs within `target`."""
    fits = [(run.wall, run.setting) for run, error in candidates if error <= target]
    if not fits:
        return "not reached"
    wall, setting = min(fits)
    return f"{wall:.3f} s ({setting})"


def work_precision_rows(case: Case, span: float, repeats: int) -> list:
    """Every sweep run with its two errors; prints what the references are and how far
    apart."""
    def reference(tol):
        return case.fmu.sampled(Solver("dopri5", rtol=tol, atol=tol), case.forces, span, SAMPLE_INTERVAL)[1]

    project_ref, project_check = reference(1e-11), reference(1e-12)
    print(f"References. Project: dopri5 rtol=atol=1e-11, the exact constrained dynamics "
          f"(differs from 1e-12 by {max_error(project_ref, project_check):.1e} m). Each MuJoCo "
          f"model's own: its RK4 run at h={MUJOCO_STEPS[-1] * 1e3:g} ms.")
    rows = [Row(run, max_error(run.positions, project_ref), max_error(run.positions, project_ref), False)
            for run in project_sweep(case, span, repeats)]
    for joints in JOINTS:
        peer = mujoco_sweep(case, span, repeats, joints)
        own_ref, check = peer[-1].positions, peer[-2].positions
        print(f"- {mujoco_name('RK4', joints)}: its own reference differs from its "
              f"h={MUJOCO_STEPS[-2] * 1e3:g} ms run by {max_error(own_ref, check):.1e} m and "
              f"from the project's reference by {max_error(own_ref, project_ref):.2e} m.")
        rows += [Row(run, max_error(run.positions, project_ref), max_error(run.positions, own_ref),
                     run is peer[-1]) for run in peer]
    print(f"The equality model's joints are soft (solref {MujocoSettings().solref[0]:g} s, solimp d = "
          f"{MujocoSettings().solimp[0]:g}) and give under load, so none of its runs gets much "
          f"closer than its reference to the project's; the ball-joint tree's joints are "
          f"exact.\n")
    return rows


def print_rows(rows: list):
    print("| engine | setting | wall (s) | error vs project ref (m) | error vs own ref (m) |")
    print("|---|---|---:|---:|---:|")
    for row in rows:
        own = "(is the ref)" if row.is_own_ref else f"{row.vs_own:.2e}"
        print(f"| {row.run.engine} | {row.run.setting} | {row.run.wall:.4f} | {row.vs_project:.2e} | {own} |")


def print_least_wall(rows: list):
    print("\nLeast wall time reaching a maximum node-position error (the project's own "
          "reference is the project reference: its engines have one row)\n")
    header = " | ".join(f"≤ {t:g} m" for t in TARGETS)
    print(f"| engine | against | {header} |")
    print("|---|---|" + "---|" * len(TARGETS))
    for engine in dict.fromkeys(row.run.engine for row in rows):
        mine = [row for row in rows if row.run.engine == engine]
        against = {"project dopri5 1e-11": [(r.run, r.vs_project) for r in mine]}
        if engine.startswith("MuJoCo"):
            against["own: its RK4, smallest h"] = [(r.run, r.vs_own) for r in mine if not r.is_own_ref]
        for name, candidates in against.items():
            cells = " | ".join(least_wall(candidates, t) for t in TARGETS)
            print(f"| {engine} | {name} | {cells} |")


def print_work_precision(case: Case, span: float, repeats: int):
    print(f"\n## Work-precision: node positions over {span:g} s (shorter than 10 s to keep "
          f"MuJoCo's small steps affordable), sampled every {SAMPLE_INTERVAL * 1e3:g} ms; "
          f"same case; wall times best of {repeats} (MuJoCo runs over {REPEATED_STEPS} "
          f"steps once). The project's runs are the FMU stepped at the sampling interval, so "
          f"dopri5's steps are clipped to it: at loose tolerances its error is that of "
          f"{SAMPLE_INTERVAL * 1e3:g} ms steps.\n")
    rows = work_precision_rows(case, span, repeats)
    print_rows(rows)
    print_least_wall(rows)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=5, help="interleaved repeats of each timing")
    parser.add_argument("--span", type=float, default=2.0, help="s of the work-precision sweep")
    args = parser.parse_args()
    print(f"mujoco {mujoco.__version__}, load average at start "
          f"{' '.join(f'{x:.2f}' for x in os.getloadavg())} on {os.cpu_count()} cores\n")
    with tempfile.TemporaryDirectory(prefix="peer-") as folder:
        case = prepare(Path(folder))
        print_timing(best_interleaved(timing_runs(case), args.repeats), args.repeats)
        print_mujoco_profile(case)
        print_work_precision(case, args.span, max(1, args.repeats // 2))
    print(f"\nload average at end {' '.join(f'{x:.2f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
