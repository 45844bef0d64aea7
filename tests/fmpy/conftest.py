"""Shared fixtures for the fmpy test suite of the FMI 2.0 co-simulation FMUs.

The FMUs are built by the project's own CLI (`tensegrity-fmu build`) into a session
temporary folder, once per scene, and loaded with fmpy. Expected values in the tests
come from the scene (read back from the FMU's `resources/scene.toml`), from physics, or
from a second run of the FMU, never from recorded outputs of the code under test.
"""

import ctypes
import hashlib
import subprocess
import tomllib
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
)
from fmpy import calloc, free

REPO = Path(__file__).resolve().parents[2]
CLI = REPO / "target" / "release" / "tensegrity-fmu"
LIBRARY = REPO / "target" / "release" / "libtensegrity_fmu_binary.so"
# The portable binary (glibc 2.28, fmu/build-binary.sh) that `tensegrity-fmu build` packages.
PORTABLE = REPO / "target" / "x86_64-unknown-linux-gnu" / "release" / LIBRARY.name
BUILTINS = ["prism2", "prism2-elastic", "icosahedron", "tower20"]

@pytest.fixture(scope="session")
def cli():
    """The CLI, built with `cargo build --release --workspace` (and the portable binary with
    fmu/build-binary.sh) if it or the FMU binary is missing."""
    if not (CLI.is_file() and LIBRARY.is_file()):
        subprocess.run(
            ["cargo", "build", "--release", "--workspace"], cwd=REPO, check=True
        )
    if not PORTABLE.is_file():
        subprocess.run(["bash", "fmu/build-binary.sh"], cwd=REPO, check=True)
    assert CLI.is_file() and LIBRARY.is_file() and PORTABLE.is_file()
    return CLI


def make_callbacks(messages):
    """fmi2CallbackFunctions whose logger appends (status, category, message) to `messages`.

    The logger is printf-like: the FMU doubles every literal '%', and we receive the format
    string as is (no varargs are passed), so '%%' is turned back into '%'.
    """

    def logger(_env, _name, status, category, message):
        messages.append(
            (
                status,
                (category or b"").decode(),
                (message or b"").decode().replace("%%", "%"),
            )
        )

    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(logger)
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    return callbacks


class FmuFile:
    """A built .fmu: its path, extracted folder, model description and scene."""

    def __init__(self, path: Path):
        self.path = path
        self.md = read_model_description(str(path))
        self.dir = extract(str(path), unzipdir=str(path.with_suffix("")) + "_x")
        with zipfile.ZipFile(path) as z:
            self.scene_text = z.read("resources/scene.toml").decode()
        self.scene = tomllib.loads(self.scene_text)
        self.variables = {v.name: v for v in self.md.modelVariables}
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.outputs = [v.name for v in self.md.modelVariables if v.causality == "output"]

    @property
    def library(self) -> Path:
        return Path(self.dir, "binaries", "linux64", self.md.coSimulation.modelIdentifier + ".so")


class Builder:
    """Builds FMUs with the CLI into a temporary folder; one build per scene."""

    def __init__(self, cli: Path, root: Path):
        self.cli = cli
        self.root = root
        self.cache = {}

    def build(self, scene_arg: str, out: Path) -> Path:
        res = subprocess.run(
            [str(self.cli), "build", scene_arg, "-o", str(out)],
            check=True,
            capture_output=True,
            text=True,
        )
        printed = Path(res.stdout.strip())
        assert printed == out, f"CLI printed {res.stdout!r}, expected the FMU path {out}"
        return out

    def builtin(self, name: str) -> FmuFile:
        if name not in self.cache:
            self.cache[name] = FmuFile(self.build(name, self.root / f"{name}.fmu"))
        return self.cache[name]

    def from_toml(self, text: str) -> FmuFile:
        """Builds a custom scene given as TOML text (cached by content)."""
        key = hashlib.sha256(text.encode()).hexdigest()[:16]
        if key not in self.cache:
            scene = self.root / f"scene_{key}.toml"
            scene.write_text(text)
            self.cache[key] = FmuFile(self.build(str(scene), self.root / f"custom_{key}.fmu"))
        return self.cache[key]

    def fresh(self, scene_arg: str, stem: str) -> Path:
        """An uncached build (for GUID stability checks)."""
        return self.build(scene_arg, self.root / f"{stem}.fmu")


@pytest.fixture(scope="session")
def fmus(cli, tmp_path_factory):
    return Builder(cli, tmp_path_factory.mktemp("fmus"))


class Slave:
    """One instance of an FMU through fmpy's FMU2Slave, with names instead of value references."""

    def __init__(self, fmu: FmuFile, name="inst", guid=None, logging=True, directory=None):
        self.file = fmu
        self.messages = []
        self.callbacks = make_callbacks(self.messages)
        self.fmu = FMU2Slave(
            guid=guid or fmu.md.guid,
            unzipDirectory=directory or fmu.dir,
            modelIdentifier=fmu.md.coSimulation.modelIdentifier,
            instanceName=name,
        )
        self.freed = False
        try:
            self.fmu.instantiate(callbacks=self.callbacks, loggingOn=logging)
        except Exception:
            self.fmu.freeLibrary()
            self.freed = True
            raise
        self.time = 0.0

    def vrs(self, names):
        return [self.file.vr[n] for n in names]

    def init(self, params=None, booleans=None, inputs=None, start=0.0, stop=None, integers=None):
        """setupExperiment, initialization mode with parameter/input values, exit."""
        self.fmu.setupExperiment(startTime=start, stopTime=stop)
        self.fmu.enterInitializationMode()
        if params:
            self.set(params)
        if integers:
            self.fmu.setInteger(self.vrs(integers), list(integers.values()))
        if booleans:
            self.fmu.setBoolean(self.vrs(booleans), [int(bool(v)) for v in booleans.values()])
        if inputs:
            self.set(inputs)
        self.fmu.exitInitializationMode()
        self.time = start
        return self

    def set(self, values: dict):
        self.fmu.setReal(self.vrs(values), list(values.values()))

    def get(self, names):
        return np.array(self.fmu.getReal(self.vrs(names)))

    def outputs(self):
        return self.get(self.file.outputs)

    def step(self, h):
        self.fmu.doStep(self.time, h)
        self.time += h

    def run(self, n, h):
        """n communication steps of h; the communication points are t0 + k h."""
        t0 = self.time
        for k in range(n):
            self.fmu.doStep(t0 + k * h, h)
            self.time = t0 + (k + 1) * h

    def status_time(self):
        return self.fmu.getRealStatus(2)  # fmi2LastSuccessfulTime

    def terminated(self):
        return self.fmu.getBooleanStatus(3)  # fmi2Terminated

    def warnings(self):
        return [m for s, c, m in self.messages if c == "logStatusWarning"]

    def errors(self):
        return [m for s, c, m in self.messages if c == "logStatusError"]

    def free(self):
        if not self.freed:
            self.freed = True
            self.fmu.freeInstance()


@pytest.fixture
def open_fmu():
    """Factory: open_fmu(fmu_file, **kw) -> Slave; every instance is freed after the test."""
    opened = []

    def factory(fmu, **kw):
        s = Slave(fmu, **kw)
        opened.append(s)
        return s

    yield factory
    for s in reversed(opened):
        s.free()


def load_library(path: Path):
    lib = ctypes.CDLL(str(path))
    lib.fmi2FreeInstance.argtypes = [ctypes.c_void_p]
    lib.fmi2FreeInstance.restype = None
    lib.fmi2Instantiate.argtypes = [
        ctypes.c_char_p,
        ctypes.c_int,
        ctypes.c_char_p,
        ctypes.c_char_p,
        ctypes.c_void_p,
        ctypes.c_int,
        ctypes.c_int,
    ]
    lib.fmi2Instantiate.restype = ctypes.c_void_p
    return lib


@pytest.fixture
def library():
    return load_library


def cable_length(slave: Slave, scene: dict, j: int) -> float:
    """Length of cable j (1-based) from the node position outputs."""
    a, b = scene["cables"][j - 1]["nodes"]
    pa = slave.get([f"node[{a}].{c}" for c in "xyz"])
    pb = slave.get([f"node[{b}].{c}" for c in "xyz"])
    return float(np.linalg.norm(pb - pa))


# rk4 (solver.method = 1) for tests of fixed-step properties: the default, dopri5, clips its
# steps at the communication points, so its last bits depend on where they fall.
RK4 = {"solver.method": 1}
