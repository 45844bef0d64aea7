"""The output folder's results: DIR/progress.csv while the sweep runs, DIR/results.csv at the end.

Rows go to progress.csv, one per sample, appended and flushed as each finishes: a kill
leaves whole rows plus at most one cut-off line, which --resume drops. When every sample
has its row, results.csv is written whole (sorted by sample) by a rename and progress.csv
is removed. DIR/sweep.json holds the SHA-256 of the spec and of the FMU(s) the rows came
from; --resume refuses when either changed, or when a row is not one of this spec's samples.
"""

import csv
import io
import json
from pathlib import Path

import sweep_files
from sweep_spec import SpecError

STATS = ("final", "min", "max")
ANOTHER = "or choose another -o"


def fmt(value) -> str:
    """A value as written: floats as their shortest round-trip decimal, so the CSV is exact."""
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(float(value)) if isinstance(value, float) else str(value)


def header(swept, outputs):
    return ["sample", *swept, "status", *[f"{o}.{s}" for o in outputs for s in STATS]]


def held_results(out: Path, resume: bool) -> bool:
    """Whether `out` holds results; refuses them unless resuming (checked again before
    anything is built, so that a refusal comes at once)."""
    path, progress = out / "results.csv", out / "progress.csv"
    # A header alone (a sweep stopped before its first row) holds nothing to lose.
    held = path.exists() or (progress.exists() and progress.read_bytes().count(b"\n") > 1)
    if held and not resume:
        where = path if path.exists() else progress
        raise SpecError(str(where), "already holds results", f"run again with --resume to finish them, {ANOTHER}")
    return held


class Results:
    def __init__(self, out: Path, swept, outputs, samples, resume: bool, digests: dict):
        self.out, self.swept, self.outputs, self.samples = Path(out), swept, outputs, samples
        self.path, self.progress, self.record = (self.out / n for n in ("results.csv", "progress.csv", "sweep.json"))
        self.header = header(swept, outputs)
        self.done = set()
        sweep_files.remove_leftovers(self.out, ["results.csv", "summary.png", "sweep.json"])
        if held_results(self.out, resume):
            self._check_record(digests)
            source = self.progress if self.progress.exists() else self.path
            rows = self._finished(source)
            if source is self.path:  # a finished sweep resumed: its rows seed a new progress file
                sweep_files.write_bytes(self.progress, _csv([self.header, *rows]).encode())
        else:
            sweep_files.write_bytes(self.record, (json.dumps(digests, indent=1) + "\n").encode())
            sweep_files.write_bytes(self.progress, _csv([self.header]).encode())
        self.file = open(self.progress, "a", newline="")

    def _check_record(self, digests):
        try:
            stored = json.loads(self.record.read_text())
            stored = {k: stored[k] for k in digests}
        except FileNotFoundError:
            raise SpecError(str(self.record), "is missing, so nothing tells which spec and FMU wrote these results",
                            f"resume only a sweep of this tool, {ANOTHER}") from None
        except (OSError, ValueError, KeyError, TypeError):
            raise SpecError(str(self.record), "is damaged (not the record this tool writes)",
                            f"restore it, {ANOTHER}") from None
        for what, label, name in (("spec", "the spec (its times, outputs or swept values)", "spec"),
                                  ("fmu", "the FMU (or the scene that builds it)", "FMU")):
            if stored[what] != digests[what]:
                raise SpecError(str(self.record), f"{label} changed since these results were written",
                                f"resume with the {name} that started them, {ANOTHER}")

    def _finished(self, source: Path):
        """The rows already written, checked against this spec's samples; the done set."""
        data = source.read_bytes()
        complete = data[: data.rfind(b"\n") + 1]
        if len(complete) != len(data):  # the row a kill interrupted
            sweep_files.write_bytes(source, complete)
        try:
            rows = list(csv.reader(io.StringIO(complete.decode())))
        except (UnicodeDecodeError, csv.Error) as e:
            raise SpecError(str(source), f"is not a CSV this tool wrote ({e})", f"restore it, {ANOTHER}") from None
        if not rows or rows[0] != self.header:
            raise SpecError(str(source), "was written for other columns than this spec's",
                            f"resume with the spec that started it, {ANOTHER}")
        for number, row in enumerate(rows[1:], start=2):
            self.done.add(self._check_row(source, number, row))
        return rows[1:]

    def _check_row(self, source, number, row):
        where = f"{source}, row {number}"
        fix = f"delete that row (its sample runs again), {ANOTHER}"
        if len(row) != len(self.header):
            raise SpecError(where, f"has {len(row)} cells, the header {len(self.header)}", fix)
        if not row[0].isascii() or not row[0].isdigit() or int(row[0]) >= len(self.samples):
            raise SpecError(where, f"sample {row[0]!r} is not a sample number below {len(self.samples)}", fix)
        index = int(row[0])
        if index in self.done:
            raise SpecError(where, f"sample {index} is there twice", fix)
        sample = self.samples[index]
        if row[1: 1 + len(self.swept)] != [fmt(sample[name]) for name in self.swept]:
            raise SpecError(where, f"sample {index} has other values than this spec's", fix)
        if not row[1 + len(self.swept)]:
            raise SpecError(where, "has no status", fix)
        return index

    def write(self, index, sample, status, extremes):
        status = " ".join(status.split())  # one line per row, whatever the FMU's message holds
        stats = []
        for name in self.outputs:
            if name in extremes:
                lo, hi, final = extremes[name]
                stats += [fmt(final), fmt(lo), fmt(hi)]
            else:  # a failed sample has no outputs
                stats += ["", "", ""]
        # One write and a flush per row: what a kill leaves is whole rows plus at most one part.
        self.file.write(_csv([[index, *[fmt(sample[n]) for n in self.swept], status, *stats]]))
        self.file.flush()
        self.done.add(index)

    def close(self):
        """Closes progress.csv; once every sample has a row, writes results.csv whole and
        removes progress.csv. Returns whether results.csv is complete."""
        self.file.close()
        if len(self.done) < len(self.samples):
            return False
        with open(self.progress, newline="") as f:
            rows = list(csv.reader(f))[1:]
        rows.sort(key=lambda row: int(row[0]))
        sweep_files.write_bytes(self.path, _csv([self.header, *rows]).encode())
        self.progress.unlink()
        return True


def _csv(rows) -> str:
    out = io.StringIO()
    csv.writer(out, lineterminator="\n").writerows(rows)
    return out.getvalue()
