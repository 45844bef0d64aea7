"""Fuzzing of sweep specs with hypothesis: arbitrary and malformed specs (wrong types, huge
numbers, NaN, nested junk, paths out of the folder) are either accepted or refused with a
SpecError of one line, never another exception, and in bounded time.

In-process: each example runs every check that `sweep.run` makes before any work
(`parse`, `check_size`, the scene keys of a variant, `resolve` against a real FMU's model
description, the first and last samples), with no subprocess per example. A few specs
run as the command does, to show exit code 2 and one line on the terminal.

CI runs a few hundred examples; a long run sets SWEEP_FUZZ_EXAMPLES and prints its figures:
    SWEEP_FUZZ_EXAMPLES=100000 .venv/bin/python -m pytest -q -s tests/fmpy/test_sweep_fuzz.py -k any_spec_is
"""

import copy
import dataclasses
import functools
import os
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

REPO = Path(__file__).resolve().parents[2]
SWEEP = REPO / "fmu" / "sweep" / "sweep.py"
sys.path.insert(0, str(SWEEP.parent))
import sweep_results  # noqa: E402
import sweep_scene  # noqa: E402
import sweep_spec  # noqa: E402
from sweep_spec import SpecError  # noqa: E402

EXAMPLES = int(os.environ.get("SWEEP_FUZZ_EXAMPLES", "200"))
# A hang detector, not a speed check: a spec is read in well under a millisecond.
FUZZ = settings(max_examples=EXAMPLES, deadline=10_000, suppress_health_check=[HealthCheck.too_slow], database=None,
                derandomize=EXAMPLES <= 200)

NAMES = ["node[7].fx", "node[7].x", "cable[*].stiffness", "cable[1].stiffness", "cable[99].stiffness",
         "solver.method", "solver.max_steps", "solver.step_size", "solver.correction", "solver.rtol", "x"]
SCENE_KEYS = ["prestress.min_tension", "cables[*].stiffness", "cables[16].stiffness", "cables[0].stiffness",
              "name", "gravity", "nodes", "nodes[1]", "prestress", "a.b[*].c", "cables[x]", ""]
PATHS = ["../../escaped", "/tmp/escaped", "a/b", "..", ".", "a\\b", "-x", "ok", "\0", "x.fmu", "x.toml"]
leaf = st.one_of(
    st.booleans(),
    st.integers(min_value=-2**63, max_value=2**63 - 1),
    st.sampled_from([0, 1, -1, 2**31 - 1, 2**31, -2**31 - 1, 10**18]),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -0.0, 1e-300, 1e300, 5e-324, float("nan"), float("inf"), -float("inf")]),
    st.text(max_size=12),
    st.sampled_from(PATHS + NAMES),
)
deep = st.integers(1, 300).map(lambda depth: functools.reduce(lambda x, _: [x], range(depth), 1.0))
junk = st.recursive(leaf, lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner, max_size=3),
                    max_leaves=12) | deep
value_lists = st.lists(st.one_of(leaf, junk), max_size=6) | junk


def table(keys):
    return st.dictionaries(st.sampled_from(keys) | st.text(max_size=12), value_lists, max_size=4) | junk


ONE_IN_8 = st.integers(0, 7)


def pick(draw, valid, bad=junk):
    """Usually a valid value, so that examples get past the first checks and reach the later ones."""
    return draw(bad if draw(ONE_IN_8) == 0 else valid)


OUTPUTS = ["node[7].x", "node[7].z", "cable[1].tension"]
SETTABLE = {"node[7].fx": st.floats(-10, 10), "cable[*].stiffness": st.floats(1, 1e4),
            "solver.method": st.integers(0, 5), "solver.max_steps": st.integers(-1, 2**32),
            "solver.correction": st.booleans(), "solver.rtol": st.floats(0, 1), "node[7].x": st.floats(-1, 1)}
SCENE_VALUES = {"prestress.min_tension": st.floats(0, 50), "cables[*].stiffness": st.floats(-1, 1e4),
                "name": st.sampled_from(PATHS) | st.text(max_size=8), "gravity": st.lists(st.floats(-10, 10), max_size=4)}
LISTS = {n: st.lists(v, min_size=1, max_size=12) for n, v in {**SETTABLE, **SCENE_VALUES}.items()}
RANGES = st.dictionaries(st.sampled_from(NAMES), st.tuples(st.floats(-10, 0), st.floats(1e-3, 10)).map(list),
                         min_size=1, max_size=2)


def lists_of(draw, names):
    return {n: pick(draw, LISTS[n], value_lists) for n in draw(st.sets(st.sampled_from(sorted(names)), max_size=3))}


@st.composite
def spec_dicts(draw):
    """Mostly well-formed specs with some of their parts replaced by junk, or junk alone."""
    if draw(st.integers(0, 9)) == 0:
        return draw(st.dictionaries(st.text(max_size=10) | st.sampled_from(sorted(sweep_spec.KNOWN)), junk, max_size=5))
    scene = draw(st.booleans())
    raw = {"scene": pick(draw, st.just("prism2-elastic"))} if scene else {"fmu": pick(draw, st.just("x.fmu"))}
    raw["stop_time"] = pick(draw, st.floats(1e-3, 1e3))
    fraction = draw(st.floats(1e-9, 1.0))
    raw["step"] = pick(draw, st.just(fraction * raw["stop_time"] if isinstance(raw["stop_time"], float) else fraction))
    raw["outputs"] = pick(draw, st.lists(st.sampled_from(OUTPUTS), min_size=1, max_size=3), st.lists(st.sampled_from(NAMES)))
    if draw(st.booleans()):
        raw["warm_start"] = pick(draw, st.floats(1e-3, 1e3))
    raw["parameters"] = lists_of(draw, SETTABLE) if draw(ONE_IN_8) else draw(table(NAMES))
    if scene and draw(st.booleans()):
        raw["scene_parameters"] = lists_of(draw, SCENE_VALUES) if draw(ONE_IN_8) else draw(table(SCENE_KEYS))
    if draw(st.integers(0, 3)) == 0:
        raw["random"] = {"n": pick(draw, st.integers(1, 10**12), leaf), "seed": pick(draw, st.integers(0, 2**63 - 1), leaf),
                         "ranges": pick(draw, RANGES, table(NAMES))} if draw(ONE_IN_8) else draw(junk)
    for key in draw(st.lists(st.sampled_from(sorted(sweep_spec.KNOWN) + ["extra"]), max_size=1)):
        raw[key] = draw(junk)  # one part replaced by junk
    return raw


@pytest.fixture(scope="module")
def context(fmus):
    elastic = fmus.builtin("prism2-elastic")
    return elastic.md, tomllib.loads(elastic.scene_text)


STATS = {"specs": 0, "accepted": 0, "seconds": 0.0, "slowest": 0.0}


@pytest.fixture(scope="module", autouse=True)
def figures():
    """A long run prints its figures (with -s): specs, accepted, time per spec."""
    yield
    if EXAMPLES > 200 and STATS["specs"]:
        print(f"\n{STATS['specs']} specs: {STATS['accepted']} accepted, {STATS['specs'] - STATS['accepted']} "
              f"refused in one line; checks {STATS['seconds'] / STATS['specs'] * 1e6:.0f} µs per spec "
              f"on average, slowest {STATS['slowest'] * 1e3:.1f} ms")


def validate(raw, md, scene):
    """Every check sweep.run makes before work starts, in its order; returns the spec."""
    spec = sweep_spec.parse(raw, Path("/nonexistent/spec.toml"))
    runs = sweep_spec.check_size(spec, force=False)
    if spec.scene:
        sweep_spec.check_scene_name("scene: name", scene["name"])
        variants = sweep_spec.Samples(dataclasses.replace(spec, parameters={}, random=None))
        for combo in (variants[0], variants[len(variants) - 1]):
            edited = copy.deepcopy(scene)
            for path, value in combo.items():
                sweep_scene.set_scene_key(edited, path, value)
            tomllib.loads(sweep_scene.dumps(edited))  # the variant the CLI would build reads back
    sweep_spec.resolve(spec, md)
    samples = sweep_spec.samples(spec)
    header = sweep_results.header(spec.swept(), spec.outputs)
    for sample in (samples[0], samples[runs - 1]):
        sweep_spec.fmu_values(spec, sample)
        assert len([sweep_results.fmt(sample[n]) for n in spec.swept()]) == len(header) - 2 - 3 * len(spec.outputs)
    return spec


def one_line(error):
    text = str(error)
    assert text and "\n" not in text and "\r" not in text and len(text.splitlines()) == 1, repr(text)


@FUZZ
@given(raw=spec_dicts())
def test_any_spec_is_accepted_or_refused_in_one_line(context, raw):
    md, scene = context
    started = time.perf_counter()
    try:
        validate(raw, md, scene)
        STATS["accepted"] += 1
    except SpecError as e:
        one_line(e)
    seconds = time.perf_counter() - started
    STATS["specs"] += 1
    STATS["seconds"] += seconds
    STATS["slowest"] = max(STATS["slowest"], seconds)


@FUZZ
@given(text=st.text(max_size=200) | spec_dicts().map(lambda d: sweep_scene.dumps(d) if isinstance(d, dict) else ""))
def test_any_spec_file_is_read_or_refused_in_one_line(tmp_path_factory, text):
    path = tmp_path_factory.getbasetemp() / "fuzz-spec.toml"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    try:
        sweep_spec.load(path)
    except SpecError as e:
        one_line(e)


@pytest.mark.parametrize("text", [
    'fmu = [[1, {a = nan}]]\nstop_time = {x = 1}\n',
    'scene = "prism2-elastic"\nstop_time = 1\nstep = 0.1\noutputs = ["node[7].x"]\n'
    '[scene_parameters]\n"name" = ["..", "ok"]\n',
    'fmu = "x.fmu"\nstop_time = 1e308\nstep = 5e-324\noutputs = ["a"]\n',
    'fmu = "x.fmu"\nstop_time = 1\nstep = 0.1\noutputs = ["a"]\n[random]\nn = 9223372036854775807\nseed = -1\nranges = 3\n',
    'fmu = "x.fmu"\nstop_time = 1\nstep = 0.1\noutputs = ["a\\nb"]\n[parameters]\n"\\u001b[31mred" = [{}]\n',
])
def test_junk_on_the_command_line_is_one_line_and_exit_2(tmp_path, text):
    (tmp_path / "spec.toml").write_text(text)
    res = subprocess.run([sys.executable, str(SWEEP), str(tmp_path / "spec.toml"), "-o", str(tmp_path / "out")],
                         capture_output=True, text=True, timeout=60)
    assert res.returncode == 2 and res.stderr.startswith("error: ") and res.stderr.count("\n") == 1, res.stderr
    assert "\x1b" not in res.stderr and not (tmp_path / "out").exists()
