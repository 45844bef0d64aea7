"""fmu/sweep/sweep.py (issue 15): grid and random sweeps on a local Dask cluster, error rows,
--resume after a kill, and spec errors.

Every sweep runs as the command a user types, in its own process group with TMPDIR under
the test's folder, and each test checks that no process of the group is left behind.
Expected values come from serial fmpy runs (`simulate_fmu`) of the same samples.
"""

import csv
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from fmpy import simulate_fmu

REPO = Path(__file__).resolve().parents[2]
SWEEP = REPO / "fmu" / "sweep" / "sweep.py"
sys.path.insert(0, str(SWEEP.parent))
import sweep_spec  # noqa: E402
from sweep import main as sweep_main  # noqa: E402

OUTPUTS = ["node[7].x", "cable[1].tension"]


def start(tmp_path, spec_text, *args):
    spec = tmp_path / "spec.toml"
    spec.write_text(spec_text)
    (tmp_path / "tmp").mkdir(exist_ok=True)
    env = dict(os.environ, TMPDIR=str(tmp_path / "tmp"))
    return subprocess.Popen([sys.executable, str(SWEEP), str(spec), "-o", str(tmp_path / "out"), *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                            start_new_session=True)


def assert_group_gone(pid, timeout=10.0):
    """No process of the sweep's group (its Dask workers included) outlives it."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            os.killpg(pid, 0)
        except ProcessLookupError:
            return
        time.sleep(0.05)
    os.killpg(pid, signal.SIGKILL)
    pytest.fail("processes of the sweep outlived it")


def sweep(tmp_path, spec_text, *args):
    proc = start(tmp_path, spec_text, *args)
    out, err = proc.communicate(timeout=120)
    assert_group_gone(proc.pid)
    return proc.returncode, out, err


def rows(tmp_path):
    with open(tmp_path / "out" / "results.csv", newline="") as f:
        return list(csv.DictReader(f))


def serial(fmu_path, values, stop_time, step):
    """final, min and max of each output from one fmpy run of the sample."""
    res = simulate_fmu(str(fmu_path), stop_time=stop_time, output_interval=step,
                       start_values=values, output=OUTPUTS)
    return {f"{o}.{s}": f(res[o]) for o in OUTPUTS for s, f in
            (("final", lambda a: a[-1]), ("min", np.min), ("max", np.max))}


def spec_for(fmu, body, stop_time=0.3, step=0.01):
    return f'fmu = "{fmu}"\nstop_time = {stop_time}\nstep = {step}\noutputs = {OUTPUTS!r}\n'.replace("'", '"') + body


@pytest.fixture(scope="module")
def elastic(fmus):
    return fmus.builtin("prism2-elastic")


def test_grid_on_two_workers_is_bit_identical_to_serial_fmpy_runs(elastic, tmp_path):
    body = '[parameters]\n"cable[*].stiffness" = [350.0, 500.0, 800.0]\n"node[7].fx" = [0.0, 3.0]\n'
    code, out, err = sweep(tmp_path, spec_for(elastic.path, body), "--workers", "2")
    assert code == 0, err
    got = rows(tmp_path)
    assert [r["sample"] for r in sorted(got, key=lambda r: int(r["sample"]))] == [str(i) for i in range(6)]
    assert {(r["cable[*].stiffness"], r["node[7].fx"]) for r in got} == {
        (k, f) for k in ("350.0", "500.0", "800.0") for f in ("0.0", "3.0")}
    cables = [n for n in elastic.vr if re.fullmatch(r"cable\[\d+\]\.stiffness", n)]
    assert len(cables) == 15
    for r in got:
        assert r["status"] == "ok"
        values = {c: float(r["cable[*].stiffness"]) for c in cables} | {"node[7].fx": float(r["node[7].fx"])}
        expected = serial(elastic.path, values, 0.3, 0.01)
        assert {k: float(r[k]) for k in expected} == expected  # bit for bit
    # the samples differ: the load moves node 7, the stiffness scales the prestress
    assert len({(r["node[7].x.max"], r["cable[1].tension.final"]) for r in got}) == 6
    # each worker instantiated its FMU once and reset it for its other samples
    m = re.search(r"6 samples run \(6 ok, 0 failed\) .* on 2 workers, (\d) FMU instances", out)
    assert m and 1 <= int(m.group(1)) <= 2, out
    png = tmp_path / "out" / "summary.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_an_invalid_value_is_an_error_row_and_the_rest_complete(elastic, tmp_path):
    body = '[parameters]\n"cable[1].stiffness" = [500.0, -5.0, 300.0, 700.0]\n'
    code, out, err = sweep(tmp_path, spec_for(elastic.path, body), "--workers", "2")
    assert code == 0, err
    got = {r["cable[1].stiffness"]: r for r in rows(tmp_path)}
    assert len(got) == 4
    bad = got.pop("-5.0")
    assert "cable[1].stiffness" in bad["status"] and "-5" in bad["status"], bad["status"]
    assert all(bad[f"{o}.{s}"] == "" for o in OUTPUTS for s in ("final", "min", "max"))
    for value, r in got.items():
        assert r["status"] == "ok"
        assert float(r["cable[1].tension.final"]) == serial(
            elastic.path, {"cable[1].stiffness": float(value)}, 0.3, 0.01)["cable[1].tension.final"]
    assert "4 samples run (3 ok, 1 failed)" in out


def test_resume_after_a_kill_runs_only_the_remaining_samples(fmus, tmp_path, capsys):
    tower = fmus.builtin("tower20")
    n = 40
    body = f'[parameters]\n"node[61].fx" = {[float(i) for i in range(n)]}\n'
    spec = f'fmu = "{tower.path}"\nstop_time = 0.4\nstep = 0.02\noutputs = ["node[61].x"]\n' + body
    proc = start(tmp_path, spec, "--workers", "2")
    progress = tmp_path / "out" / "progress.csv"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and (not progress.exists() or progress.read_text().count("\n") < 6):
        time.sleep(0.01)
    os.killpg(proc.pid, signal.SIGKILL)  # the sweep and its workers, as a kill -9 of the group
    proc.communicate()
    assert_group_gone(proc.pid)
    before = progress.read_bytes()
    done = before[: before.rfind(b"\n") + 1].count(b"\n") - 1
    assert 5 <= done < n, f"{done} rows when killed: the sweep was not interrupted"
    assert not (tmp_path / "out" / "results.csv").exists()  # written whole at the end, or not at all
    # without --resume the finished rows are never overwritten
    assert sweep_main([str(tmp_path / "spec.toml"), "-o", str(tmp_path / "out")]) == 2
    assert "progress.csv: already holds results; run again with --resume" in capsys.readouterr().err
    assert progress.read_bytes() == before
    code, out, err = sweep(tmp_path, spec, "--workers", "2", "--resume")
    assert code == 0, err
    assert f"resuming: {done} of {n} samples already done, {n - done} to run" in out
    assert f"{n - done} samples run ({n - done} ok, 0 failed)" in out
    assert not progress.exists()
    lines = (tmp_path / "out" / "results.csv").read_text().splitlines()
    finished = before[: before.rfind(b"\n") + 1].decode().splitlines()
    assert lines[0] == finished[0] and set(finished[1:]) <= set(lines[1:])  # finished rows kept as written
    assert [int(line.split(",")[0]) for line in lines[1:]] == list(range(n))  # sorted, each sample once
    got = rows(tmp_path)
    assert sorted(int(r["sample"]) for r in got) == list(range(n))  # each sample once
    assert all(r["status"] == "ok" for r in got)
    by_load = {float(r["node[61].fx"]): float(r["node[61].x.max"]) for r in got}
    assert by_load[float(n - 1)] > by_load[1.0] > by_load[0.0]  # a larger load sways the top further


RANDOM = """
[parameters]
"node[7].fy" = [1.5]

[random]
n = 5
seed = {seed}

[random.ranges]
"cable[*].stiffness" = [300.0, 900.0]
"node[7].fx" = [-2.0, 2.0]
"""


def test_random_sweep_with_a_seed_is_reproducible(elastic, tmp_path):
    spec = spec_for(elastic.path, RANDOM.format(seed=7), stop_time=0.2)
    first, second = tmp_path / "a", tmp_path / "b"
    for folder in (first, second):
        folder.mkdir()
        code, out, err = sweep(folder, spec, "--workers", "2")
        assert code == 0, err
    a, b = rows(first), rows(second)
    key = lambda r: int(r["sample"])  # noqa: E731 (rows arrive in finishing order)
    assert sorted(a, key=key) == sorted(b, key=key)
    assert len(a) == 5 and all(r["status"] == "ok" and r["node[7].fy"] == "1.5" for r in a)
    stiffness = [float(r["cable[*].stiffness"]) for r in a]
    assert all(300.0 <= k <= 900.0 for k in stiffness) and len(set(stiffness)) == 5
    assert all(-2.0 <= float(r["node[7].fx"]) <= 2.0 for r in a)
    # another seed draws other samples
    other = sweep_spec.samples(sweep_spec.load(_write(tmp_path / "c.toml", spec_for(elastic.path, RANDOM.format(seed=8)))))
    assert {s["cable[*].stiffness"] for s in other}.isdisjoint(stiffness)


def _write(path, text):
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    "body, named, fix",
    [
        ('[parameters]\n"cable[99].stiffness" = [1.0]\n', 'parameters."cable[99].stiffness": no FMU variable', "did you mean"),
        ('[parameters]\n"node[7].x" = [1.0]\n', 'parameters."node[7].x": node[7].x is an output', "sweep parameters and inputs"),
        ('[parameters]\n"solver.method" = [1.5]\n', 'parameters."solver.method": solver.method is a Integer, got 1.5', "write integers"),
        ('[parameters]\n"node[7].fx" = 3.0\n', 'parameters."node[7].fx": must be a non-empty list', '"node[7].fx" = [value, ...]'),
        ('stop = 2\n', "stop: unknown key", "use only"),
        ('[random]\nn = 3\nseed = 1\n', "random.ranges: missing", "[random.ranges]"),
    ],
)
def test_bad_specs_name_the_key_the_reason_and_the_fix(elastic, tmp_path, capsys, body, named, fix):
    # In-process (the command's own main), so each case costs no interpreter start-up;
    # the subprocess test below shows the same on the command line.
    code = sweep_main([str(_write(tmp_path / "spec.toml", spec_for(elastic.path, body))), "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("error: ") and named in err and fix in err, err
    assert not (tmp_path / "out" / "results.csv").exists()


def test_missing_and_mistyped_top_level_keys(elastic, tmp_path):
    code, _, err = sweep(tmp_path, f'fmu = "{elastic.path}"\nstep = 0.01\noutputs = ["node[7].x"]\n')
    assert code == 2 and "stop_time: missing" in err and "write stop_time = " in err
    code, _, err = sweep(tmp_path, f'fmu = "{elastic.path}"\nstop_time = 1\nstep = "fast"\noutputs = ["node[7].x"]\n')
    assert code == 2 and "step: must be a number, got 'fast'" in err and "Traceback" not in err


def test_scene_parameters_build_one_fmu_per_variant(elastic, fmus, tmp_path):
    """Prestress and stiffness are scene keys (the rest lengths follow from both): each
    combination is built into its own FMU and equals the FMU built from the edited scene."""
    scene = tmp_path / "prism.toml"
    scene.write_text(elastic.scene_text)
    body = ('[scene_parameters]\n"prestress.min_tension" = [5.0, 20.0]\n"cables[*].stiffness" = [300.0, 600.0, -1.0]\n'
            '[parameters]\n"node[7].fx" = [2.0]\n')
    spec = f'scene = "prism.toml"\nstop_time = 0.2\nstep = 0.01\noutputs = {OUTPUTS!r}\n'.replace("'", '"') + body
    code, out, err = sweep(tmp_path, spec, "--workers", "2")
    assert code == 0, err
    got = rows(tmp_path)
    # a variant the CLI refuses to build is an error row for each of its samples
    refused = [r for r in got if r["cables[*].stiffness"] == "-1.0"]
    assert [r["status"] for r in refused] == ["build failed: cables[1].stiffness: must be ≥ 0, got -1"] * 2
    got = [r for r in got if r not in refused]
    assert len(got) == 4 and len(list((tmp_path / "out" / "fmus").glob("*.fmu"))) == 4
    final = {}
    for r in got:
        assert r["status"] == "ok"
        text = elastic.scene_text.replace("min_tension = 10.0", f"min_tension = {r['prestress.min_tension']}")
        text = text.replace("stiffness = 500.0", f"stiffness = {r['cables[*].stiffness']}")
        edited = tmp_path / f"edited-{r['sample']}.toml"
        edited.write_text(text)
        fmu = fmus.build(str(edited), tmp_path / f"edited-{r['sample']}.fmu")
        expected = serial(fmu, {"node[7].fx": 2.0}, 0.2, 0.01)
        assert {k: float(r[k]) for k in expected} == expected  # bit for bit
        final[r["prestress.min_tension"], r["cables[*].stiffness"]] = float(r["cable[1].tension.min"])
    # the prestress sets the tensions, whatever the stiffness
    assert final["20.0", "300.0"] / final["5.0", "300.0"] == pytest.approx(4.0, rel=0.05)


def test_warm_start_runs_every_sample_from_one_settled_state(fmus, open_fmu, tmp_path):
    """warm_start = 0.5: the structure sags under gravity for 0.5 s once, and each sample
    goes on from that state with its own load, as one uninterrupted run would."""
    sagging = fmus.from_toml("gravity = [0.0, 0.0, -9.81]\n" + fmus.builtin("prism2-elastic").scene_text)
    body = 'warm_start = 0.5\n[parameters]\n"node[7].fx" = [0.0, 4.0]\n'
    code, out, err = sweep(tmp_path, spec_for(sagging.path, body, stop_time=0.2), "--workers", "2")
    assert code == 0, err
    for r in rows(tmp_path):
        assert r["status"] == "ok"
        ref = open_fmu(sagging, name=f"ref{r['sample']}").init()
        points = [k * 0.01 for k in range(51)]
        for t, t_next in zip(points, points[1:]):
            ref.fmu.doStep(t, t_next - t)
        z_settled = ref.get(["node[7].z"])[0]
        ref.set({"node[7].fx": float(r["node[7].fx"])})
        seen = [ref.get(OUTPUTS)]
        points = [points[-1] + k * 0.01 for k in range(21)]
        for t, t_next in zip(points, points[1:]):
            ref.fmu.doStep(t, t_next - t)
            seen.append(ref.get(OUTPUTS))
        seen = np.array(seen)
        for i, o in enumerate(OUTPUTS):
            assert [float(r[f"{o}.{s}"]) for s in ("final", "min", "max")] == [
                seen[-1, i], seen[:, i].min(), seen[:, i].max()]  # bit for bit
        # the settled state is not the scene's start: gravity has moved the top
        assert abs(z_settled - sagging.scene["nodes"][6][2]) > 1e-3


@pytest.mark.parametrize(
    "scene_lines, named",
    [
        ('scene = "tower21"\n', "scene: no built-in scene is called 'tower21'"),
        ('scene = "prism2-elastic"\n[scene_parameters]\n"prestress.min_tensoin" = [1.0]\n',
         'scene_parameters."prestress.min_tensoin": the scene has no key \'min_tensoin\' there; add the key'),
        ('scene = "prism2-elastic"\n[scene_parameters]\n"cables[16].stiffness" = [1.0]\n',
         'scene_parameters."cables[16].stiffness": cables has 15 entries, counted from 1; use an index from 1 to 15'),
    ],
)
def test_bad_scene_keys_are_spec_errors(cli, tmp_path, capsys, scene_lines, named):
    top = 'stop_time = 0.1\nstep = 0.01\noutputs = ["node[7].x"]\n'
    head, _, tables = scene_lines.partition("\n")
    code = sweep_main([str(_write(tmp_path / "spec.toml", head + "\n" + top + tables)), "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("error: ") and named in err, err
