"""How far the top of tower20 sways under a side load, against prestress and cable stiffness.

Runs the sweep of fmu/examples/tower_sway.toml (20 FMUs: 5 prestress levels × 4 cable
stiffnesses, each loaded with 0.1 N along +x on the three top nodes for 5 s) on a local Dask
cluster, then draws the largest displacement of node 61 along the load against the
prestress, one line per stiffness, into DIR/tower_sway.png and prints it as a table.

    .venv/bin/python fmu/examples/tower_sway.py [-o tower-sway] [--workers 2]
"""

import argparse
import csv
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "sweep"))
import sweep  # noqa: E402
from sweep_scene import scene_data  # noqa: E402

SPEC = HERE / "tower_sway.toml"
PRESTRESS, STIFFNESS = "prestress.min_tension", "cables[*].stiffness"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("-o", "--output", default="tower-sway")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--resume", action="store_true")
    args = parser.parse_args()
    out = Path(args.output)
    sweep.run(SPEC, out, workers=args.workers, resume=args.resume)
    x0 = scene_data("tower20", sweep.CLI)["nodes"][60][0]  # node 61 at the start, m
    with open(out / "results.csv", newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["status"] == "ok"]
    sway = {}  # stiffness -> [(prestress, mm)]
    for r in rows:
        sway.setdefault(float(r[STIFFNESS]), []).append(
            (float(r[PRESTRESS]), 1000 * (float(r["node[61].x.max"]) - x0)))
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    print(f"{'stiffness N/m':>14} | sway of node 61 (mm) at prestress " + ", ".join(
        f"{p:g}" for p, _ in sorted(next(iter(sway.values())))) + " N")
    for k, points in sorted(sway.items()):
        points.sort()
        ax.plot(*zip(*points), "o-", label=f"{k:g} N/m")
        print(f"{k:>14g} | " + ", ".join(f"{mm:.1f}" for _, mm in points))
    ax.set_xscale("log")
    prestress = sorted({p for points in sway.values() for p, _ in points})
    ax.set_xticks(prestress, [f"{p:g}" for p in prestress])
    ax.minorticks_off()
    ax.set_xlabel("prestress: least cable tension (N)")
    ax.set_ylabel("largest sway of node 61 along the load (mm)")
    ax.set_title("tower20, 0.1 N along +x on each top node, first 5 s")
    ax.grid(alpha=0.3, which="both")
    ax.legend(title="cable stiffness")
    fig.tight_layout()
    fig.savefig(out / "tower_sway.png", dpi=100)
    print(f"wrote {out / 'tower_sway.png'}")


if __name__ == "__main__":
    main()
