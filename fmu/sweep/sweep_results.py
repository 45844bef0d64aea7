"""DIR/results.csv: one row per sample, appended and flushed as each sample finishes.

A killed sweep loses at most the row being written (a last line without its newline is
cut off on resume). `--resume` keeps the finished rows, checks that they are this spec's
samples (same columns, same values) and runs only the others.
"""

import csv
import io
from pathlib import Path

from sweep_spec import SpecError

STATS = ("final", "min", "max")


def fmt(value) -> str:
    """A value as written: floats as their shortest round-trip decimal, so the CSV is exact."""
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(float(value)) if isinstance(value, float) else str(value)


def header(swept, outputs):
    return ["sample", *swept, "status", *[f"{o}.{s}" for o in outputs for s in STATS]]


class Results:
    def __init__(self, path: Path, swept, outputs, samples, resume: bool):
        self.path, self.swept, self.outputs = path, swept, outputs
        self.header = header(swept, outputs)
        self.done = set()
        # A header alone (a sweep stopped before its first row) holds nothing to lose.
        if path.exists() and path.read_bytes().count(b"\n") > 1 and not resume:
            raise SpecError(str(path), "already holds results",
                            "run again with --resume to finish them, or choose another -o")
        if path.exists():
            self.done = self._finished(samples)
        new = not path.exists() or path.stat().st_size == 0
        self.file = open(path, "a", newline="")
        if new:
            self._line(self.header)

    def _finished(self, samples):
        data = self.path.read_bytes()
        complete = data[: data.rfind(b"\n") + 1]
        if len(complete) != len(data):  # the row a kill interrupted
            self.path.write_bytes(complete)
        rows = list(csv.reader(io.StringIO(complete.decode())))
        if rows and rows[0] != self.header:
            raise SpecError(str(self.path), "was written for other columns than this spec's",
                            "resume with the spec that started it, or choose another -o")
        done = set()
        for row in rows[1:]:
            index = int(row[0])
            expected = [str(index)] + [fmt(samples[index][name]) if index < len(samples) else "?" for name in self.swept]
            if row[: 1 + len(self.swept)] != expected:
                raise SpecError(str(self.path), f"sample {index} has other values than this spec's",
                                "resume with the spec that started it, or choose another -o")
            done.add(index)
        return done

    def _line(self, cells):
        out = io.StringIO()
        csv.writer(out, lineterminator="\n").writerow(cells)
        # One write and a flush per row: what a kill leaves is whole rows plus at most one part.
        self.file.write(out.getvalue())
        self.file.flush()

    def write(self, index, sample, status, extremes):
        status = " ".join(status.split())  # one line per row, whatever the FMU's message holds
        stats = []
        for name in self.outputs:
            if name in extremes:
                lo, hi, final = extremes[name]
                stats += [fmt(final), fmt(lo), fmt(hi)]
            else:  # a failed sample has no outputs
                stats += ["", "", ""]
        self._line([index, *[fmt(sample[n]) for n in self.swept], status, *stats])
        self.done.add(index)

    def close(self):
        self.file.close()
