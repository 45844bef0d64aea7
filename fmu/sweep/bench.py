"""Sweep throughput on 1 and 2 local Dask workers (a benchmark, not a test).

    .venv/bin/python fmu/sweep/bench.py [--samples 48] [--stop-time 1.0] [--repeats 3]

Runs the same tower20 grid (cable stiffness × a load on the top node) with `sweep.run`
on a LocalCluster of 1 and of 2 workers, alternating, and prints samples per second
(from the first submission to the last row: cluster start-up and FMU extraction are not
counted), the best of the repeats, and the ratio.
"""

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import sweep  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=int, default=48, help="a multiple of 6 (6 stiffnesses × loads)")
    parser.add_argument("--stop-time", type=float, default=1.0, help="s of simulated time per sample")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    if args.samples < 42 or args.samples % 6:
        parser.error("--samples: give a multiple of 6 of at least 42 (the issue asks for 40 runs or more)")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        fmu = tmp / "tower20.fmu"
        subprocess.run([str(sweep.CLI), "build", "tower20", "-o", str(fmu)], check=True, capture_output=True)
        loads = [float(i) for i in range(args.samples // 6)]
        spec = tmp / "bench.toml"
        spec.write_text(
            f'fmu = "{fmu}"\nstop_time = {args.stop_time}\nstep = 0.01\noutputs = ["node[61].x", "cable[1].tension"]\n'
            f'[parameters]\n"cable[*].stiffness" = [300.0, 400.0, 500.0, 600.0, 700.0, 800.0]\n"node[61].fx" = {loads}\n'
        )
        rates = {1: [], 2: []}
        for repeat in range(args.repeats):
            for workers in (1, 2):
                stats = sweep.run(spec, tmp / f"out-{workers}-{repeat}", workers=workers, log=lambda _: None)
                assert stats["ok"] == stats["ran"] == 6 * len(loads)
                rates[workers].append(stats["ran"] / stats["seconds"])
                print(f"{workers} worker(s), run {repeat + 1}: {stats['ran']} samples in {stats['seconds']:.2f} s, "
                      f"{rates[workers][-1]:.2f} samples/s, {stats['instances']} FMU instances", flush=True)
    best = {w: max(r) for w, r in rates.items()}
    print(f"tower20, {6 * len(loads)} samples of {args.stop_time} s (rk4, 1 ms, outputs every 10 ms), best of {args.repeats}:")
    print(f"  1 worker:  {best[1]:.2f} samples/s")
    print(f"  2 workers: {best[2]:.2f} samples/s")
    print(f"  ratio:     {best[2] / best[1]:.2f}")


if __name__ == "__main__":
    main()
