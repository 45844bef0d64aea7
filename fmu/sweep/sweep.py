"""Parameter sweeps and Monte Carlo runs of a tensegrity FMU on Dask.

    .venv/bin/python fmu/sweep/sweep.py SPEC.toml [--workers N | --scheduler ADDRESS] -o DIR [--resume] [--force]

Runs every sample of SPEC.toml (the full grid of [parameters], or [random] draws) on a
Dask LocalCluster of N worker processes, or on the workers of a running scheduler, and
writes DIR/results.csv (a row per sample, as each finishes) and DIR/summary.png. The spec
format is in docs/sweeps.md.
"""

import argparse
import hashlib
import io
import json
import logging
import signal
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))  # when imported from elsewhere (tests, the benchmark)

import sweep_scene  # noqa: E402
import sweep_spec  # noqa: E402
import sweep_results  # noqa: E402
from sweep_results import Results  # noqa: E402
from sweep_spec import SpecError  # noqa: E402

CLI = HERE.parents[1] / "target" / "release" / "tensegrity-fmu"
WORKER_WAIT = 60  # s for a remote scheduler to have a worker
IN_FLIGHT_PER_WORKER = 8  # tasks submitted ahead per worker: enough to keep each busy
MAX_WORKERS = 256  # local worker processes


# Dask, fmpy, tqdm and matplotlib are imported where they are used: a spec's mistake is
# reported in a fraction of the seconds their imports take.


def connect(workers, scheduler):
    from distributed import Client, LocalCluster

    if scheduler:
        try:
            client = Client(scheduler, timeout=WORKER_WAIT)
        except (OSError, ValueError, TypeError) as e:
            raise SpecError("--scheduler", f"cannot reach {scheduler} ({' '.join(str(e).split())[:200]})",
                            "check the address (tcp://HOST:8786) and that `dask scheduler` runs there") from None
        try:
            client.wait_for_workers(1, timeout=WORKER_WAIT)
        except TimeoutError:
            client.close()
            raise SpecError("--scheduler", f"no worker joined {scheduler} within {WORKER_WAIT} s",
                            f"start one with `dask worker {scheduler}`") from None
        return client, None
    # The workers ignore Ctrl-C (it reaches the whole process group): this process stops
    # them when it closes the cluster, instead of each printing its own traceback.
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        # Dask's own log stays quiet: a lost worker shows in its sample's status.
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               dashboard_address=None, silence_logs=logging.CRITICAL)
    finally:
        signal.signal(signal.SIGINT, previous)
    return Client(cluster), cluster


def run(spec_path, out, workers=2, scheduler=None, resume=False, log=print, force=False):
    """Runs the sweep; returns what the summary line prints (samples run, ok, seconds, instances, workers)."""
    spec = sweep_spec.load(spec_path)
    runs = sweep_spec.check_size(spec, force)  # before anything is built or written
    out = Path(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise SpecError("-o", f"cannot make the folder {out} ({e.strerror})", "choose a folder you can write") from None
    sweep_results.held_results(out, resume)
    samples = sweep_spec.samples(spec)
    archives, variants = sweep_scene.build_variants(spec, out, CLI)
    if not archives:
        raise SpecError("scene_parameters", f"no variant of the scene could be built ({next(iter(variants.values()))})",
                        "fix the values")
    # The variants differ in values only, so any one's variables stand for all.
    md = _model_description(spec, next(iter(archives.values())))
    sweep_spec.resolve(spec, md)
    digests = {"spec": spec.digest(),
               "fmu": hashlib.sha256(json.dumps(variants, sort_keys=True).encode()).hexdigest()}
    results = Results(out, spec.swept(), spec.outputs, samples, resume, digests)
    todo = [i for i in range(runs) if i not in results.done]
    if results.done:
        log(f"resuming: {len(results.done)} of {runs} samples already done, {len(todo)} to run")
    stats = {"ran": 0, "ok": 0, "seconds": 0.0, "instances": 0, "workers": 0}
    client, cluster = connect(workers, scheduler) if todo else (None, None)
    try:
        if todo:
            stats = _run_on(client, spec, samples, variants, archives, todo, results)
    finally:
        complete = results.close()
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
    if not complete:  # only a stop on the way leaves samples without a row
        raise SpecError(str(results.progress), f"{len(results.done)} of {runs} samples done",
                        "run again with --resume to finish the others")
    import sweep_plot

    sweep_plot.summary(out / "results.csv", spec.swept(), spec.outputs, out / "summary.png")
    log(f"{stats['ran']} samples run ({stats['ok']} ok, {stats['ran'] - stats['ok']} failed) "
        f"in {stats['seconds']:.2f} s: {stats['ran'] / max(stats['seconds'], 1e-9):.2f} samples/s "
        f"on {stats['workers']} worker{'s' * (stats['workers'] != 1)}, {stats['instances']} FMU instances")
    log(f"wrote {out / 'results.csv'} and {out / 'summary.png'}")
    return stats


def _model_description(spec, archive):
    from fmpy import read_model_description

    where = str(spec.fmu) if spec.fmu else "the scene's FMU"
    try:
        md = read_model_description(io.BytesIO(archive))
    except Exception as e:  # fmpy reports a bad description with whatever lxml or its own checks raise
        raise SpecError("fmu", f"{where}: modelDescription.xml cannot be read ({' '.join(str(e).split())[:200]})",
                        "give an FMU built with `tensegrity-fmu build`") from None
    if md.fmiVersion != "2.0" or md.coSimulation is None:
        raise SpecError("fmu", f"{where} is not an FMI 2.0 co-simulation FMU",
                        "give an FMU built with `tensegrity-fmu build`")
    return md


def _run_on(client, spec, samples, variants, archives, todo, results):
    from distributed import as_completed
    from tqdm import tqdm

    import sweep_worker

    client.upload_file(str(HERE / "sweep_worker.py"))  # remote workers need no checkout
    client.register_plugin(sweep_worker.FmuPlugin(archives), name=sweep_worker.PLUGIN)
    n_workers = len(client.scheduler_info()["workers"])
    settled = {}
    if spec.warm_start:
        settled = {key: client.submit(sweep_worker.settle, key, {}, spec.warm_start, spec.step, pure=False)
                   for key in archives}
    started = time.perf_counter()
    instances, ok = set(), 0
    pending, futures = iter(todo), {}
    running = as_completed()

    def submit_next():
        """Submits the next sample that runs; a sample whose variant failed to build gets its row."""
        for index in pending:
            sample = samples[index]
            key = variants[sweep_scene.variant(spec, sample)]
            if isinstance(key, sweep_scene.BuildError):
                results.write(index, sample, f"build failed: {key}", {})
                bar.update()
                continue
            future = client.submit(sweep_worker.run_sample, key, sweep_spec.fmu_values(spec, sample), spec.outputs,
                                   spec.stop_time, spec.step, settled.get(key), pure=False)
            futures[future] = index, sample
            running.add(future)
            return

    with tqdm(total=len(todo), unit="sample", disable=None) as bar:
        # A bounded number of tasks in flight: a large sweep holds no million futures.
        for _ in range(IN_FLIGHT_PER_WORKER * max(n_workers, 1)):
            submit_next()
        for future in running:
            index, sample = futures.pop(future)
            try:
                status, extremes, instance = future.result()
                instances.add(instance)
            except Exception as e:  # a worker lost or a settling run failed: this sample's row says so
                status, extremes = f"failed: {e}", {}
            ok += status == "ok"
            results.write(index, sample, status, extremes)
            bar.update()
            submit_next()
    seconds = time.perf_counter() - started
    client.unregister_worker_plugin(sweep_worker.PLUGIN)  # frees the instances on the workers
    return {"ran": len(todo), "ok": ok, "seconds": seconds, "instances": len(instances), "workers": n_workers}


def _interrupt(_signal, _frame):
    raise KeyboardInterrupt


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, not the usage block
        self.exit(2, f"error: {message}; see --help\n")


def main(argv=None):
    parser = _Parser(description=__doc__.split("\n\n")[0])
    parser.add_argument("spec", help="the sweep spec (TOML)")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, default=2, help="worker processes of a local cluster (default 2)")
    where.add_argument("--scheduler", help="address of a running Dask scheduler, e.g. tcp://10.0.0.5:8786")
    parser.add_argument("-o", "--output", required=True, help="folder for results.csv and summary.png")
    parser.add_argument("--resume", action="store_true", help="keep the finished rows of DIR and run the rest")
    parser.add_argument("--force", action="store_true",
                        help=f"run a sweep past {sweep_spec.MAX_RUNS:.0e} samples or "
                             f"{sweep_spec.MAX_RESULT_BYTES / 1e9:.0f} GB of results")
    args = parser.parse_args(argv)
    if not 1 <= args.workers <= MAX_WORKERS:
        parser.error(f"--workers must be from 1 to {MAX_WORKERS}")
    for stop in (signal.SIGTERM, signal.SIGHUP):  # as Ctrl-C: close the cluster, keep progress.csv
        signal.signal(stop, _interrupt)
    try:
        run(args.spec, args.output, args.workers, args.scheduler, args.resume, force=args.force)
    except SpecError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except OSError as e:  # the output folder: full, read-only, a file where a folder should be
        print(f"error: {e.filename or args.output}: {e.strerror or e}; free space or choose another -o", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"error: interrupted; the finished rows are in {Path(args.output) / 'progress.csv'}, "
              "run again with --resume to finish", file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
