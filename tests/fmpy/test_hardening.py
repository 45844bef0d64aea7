"""Hostile settings and API misuse found by fuzzing and importer trials (issue 10, items 1-5):
each call ends in bounded time with a clear error naming the key or call, nothing reaches
stderr, nothing partial is left behind, and a refused call leaves the instance running."""

import ctypes
import hashlib
import subprocess
import time

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from conftest import FmuFile

MAGIC_AND_VERSION = 8 + 4


@pytest.fixture
def prism2(fmus):
    return fmus.builtin("prism2")


def base_scene(cli, name="prism2-elastic"):
    return subprocess.run([str(cli), "scene", name], check=True, capture_output=True, text=True).stdout


def with_key(text, key, value):
    """The scene text with top-level `key = value` replaced (or added first)."""
    lines = [l for l in text.splitlines() if not l.startswith(f"{key} =")]
    return f"{key} = {value}\n" + "\n".join(lines) + "\n"


def build(cli, tmp_path, text, stem="scene"):
    scene = tmp_path / f"{stem}.toml"
    scene.write_text(text, encoding="utf-8")
    out = tmp_path / f"{stem}.fmu"
    started = time.monotonic()
    res = subprocess.run([str(cli), "build", str(scene), "-o", str(out)], capture_output=True, text=True, timeout=60)
    return res, out, time.monotonic() - started


def leftovers(tmp_path):
    return sorted(p.name for p in tmp_path.iterdir() if p.suffix != ".toml")


# --- 1. unbounded work ----------------------------------------------------------------


@pytest.mark.parametrize("step", ["1e-12", "1e-300"])
def test_tiny_step_size_is_refused_at_build(cli, tmp_path, step):
    text = base_scene(cli).replace("step_size = 0.001", f"step_size = {step}")
    assert f"step_size = {step}" in text
    res, out, _ = build(cli, tmp_path, text)
    assert res.returncode != 0
    assert "solver.step_size" in res.stderr and "time scale" in res.stderr, res.stderr
    assert not out.exists() and leftovers(tmp_path) == []


def test_tiny_step_size_set_in_initialization_is_refused_and_can_be_fixed(prism2, open_fmu):
    s = open_fmu(prism2)
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.enterInitializationMode()
    s.set({"solver.step_size": 1e-12})
    with pytest.raises(FMICallException):
        s.fmu.exitInitializationMode()
    assert any("solver.step_size" in m and "time scale" in m for m in s.errors()), s.errors()
    s.set({"solver.step_size": 1e-3})  # the instance is still initializing: fix and go on
    s.fmu.exitInitializationMode()
    s.run(3, 0.001)
    ref = open_fmu(prism2, name="ref").init()
    ref.run(3, 0.001)
    assert np.array_equal(s.outputs(), ref.outputs())


@pytest.mark.parametrize("method", [1, 2, 3])
def test_huge_communication_step_is_refused_by_max_steps(prism2, open_fmu, method):
    s = open_fmu(prism2)
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.enterInitializationMode()
    s.fmu.setInteger(s.vrs(["solver.method"]), [method])
    s.fmu.exitInitializationMode()
    before = s.outputs()
    started = time.monotonic()
    with pytest.raises(FMICallException) as e:
        s.fmu.doStep(0.0, 1e6)
    took = time.monotonic() - started
    assert e.value.status == 3
    assert any("solver.max_steps = 100000" in m for m in s.errors()), s.errors()
    print(f"\nmethod {method}: doStep(0, 1e6 s) refused after {took:.3f} s")
    assert np.array_equal(s.outputs(), before) and s.status_time() == 0.0
    s.run(2, 0.001)  # nothing was integrated and the instance carries on
    assert s.status_time() == pytest.approx(0.002, abs=1e-15)


def serialized(s):
    state = s.fmu.getFMUstate()
    data = bytes(s.fmu.serializeFMUstate(state))
    s.fmu.freeFMUstate(state)
    return data


def with_time(data, guid, value):
    """The serialized state with its communication time replaced and the checksum redone."""
    at = MAGIC_AND_VERSION + 8 + len(guid.encode()) + 1
    body = bytearray(data[:-32])
    body[at : at + 8] = np.float64(value).tobytes()
    return bytes(body) + hashlib.sha256(body).digest()


@pytest.mark.parametrize("edited", [1e6, 1e16, -5.0])
def test_edited_time_in_serialized_state_is_refused(prism2, open_fmu, edited):
    s = open_fmu(prism2).init()
    s.run(5, 0.001)
    data = serialized(s)
    assert np.frombuffer(data, np.float64, 1, MAGIC_AND_VERSION + 8 + len(prism2.md.guid) + 1)[0] == pytest.approx(0.005)
    with pytest.raises(FMICallException):
        s.fmu.deSerializeFMUstate(with_time(data, prism2.md.guid, edited))
    assert any("fmi2DeSerializeFMUstate" in m and "differs" in m for m in s.errors()), s.errors()
    s.run(1, 0.001)  # the running instance is untouched
    assert s.status_time() == pytest.approx(0.006, abs=1e-15)


# --- 2. names that break importers -------------------------------------------------------


@pytest.mark.parametrize("char", ["\\u0001", "\\u001B", "\\uFFFE"])
@pytest.mark.parametrize("key", ["name", "description"])
def test_control_character_in_name_or_description_is_refused(cli, tmp_path, char, key):
    text = with_key(base_scene(cli), key, f'"a{char}b"')
    res, out, _ = build(cli, tmp_path, text)
    assert res.returncode != 0
    assert res.stderr.startswith(f"error: {key}: character 2 is U+"), res.stderr
    assert not out.exists() and leftovers(tmp_path) == []


@pytest.mark.parametrize("length", [253, 65_000])
def test_overlong_name_is_refused_naming_the_key_without_a_partial_file(cli, tmp_path, length):
    res, out, took = build(cli, tmp_path, with_key(base_scene(cli), "name", '"' + "n" * length + '"'))
    assert res.returncode != 0
    assert f"name: has {length} characters; at most 100 are allowed. Shorten it" in res.stderr
    assert len(res.stderr) < 300  # the 65,000 characters are not echoed
    assert not out.exists() and leftovers(tmp_path) == []
    assert took < 30


def test_multibyte_name_is_limited_in_bytes_for_file_names(cli, tmp_path):
    res, out, _ = build(cli, tmp_path, with_key(base_scene(cli), "name", '"' + "塔" * 80 + '"'))
    assert res.returncode != 0
    assert "name: takes 240 bytes in UTF-8; at most 200 are allowed" in res.stderr, res.stderr
    assert not out.exists() and leftovers(tmp_path) == []
    # the default output name <name>.fmu of the longest multi-byte name is a valid file name
    scene = tmp_path / "tower.toml"
    scene.write_text(with_key(base_scene(cli), "name", '"' + "塔" * 66 + '"'), encoding="utf-8")
    res = subprocess.run([str(cli), "build", str(scene)], capture_output=True, text=True, cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    assert (tmp_path / ("塔" * 66 + ".fmu")).is_file()


def test_longest_name_builds_an_fmu_that_unzips_with_a_c_identifier(cli, tmp_path):
    name = "9é" + "x" * 98  # 100 characters, a leading digit and a non-ASCII letter
    res, out, _ = build(cli, tmp_path, with_key(base_scene(cli), "name", f'"{name}"'), stem="long")
    assert res.returncode == 0, res.stderr
    fmu = FmuFile(out)  # fmpy reads and unzips it
    identifier = fmu.md.coSimulation.modelIdentifier
    assert fmu.md.modelName == name
    assert identifier == ("t_9_" + "x" * 98)[:63]
    assert identifier.isidentifier() and identifier.isascii()
    assert fmu.library.is_file()


def test_failed_build_keeps_an_existing_fmu(cli, tmp_path, prism2):
    out = tmp_path / "keep.fmu"
    out.write_bytes(prism2.path.read_bytes())
    scene = tmp_path / "bad.toml"
    scene.write_text(with_key(base_scene(cli), "name", '"a\\u0001"'))
    res = subprocess.run([str(cli), "build", str(scene), "-o", str(out)], capture_output=True, text=True)
    assert res.returncode != 0
    assert out.read_bytes() == prism2.path.read_bytes()
    assert leftovers(tmp_path) == ["keep.fmu"]


# --- 3. extreme values ------------------------------------------------------------------


def add_table(text, table, body):
    return text + f"\n[[{table}]]\n{body}\n"


@pytest.mark.parametrize(
    "edit, key",
    [
        (lambda t: t.replace("mass = 1.0", "mass = 1e-300", 1), "bars[1].mass"),
        (lambda t: t.replace("mass = 1.0", "mass = 1e300", 1), "bars[1].mass"),
        (lambda t: add_table(t, "point_masses", "node = 7\nmass = 1e15"), "point_masses[1].mass"),
        (lambda t: add_table(t, "bars", "nodes = [4, 1]\nmass = 1.0"), "bars[7].nodes"),
    ],
    ids=["tiny-bar-mass", "huge-bar-mass", "huge-point-mass", "duplicated-bar"],
)
def test_extreme_masses_and_duplicated_bars_are_refused_at_load(cli, tmp_path, edit, key):
    res, out, _ = build(cli, tmp_path, edit(base_scene(cli)))
    assert res.returncode != 0
    assert res.stderr.startswith(f"error: {key}: "), res.stderr
    assert not out.exists()


@pytest.mark.parametrize("mass", [1e-300, 1e300])
def test_extreme_bar_mass_set_as_parameter_is_refused(prism2, open_fmu, mass):
    s = open_fmu(prism2)
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.enterInitializationMode()
    with pytest.raises(FMICallException):
        s.set({"bar[1].mass": mass})
    assert any("bar[1].mass" in m and "bars[1].mass" in m for m in s.errors()), s.errors()
    s.fmu.exitInitializationMode()
    s.run(2, 0.001)
    assert np.all(np.isfinite(s.outputs()))


def test_start_time_too_large_to_advance_is_refused(prism2, open_fmu):
    s = open_fmu(prism2)
    s.fmu.setupExperiment(startTime=1e16)
    s.fmu.enterInitializationMode()
    with pytest.raises(FMICallException):
        s.fmu.exitInitializationMode()
    assert any("start time 10000000000000000" in m and "resolution" in m for m in s.errors()), s.errors()
    s.fmu.reset()
    s.init(start=1e3)  # a large but representable start works
    s.run(3, 0.001)
    assert s.status_time() == pytest.approx(1e3 + 0.003, abs=1e-9)


# --- 4. host-side aborts -------------------------------------------------------------------

HUGE = 8_796_093_022_208  # 2**43: "memory allocation of 8796093022208 bytes failed" before


@pytest.mark.parametrize("call", ["fmi2GetReal", "fmi2GetBoolean", "fmi2GetInteger", "fmi2SetReal", "fmi2SetBoolean", "fmi2SetInteger"])
def test_huge_nvr_is_refused_without_aborting_or_printing(prism2, open_fmu, capfd, call):
    s = open_fmu(prism2).init()
    vr = (ctypes.c_uint * 1)(0)
    value = (ctypes.c_double * 1)() if call.endswith("Real") else (ctypes.c_int * 1)()
    with pytest.raises(FMICallException) as e:
        getattr(s.fmu, call)(s.fmu.component, vr, HUGE, value)
    assert e.value.status == 3
    assert any(call in m and f"nvr = {HUGE}" in m for m in s.errors()), s.errors()
    out, err = capfd.readouterr()
    assert out == "" and err == ""
    s.run(1, 0.001)  # still running


def test_huge_category_count_is_refused_and_a_refused_logging_call_changes_nothing(prism2, open_fmu, capfd):
    s = open_fmu(prism2, logging=False).init()
    names = (ctypes.c_char_p * 2)(b"logEvents", b"noSuchCategory")
    with pytest.raises(FMICallException):
        s.fmu.fmi2SetDebugLogging(s.fmu.component, 1, HUGE, names)
    assert any(f"nCategories = {HUGE}" in m for m in s.errors()), s.errors()
    with pytest.raises(FMICallException):
        s.fmu.fmi2SetDebugLogging(s.fmu.component, 1, 2, names)
    assert any("unknown log category 'noSuchCategory'; nothing was changed" in m for m in s.errors())
    s.run(2, 0.001)
    assert [m for _, c, m in s.messages if c == "logEvents"] == []  # logEvents stayed off
    out, err = capfd.readouterr()
    assert out == "" and err == ""


def test_free_fmu_state_ignores_null(prism2, open_fmu):
    s = open_fmu(prism2).init()
    lib = s.fmu.dll
    lib.fmi2FreeFMUstate.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
    null_state = ctypes.c_void_p(None)
    assert lib.fmi2FreeFMUstate(s.fmu.component, ctypes.byref(null_state)) == 0
    assert lib.fmi2FreeFMUstate(s.fmu.component, None) == 0
    assert s.errors() == []


# --- 5. a refused set does not poison the instance ------------------------------------------


def test_refused_fixed_parameter_set_keeps_the_simulation_running(prism2, open_fmu):
    s = open_fmu(prism2).init()
    s.run(5, 0.001)
    with pytest.raises(FMICallException) as e:
        s.set({"solver.step_size": 0.002})
    assert e.value.status == 3
    assert any("solver.step_size is a fixed parameter" in m for m in s.errors())
    s.run(5, 0.001)
    ref = open_fmu(prism2, name="ref").init()
    ref.run(10, 0.001)
    assert np.array_equal(s.outputs(), ref.outputs())


def test_failed_computation_still_enters_the_error_state(prism2, open_fmu):
    """A numerical failure is not a refusal: the standard's Error state, left by reset."""
    s = open_fmu(prism2).init()
    s.set({"node[7].fx": 1e307})
    with pytest.raises(FMICallException):
        s.fmu.doStep(0.0, 0.001)
    with pytest.raises(FMICallException):
        s.fmu.doStep(0.0, 0.001)
    assert any("not allowed in mode Error" in m for m in s.errors())
    s.fmu.reset()
    s.init()
    s.run(1, 0.001)
