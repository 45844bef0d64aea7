"""FMU state: get/set/free, serialize/deserialize, and rejection of foreign or corrupt buffers (issue 3, item 4)."""

import hashlib
import struct
import tomllib

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from conftest import RK4

FORCE = {"node[7].fx": 8.0, "node[9].fz": -2.0}


@pytest.fixture
def elastic(fmus):
    return fmus.builtin("prism2-elastic")


def reference(open_fmu, fmu, steps, h=0.001, **init):
    """Outputs of an uninterrupted run of `steps` steps (a second, independent instance)."""
    ref = open_fmu(fmu, name=f"ref{steps}").init(**init)
    ref.run(steps, h)
    return ref.outputs()


def test_get_set_state_round_trip_is_bit_identical(elastic, open_fmu):
    s = open_fmu(elastic).init(inputs=FORCE, integers=RK4)
    s.run(30, 0.001)
    state = s.fmu.getFMUstate()
    at_state = s.outputs()
    s.set({"node[7].fx": -50.0, "node[8].fy": 12.0})  # inputs are part of the state too
    s.run(20, 0.001)
    diverged = s.outputs()
    s.fmu.setFMUstate(state)
    s.time = 0.03
    assert np.array_equal(s.outputs(), at_state)
    assert s.get(["node[7].fx", "node[8].fy"]).tolist() == [8.0, 0.0]
    assert s.status_time() == pytest.approx(0.03, abs=1e-15)
    s.run(20, 0.001)
    uninterrupted = reference(open_fmu, elastic, 50, inputs=FORCE, integers=RK4)
    assert np.array_equal(s.outputs(), uninterrupted)
    assert not np.array_equal(diverged, uninterrupted)
    # the state can be set again, any number of times
    s.fmu.setFMUstate(state)
    assert np.array_equal(s.outputs(), at_state)
    s.fmu.freeFMUstate(state)


def test_set_state_rewinds_time_for_the_next_step(elastic, open_fmu):
    s = open_fmu(elastic).init(inputs=FORCE)
    s.run(10, 0.001)
    state = s.fmu.getFMUstate()
    s.run(10, 0.001)
    s.fmu.setFMUstate(state)
    with pytest.raises(FMICallException):
        s.fmu.doStep(0.02, 0.001)  # the instance is back at t = 0.01
    s.fmu.setFMUstate(state)  # recovers from that error too
    s.fmu.doStep(0.01, 0.001)
    s.fmu.freeFMUstate(state)


def test_serialize_deserialize_round_trip_same_instance(elastic, open_fmu):
    s = open_fmu(elastic).init(inputs=FORCE, integers=RK4)
    s.run(25, 0.001)
    state = s.fmu.getFMUstate()
    blob = s.fmu.serializeFMUstate(state)
    assert blob == s.fmu.serializeFMUstate(state)  # deterministic
    s.fmu.freeFMUstate(state)
    at_state = s.outputs()
    s.run(25, 0.001)
    restored = s.fmu.deSerializeFMUstate(blob)
    s.fmu.setFMUstate(restored)
    s.time = 0.025
    assert np.array_equal(s.outputs(), at_state)
    assert s.fmu.serializeFMUstate(restored) == blob
    s.run(25, 0.001)
    assert np.array_equal(s.outputs(), reference(open_fmu, elastic, 50, inputs=FORCE, integers=RK4))
    s.fmu.freeFMUstate(restored)


def test_serialized_state_moves_to_another_instance(elastic, open_fmu):
    a = open_fmu(elastic, name="a").init(inputs=FORCE)
    a.run(40, 0.001)
    blob = a.fmu.serializeFMUstate(a.fmu.getFMUstate())
    b = open_fmu(elastic, name="b").init()  # different inputs, at t = 0
    state = b.fmu.deSerializeFMUstate(blob)
    b.fmu.setFMUstate(state)
    b.time = 0.04
    assert np.array_equal(b.outputs(), a.outputs())
    a.run(10, 0.001)
    b.run(10, 0.001)
    assert np.array_equal(b.outputs(), a.outputs())
    b.fmu.freeFMUstate(state)


def test_state_carries_parameters_set_in_initialization(elastic, open_fmu):
    heavy = open_fmu(elastic, name="heavy").init(params={"bar[5].mass": 3.0}, inputs=FORCE)
    heavy.run(20, 0.001)
    blob = heavy.fmu.serializeFMUstate(heavy.fmu.getFMUstate())
    plain = open_fmu(elastic, name="plain").init(inputs=FORCE)
    plain.run(20, 0.001)
    plain.fmu.setFMUstate(plain.fmu.deSerializeFMUstate(blob))
    plain.time = 0.02
    assert plain.get(["bar[5].mass"])[0] == 3.0
    heavy.run(30, 0.001)
    plain.run(30, 0.001)
    assert np.array_equal(plain.outputs(), heavy.outputs())
    unchanged = reference(open_fmu, elastic, 50, inputs=FORCE)
    assert not np.array_equal(plain.outputs(), unchanged)


def test_state_from_initialization_mode(elastic, open_fmu):
    s = open_fmu(elastic)
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.enterInitializationMode()
    early = s.fmu.getFMUstate()
    s.fmu.exitInitializationMode()
    s.run(5, 0.001)
    s.fmu.setFMUstate(early)
    s.set(FORCE)  # an input, in initialization mode again
    s.fmu.exitInitializationMode()
    s.time = 0.0
    s.run(30, 0.001)
    assert np.array_equal(s.outputs(), reference(open_fmu, elastic, 30, inputs=FORCE))
    s.fmu.freeFMUstate(early)


# --- rejected buffers ----------------------------------------------------------------


def header_offsets(blob):
    """(guid_start, guid_end, time_offset) of the serialized layout: magic, version, GUID, mode, time."""
    (n,) = struct.unpack_from("<Q", blob, 12)
    return 20, 20 + n, 20 + n + 1


def corruptions(blob):
    g0, g1, t = header_offsets(blob)
    flip = lambda b, i: b[:i] + bytes([b[i] ^ 0xFF]) + b[i + 1 :]  # noqa: E731
    return {
        "magic": flip(blob, 0),
        "version": flip(blob, 8),
        "guid length": flip(blob, 12),
        "guid": flip(blob, g0 + 5),
        "mode": flip(blob, g1),
        "nan time": blob[:t] + struct.pack("<d", float("nan")) + blob[t + 8 :],
        "truncated to half": blob[: len(blob) // 2],
        "truncated by one": blob[:-1],
        "header only": blob[:12],
        "trailing byte": blob + b"\0",
        "empty": b"",
        "garbage": bytes(range(256)) * 4,
    }


@pytest.fixture
def prism2_blob(fmus, open_fmu):
    s = open_fmu(fmus.builtin("prism2"), name="source").init()
    s.run(10, 0.001)
    state = s.fmu.getFMUstate()
    blob = s.fmu.serializeFMUstate(state)
    s.fmu.freeFMUstate(state)
    return blob


def assert_rejected_then_usable(s, blob, open_fmu):
    before = s.outputs()
    with pytest.raises(FMICallException) as e:
        state = s.fmu.deSerializeFMUstate(blob)
        s.fmu.setFMUstate(state)  # should not get here; if it does, setting must fail
    assert e.value.status == 3
    assert s.errors(), "the rejection was not logged"
    s.fmu.reset()
    s.init()
    s.run(10, 0.001)
    assert np.array_equal(s.outputs(), before)  # same history as before the rejection


@pytest.mark.parametrize(
    "kind",
    [
        "magic", "version", "guid length", "guid", "mode", "nan time", "truncated to half",
        "truncated by one", "header only", "trailing byte", "empty", "garbage",
    ],
)
def test_corrupt_buffer_is_rejected_and_instance_recovers(fmus, open_fmu, prism2_blob, kind):
    bad = corruptions(prism2_blob)[kind]
    assert bad != prism2_blob
    s = open_fmu(fmus.builtin("prism2")).init()
    s.run(10, 0.001)
    assert_rejected_then_usable(s, bad, open_fmu)


def test_state_of_a_different_fmu_is_rejected(fmus, open_fmu):
    other = open_fmu(fmus.builtin("prism2-elastic"), name="other").init()
    other.run(10, 0.001)
    foreign = other.fmu.serializeFMUstate(other.fmu.getFMUstate())
    s = open_fmu(fmus.builtin("prism2")).init()
    s.run(10, 0.001)
    assert_rejected_then_usable(s, foreign, open_fmu)
    assert any("another FMU" in m or "GUID" in m for m in s.errors())


def test_every_flipped_bit_past_the_header_is_rejected(fmus, open_fmu, prism2_blob):
    """Flip the low bit of each byte after the GUID, one at a time: a state double, an input,
    a length, or (if the buffer carries it) the scene text, where '5' becomes '4' in a node
    coordinate. Such a buffer is well-formed but no instance of this FMU produced it.
    """
    fmu = fmus.builtin("prism2")
    s = open_fmu(fmu).init()
    s.run(10, 0.001)
    before = s.outputs()
    _, guid_end, _ = header_offsets(prism2_blob)
    accepted = []
    for i in range(guid_end, len(prism2_blob)):
        bad = prism2_blob[:i] + bytes([prism2_blob[i] ^ 0x01]) + prism2_blob[i + 1 :]
        try:
            state = s.fmu.deSerializeFMUstate(bad)
            s.fmu.setFMUstate(state)
        except FMICallException:
            continue
        s.fmu.freeFMUstate(state)
        changed = [n for n, a, b in zip(fmu.outputs, before, s.outputs()) if a != b]
        accepted.append((i, prism2_blob[i - 6 : i + 6], changed[:3]))
    s.fmu.reset()
    s.init()
    s.run(10, 0.001)
    assert np.array_equal(s.outputs(), before)
    moved_pinned = [a for a in accepted if any(n.startswith(("node[1].", "node[2].", "node[3].")) for n in a[2])]
    assert accepted == [], (
        f"{len(accepted)} of {len(prism2_blob) - guid_end} corrupt buffers accepted, "
        f"{len(moved_pinned)} of them moving a pinned node; e.g. {(moved_pinned or accepted)[:3]}"
    )


@pytest.mark.parametrize("method,h", [(2, 0.05), (3, 0.001), (4, 0.001)])  # dopri5, rattle, sdirk3
def test_state_resumes_bit_identically_for_every_method(elastic, open_fmu, method, h):
    """Methods that carry values between steps (dopri5's step size and last stage, rattle's
    acceleration, sdirk3's iteration matrix, rebuilt where it was taken) must resume exactly
    after set and after serialize/deserialize."""

    def start(name):
        s = open_fmu(elastic, name=name)
        s.fmu.setupExperiment(startTime=0.0)
        s.fmu.enterInitializationMode()
        s.fmu.setInteger(s.vrs(["solver.method"]), [method])
        s.set(FORCE)
        s.fmu.exitInitializationMode()
        return s

    def steps(slave, first, last):
        # The same communication points k h in every run: an adaptive method's last
        # internal step is clipped to them, so they must agree to the bit.
        for k in range(first, last):
            slave.fmu.doStep(k * h, h)

    ref = start("ref")
    steps(ref, 0, 20)
    s = start("s")
    steps(s, 0, 10)
    state = s.fmu.getFMUstate()
    blob = s.fmu.serializeFMUstate(state)
    steps(s, 10, 20)
    assert np.array_equal(s.outputs(), ref.outputs())
    for restored in (state, s.fmu.deSerializeFMUstate(blob)):
        s.fmu.setFMUstate(restored)
        steps(s, 10, 20)
        assert np.array_equal(s.outputs(), ref.outputs())
        s.fmu.freeFMUstate(restored)


# --- forged buffers: well-formed, resealed with a recomputed SHA-256 -----------------


def layout(blob):
    """Offsets of the fields a forger edits, read from the serialized layout: magic,
    version, GUID, mode, two times, stop flag and time, then arrays with u64 lengths."""
    at = 20 + struct.unpack_from("<Q", blob, 12)[0] + 1 + 8 + 8 + 1 + 8
    fields = {}
    for name, size in (("y", 8), ("force_density", 8), ("node_force", 24), ("rest_length", 8), ("warned", 1)):
        (n,) = struct.unpack_from("<Q", blob, at)
        fields[name] = (at, n)
        at += 8 + n * size
    at += 1  # the pending-rebuild flag
    (n,) = struct.unpack_from("<Q", blob, at)
    fields["parameters"] = (at, n)
    return fields


def resealed(body):
    return bytes(body) + hashlib.sha256(bytes(body)).digest()


def with_double(blob, field, k, value):
    at, n = layout(blob)[field]
    assert k < n
    body = bytearray(blob[:-32])
    struct.pack_into("<d", body, at + 8 + 8 * k, value)
    return resealed(body)


def parameter_index(fmu, name):
    """The state holds parameter values in value-reference order."""
    parameters = sorted(
        (v for v in fmu.md.modelVariables if v.causality == "parameter"), key=lambda v: v.valueReference
    )
    return [v.name for v in parameters].index(name)


def forged(fmu, blob):
    return {
        "solver.method = 7": with_double(blob, "parameters", parameter_index(fmu, "solver.method"), 7.0),
        "solver.correction = 0.5": with_double(blob, "parameters", parameter_index(fmu, "solver.correction"), 0.5),
        "node at 1e300 m": with_double(blob, "y", 0, 1e300),
        "one force-density input short": short_array(blob, "force_density"),
    }


def short_array(blob, field):
    at, n = layout(blob)[field]
    body = blob[:at] + struct.pack("<Q", n - 1) + blob[at + 8 : at + 8 + 8 * (n - 1)] + blob[at + 8 + 8 * n : -32]
    return resealed(body)


@pytest.mark.parametrize(
    "kind,parts",
    [
        ("solver.method = 7", ["solver.method = 7 is not a method (1 = rk4, 2 = dopri5, 3 = rattle, 4 = sdirk3)"]),
        ("solver.correction = 0.5", ["solver.correction = 0.5 is not a Boolean (0 or 1)"]),
        # The reduced coordinate moves a bar end by 1/√2 of itself (two bars share the node).
        ("node at 1e300 m", ["position: x = 7.07106781186547", "e+299 m is outside ±1e9 m"]),
        ("one force-density input short", ["holds {n} force-density inputs, this FMU has {cables}"]),
    ],
)
def test_forged_state_with_a_recomputed_checksum_is_refused_naming_the_field(
    fmus, open_fmu, prism2_blob, kind, parts
):
    fmu = fmus.builtin("prism2")
    cables = len(tomllib.loads(fmu.scene_text)["cables"])  # all force-density controlled
    bad = forged(fmu, prism2_blob)[kind]
    assert hashlib.sha256(bad[:-32]).digest() == bad[-32:]
    s = open_fmu(fmu).init()
    s.run(10, 0.001)
    assert_rejected_then_usable(s, bad, open_fmu)
    refusals = [m for m in s.errors() if m.startswith("fmi2DeSerializeFMUstate: ")]
    assert len(refusals) == 1, s.errors()
    for part in parts:
        assert part.format(n=cables - 1, cables=cables) in refusals[0], refusals[0]
