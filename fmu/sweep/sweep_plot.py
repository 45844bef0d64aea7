"""DIR/summary.png: each output against each swept parameter, from DIR/results.csv.

One panel per (output, swept column): the final value as points joined along the swept
column for each combination of the other swept columns (a line per combination, coloured
by the first of them), and the run's min–max range as a faint bar at each point, nudged
sideways per line so that bars of equal x stay apart. Failed samples are left out and
counted in the title.
"""

import csv
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only: no display on workers, CI or a remote login
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import sweep_files  # noqa: E402

BOOLEAN = ("false", "true")


def _float(cell):
    try:
        return float(cell)
    except ValueError:
        return None


def _axis(cells):
    """Where each cell of a swept column sits on its axis, and the tick labels of a column
    that holds no numbers: a Boolean's false/true, a scene name or a list (at 0, 1, ...)."""
    distinct = list(dict.fromkeys(cells))
    if all(_float(c) is not None for c in distinct):
        return {c: float(c) for c in distinct}, None
    if set(distinct) <= set(BOOLEAN):
        distinct = list(BOOLEAN)
    return {c: float(i) for i, c in enumerate(distinct)}, distinct


def _output(cell):
    return float(cell) if cell else np.nan  # a failed sample's empty cell


def summary(results_csv, swept, outputs, png):
    with open(results_csv, newline="") as f:
        rows = list(csv.DictReader(f))
    good = [r for r in rows if r["status"] == "ok"]
    # A column held at one value explains nothing: plot against the ones that vary.
    varying = [c for c in swept if len({r[c] for r in good}) > 1] or swept or ["sample"]
    axes_of = {c: _axis([r[c] for r in good]) for c in varying}
    fig, axes = plt.subplots(len(outputs), len(varying), squeeze=False,
                             figsize=(4.2 * len(varying) + 1.2, 3.2 * len(outputs) + 0.6))
    for i, output in enumerate(outputs):
        for j, column in enumerate(varying):
            _panel(axes[i][j], good, column, [c for c in varying if c != column], output, axes_of)
    failed = len(rows) - len(good)
    fig.suptitle(f"{len(good)} of {len(rows)} samples ({failed} failed, not shown)" if failed else f"{len(rows)} samples")
    fig.tight_layout()
    sweep_files.write_atomic(Path(png), lambda f: fig.savefig(f, format="png", dpi=100))
    plt.close(fig)


def _panel(ax, rows, column, others, output, axes_of):
    at = {c: axes_of[c][0] for c in axes_of}
    groups = {}
    for r in rows:
        groups.setdefault(tuple(r[c] for c in others), []).append(r)
    colour_values = sorted({at[others[0]][k[0]] for k in groups}) if others else [0.0]
    cmap = plt.get_cmap("viridis")
    xs = [at[column][r[column]] for r in rows]
    nudge = 0.012 * (max(xs) - min(xs)) if len(groups) < len(rows) and xs else 0.0
    for g, (group_key, members) in enumerate(
            sorted(groups.items(), key=lambda kv: [at[c][x] for c, x in zip(others, kv[0])])):
        members.sort(key=lambda r: at[column][r[column]])
        x = np.array([at[column][r[column]] for r in members])
        final, lo, hi = (np.array([_output(r[f"{output}.{s}"]) for r in members]) for s in ("final", "min", "max"))
        shade = colour_values.index(at[others[0]][group_key[0]]) / max(len(colour_values) - 1, 1) if others else 0.0
        label = ", ".join(f"{c} = {v}" for c, v in zip(others, group_key)) if len(groups) <= 8 and others else None
        colour = cmap(0.85 * shade)
        ax.vlines(x + (g - (len(groups) - 1) / 2) * nudge, lo, hi, color=colour, alpha=0.35, linewidth=1.5)
        ax.plot(x, final, "o-" if len(groups) < len(rows) else "o", color=colour, markersize=3.5, label=label)
    labels = axes_of[column][1]
    if labels:
        ax.set_xticks(range(len(labels)), labels)
        ax.set_xlim(-0.5, len(labels) - 0.5)
    ax.set_xlabel(column)
    ax.set_ylabel(f"{output}\n(final; bars: min to max)", fontsize=8)
    ax.grid(alpha=0.3)
    if any(line.get_label() and not line.get_label().startswith("_") for line in ax.get_lines()):
        ax.legend(fontsize=6)
