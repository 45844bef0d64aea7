"""The instance state machine, instantiation checks and misuse through fmpy's low-level API (issue 3, items 1-3, 5)."""

import ctypes
import shutil

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CoSimulation, fmi2ModelExchange

from conftest import RK4, make_callbacks


@pytest.fixture
def prism2(fmus):
    return fmus.builtin("prism2")


def all_reals(s):
    return [n for n, v in s.file.variables.items() if v.type == "Real"]


def test_types_platform_and_version(prism2, open_fmu):
    s = open_fmu(prism2)
    assert s.fmu.getTypesPlatform() == "default"
    assert s.fmu.getVersion() == "2.0"


# --- instantiation -------------------------------------------------------------------


def test_wrong_guid_fails_instantiate_with_message(prism2, fmus):
    messages = []
    with pytest.raises(Exception, match="Failed to instantiate"):
        fmu_try(prism2, messages, guid="{00000000-0000-0000-0000-000000000000}")
    assert any("GUID" in m for _, _, m in messages)
    # the GUID of another scene (same binary) is just as wrong
    with pytest.raises(Exception, match="Failed to instantiate"):
        fmu_try(prism2, messages, guid=fmus.builtin("prism2-elastic").md.guid)


def fmu_try(fmu, messages, guid=None, directory=None, name="inst"):
    f = FMU2Slave(
        guid=guid or fmu.md.guid,
        unzipDirectory=directory or fmu.dir,
        modelIdentifier=fmu.md.coSimulation.modelIdentifier,
        instanceName=name,
    )
    try:
        f.instantiate(callbacks=make_callbacks(messages), loggingOn=True)
    finally:
        if f.component is None:
            f.freeLibrary()
    return f


def test_missing_resources_folder_fails_instantiate(prism2, tmp_path):
    copy = tmp_path / "no_resources"
    shutil.copytree(prism2.dir, copy, ignore=shutil.ignore_patterns("resources"))
    messages = []
    with pytest.raises(Exception, match="Failed to instantiate"):
        fmu_try(prism2, messages, directory=str(copy))
    assert messages and messages[-1][1] == "logStatusError"


def test_unreadable_scene_fails_instantiate(prism2, tmp_path):
    copy = tmp_path / "bad_scene"
    shutil.copytree(prism2.dir, copy)
    (copy / "resources" / "scene.toml").unlink()
    (copy / "resources" / "scene.toml").mkdir()  # a folder cannot be read as the scene
    messages = []
    with pytest.raises(Exception, match="Failed to instantiate"):
        fmu_try(prism2, messages, directory=str(copy))
    assert any("scene" in m for _, _, m in messages)


def test_percent_encoded_resource_uri_is_accepted(prism2, tmp_path, open_fmu):
    copy = tmp_path / "dir with space%and percent"
    shutil.copytree(prism2.dir, copy)
    s = open_fmu(prism2, directory=str(copy))  # fmpy passes file:///...%20...%25...
    s.init()
    s.run(3, 0.001)


def test_raw_instantiate_argument_checks_and_free_null(prism2, library):
    lib = library(prism2.library)
    messages = []
    cb = make_callbacks(messages)
    guid = prism2.md.guid.encode()
    res = str(prism2.dir).rstrip("/") + "/resources"
    good = f"file://{res}".encode()
    short = f"file:{res}".encode()  # file:/... form
    ptr = ctypes.cast(ctypes.byref(cb), ctypes.c_void_p)

    lib.fmi2FreeInstance(None)  # must be harmless
    for uri in (good, short):
        c = lib.fmi2Instantiate(b"raw", fmi2CoSimulation, guid, uri, ptr, 0, 1)
        assert c, f"instantiate failed for {uri!r}: {messages}"
        lib.fmi2FreeInstance(c)
    assert not lib.fmi2Instantiate(b"", fmi2CoSimulation, guid, good, ptr, 0, 1)
    assert not lib.fmi2Instantiate(b"raw", fmi2ModelExchange, guid, good, ptr, 0, 1)
    assert not lib.fmi2Instantiate(b"raw", fmi2CoSimulation, None, good, ptr, 0, 1)
    assert not lib.fmi2Instantiate(b"raw", fmi2CoSimulation, guid, None, ptr, 0, 1)
    assert not lib.fmi2Instantiate(b"raw", fmi2CoSimulation, guid, good, None, 0, 1)
    no_logger = fmi2CallbackFunctions()
    assert not lib.fmi2Instantiate(
        b"raw", fmi2CoSimulation, guid, good, ctypes.cast(ctypes.byref(no_logger), ctypes.c_void_p), 0, 1
    )
    lib.fmi2FreeInstance(None)
    c = lib.fmi2Instantiate(b"again", fmi2CoSimulation, guid, good, ptr, 0, 1)
    assert c
    lib.fmi2FreeInstance(c)


# --- illegal call sequences ----------------------------------------------------------


def test_do_step_before_initialization_is_an_error(prism2, open_fmu, capfd):
    s = open_fmu(prism2)
    with pytest.raises(FMICallException) as e:
        s.fmu.doStep(0.0, 0.001)
    assert e.value.status == 3
    assert any("illegal call sequence" in m for m in s.errors())
    s.fmu.reset()
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.enterInitializationMode()
    with pytest.raises(FMICallException):
        s.fmu.doStep(0.0, 0.001)  # still initializing
    out, err = capfd.readouterr()
    assert out == "" and err == ""  # messages go to the logger only, never to stdout/stderr


def test_get_real_before_initialization_is_an_error(prism2, open_fmu):
    s = open_fmu(prism2)
    with pytest.raises(FMICallException):
        s.get(["node[7].x"])


def test_set_fixed_parameter_after_initialization_is_an_error(prism2, open_fmu):
    s = open_fmu(prism2).init()
    with pytest.raises(FMICallException):
        s.set({"solver.step_size": 2e-3})
    assert any("solver.step_size is a fixed parameter" in m for m in s.errors())
    with pytest.raises(FMICallException):
        s.fmu.setBoolean(s.vrs(["solver.correction"]), [0])


def test_unknown_value_reference_and_wrong_types_are_errors(prism2, open_fmu):
    s = open_fmu(prism2).init()
    bad = len(prism2.md.modelVariables) + 7
    with pytest.raises(FMICallException):
        s.fmu.getReal([bad])
    assert any(str(bad) in m for m in s.errors())
    for call in (
        lambda: s.fmu.setReal([bad], [1.0]),
        lambda: s.set({"node[7].x": 1.0}),  # an output
        lambda: s.fmu.getReal(s.vrs(["solver.correction"])),  # a Boolean
        lambda: s.fmu.getInteger([0]),
        lambda: s.fmu.getString([0]),
    ):
        s.fmu.reset()
        s.init()
        with pytest.raises(FMICallException):
            call()


def test_set_debug_logging_unknown_category_is_an_error(prism2, open_fmu):
    s = open_fmu(prism2)
    s.fmu.setDebugLogging(True, ["logStatusError"])
    with pytest.raises(FMICallException):
        s.fmu.setDebugLogging(True, ["noSuchCategory"])


def test_log_messages_escape_percent_for_printf(prism2, library):
    raw = []
    cb = make_callbacks([])
    logger_type = type(cb.logger)
    cb.logger = logger_type(lambda env, name, status, cat, msg: raw.append(msg.decode()))
    s_lib = library(prism2.library)
    uri = ("file://" + str(prism2.dir).rstrip("/") + "/resources").encode()
    c = s_lib.fmi2Instantiate(
        b"pct", fmi2CoSimulation, prism2.md.guid.encode(), uri,
        ctypes.cast(ctypes.byref(cb), ctypes.c_void_p), 0, 1,
    )
    assert c
    try:
        s_lib.fmi2SetDebugLogging.argtypes = [
            ctypes.c_void_p, ctypes.c_int, ctypes.c_size_t, ctypes.POINTER(ctypes.c_char_p)
        ]
        cats = (ctypes.c_char_p * 1)(b"bad%s%n")
        assert s_lib.fmi2SetDebugLogging(c, 1, 1, cats) == 3
    finally:
        s_lib.fmi2FreeInstance(c)
    assert raw, "no message logged"
    assert "bad%%s%%n" in raw[-1]
    assert "%" not in raw[-1].replace("%%", "")


def test_log_categories_are_honoured(prism2, open_fmu):
    s = open_fmu(prism2, logging=True)
    s.fmu.setDebugLogging(False, ["logStatusError"])
    with pytest.raises(FMICallException):
        s.fmu.doStep(0.0, 0.001)
    assert s.errors() == []
    s.fmu.reset()
    s.fmu.setDebugLogging(True, ["logStatusError"])
    with pytest.raises(FMICallException):
        s.fmu.doStep(0.0, 0.001)
    assert len(s.errors()) == 1
    s.fmu.reset()
    s.init()
    s.fmu.setDebugLogging(False, ["logStatusWarning"])
    s.set({"cable[7].force_density": -1.0})  # a warning, but warnings are off
    assert s.warnings() == []
    declared = {c.name for c in prism2.md.logCategories}
    assert {c for _, c, _ in s.messages} <= declared


def test_logging_off_sends_no_informational_messages(prism2, open_fmu):
    s = open_fmu(prism2, logging=False).init()
    s.run(5, 0.001)
    s.fmu.reset()
    s.init()
    assert [c for _, c, _ in s.messages if c not in ("logStatusWarning", "logStatusError")] == []


def test_terminate_then_status_and_no_more_steps(prism2, open_fmu):
    s = open_fmu(prism2).init()
    s.run(5, 0.001)
    assert s.terminated() is False
    assert s.status_time() == pytest.approx(0.005, abs=1e-15)
    s.fmu.terminate()
    assert s.terminated() is True
    with pytest.raises(FMICallException):
        s.fmu.doStep(0.005, 0.001)


# --- reset ---------------------------------------------------------------------------


def test_reset_restores_exactly_the_post_instantiate_state(prism2, open_fmu):
    s = open_fmu(prism2)
    names = all_reals(s)
    state = s.fmu.getFMUstate()  # legal right after instantiate
    fresh_blob = s.fmu.serializeFMUstate(state)
    s.fmu.freeFMUstate(state)
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.enterInitializationMode()
    fresh = s.get(names)
    s.set({"bar[2].mass": 3.0, "cable[7].force_density": 40.0})
    s.fmu.exitInitializationMode()
    s.set({"node[8].fy": 7.0})
    s.run(40, 0.001)
    assert not np.array_equal(s.get(names), fresh)
    s.fmu.reset()
    # everything an FMU state holds (mode, time, inputs, parameters, state) is as after instantiate
    state = s.fmu.getFMUstate()
    assert s.fmu.serializeFMUstate(state) == fresh_blob
    s.fmu.freeFMUstate(state)
    with pytest.raises(FMICallException):
        s.get(names)  # back in Instantiated: GetReal is illegal again
    s.fmu.reset()
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.enterInitializationMode()
    assert np.array_equal(s.get(names), fresh)
    assert s.fmu.getBoolean(s.vrs(["solver.correction"])) == [1]
    s.fmu.exitInitializationMode()
    s.time = 0.0
    s.set({"node[8].fy": 7.0})
    s.run(40, 0.001)  # time restarts at 0
    ref = open_fmu(prism2, name="ref").init()
    ref.set({"node[8].fy": 7.0})
    ref.run(40, 0.001)
    assert np.array_equal(s.outputs(), ref.outputs())


# --- DoStep --------------------------------------------------------------------------


@pytest.mark.parametrize(
    "t, h",
    [(0.5, 0.001), (0.0005, 0.001), (0.0, 0.0), (0.0, -0.001), (0.0, float("nan"))],
)
def test_do_step_bad_point_or_size_is_an_error(prism2, open_fmu, t, h):
    s = open_fmu(prism2).init()
    before = s.outputs()
    with pytest.raises(FMICallException):
        s.fmu.doStep(t, h)
    assert any("fmi2DoStep" in m for m in s.errors())
    assert s.status_time() == 0.0
    assert np.array_equal(s.outputs(), before)
    # a refused call changed nothing, so the instance carries on where it was
    s.run(2, 0.001)
    assert s.status_time() == pytest.approx(0.002, abs=1e-15)
    ref = open_fmu(prism2, name="ref").init()
    ref.run(2, 0.001)
    assert np.array_equal(s.outputs(), ref.outputs())


def test_one_10ms_step_equals_ten_1ms_steps(fmus, open_fmu):
    fmu = fmus.builtin("prism2-elastic")
    a = open_fmu(fmu, name="a").init(inputs={"node[7].fx": 20.0}, integers=RK4)
    b = open_fmu(fmu, name="b").init(inputs={"node[7].fx": 20.0}, integers=RK4)
    a.run(5, 0.01)
    b.run(50, 0.001)
    assert np.max(np.abs(a.outputs() - b.outputs())) <= 1e-12
    assert a.status_time() == pytest.approx(b.status_time(), abs=1e-12)


def test_step_not_a_multiple_of_internal_step_shortens_the_last_one(fmus, open_fmu):
    fmu = fmus.builtin("prism2-elastic")
    force = {"node[7].fx": 20.0}
    a = open_fmu(fmu, name="a").init(inputs=force, integers=RK4)
    a.run(4, 0.0025)
    assert a.status_time() == pytest.approx(0.01, abs=1e-14)
    a.fmu.doStep(a.status_time(), 0.001)  # time continues from 0.01
    assert a.status_time() == pytest.approx(0.011, abs=1e-14)
    # internal steps 1 + 1 + 0.5 ms, then 1 + 1 + 0.5 ms ...
    b = open_fmu(fmu, name="b").init(inputs=force, integers=RK4)
    for t, h in [(0.0, 0.001), (0.001, 0.001), (0.002, 0.0005)]:
        b.fmu.doStep(t, h)
    c = open_fmu(fmu, name="c").init(inputs=force, integers=RK4)
    c.fmu.doStep(0.0, 0.0025)
    assert np.max(np.abs(b.outputs() - c.outputs())) <= 1e-12
    # and close to a run in whole internal steps (RK4 error of the shortened steps only)
    d = open_fmu(fmu, name="d").init(inputs=force, integers=RK4)
    d.run(11, 0.001)
    pos = [n for n in fmu.outputs if n.startswith("node[") and n[-2] == "."]
    diff = np.max(np.abs(a.get(pos) - d.get(pos)))
    assert 0 < diff < 1e-9


def test_last_successful_time_status(prism2, open_fmu):
    s = open_fmu(prism2)
    with pytest.raises(FMICallException):
        s.status_time()  # not before initialization
    s.fmu.reset()
    s.init(start=0.25)
    assert s.status_time() == 0.25
    s.run(3, 0.001)
    assert s.status_time() == pytest.approx(0.253, abs=1e-14)
