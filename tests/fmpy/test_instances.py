"""Several instances in one process: no shared global state, threads, and many life cycles (issue 3, item 2)."""

import ctypes
import threading
from pathlib import Path

import numpy as np
from fmpy.fmi2 import fmi2CoSimulation

from conftest import make_callbacks

FORCE = {"node[7].fx": 6.0, "node[8].fy": -3.0}


def test_stepping_one_instance_leaves_the_other_unchanged(fmus, open_fmu):
    fmu = fmus.builtin("prism2-elastic")
    a = open_fmu(fmu, name="a").init(inputs=FORCE)
    b = open_fmu(fmu, name="b").init(inputs=FORCE)
    b_before = b.outputs()
    a.set({"node[9].fz": 20.0})
    a.run(100, 0.001)
    assert np.array_equal(b.outputs(), b_before)
    assert b.status_time() == 0.0
    assert b.get(["node[9].fz"])[0] == 0.0
    # interleaved stepping gives the same results as each instance alone
    c = open_fmu(fmu, name="c").init(inputs=FORCE)
    t_a = a.time
    for k in range(50):
        b.fmu.doStep(k * 0.001, 0.001)  # the same communication points as run()
        c.fmu.doStep(k * 0.001, 0.001)
        a.fmu.doStep(t_a + k * 0.001, 0.001)
    alone = open_fmu(fmu, name="alone").init(inputs=FORCE)
    alone.run(50, 0.001)
    assert np.array_equal(b.outputs(), alone.outputs())
    assert np.array_equal(c.outputs(), alone.outputs())


def test_errors_and_reset_of_one_instance_do_not_touch_the_other(fmus, open_fmu):
    fmu = fmus.builtin("prism2")
    a = open_fmu(fmu, name="a").init()
    b = open_fmu(fmu, name="b").init(inputs=FORCE)
    b.run(20, 0.001)
    snapshot = b.outputs()
    try:
        a.set({"node[7].fx": float("nan")})
    except Exception:
        pass
    a.fmu.reset()
    a.free()
    assert np.array_equal(b.outputs(), snapshot)
    b.run(5, 0.001)


def test_two_different_fmus_in_one_process(fmus, open_fmu):
    p = fmus.builtin("prism2")
    e = fmus.builtin("prism2-elastic")
    a = open_fmu(p, name="p").init(inputs=FORCE)
    b = open_fmu(e, name="e").init(inputs=FORCE)
    a.run(30, 0.001)
    b.run(30, 0.001)
    a_alone = open_fmu(p, name="p_alone").init(inputs=FORCE)
    a_alone.run(30, 0.001)
    assert np.array_equal(a.outputs(), a_alone.outputs())
    b_alone = open_fmu(e, name="e_alone").init(inputs=FORCE)
    b_alone.run(30, 0.001)
    assert np.array_equal(b.outputs(), b_alone.outputs())
    # same start geometry, different cable laws: the first output rows agree, the motion does not
    assert p.scene["nodes"] == e.scene["nodes"]
    pos = [n for n in p.outputs if n.startswith("node[") and n[-2] == "."]
    assert not np.array_equal(a.get(pos), b.get(pos))


def test_two_threads_match_sequential_runs(fmus, open_fmu):
    fmu = fmus.builtin("tower20")
    top = fmu.scene["force_inputs"]
    inputs = [{f"node[{top[0]}].fx": 4.0}, {f"node[{top[1]}].fy": -4.0}]
    sequential = []
    for k, inp in enumerate(inputs):
        s = open_fmu(fmu, name=f"seq{k}").init(inputs=inp)
        s.run(300, 0.001)
        sequential.append(s.outputs())
    threaded = [open_fmu(fmu, name=f"thr{k}").init(inputs=inp) for k, inp in enumerate(inputs)]
    errors = []

    def work(s):
        try:
            s.run(300, 0.001)
        except Exception as e:  # pragma: no cover - reported below
            errors.append(e)

    threads = [threading.Thread(target=work, args=(s,)) for s in threaded]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []
    for s, ref in zip(threaded, sequential):
        assert np.array_equal(s.outputs(), ref)
    assert not np.array_equal(sequential[0], sequential[1])


def test_thousand_instantiate_reset_free_cycles(fmus, open_fmu):
    fmu = fmus.builtin("prism2")
    host = open_fmu(fmu, name="host")  # keeps the library loaded and gives fmpy's bindings
    f = host.fmu
    messages = []
    cb = make_callbacks(messages)
    uri = Path(fmu.dir, "resources").as_uri().encode()
    guid = fmu.md.guid.encode()
    vr = (ctypes.c_uint * 1)(fmu.vr["node[7].x"])
    x = (ctypes.c_double * 1)()
    x0 = fmu.scene["nodes"][6][0]
    for k in range(1000):
        c = f.fmi2Instantiate(b"cycle", fmi2CoSimulation, guid, uri, ctypes.byref(cb), 0, 0)
        assert c, f"cycle {k}: {messages[-1:]}"
        f.fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0)
        f.fmi2EnterInitializationMode(c)
        f.fmi2ExitInitializationMode(c)
        f.fmi2DoStep(c, 0.0, 0.001, 1)
        f.fmi2Reset(c)
        f.fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0)
        f.fmi2EnterInitializationMode(c)
        f.fmi2GetReal(c, vr, 1, x)
        assert x[0] == x0
        f.fmi2FreeInstance(c)
    assert messages == []
