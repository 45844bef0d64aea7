"""An external controller stepping a tensegrity FMU through fmpy's low-level FMU2Slave API.

The loop is the one every co-simulation master runs: set the inputs, fmi2DoStep one
communication interval, read the outputs, compute the next command. The names come from the
FMU's modelDescription.xml, so the script runs on any FMU that the project builds and picks
its actuator from the inputs the FMU has:

- force-density inputs (`cable[K].force_density`, scenes with `control = "force_density"`
  cables such as prism2): a PD law shortens one cable by 2 % of its length. Raising a
  cable's force density pulls its two nodes together, so the command is the start density
  plus terms in the length error and its rate, clamped at 0 (a cable cannot push). Only
  this length is controlled: the other densities are held, so the rest of the structure
  drifts once the cable leaves equilibrium. Run long, one cable cannot hold the structure's
  other modes; lqr_controller.py designs a feedback on every force density that can.
- else nodal force inputs (`node[N].fx`, the nodes of a scene's `force_inputs`): a PID law
  moves the first loaded node 2 cm along x (the integral term removes the offset that the
  structure's stiffness leaves).
- else the FMU has nothing to control, and the script says so (exit status 2).

    .venv/bin/python fmu/examples/controller.py prism2.fmu [--stop-time 2] [--step 0.001]
"""

import shutil
import sys

import numpy as np
from fmpy import extract
from fmpy.fmi2 import FMU2Slave

from fmu_variables import FmuVariables, Parser, check_fmu, fail, run_main

SHORTENING = 0.02  # the cable's target length is 2 % shorter than at the start
KP_DENSITY, KD_DENSITY = 300.0, 30.0  # N/m per m, N/m per m/s
OFFSET = 0.02  # m, the loaded node's target is this far along +x from its start
KP_FORCE, KI_FORCE, KD_FORCE = 300.0, 300.0, 30.0  # N/m, N/(m s), N s/m


class CableLengthLaw:
    """PD on one cable's length through its force density."""

    def __init__(self, fmu, cable):
        self.a, self.b = fmu.cable_ends[cable]
        self.commanded = [f"cable[{cable}].force_density"]
        self.measured = (fmu.position(self.a) + fmu.position(self.b)
                         + fmu.velocity(self.a) + fmu.velocity(self.b))
        self.q0 = fmu.start[self.commanded[0]]
        self.coordinate = f"cable[{cable}] length (nodes {self.a}-{self.b})"
        self.target = None

    def __call__(self, y, _h):
        pa, pb, va, vb = y[0:3], y[3:6], y[6:9], y[9:12]
        d = pb - pa
        length = float(np.linalg.norm(d))
        rate = float(d @ (vb - va)) / length
        if self.target is None:
            self.target = (1.0 - SHORTENING) * length
        q = max(0.0, self.q0 + KP_DENSITY * (length - self.target) + KD_DENSITY * rate)
        return length, [q]


class NodePositionLaw:
    """PID on a loaded node's x through its force input."""

    def __init__(self, fmu, node):
        self.commanded = [f"node[{node}].fx"]
        self.measured = [f"node[{node}].x", f"node[{node}].vx"]
        self.coordinate = f"node[{node}].x"
        self.target = None
        self.integral = 0.0

    def __call__(self, y, h):
        x, vx = y
        if self.target is None:
            self.target = x + OFFSET
        error = x - self.target
        self.integral += error * h
        return x, [-KP_FORCE * error - KI_FORCE * self.integral - KD_FORCE * vx]


def choose_law(fmu, path):
    """The law for the FMU's inputs, or a one-line explanation when it has none to use."""
    cables = [int(n[len("cable["):n.index("]")]) for n in fmu.force_density_inputs]
    # Prefer a cable that moves a free node at both ends; the last such one is highest up.
    usable = [k for k in cables if k in fmu.cable_ends]
    both_free = [k for k in usable if all(n in fmu.free for n in fmu.cable_ends[k])]
    if both_free or usable:
        return CableLengthLaw(fmu, (both_free or usable)[-1])
    if fmu.force_input_nodes:
        return NodePositionLaw(fmu, fmu.force_input_nodes[0])
    fail(f"{path} has no inputs to control (no cable[K].force_density, no node[N].fx): give its "
         "scene force-density cables (control = \"force_density\") or force_inputs = [nodes]")


def run(path, law, fmu, stop_time, step, every, out=sys.stdout):
    """Steps the FMU under `law`; returns times, the controlled coordinate and the commands."""
    md = fmu.md
    unzipdir = extract(str(path))
    slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir,
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="controller")
    measured = [fmu.vr[n] for n in law.measured]
    commanded = [fmu.vr[n] for n in law.commanded]
    n_steps = round(stop_time / step)
    times, values, commands = [], [], []
    try:
        slave.instantiate()
        slave.setupExperiment(startTime=0.0, stopTime=stop_time)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        print(f"controlling {law.coordinate} with {law.commanded[0]}", file=out)
        print(f"{'t [s]':>6} {'value':>12} {'target':>12} {'command':>12}", file=out)
        for k in range(n_steps + 1):
            t = k * step
            value, u = law(np.array(slave.getReal(measured)), step)
            times.append(t)
            values.append(value)
            commands.append(u[0])
            if k % every == 0:
                print(f"{t:6.2f} {value:12.6f} {law.target:12.6f} {u[0]:12.4f}", file=out)
            if k == n_steps:
                break
            slave.setReal(commanded, u)
            slave.doStep(currentCommunicationPoint=t, communicationStepSize=step)
        slave.terminate()
    finally:
        slave.freeInstance()
        shutil.rmtree(unzipdir, ignore_errors=True)
    return np.array(times), np.array(values), np.array(commands)


def main(argv=None):
    ap = Parser(description=__doc__.split("\n\n")[0])
    ap.add_argument("fmu", help="an FMU built by tensegrity-fmu")
    ap.add_argument("--stop-time", type=float, default=2.0, help="s (default 2)")
    ap.add_argument("--step", type=float, default=1e-3, help="communication step, s (default 0.001)")
    ap.add_argument("--print-every", type=float, default=0.1, help="s between lines (default 0.1)")
    args = ap.parse_args(argv)
    for option in ("stop_time", "step", "print_every"):
        value = getattr(args, option)
        if not (np.isfinite(value) and value > 0):
            fail(f"--{option.replace('_', '-')} {value:g}: must be a positive number of seconds")
    fmu = FmuVariables(check_fmu(args.fmu))
    law = choose_law(fmu, args.fmu)
    every = max(1, round(args.print_every / args.step))
    times, values, _ = run(args.fmu, law, fmu, args.stop_time, args.step, every)
    start, end = abs(values[0] - law.target), abs(values[-1] - law.target)
    print(f"{law.coordinate}: {start:.6f} from the target at the start, {end:.6f} at "
          f"{times[-1]:g} s")
    return times, values, law.target


if __name__ == "__main__":
    run_main(main)
