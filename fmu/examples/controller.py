"""A Python controller stepping the tensegrity FMU through fmpy's low-level FMU2Slave API.

Scene prism2 (the default FMU): all 15 cables are force-density controlled. Cable 14 runs
from node 5 (middle ring) to node 7 (top ring); raising its force density pulls node 7
toward node 5, i.e. toward smaller x. A PD law on node[7].x / node[7].vx drives node 7 to a
target x, with the force density clamped to stay positive. Only x is controlled: with the
other 14 densities held, the structure sags (node[7].z) once cable 14 leaves equilibrium.

This hand-tuned law only looks fine over its 2 s horizon: run longer it diverges (node 7
falls to x = -0.96 m by 6 s), because one cable cannot hold the structure's other modes.
See lqr_controller.py for a controller that stays bounded: an LQR state feedback on all 15
force densities, designed on the model of `tensegrity-fmu linearize`.

    .venv/bin/python fmu/examples/controller.py [prism2.fmu]
"""

import shutil
import sys

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

CABLE = "cable[14].force_density"  # nodes 5 -> 7
X_TARGET = 0.28  # m (node 7 starts at x = 0.2887 m)
KP, KD = 300.0, 30.0  # N/m per m, N/m per m/s


def pd_command(q0, x, vx):
    """PD law: pull harder while node 7 is right of the target or moving right."""
    return max(0.0, q0 + KP * (x - X_TARGET) + KD * vx)


def main(fmu_path="prism2.fmu"):
    md = read_model_description(fmu_path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    start = {v.name: float(v.start) for v in md.modelVariables if v.causality == "input"}

    h, t_end = 1e-3, 2.0  # communication step and stop time, s
    q0 = start[CABLE]  # equilibrium force density, N/m

    unzipdir = extract(fmu_path)
    fmu = FMU2Slave(
        guid=md.guid,
        unzipDirectory=unzipdir,
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="controller",
    )
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0, stopTime=t_end)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()

    watch = ["node[7].x", "node[7].z", "node[7].vx"]
    watch_vr = [vr[n] for n in watch]
    print(f"{'t [s]':>6} {'node[7].x [m]':>14} {'node[7].z [m]':>14} {'q14 [N/m]':>10}")
    n_steps = round(t_end / h)
    for k in range(n_steps + 1):
        t = k * h
        x, z, vx = fmu.getReal(watch_vr)
        q = pd_command(q0, x, vx)
        if k % 100 == 0:
            print(f"{t:6.2f} {x:14.6f} {z:14.6f} {q:10.3f}")
        if k == n_steps:
            break
        fmu.setReal([vr[CABLE]], [q])
        fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)

    fmu.terminate()
    fmu.freeInstance()
    shutil.rmtree(unzipdir, ignore_errors=True)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "prism2.fmu")
