"""What runs on a Dask worker: the FMUs extracted and instantiated once, then one sample per task.

This module is shipped to every worker with `Client.upload_file`, so a remote worker needs
only fmpy, numpy and distributed installed, no checkout. It imports nothing from the sweep.

`FmuPlugin` carries the FMU archives (bytes, so no shared file system is needed), extracts
each once per worker and keeps one FMU2Slave per FMU and worker thread. `run_sample`
re-initializes that instance with fmi2Reset, or rewinds it to the shared settled state
(`warm_start`), so a sample pays no extraction and no library loading.
"""

import math
import os
import shutil
import socket
import tempfile
import threading
from pathlib import Path

from distributed import WorkerPlugin, get_worker
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy import calloc, free

PLUGIN = "tensegrity-sweep"


class Instance:
    """One FMU2Slave with its model description, value references and logged errors."""

    serial = 0  # instances created in this process: how reuse shows (sweep summary line)

    def __init__(self, fmu_dir: Path):
        self.md = read_model_description(str(fmu_dir / "modelDescription.xml"))
        self.variables = {v.name: v for v in self.md.modelVariables}
        self.errors = []
        self.callbacks = self._callbacks()
        self.slave = FMU2Slave(
            guid=self.md.guid,
            unzipDirectory=str(fmu_dir),
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName="sweep",
        )
        self.slave.instantiate(callbacks=self.callbacks, loggingOn=True)
        Instance.serial += 1
        self.id = f"{socket.gethostname()}:{os.getpid()}:{Instance.serial}"
        self.used = False  # a used instance is reset (or rewound) before the next sample
        # Held while a sample runs: a worker closing (Ctrl-C, a lost scheduler) must not
        # free an instance that its task thread is still stepping.
        self.busy = threading.Lock()

    def _callbacks(self):
        # The FMU explains every error through the logger only; keep those lines for `status`.
        def logger(_env, _name, status, category, message):
            if status >= 3:  # fmi2Error, fmi2Fatal
                self.errors.append((message or b"").decode().replace("%%", "%"))

        callbacks = fmi2CallbackFunctions()
        callbacks.logger = fmi2CallbackLoggerTYPE(logger)
        callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        return callbacks

    def set(self, values: dict):
        """Sets named values with the setter of each variable's type."""
        by_type = {"Real": {}, "Integer": {}, "Boolean": {}}
        for name, value in values.items():
            v = self.variables[name]
            by_type[v.type][v.valueReference] = value
        if by_type["Real"]:
            self.slave.setReal(list(by_type["Real"]), [float(x) for x in by_type["Real"].values()])
        if by_type["Integer"]:
            self.slave.setInteger(list(by_type["Integer"]), [int(x) for x in by_type["Integer"].values()])
        if by_type["Boolean"]:
            self.slave.setBoolean(list(by_type["Boolean"]), [bool(x) for x in by_type["Boolean"].values()])

    def free(self):
        self.slave.freeInstance()
        self.slave.freeLibrary()


class FmuPlugin(WorkerPlugin):
    """Extracts the sweep's FMUs once on each worker and hands out one instance per thread."""

    name = PLUGIN

    def __init__(self, archives: dict):
        self.archives = archives  # FMU key -> the .fmu file's bytes

    def setup(self, worker):
        self.root = Path(tempfile.mkdtemp(prefix="tensegrity-sweep-"))
        self.dirs = {}
        for key, data in self.archives.items():
            archive = self.root / f"{key}.fmu"
            archive.write_bytes(data)
            self.dirs[key] = self.root / key
            shutil.unpack_archive(str(archive), str(self.dirs[key]), "zip")
        self.local = threading.local()
        self.lock = threading.Lock()
        self.instances = []

    def instance(self, key) -> Instance:
        cache = self.local.__dict__.setdefault("instances", {})
        if key not in cache:
            cache[key] = Instance(self.dirs[key])
            with self.lock:
                self.instances.append(cache[key])
        return cache[key]

    def discard(self, key):
        """Frees this thread's instance of `key` (after a reset that failed); the next call makes a new one."""
        inst = self.local.__dict__.get("instances", {}).pop(key, None)
        if inst is not None:
            with self.lock:
                self.instances.remove(inst)
            inst.free()

    def teardown(self, worker):
        for inst in self.instances:
            # One still running is left to the process's exit: freeing it under its
            # thread's feet corrupted the heap.
            if inst.busy.acquire(blocking=False):
                inst.free()
        shutil.rmtree(self.root, ignore_errors=True)


def communication_points(start, stop, step):
    """fmpy's simulate_fmu grid: start + k·step, the last point clipped to `stop`; a point
    within fmpy's isclose of `stop` is the last one, as it is."""
    points = [start]
    k = 0
    while not (points[-1] > stop or math.isclose(points[-1], stop)):
        k += 1
        t = start + k * step
        if t > stop and not math.isclose(t, stop):
            t = stop
        points.append(t)
    return points


def _record(inst, names, extremes):
    values = inst.slave.getReal([inst.variables[n].valueReference for n in names])
    for name, value in zip(names, values):
        lo, hi, _ = extremes.get(name, (value, value, value))
        extremes[name] = (min(lo, value), max(hi, value), value)


def _start(inst, values, stop_time, warm):
    """Brings the instance to the sample's start: fresh initialization or the settled state."""
    if warm is None:
        if inst.used:
            inst.slave.reset()
        inst.slave.setupExperiment(startTime=0.0, stopTime=stop_time)
        inst.set(values)  # before initialization, where fmpy's simulate_fmu sets start values
        inst.slave.enterInitializationMode()
        inst.slave.exitInitializationMode()
        return 0.0
    settled_time, state_bytes = warm
    if not inst.used:
        inst.slave.setupExperiment(startTime=0.0)
        inst.slave.enterInitializationMode()
        inst.slave.exitInitializationMode()
    state = inst.slave.deSerializeFMUstate(state_bytes)
    try:
        inst.slave.setFMUstate(state)
    finally:
        inst.slave.freeFMUstate(state)
    inst.set(values)  # tunable parameters and inputs act from the next step
    return settled_time


def run_sample(key, values, outputs, stop_time, step, warm=None):
    """Runs one sample on this worker's instance of FMU `key`.

    Returns (status, {output: (min, max, final)}, instance id); status is "ok" or the
    FMU's error message. A sample's run covers `stop_time` seconds from its start (0, or
    the settled time of a warm start), recording the outputs at every communication point.
    """
    plugin = get_worker().plugins[PLUGIN]
    inst = plugin.instance(key)
    with inst.busy:
        return _run(plugin, key, inst, values, outputs, stop_time, step, warm)


def _run(plugin, key, inst, values, outputs, stop_time, step, warm):
    inst.errors.clear()
    extremes = {}
    try:
        start = _start(inst, values, stop_time, warm)
        inst.used = True
        _record(inst, outputs, extremes)
        points = communication_points(start, start + stop_time, step)
        for t, t_next in zip(points, points[1:]):
            inst.slave.doStep(currentCommunicationPoint=t, communicationStepSize=t_next - t)
            _record(inst, outputs, extremes)
    except FMICallException as e:
        inst.used = True
        message = " | ".join(inst.errors) or str(e)
        _recover(plugin, key, inst)
        return message, {}, inst.id
    return "ok", extremes, inst.id


def _recover(plugin, key, inst):
    """A failed sample's instance is reset at once; one whose reset fails is freed, and the
    next sample on this thread instantiates a new one."""
    try:
        inst.slave.reset()
        inst.used = False
    except FMICallException:
        plugin.discard(key)


def settle(key, values, settle_time, step):
    """The shared settling run of a warm start: the FMU at `values`, run for `settle_time`;
    returns (time reached, serialized FMU state)."""
    inst = Instance(get_worker().plugins[PLUGIN].dirs[key])
    try:
        inst.slave.setupExperiment(startTime=0.0)
        inst.set(values)
        inst.slave.enterInitializationMode()
        inst.slave.exitInitializationMode()
        points = communication_points(0.0, settle_time, step)
        for t, t_next in zip(points, points[1:]):
            inst.slave.doStep(currentCommunicationPoint=t, communicationStepSize=t_next - t)
        state = inst.slave.getFMUstate()
        data = bytes(inst.slave.serializeFMUstate(state))
        inst.slave.freeFMUstate(state)
        return points[-1], data
    except FMICallException as e:
        raise RuntimeError(" | ".join(inst.errors) or str(e)) from None
    finally:
        inst.free()
