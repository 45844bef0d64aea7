"""Parameter sweeps and Monte Carlo runs of a tensegrity FMU on Dask.

    .venv/bin/python fmu/sweep/sweep.py SPEC.toml [--workers N | --scheduler ADDRESS] -o DIR [--resume]

Runs every sample of SPEC.toml (the full grid of [parameters], or [random] draws) on a
Dask LocalCluster of N worker processes, or on the workers of a running scheduler, and
writes DIR/results.csv (a row per sample, as each finishes) and DIR/summary.png. The spec
format is in docs/sweeps.md.
"""

import argparse
import io
import logging
import sys
import time
from pathlib import Path

from distributed import Client, LocalCluster, as_completed
from fmpy import read_model_description
from tqdm import tqdm

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))  # when imported from elsewhere (tests, the benchmark)

import sweep_plot  # noqa: E402
import sweep_scene  # noqa: E402
import sweep_spec  # noqa: E402
import sweep_worker  # noqa: E402
from sweep_results import Results  # noqa: E402
from sweep_spec import SpecError  # noqa: E402

CLI = HERE.parents[1] / "target" / "release" / "tensegrity-fmu"
WORKER_WAIT = 60  # s for a remote scheduler to have a worker


def connect(workers, scheduler):
    if scheduler:
        client = Client(scheduler)
        try:
            client.wait_for_workers(1, timeout=WORKER_WAIT)
        except TimeoutError:
            client.close()
            raise SpecError("--scheduler", f"no worker joined {scheduler} within {WORKER_WAIT} s",
                            f"start one with `dask worker {scheduler}`") from None
        return client, None
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                           dashboard_address=None, silence_logs=logging.ERROR)
    return Client(cluster), cluster


def run(spec_path, out, workers=2, scheduler=None, resume=False, log=print):
    """Runs the sweep; returns what the summary line prints (samples run, ok, seconds, instances, workers)."""
    spec = sweep_spec.load(spec_path)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    samples = sweep_spec.samples(spec)
    archives, keys = sweep_scene.build_variants(spec, samples, out, CLI)
    if not archives:
        raise SpecError("scene_parameters", f"no variant of the scene could be built ({keys[0]})", "fix the values")
    # The variants differ in values only, so any one's variables stand for all.
    md = read_model_description(io.BytesIO(next(iter(archives.values()))))
    sweep_spec.resolve(spec, md)
    results = Results(out / "results.csv", spec.swept(), spec.outputs, samples, resume)
    todo = [i for i in range(len(samples)) if i not in results.done]
    if results.done:
        log(f"resuming: {len(results.done)} of {len(samples)} samples already done, {len(todo)} to run")
    stats = {"ran": 0, "ok": 0, "seconds": 0.0, "instances": 0, "workers": 0}
    client, cluster = connect(workers, scheduler) if todo else (None, None)
    try:
        if todo:
            stats = _run_on(client, spec, samples, keys, archives, todo, results)
    finally:
        results.close()
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
    sweep_plot.summary(out / "results.csv", spec.swept(), spec.outputs, out / "summary.png")
    log(f"{stats['ran']} samples run ({stats['ok']} ok, {stats['ran'] - stats['ok']} failed) "
        f"in {stats['seconds']:.2f} s: {stats['ran'] / max(stats['seconds'], 1e-9):.2f} samples/s "
        f"on {stats['workers']} worker{'s' * (stats['workers'] != 1)}, {stats['instances']} FMU instances")
    log(f"wrote {out / 'results.csv'} and {out / 'summary.png'}")
    return stats


def _run_on(client, spec, samples, keys, archives, todo, results):
    client.upload_file(str(HERE / "sweep_worker.py"))  # remote workers need no checkout
    client.register_plugin(sweep_worker.FmuPlugin(archives), name=sweep_worker.PLUGIN)
    n_workers = len(client.scheduler_info()["workers"])
    settled = {}
    if spec.warm_start:
        settled = {key: client.submit(sweep_worker.settle, key, {}, spec.warm_start, spec.step, pure=False)
                   for key in archives}
    started = time.perf_counter()
    futures, instances, ok = {}, set(), 0
    for index in todo:
        key = keys[index]
        if isinstance(key, sweep_scene.BuildError):
            results.write(index, samples[index], f"build failed: {key}", {})
            continue
        values = sweep_spec.fmu_values(spec, samples[index])
        future = client.submit(sweep_worker.run_sample, key, values, spec.outputs, spec.stop_time, spec.step,
                               settled.get(key), pure=False)
        futures[future] = index
    with tqdm(total=len(todo), initial=len(todo) - len(futures), unit="sample", disable=None) as bar:
        for future in as_completed(futures):
            index = futures.pop(future)
            try:
                status, extremes, instance = future.result()
                instances.add(instance)
            except Exception as e:  # a worker lost or a settling run failed: this sample's row says so
                status, extremes = f"failed: {e}", {}
            ok += status == "ok"
            results.write(index, samples[index], status, extremes)
            bar.update()
    seconds = time.perf_counter() - started
    client.unregister_worker_plugin(sweep_worker.PLUGIN)  # frees the instances on the workers
    return {"ran": len(todo), "ok": ok, "seconds": seconds, "instances": len(instances), "workers": n_workers}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("spec", help="the sweep spec (TOML)")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, default=2, help="worker processes of a local cluster (default 2)")
    where.add_argument("--scheduler", help="address of a running Dask scheduler, e.g. tcp://10.0.0.5:8786")
    parser.add_argument("-o", "--output", required=True, help="folder for results.csv and summary.png")
    parser.add_argument("--resume", action="store_true", help="keep the finished rows of DIR/results.csv and run the rest")
    args = parser.parse_args(argv)
    if args.workers < 1:
        parser.error("--workers must be at least 1")
    try:
        run(args.spec, args.output, args.workers, args.scheduler, args.resume)
    except SpecError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
