"""What the examples read from any FMU that tensegrity-fmu builds: its variables by kind.

Every name comes from the FMU's modelDescription.xml, so the examples work on every scene:
node positions `node[N].x|y|z` and velocities `node[N].vx|vy|vz` (outputs), pin reactions
`node[N].reaction_x` (outputs of the pinned nodes only), cable tensions `cable[K].tension`
(outputs, described as "tension of cable K (nodes A–B)"), the constraint residuals
`constraint.length_error` and `constraint.orthogonality_error`, and the inputs:
`cable[K].force_density` for force-density controlled cables and `node[N].fx|fy|fz` for the
nodes a scene lists in `force_inputs`.

User mistakes (a missing file, a file that is not an FMU, a bad option) end the program with
one line on stderr and exit status 2, as command-line tools do.
"""

import argparse
import re
import sys
import zipfile
from pathlib import Path

from fmpy import read_model_description

INDEXED = re.compile(r"^(node|cable)\[(\d+)\]\.(\w+)$")
CABLE_ENDS = re.compile(r"nodes (\d+)\s*[-–]\s*(\d+)")


def fail(message):
    """Ends the program with one line on stderr and exit status 2 (a usage error)."""
    print(f"{Path(sys.argv[0]).name}: error: {message}", file=sys.stderr)
    sys.exit(2)


def run_main(main):
    """Runs an example's `main`: a call that the FMU refuses (a value out of range, a step
    beyond the solver's limits) or a file that can't be written ends the program with the
    reason on one line and exit status 1, not a traceback; Ctrl-C ends it quietly."""
    try:
        main()
    except KeyboardInterrupt:
        sys.exit(130)
    except Exception as e:  # noqa: BLE001 - every failure becomes one line for the user
        message = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        print(f"{Path(sys.argv[0]).name}: error: {message}", file=sys.stderr)
        sys.exit(1)


class Parser(argparse.ArgumentParser):
    """argparse whose errors are one line (no usage block) with exit status 2."""

    def error(self, message):
        fail(f"{message} (see --help)")


def check_fmu(path):
    """The model description of the FMU at `path`, or a one-line error naming what is wrong."""
    path = Path(path)
    if not path.exists():
        fail(f"{path}: no such file (build one with `tensegrity-fmu build SCENE -o {path.name}`)")
    if not path.is_file() or not zipfile.is_zipfile(path):
        fail(f"{path} is not an FMU (an FMU is a zip archive; build one with `tensegrity-fmu build`)")
    with zipfile.ZipFile(path) as archive:
        if "modelDescription.xml" not in archive.namelist():
            fail(f"{path} is not an FMU: the archive has no modelDescription.xml")
    try:
        md = read_model_description(str(path))
    except Exception as exc:  # fmpy raises several types for malformed XML
        fail(f"{path}: unreadable modelDescription.xml ({str(exc).splitlines()[0]})")
    if md.coSimulation is None:
        fail(f"{path} is not a co-simulation FMU (the examples step FMI 2.0 co-simulation FMUs)")
    return md


class FmuVariables:
    """An FMU's variables grouped by what they mean, with value references and start values."""

    def __init__(self, md):
        self.md = md
        self.name = md.modelName
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.start = {v.name: float(v.start) for v in md.modelVariables
                      if v.start is not None and v.type == "Real"}
        self.inputs = [v.name for v in md.modelVariables if v.causality == "input"]
        nodes, pinned, cables, self.cable_ends = set(), set(), set(), {}
        for v in md.modelVariables:
            m = INDEXED.match(v.name)
            if not m or v.causality != "output":
                continue
            kind, index, field = m.group(1), int(m.group(2)), m.group(3)
            if kind == "node" and field == "x":
                nodes.add(index)
            elif kind == "node" and field == "reaction_x":
                pinned.add(index)
            elif kind == "cable" and field == "tension":
                cables.add(index)
                ends = CABLE_ENDS.search(v.description or "")
                if ends:
                    self.cable_ends[index] = (int(ends.group(1)), int(ends.group(2)))
        self.nodes = sorted(nodes)
        self.pinned = sorted(pinned)
        self.free = [n for n in self.nodes if n not in pinned]
        self.cables = sorted(cables)
        self.force_density_inputs = [n for n in self.inputs if n.endswith(".force_density")]
        self.force_input_nodes = sorted(
            int(INDEXED.match(n).group(2)) for n in self.inputs if INDEXED.match(n)
            and n.endswith(".fx"))

    @staticmethod
    def position(node):
        return [f"node[{node}].{a}" for a in "xyz"]

    @staticmethod
    def velocity(node):
        return [f"node[{node}].v{a}" for a in "xyz"]

    def tensions(self):
        return [f"cable[{k}].tension" for k in self.cables]

    def residuals(self):
        return [n for n in ("constraint.length_error", "constraint.orthogonality_error")
                if n in self.vr]
