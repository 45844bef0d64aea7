"""Simulates a tensegrity FMU with fmpy and prints what happened; plots it with --plot.

Works on any FMU that `tensegrity-fmu build` makes: the variable names come from the FMU's
modelDescription.xml. The summary gives the final node positions (every node of a small
structure, the ones that moved most of a large one), the cable tensions at the end, the
largest constraint residuals of the run and the energy. `--input NAME=VALUE` holds an input
at a value for the whole run (for instance a force on a loaded node); the other inputs keep
their start values.

    .venv/bin/python fmu/examples/simulate.py prism2.fmu --input 'node[7].fx=5' --plot out/prism2.png
"""

import sys

import numpy as np
from fmpy import simulate_fmu

from fmu_variables import FmuVariables, Parser, check_fmu, fail, run_main

SHOWN_NODES = 12  # a structure with more nodes shows the ones that moved most


def parse_inputs(pairs, fmu):
    """`NAME=VALUE` pairs as a dict, each NAME an input of the FMU."""
    values = {}
    for pair in pairs:
        name, sep, value = pair.partition("=")
        if not sep:
            fail(f"--input {pair!r}: expected NAME=VALUE, e.g. --input 'node[7].fx=5'")
        if name not in fmu.inputs:
            shown = ", ".join(fmu.inputs[:6]) + (", ..." if len(fmu.inputs) > 6 else "")
            fail(f"--input {name!r}: not an input of {fmu.name} (its inputs: {shown or 'none'})")
        try:
            values[name] = float(value)
        except ValueError:
            fail(f"--input {pair!r}: {value!r} is not a number")
    return values


def simulate(path, fmu, stop_time, output_interval, inputs):
    """fmpy's simulate_fmu with the outputs the summary needs; a structured array by name."""
    outputs = [n for node in fmu.nodes for n in fmu.position(node)]
    outputs += fmu.tensions() + fmu.residuals()
    outputs += ["energy.total"] if "energy.total" in fmu.vr else []
    return simulate_fmu(str(path), stop_time=stop_time, output_interval=output_interval,
                        start_values=inputs, output=outputs)


def positions(result, fmu):
    """Node positions as an array (samples, nodes, 3)."""
    return np.stack([np.column_stack([result[n] for n in fmu.position(node)])
                     for node in fmu.nodes], axis=1)


def summarize(result, fmu, out=sys.stdout):
    t = result["time"]
    p = positions(result, fmu)
    moved = np.linalg.norm(p[-1] - p[0], axis=1)
    print(f"{fmu.name}: {len(fmu.nodes)} nodes ({len(fmu.pinned)} pinned), "
          f"{len(fmu.cables)} cables, {t[0]:g} to {t[-1]:g} s, {len(t)} samples", file=out)
    shown = range(len(fmu.nodes))
    title = "final node positions [m]"
    if len(fmu.nodes) > SHOWN_NODES:
        shown = sorted(np.argsort(-moved, kind="stable")[:SHOWN_NODES])
        title += f" (the {SHOWN_NODES} of {len(fmu.nodes)} nodes that moved most)"
    print(title, file=out)
    print(f"  {'node':<9} {'x':>10} {'y':>10} {'z':>10} {'moved':>10}", file=out)
    for i in shown:
        x, y, z = p[-1, i]
        print(f"  {f'node[{fmu.nodes[i]}]':<9} {x:10.6f} {y:10.6f} {z:10.6f} {moved[i]:10.6f}",
              file=out)
    tensions = np.array([result[n][-1] for n in fmu.tensions()])
    if len(tensions):
        lo, hi = int(np.argmin(tensions)), int(np.argmax(tensions))
        slack = int(np.sum(tensions <= 0.0))
        print(f"cable tensions at {t[-1]:g} s [N]: min {tensions[lo]:.4f} "
              f"(cable[{fmu.cables[lo]}]), max {tensions[hi]:.4f} (cable[{fmu.cables[hi]}]), "
              f"{slack} slack", file=out)
    for name in fmu.residuals():
        print(f"{name}: largest {np.max(np.abs(result[name])):.3e} over the run", file=out)
    if "energy.total" in fmu.vr:
        e = result["energy.total"]
        print(f"energy.total: {e[0]:.6f} J at the start, {e[-1]:.6f} J at the end", file=out)


def plot(result, fmu, png):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = result["time"]
    p = positions(result, fmu)
    moved = np.linalg.norm(p - p[0], axis=2) * 1e3
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    labelled = len(fmu.nodes) <= 12
    for i in range(len(fmu.nodes)):
        if fmu.nodes[i] in fmu.pinned:
            continue
        top.plot(t, moved[:, i], lw=1.2 if labelled else 0.7,
                 label=f"node {fmu.nodes[i]}" if labelled else None)
    top.set_ylabel("distance from start [mm]")
    top.set_title(f"{fmu.name}: free nodes (top), cable tensions (bottom)")
    if labelled:
        top.legend(fontsize=7, ncol=3)
    for name in fmu.tensions():
        bottom.plot(t, result[name], lw=1.0 if len(fmu.cables) <= 30 else 0.5)
    bottom.set_ylabel("cable tension [N]")
    bottom.set_xlabel("time [s]")
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    try:
        fig.savefig(png, dpi=110)
    except OSError as exc:
        fail(f"--plot {png}: cannot write it ({exc.strerror or exc})")
    print(f"plot: {png}")


def main(argv=None):
    ap = Parser(description=__doc__.split("\n\n")[0])
    ap.add_argument("fmu", help="an FMU built by tensegrity-fmu")
    ap.add_argument("--stop-time", type=float, help="s (default: the FMU's DefaultExperiment)")
    ap.add_argument("--output-interval", type=float, help="s (default: the FMU's step size)")
    ap.add_argument("--input", action="append", default=[], metavar="NAME=VALUE",
                    help="hold an input at VALUE (repeatable)")
    ap.add_argument("--plot", metavar="PNG", help="draw node motion and cable tensions")
    args = ap.parse_args(argv)
    fmu = FmuVariables(check_fmu(args.fmu))
    for option in ("stop_time", "output_interval"):
        value = getattr(args, option)
        if value is not None and not (np.isfinite(value) and value > 0):
            fail(f"--{option.replace('_', '-')} {value:g}: must be a positive number of seconds")
    inputs = parse_inputs(args.input, fmu)
    result = simulate(args.fmu, fmu, args.stop_time, args.output_interval, inputs)
    summarize(result, fmu)
    if args.plot:
        plot(result, fmu, args.plot)
    return result


if __name__ == "__main__":
    run_main(main)
