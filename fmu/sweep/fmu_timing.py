"""Times fmpy on one FMU; `tensegrity-fmu bench fmu` runs it as `python -c` with the
FMU's path and reads the one JSON line it prints: seconds to read modelDescription.xml
(`read_model_description`, schema validation included), to instantiate and initialize, and
of the first two `doStep`s of the default experiment's step, with that step.

    .venv/bin/python fmu/sweep/fmu_timing.py tower20.fmu
"""

import json
import shutil
import sys
import time


def main(path):
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    started = time.perf_counter()
    md = read_model_description(path)
    read = time.perf_counter() - started
    folder = extract(path)
    try:
        started = time.perf_counter()
        fmu = FMU2Slave(
            guid=md.guid,
            unzipDirectory=folder,
            modelIdentifier=md.coSimulation.modelIdentifier,
            instanceName="bench",
        )
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        initialize = time.perf_counter() - started
        step = float(md.defaultExperiment.stepSize)
        do_step = []
        for k in range(2):
            started = time.perf_counter()
            fmu.doStep(currentCommunicationPoint=k * step, communicationStepSize=step)
            do_step.append(time.perf_counter() - started)
        fmu.terminate()
        fmu.freeInstance()
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    print(json.dumps({"read": read, "initialize": initialize, "do_step": do_step, "step": step}))


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: fmu_timing.py FMU")
    main(sys.argv[1])
