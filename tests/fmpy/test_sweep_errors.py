"""fmu/sweep/sweep.py refuses every spec or file mistake with one line on stderr (where,
what, how to fix) and exit code 2, before any work: missing and malformed files, sizes
past the limits, values outside the FMU's ranges, a resume of other results, paths that
leave the output folder. Booleans run end to end. Most cases call the command's own
`main` in-process (no Dask cluster starts before a mistake is found); a few run it as a
user does, to show that no traceback reaches the terminal.
"""

import csv
import json
import math
import os
import re
import shutil
import signal
import subprocess
import sys
import time
import tracemalloc
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import simulate_fmu

REPO = Path(__file__).resolve().parents[2]
SWEEP = REPO / "fmu" / "sweep" / "sweep.py"
sys.path.insert(0, str(SWEEP.parent))
import sweep_files  # noqa: E402
import sweep_spec  # noqa: E402
from sweep import main as sweep_main  # noqa: E402

TOP = 'stop_time = 0.1\nstep = 0.01\noutputs = ["node[7].x"]\n'


@pytest.fixture(scope="module")
def elastic(fmus):
    return fmus.builtin("prism2-elastic")


def refused(tmp_path, capsys, text, *args, spec_name="spec.toml"):
    """Runs the sweep in-process on `text`; returns its one error line (exit code 2)."""
    spec = tmp_path / spec_name
    spec.write_text(text)
    code = sweep_main([str(spec), "-o", str(tmp_path / "out"), *args])
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.startswith("error: ") and err.count("\n") == 1, err
    return err.strip()


def command(tmp_path, text, *args):
    spec = tmp_path / "spec.toml"
    spec.write_text(text)
    return subprocess.run([sys.executable, str(SWEEP), str(spec), "-o", str(tmp_path / "out"), *args],
                          capture_output=True, text=True, timeout=120)


# --- files ---------------------------------------------------------------------------

def test_a_missing_spec_file_a_directory_and_binary_junk(tmp_path, capsys):
    assert sweep_main([str(tmp_path / "nope.toml"), "-o", str(tmp_path / "out")]) == 2
    assert capsys.readouterr().err == f"error: {tmp_path / 'nope.toml'}: no such file; give the path of a sweep spec (.toml)\n"
    assert sweep_main([str(tmp_path), "-o", str(tmp_path / "out")]) == 2
    assert "cannot be read (Is a directory)" in capsys.readouterr().err
    (tmp_path / "junk.toml").write_bytes(b"\xff\xfe\x00stop")
    assert sweep_main([str(tmp_path / "junk.toml"), "-o", str(tmp_path / "out")]) == 2
    assert "not UTF-8 text (byte 0)" in capsys.readouterr().err
    (tmp_path / "deep.toml").write_text("a = " + "[" * 100_000 + "]" * 100_000)
    assert sweep_main([str(tmp_path / "deep.toml"), "-o", str(tmp_path / "out")]) == 2
    assert "deep.toml: nests arrays or tables too deeply to read" in capsys.readouterr().err
    (tmp_path / "deep2.toml").write_text('fmu = "x.fmu"\n' + TOP + '[parameters]\n"a" = ' + "[" * 300 + "]" * 300)
    assert sweep_main([str(tmp_path / "deep2.toml"), "-o", str(tmp_path / "out")]) == 2
    assert 'parameters."a": nests lists more than 8 deep' in capsys.readouterr().err


def test_an_output_folder_that_cannot_be_made(elastic, tmp_path, capsys):
    (tmp_path / "file").write_text("")
    for out in (tmp_path / "file", tmp_path / "file" / "sub"):
        (tmp_path / "spec.toml").write_text(f'fmu = "{elastic.path}"\n{TOP}')
        assert sweep_main([str(tmp_path / "spec.toml"), "-o", str(out)]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"error: -o: cannot make the folder {out} (") and err.count("\n") == 1, err


@pytest.mark.parametrize("name, content, reason", [
    ("gone.json", None, "no such file"),
    ("bad.json", '{"name": "x", "nodes": [[0, 0, 0],]}', "is not valid JSON (line 1, column 35"),
    ("list.json", "[1, 2]", "holds a list, not a scene table"),
    ("bad.toml", "name = \n", "is not valid TOML"),
    ("deep.json", "[" * 100_000 + "]" * 100_000, "nests arrays or objects too deeply to read"),
    ("deeper.json", '{"name": "x", "a": ' + "[" * 500 + "]" * 500 + "}", "nests arrays or objects more than 16 deep"),
])
def test_a_scene_file_missing_or_malformed(tmp_path, capsys, name, content, reason):
    if content is not None:
        (tmp_path / name).write_text(content)
    err = refused(tmp_path, capsys, f'scene = "{name}"\n' + TOP)
    assert err.startswith("error: scene: ") and reason in err and str(tmp_path / name) in err, err


def test_an_fmu_that_is_not_a_zip_or_a_zip_that_is_not_an_fmu(tmp_path, capsys):
    (tmp_path / "text.fmu").write_text("not a zip")
    err = refused(tmp_path, capsys, 'fmu = "text.fmu"\n' + TOP)
    assert err == f"error: fmu: {tmp_path / 'text.fmu'} is not an FMU (not a zip archive); give an FMU built with `tensegrity-fmu build`"
    with zipfile.ZipFile(tmp_path / "zip.fmu", "w") as z:
        z.writestr("readme.txt", "hello")
    err = refused(tmp_path, capsys, 'fmu = "zip.fmu"\n' + TOP)
    assert "zip.fmu is a zip archive without modelDescription.xml, not an FMU" in err
    with zipfile.ZipFile(tmp_path / "xml.fmu", "w") as z:
        z.writestr("modelDescription.xml", "<fmiModelDescription")
    err = refused(tmp_path, capsys, 'fmu = "xml.fmu"\n' + TOP)
    assert "xml.fmu: modelDescription.xml cannot be read" in err
    assert not (tmp_path / "out" / "progress.csv").exists()


def test_no_traceback_reaches_the_terminal(tmp_path):
    """As a user runs it: each mistake is one line on stderr, exit code 2."""
    (tmp_path / "bad.json").write_text("{")
    (tmp_path / "text.fmu").write_text("no")
    cases = [f'scene = "bad.json"\n{TOP}', f'fmu = "text.fmu"\n{TOP}', f'fmu = "text.fmu"\n{TOP}[parameters]\n"a" = [nan]\n',
             "stop_time = [", f'fmu = "text.fmu"\n{TOP}[random]\nn = 1000000000\nseed = 1\n[random.ranges]\n"a" = [0, 1]\n']
    for text in cases:
        res = command(tmp_path, text)
        assert res.returncode == 2 and res.stderr.startswith("error: ") and res.stderr.count("\n") == 1, res.stderr
        assert "Traceback" not in res.stderr and res.stdout == ""
    res = subprocess.run([sys.executable, str(SWEEP), "spec.toml", "--workers", "x", "-o", "o"], capture_output=True, text=True)
    assert res.returncode == 2 and res.stderr.count("\n") == 1 and "--workers: invalid int value: 'x'" in res.stderr


# --- sizes ---------------------------------------------------------------------------

def test_a_grid_of_1e10_samples_is_refused_by_counting_without_building_it(tmp_path, capsys):
    lists = "".join(f'"node[{j}].fx" = {[float(v) for v in range(10)]}\n' for j in range(1, 11))
    tracemalloc.start()
    err = refused(tmp_path, capsys, f'fmu = "none.fmu"\n{TOP}[parameters]\n{lists}')
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert "parameters: the sweep holds 10,000,000,000 runs (results.csv: 10,000,000,000 rows of 15 columns" in err
    assert "more than the limit of 1,000,000 runs or 2 GB; sweep fewer values, or pass --force" in err
    assert peak < 20e6, peak  # a materialised grid of 1e10 dicts would need terabytes
    assert not (tmp_path / "out").exists()  # refused before anything was written


def test_random_n_of_1e9_is_refused_and_force_lets_it_through(tmp_path, capsys):
    text = f'fmu = "x.fmu"\n{TOP}[random]\nn = 1000000000\nseed = 1\n[random.ranges]\n"node[7].fx" = [0.0, 1.0]\n'
    err = refused(tmp_path, capsys, text)
    assert "random.n: the sweep holds 1,000,000,000 runs" in err
    spec = sweep_spec.load(tmp_path / "spec.toml")
    assert sweep_spec.check_size(spec, force=True) == 10**9
    samples = sweep_spec.samples(spec)  # computed on demand: the last draw costs no more than the first
    u = np.random.default_rng(1).random(3)
    assert [samples[i]["node[7].fx"] for i in range(3)] == [float(x) for x in u]
    assert 0.0 <= samples[10**9 - 1]["node[7].fx"] < 1.0
    # with two ranges, draw i is row i of the (n, 2) matrix a materialised sweep would draw
    (tmp_path / "two.toml").write_text(text.replace("n = 1000000000", "n = 50") + '"node[7].fy" = [-4.0, 4.0]\n')
    two = sweep_spec.samples(sweep_spec.load(tmp_path / "two.toml"))
    u = np.random.default_rng(1).random((50, 2))
    assert [(s["node[7].fx"], s["node[7].fy"]) for s in two] == [(float(a), -4.0 + 8.0 * float(b)) for a, b in u]


def test_results_past_2_gb_are_refused_even_with_few_runs(tmp_path, capsys):
    outputs = [f"node[{j}].x" for j in range(1, 200)]  # 2 + 1 + 3·199 = 600 columns
    text = (f'fmu = "x.fmu"\nstop_time = 0.1\nstep = 0.01\noutputs = {json.dumps(outputs)}\n'
            f'[random]\nn = 200000\nseed = 1\n[random.ranges]\n"a" = [0.0, 1.0]\n')
    err = refused(tmp_path, capsys, text)
    size = 200_000 * 600 * sweep_spec.CELL_BYTES / 1e9
    assert f"200,000 rows of 600 columns, about {size:.3g} GB" in err and size > 2


def test_scene_variants_past_the_build_limit_are_refused_before_any_build(tmp_path, capsys):
    values = [float(v) for v in range(40)]
    text = (f'scene = "prism2-elastic"\n{TOP}[scene_parameters]\n"cables[*].stiffness" = {values}\n'
            f'"prestress.min_tension" = {values}\n')
    err = refused(tmp_path, capsys, text)
    assert err == ("error: scene_parameters: the sweep builds 1,600 FMUs, one per scene variant (about 0.2 s and "
                   "1.5 MB each), more than the limit of 1,000; sweep fewer scene values (swept FMU parameters need "
                   "no build), or pass --force")
    assert not (tmp_path / "out").exists()
    assert sweep_spec.check_size(sweep_spec.load(tmp_path / "spec.toml"), force=True) == 1600


@pytest.mark.parametrize("lines, key", [
    (f'stop_time = {10 ** 400}\nstep = 0.01\n', "stop_time"),
    (f'stop_time = 1.0\nstep = 0.01\n[parameters]\n"node[7].fx" = [1.0, {10 ** 400}]\n', 'parameters."node[7].fx"'),
    (f'stop_time = 1.0\nstep = 0.01\n[random]\nn = 2\nseed = 1\n[random.ranges]\n"a" = [0, {10 ** 400}]\n',
     'random.ranges."a"'),
])
def test_integers_beyond_a_float_are_refused_in_one_line(tmp_path, capsys, lines, key):
    err = refused(tmp_path, capsys, f'fmu = "x.fmu"\noutputs = ["a"]\n{lines}')
    assert err == (f"error: {key}: holds an integer too large for a 64-bit float (401 digits); "
                   "give numbers below 1.8e308"), err


def test_the_points_per_run_limit_is_the_cli_row_limit():
    text = (REPO / "src" / "cli" / "simulate.rs").read_text()
    rust = float(re.search(r"pub const MAX_ROWS: f64 = ([0-9.e]+);", text).group(1))
    assert sweep_spec.MAX_POINTS == rust


@pytest.mark.parametrize("lines, reason", [
    ("stop_time = nan\nstep = 0.01\n", "stop_time: must be a positive finite number, got nan"),
    ("stop_time = inf\nstep = 0.01\n", "stop_time: must be a positive finite number, got inf"),
    ("stop_time = 1.0\nstep = -0.01\n", "step: must be a positive finite number, got -0.01"),
    ("stop_time = 1.0\nstep = 0\n", "step: must be a positive finite number, got 0"),
    ("stop_time = 1e6\nstep = 1e-3\n", "stop_time: 1000000.0 s at step 0.001 s is 1e+09 communication points per run, "
     "more than the limit of 1e+07; shorten stop_time or raise step"),
    ("stop_time = 1.0\nstep = 1e-3\nwarm_start = 1e5\n", "warm_start: 100000.0 s at step 0.001 s is 1e+08"),
    ("stop_time = 1.0\nstep = true\n", "step: must be a number, got True"),
])
def test_times_are_finite_positive_and_bounded(tmp_path, capsys, lines, reason):
    err = refused(tmp_path, capsys, f'fmu = "x.fmu"\noutputs = ["a"]\n{lines}')
    assert err.startswith(f"error: {reason}"), err


# --- values against the FMU ----------------------------------------------------------

def test_values_outside_the_model_descriptions_ranges(elastic, tmp_path, capsys):
    variables = {v.name: v for v in elastic.md.modelVariables}
    method, steps, h = variables["solver.method"], variables["solver.max_steps"], variables["solver.step_size"]
    top = f'fmu = "{elastic.path}"\n{TOP}[parameters]\n'
    err = refused(tmp_path, capsys, top + f'"solver.method" = [{method.min}, {int(method.max) + 1}]\n')
    assert f"solver.method = {int(method.max) + 1} is outside its range [{method.min}, {method.max}]" in err
    # 2^31 does not fit an fmi2Integer (it would arrive as -2^31)
    err = refused(tmp_path, capsys, top + f'"solver.max_steps" = [{2**31}]\n')
    assert f"solver.max_steps = {2**31} is outside its range [1, {2**31 - 1}]" in err and int(steps.max) == 2**31 - 1
    err = refused(tmp_path, capsys, top + '"solver.step_size" = [-0.001]\n')
    assert f"solver.step_size = -0.001 is outside its range [{float(h.min)}, inf]" in err
    err = refused(tmp_path, capsys, top + '"node[7].fx" = [1.0, nan]\n')
    assert 'parameters."node[7].fx": holds nan; give finite numbers' in err
    err = refused(tmp_path, capsys, f'fmu = "{elastic.path}"\n{TOP}[random]\nn = 2\nseed = 0\n'
                                    '[random.ranges]\n"solver.method" = [1, 3]\n')
    assert 'random.ranges."solver.method": solver.method is a Integer: draws are real numbers' in err


def test_boolean_parameters_run_end_to_end_with_their_summary_plot(elastic, tmp_path):
    body = '[parameters]\n"solver.locate_events" = [true, false]\n"node[7].fx" = [0.0, 3.0]\n'
    res = command(tmp_path, f'fmu = "{elastic.path}"\nstop_time = 0.3\nstep = 0.01\noutputs = ["node[7].x"]\n' + body,
                  "--workers", "1")
    assert res.returncode == 0, res.stderr
    with open(tmp_path / "out" / "results.csv", newline="") as f:
        got = list(csv.DictReader(f))
    assert [(r["solver.locate_events"], r["node[7].fx"]) for r in got] == [
        ("true", "0.0"), ("true", "3.0"), ("false", "0.0"), ("false", "3.0")]
    for r in got:
        ref = simulate_fmu(str(elastic.path), stop_time=0.3, output_interval=0.01, output=["node[7].x"],
                           start_values={"solver.locate_events": r["solver.locate_events"] == "true",
                                         "node[7].fx": float(r["node[7].fx"])})
        assert (r["status"], float(r["node[7].x.final"]), float(r["node[7].x.max"])) == (
            "ok", ref["node[7].x"][-1], ref["node[7].x"].max())
    assert (tmp_path / "out" / "summary.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


# --- paths ---------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["../../escaped", "/tmp/escaped", "a/b", "a\\b", ".hidden", ""])
def test_a_scene_name_never_leaves_the_output_folder(tmp_path, capsys, name):
    text = f'scene = "prism2-elastic"\n{TOP}[scene_parameters]\n"name" = ["ok", {json.dumps(name)}]\n'
    err = refused(tmp_path, capsys, text)
    assert err.startswith('error: scene_parameters."name": '), err
    assert not (tmp_path / "out").exists() and not list(tmp_path.parent.glob("escaped*"))


def test_a_scene_files_own_name_is_checked_before_anything_is_written(elastic, tmp_path, capsys):
    (tmp_path / "evil.toml").write_text('name = "../../escaped"\n' + elastic.scene_text.split("\n", 1)[1])
    err = refused(tmp_path, capsys, f'scene = "evil.toml"\n{TOP}')
    assert "evil.toml: name: '../../escaped' would name a file outside the output folder" in err
    assert not (tmp_path / "out" / "fmus").exists()


# --- resume ----------------------------------------------------------------------------

@pytest.fixture(scope="module")
def finished(elastic, tmp_path_factory):
    """A finished 3-sample sweep; each test works on a copy."""
    root = tmp_path_factory.mktemp("finished")
    text = f'fmu = "{elastic.path}"\n{TOP}[parameters]\n"node[7].fx" = [0.0, 1.0, 2.0]\n'
    res = command(root, text, "--workers", "1")
    assert res.returncode == 0, res.stderr
    return root, text


def copy_of(finished, tmp_path):
    root, text = finished
    shutil.copytree(root / "out", tmp_path / "out")
    return text


def test_a_folder_with_results_is_refused_before_any_fmu_is_built(finished, tmp_path, capsys):
    copy_of(finished, tmp_path)
    text = f'scene = "prism2-elastic"\n{TOP}[scene_parameters]\n"prestress.min_tension" = [5.0, 10.0]\n'
    err = refused(tmp_path, capsys, text)
    assert err.startswith(f"error: {tmp_path / 'out' / 'results.csv'}: already holds results; run again with "
                          "--resume"), err
    assert not (tmp_path / "out" / "fmus").exists()


def test_resume_refuses_a_changed_spec_or_fmu_and_says_which(finished, fmus, tmp_path, capsys):
    text = copy_of(finished, tmp_path)
    err = refused(tmp_path, capsys, text.replace("stop_time = 0.1", "stop_time = 0.2"), "--resume")
    assert err == (f"error: {tmp_path / 'out' / 'sweep.json'}: the spec (its times, outputs or swept values) changed "
                   "since these results were written; resume with the spec that started them, or choose another -o")
    other = fmus.from_toml(fmus.builtin("prism2-elastic").scene_text.replace("mass = 1.0", "mass = 1.5", 1))
    err = refused(tmp_path, capsys, re.sub(r'fmu = ".*"', f'fmu = "{other.path}"', text), "--resume")
    assert "sweep.json: the FMU (or the scene that builds it) changed since these results were written" in err
    assert "resume with the FMU that started them" in err
    # the same spec and FMU resume: nothing is left to run
    (tmp_path / "spec.toml").write_text(text)
    assert sweep_main([str(tmp_path / "spec.toml"), "-o", str(tmp_path / "out"), "--resume"]) == 0
    assert "resuming: 3 of 3 samples already done, 0 to run" in capsys.readouterr().out
    (tmp_path / "out" / "sweep.json").unlink()
    err = refused(tmp_path, capsys, text, "--resume")
    assert "sweep.json: is missing, so nothing tells which spec and FMU wrote these results" in err


@pytest.mark.parametrize("row, reason", [
    ("x,0.0,ok,1,1,1", "sample 'x' is not a sample number below 3"),
    ("7,0.0,ok,1,1,1", "sample '7' is not a sample number below 3"),
    ("1,0.0,ok", "has 3 cells, the header 6"),
    ("1,5.0,ok,1,1,1", "sample 1 has other values than this spec's"),
    ("0,0.0,ok,1,1,1", "sample 0 is there twice"),
    ("2,2.0,,1,1,1", "has no status"),
])
def test_a_malformed_row_of_the_progress_file_names_its_row(finished, tmp_path, capsys, row, reason):
    text = copy_of(finished, tmp_path)
    out = tmp_path / "out"
    lines = (out / "results.csv").read_text().splitlines()
    (out / "progress.csv").write_text("\n".join([lines[0], lines[1], row, ""]))
    (out / "results.csv").unlink()
    err = refused(tmp_path, capsys, text, "--resume")
    assert err == (f"error: {out / 'progress.csv'}, row 3: {reason}; delete that row (its sample runs again), "
                   "or choose another -o")


# --- files written whole ----------------------------------------------------------------

def test_a_file_is_replaced_whole_or_left_as_it_was(tmp_path):
    target = tmp_path / "results.csv"
    target.write_text("old\n")

    def fails_half_way(f):
        f.write(b"new, half")
        raise OSError(28, "No space left on device")

    with pytest.raises(OSError):
        sweep_files.write_atomic(target, fails_half_way)
    assert target.read_text() == "old\n" and sorted(p.name for p in tmp_path.iterdir()) == ["results.csv"]
    sweep_files.write_bytes(target, b"new\n")
    assert target.read_text() == "new\n" and oct(target.stat().st_mode & 0o777) == oct(0o666 & ~_umask())


def _umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask


def test_leftovers_of_a_killed_sweep_are_removed_by_the_next(finished, tmp_path, capsys):
    text = copy_of(finished, tmp_path)
    out = tmp_path / "out"
    (out / ".results.csv.k3j2.tmp").write_text("half")
    (out / ".summary.png.x8.tmp").write_text("half")
    (out / ".mine.tmp").write_text("not the sweep's")
    (tmp_path / "spec.toml").write_text(text)
    assert sweep_main([str(tmp_path / "spec.toml"), "-o", str(out), "--resume"]) == 0, capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == [".mine.tmp", "results.csv", "summary.png", "sweep.json"]
    assert math.isfinite(float(next(csv.DictReader(open(out / "results.csv")))["node[7].x.final"]))


@pytest.mark.parametrize("stop", [signal.SIGINT, signal.SIGTERM])
def test_ctrl_c_or_sigterm_stops_cleanly_and_the_sweep_resumes(fmus, tmp_path, stop):
    """A Ctrl-C reaches the sweep and its workers (the terminal's process group): one line,
    exit 130, no process left, whole rows kept in progress.csv; --resume finishes them."""
    tower = fmus.builtin("tower20")
    n = 40
    text = (f'fmu = "{tower.path}"\nstop_time = 0.4\nstep = 0.02\noutputs = ["node[61].x"]\n'
            f'[parameters]\n"node[61].fx" = {[float(i) for i in range(n)]}\n')
    (tmp_path / "spec.toml").write_text(text)
    progress = tmp_path / "out" / "progress.csv"
    proc = subprocess.Popen([sys.executable, str(SWEEP), str(tmp_path / "spec.toml"), "-o", str(tmp_path / "out")],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and (not progress.exists() or progress.read_text().count("\n") < 4):
        time.sleep(0.01)
    os.killpg(proc.pid, stop)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130
    assert err == (f"error: interrupted; the finished rows are in {progress}, run again with --resume to finish\n")
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        try:
            os.killpg(proc.pid, 0)
        except ProcessLookupError:
            break
        time.sleep(0.05)
    else:
        os.killpg(proc.pid, signal.SIGKILL)
        pytest.fail("processes of the sweep outlived it")
    lines = progress.read_text().splitlines()
    assert 3 <= len(lines) - 1 < n and not (tmp_path / "out" / "results.csv").exists()
    res = command(tmp_path, text, "--resume")
    assert res.returncode == 0, res.stderr
    with open(tmp_path / "out" / "results.csv", newline="") as f:
        got = list(csv.DictReader(f))
    assert [int(r["sample"]) for r in got] == list(range(n)) and all(r["status"] == "ok" for r in got)


def test_the_summary_plots_columns_that_hold_no_numbers(tmp_path):
    """Booleans sit at false = 0, true = 1; a scene list or name at 0, 1, ... in the order met."""
    import sweep_plot

    assert sweep_plot._axis(["true", "false", "true"]) == ({"false": 0.0, "true": 1.0}, ["false", "true"])
    gravity = ["[0.0, 0.0, -9.81]", "[0.0, 0.0, 0.0]"]
    assert sweep_plot._axis(gravity) == ({gravity[0]: 0.0, gravity[1]: 1.0}, gravity)
    assert sweep_plot._axis(["2.5", "1e3"]) == ({"2.5": 2.5, "1e3": 1000.0}, None)
    results = tmp_path / "results.csv"
    with open(results, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["sample", "gravity", "flag", "status", "x.final", "x.min", "x.max"])
        for i, (g, flag) in enumerate([(g, b) for g in gravity for b in ("true", "false")]):
            w.writerow([i, g, flag, "ok" if i < 3 else "failed: no", *([i, i - 1, i + 1] if i < 3 else ["", "", ""])])
    sweep_plot.summary(results, ["gravity", "flag"], ["x"], tmp_path / "summary.png")
    assert (tmp_path / "summary.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
