"""The sweep spec (TOML) and its samples.

Reading is in two passes: `load` checks the file's own structure, types and sizes;
`resolve` checks the names and values against the FMU's variables (their type and the
min/max of the model description) once the FMU is known. Every mistake is a SpecError
naming the key, the reason and the fix. Samples are counted by multiplying and computed
one at a time, so a grid too large to run is refused without being built.
"""

import difflib
import hashlib
import json
import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np


class SpecError(Exception):
    """A mistake of the user's, shown as one line: where, what is wrong, how to fix it."""

    def __init__(self, key, reason, fix):
        super().__init__(" ".join(f"{key}: {reason}; {fix}".split()))


KNOWN = {"fmu", "scene", "stop_time", "step", "outputs", "warm_start", "parameters",
         "scene_parameters", "random"}
# Communication points of one run at most: the CLI's `simulate` limit on rows (MAX_ROWS in
# src/cli/simulate.rs; tests/fmpy/test_sweep_errors.py checks they agree).
MAX_POINTS = 10**7
MAX_RUNS = 10**6  # samples of one sweep without --force
MAX_VARIANTS = 1000  # scene variants (FMUs built) of one sweep without --force
MAX_RESULT_BYTES = 2e9  # estimated size of results.csv without --force
CELL_BYTES = 24  # a float's shortest round-trip decimal and its comma, at most
INT32 = (-2**31, 2**31 - 1)  # fmi2Integer


@dataclass
class Spec:
    path: Path
    fmu: Path | None  # a built FMU, or
    scene: str | None  # a built-in scene name or a scene file, built into one FMU per variant
    stop_time: float
    step: float
    outputs: list
    warm_start: float  # seconds of the shared settling run; 0 = none
    parameters: dict  # FMU variable name (or pattern with [*]) -> list of values
    scene_parameters: dict  # scene key path -> list of values
    random: dict | None = None  # {"n", "seed", "ranges": {name: (low, high)}}
    expanded: dict = field(default_factory=dict)  # parameter name -> matching variable names

    def swept(self):
        """Column names of the swept values: scene keys first, then FMU variables."""
        names = list(self.scene_parameters) + list(self.parameters)
        return names + list(self.random["ranges"]) if self.random else names

    def runs(self) -> int:
        """How many samples, by multiplying the list lengths: nothing is built."""
        return self.random["n"] if self.random else math.prod(len(v) for v in self.lists().values())

    def lists(self):
        return {**self.scene_parameters, **self.parameters}

    def digest(self) -> str:
        """SHA-256 of what the spec asks to run (not where the FMU or scene file lies:
        the FMU's own hash covers that), as stored with the results for --resume."""
        what = {k: getattr(self, k) for k in ("stop_time", "step", "outputs", "warm_start",
                                              "parameters", "scene_parameters", "random")}
        return hashlib.sha256(json.dumps(what, sort_keys=True).encode()).hexdigest()


def _number(key, value, positive=True):
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SpecError(key, f"must be a number, got {_show(value)}", f"write e.g. {key} = 1.0")
    _float(key, value)
    if not math.isfinite(value) or (positive and value <= 0):
        raise SpecError(key, f"must be a {'positive ' * positive}finite number, got {_show(value)}",
                        f"write e.g. {key} = 1.0")
    return float(value)


def _float(key, value):
    """`value` as a float; TOML integers have no bound, floats stop near 1.8e308."""
    try:
        return float(value)
    except OverflowError:
        raise SpecError(key, f"holds an integer too large for a 64-bit float ({len(str(abs(value)))} digits)",
                        "give numbers below 1.8e308") from None


def _show(value, limit=60):
    """A value as the message shows it: short, on one line."""
    text = " ".join(repr(value).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def key_name(key):
    """A key of the user's as the message names it: as written if printable and short."""
    return key if isinstance(key, str) and key.isprintable() and len(key) <= 60 else _show(key)


MAX_DEPTH = 8  # lists in lists of a swept value (a scene's nodes are 2)


def _finite_values(key, value, depth=0):
    """Numbers anywhere in a swept value (a scene list such as gravity too) must be finite."""
    if isinstance(value, float) and not math.isfinite(value):
        raise SpecError(key, f"holds {value!r}", "give finite numbers")
    if isinstance(value, int) and not isinstance(value, bool):
        _float(key, value)
    if isinstance(value, dict):
        raise SpecError(key, f"holds a table {_show(value)}", "give numbers, true/false, strings or lists of them")
    if isinstance(value, list):
        if depth == MAX_DEPTH:
            raise SpecError(key, f"nests lists more than {MAX_DEPTH} deep", "give numbers or lists of numbers")
        for item in value:
            _finite_values(key, item, depth + 1)


def _value_lists(table_key, table):
    if not isinstance(table, dict):
        raise SpecError(table_key, f"must be a table of names to lists of values, got {_show(table)}",
                        f'write [{table_key}] then lines like "cable[1].stiffness" = [250.0, 500.0]')
    for name, values in table.items():
        key = f'{table_key}."{key_name(name)}"'
        if not isinstance(values, list) or not values:
            raise SpecError(key, f"must be a non-empty list of values, got {_show(values)}",
                            f'write "{name}" = [value, ...] (one value holds it constant)')
        for value in values:
            _finite_values(key, value)
    return dict(table)


def load(path) -> Spec:
    path = Path(path)
    try:
        raw = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise SpecError(str(path), "no such file", "give the path of a sweep spec (.toml)") from None
    except UnicodeDecodeError as e:
        raise SpecError(str(path), f"not UTF-8 text (byte {e.start})", "give a sweep spec (TOML, UTF-8)") from None
    except OSError as e:
        raise SpecError(str(path), f"cannot be read ({e.strerror})", "give a readable sweep spec (.toml)") from None
    except tomllib.TOMLDecodeError as e:
        raise SpecError(str(path), f"not valid TOML ({e})", "fix the TOML syntax at that line") from None
    except RecursionError:
        raise SpecError(str(path), "nests arrays or tables too deeply to read", "write a sweep spec (docs/sweeps.md)") from None
    return parse(raw, path)


def parse(raw: dict, path: Path) -> Spec:
    """The spec from the parsed TOML; `path` places relative file names."""
    for key in raw:
        if key not in KNOWN:
            raise SpecError(key_name(key), "unknown key", f"use only {', '.join(sorted(KNOWN))}")
    if ("fmu" in raw) == ("scene" in raw):
        raise SpecError("fmu/scene", "exactly one of the two is needed",
                        'write fmu = "tower20.fmu" or scene = "tower20" (a built-in name or a scene file)')
    for key in ("fmu", "scene"):
        if key in raw and (not isinstance(raw[key], str) or not raw[key].strip() or "\0" in raw[key]):
            raise SpecError(key, f"must be a file name or scene name, got {_show(raw[key])}", f'write {key} = "tower20"')
    for key in ("stop_time", "step", "outputs"):
        if key not in raw:
            raise SpecError(key, "missing", {"outputs": 'write outputs = ["node[61].x"]'}.get(key, f"write {key} = 0.01"))
    outputs = raw["outputs"]
    if not isinstance(outputs, list) or not outputs or not all(isinstance(o, str) for o in outputs):
        raise SpecError("outputs", f"must be a non-empty list of FMU variable names, got {_show(outputs)}",
                        'write outputs = ["node[61].x", "cable[1].tension"]')
    spec = Spec(
        path=path,
        fmu=path.parent / raw["fmu"] if "fmu" in raw else None,
        scene=raw.get("scene"),
        stop_time=_number("stop_time", raw["stop_time"]),
        step=_number("step", raw["step"]),
        outputs=outputs,
        warm_start=_number("warm_start", raw["warm_start"]) if "warm_start" in raw else 0.0,
        parameters=_value_lists("parameters", raw.get("parameters", {})),
        scene_parameters=_value_lists("scene_parameters", raw.get("scene_parameters", {})),
        random=_random(raw["random"]) if "random" in raw else None,
    )
    _check_times(spec)
    if spec.scene_parameters and spec.fmu:
        raise SpecError("scene_parameters", "need a scene to build, not a built FMU", 'name the scene: scene = "tower20"')
    for value in spec.scene_parameters.get("name", []):
        check_scene_name('scene_parameters."name"', value)
    if spec.scene and spec.scene.endswith((".toml", ".json")):  # a file, not a built-in name
        spec.scene = str(path.parent / spec.scene)
    if spec.random:
        for table, lists in (("parameters", spec.parameters), ("scene_parameters", spec.scene_parameters)):
            for name, values in lists.items():
                if len(values) != 1:
                    raise SpecError(f'{table}."{key_name(name)}"', "a random sweep holds these at one value",
                                    "give one value, or sweep the variable in [random.ranges] with [low, high]")
        for name in spec.random["ranges"]:
            if name in spec.parameters or name in spec.scene_parameters:
                raise SpecError(f'random.ranges."{key_name(name)}"', "is also held in another table", "name it in one table only")
    return spec


def _check_times(spec):
    if spec.step > spec.stop_time:
        raise SpecError("step", f"{spec.step} is longer than stop_time {spec.stop_time}", "use a step ≤ stop_time")
    for key in ("stop_time", "warm_start"):
        points = getattr(spec, key) / spec.step
        if points > MAX_POINTS:
            raise SpecError(key, f"{getattr(spec, key)} s at step {spec.step} s is {points:.3g} communication points "
                            f"per run, more than the limit of {MAX_POINTS:.0e}", f"shorten {key} or raise step")


def check_scene_name(key, name):
    """A scene name becomes file names in DIR/fmus: nothing that leaves the folder."""
    if not isinstance(name, str) or not name.strip():
        raise SpecError(key, f"a scene name must be a non-empty string, got {_show(name)}", 'write e.g. "tower-a"')
    if any(c in name for c in "/\\\0") or name.startswith((".", "-")) or Path(name).is_absolute():
        raise SpecError(key, f"{_show(name)} would name a file outside the output folder",
                        "use letters, digits, spaces, '-', '_' or '.', not starting with '.' or '-', without / or \\")


def _random(table):
    if not isinstance(table, dict):
        raise SpecError("random", f"must be a table, got {_show(table)}", "write [random] with n, seed and [random.ranges]")
    for key in table:
        if key not in ("n", "seed", "ranges"):
            raise SpecError(f"random.{key_name(key)}", "unknown key", "use only n, seed and ranges")
    for key in ("n", "seed", "ranges"):
        if key not in table:
            raise SpecError(f"random.{key}", "missing",
                            {"n": "write n = 20 (samples)", "seed": "write seed = 1 (any integer)",
                             "ranges": '[random.ranges] with lines like "cable[1].stiffness" = [250.0, 1000.0]'}[key])
    for key in ("n", "seed"):
        if isinstance(table[key], bool) or not isinstance(table[key], int) or table[key] < (1 if key == "n" else 0):
            raise SpecError(f"random.{key}", f"must be a {'positive' if key == 'n' else 'non-negative'} integer, got {_show(table[key])}",
                            f"write {key} = 20")
    ranges = {}
    for name, bounds in _value_lists("random.ranges", table["ranges"]).items():
        key = f'random.ranges."{key_name(name)}"'
        if len(bounds) != 2:
            raise SpecError(key, f"must be [low, high], got {_show(bounds)}", f'write "{name}" = [250.0, 1000.0]')
        low, high = (_number(key, b, positive=False) for b in bounds)
        if not low < high:
            raise SpecError(key, f"low {low} must be below high {high}", "swap or widen the range")
        ranges[name] = (low, high)
    if not ranges:
        raise SpecError("random.ranges", "names no variable", 'add lines like "cable[1].stiffness" = [250.0, 1000.0]')
    return {"n": table["n"], "seed": table["seed"], "ranges": ranges}


def check_size(spec: Spec, force: bool):
    """Refuses, before any work, a sweep past MAX_RUNS samples, MAX_RESULT_BYTES of results
    or MAX_VARIANTS scene variants (each an FMU to build)."""
    variants = math.prod(len(v) for v in spec.scene_parameters.values())
    if variants > MAX_VARIANTS and not force:
        raise SpecError("scene_parameters", f"the sweep builds {variants:,} FMUs, one per scene variant "
                        f"(about 0.2 s and 1.5 MB each), more than the limit of {MAX_VARIANTS:,}",
                        "sweep fewer scene values (swept FMU parameters need no build), or pass --force")
    runs = spec.runs()
    columns = 2 + len(spec.swept()) + 3 * len(spec.outputs)
    size = runs * columns * CELL_BYTES
    if force or (runs <= MAX_RUNS and size <= MAX_RESULT_BYTES):
        return runs
    key = "random.n" if spec.random else "parameters"
    raise SpecError(key, f"the sweep holds {runs:,} runs (results.csv: {runs:,} rows of {columns} columns, "
                    f"about {size / 1e9:.3g} GB), more than the limit of {MAX_RUNS:,} runs or "
                    f"{MAX_RESULT_BYTES / 1e9:.0f} GB", "sweep fewer values, or pass --force to run it anyway")


def _close(name, names):
    near = difflib.get_close_matches(name, names, n=3)
    return f"did you mean {', '.join(near)}?" if near else "see the FMU's modelDescription.xml (`fmpy info X.fmu`)"


def _pattern(name):
    """`cable[*].stiffness` matches every cable[j].stiffness."""
    return re.compile(re.escape(name).replace(r"\[\*\]", r"\[\d+\]") + r"\Z")


TYPES = {"Real": (int, float), "Integer": (int,), "Boolean": (bool,)}


def resolve(spec: Spec, md):
    """Checks the names against the FMU's model description and expands the [*] patterns."""
    variables = {v.name: v for v in md.modelVariables}
    tables = [("parameters", spec.parameters)]
    if spec.random:
        tables.append(("random.ranges", spec.random["ranges"]))
    for table, lists in tables:
        for name, values in lists.items():
            key = f'{table}."{key_name(name)}"'
            rx = _pattern(name)
            matches = [n for n in variables if rx.match(n)]
            if not matches:
                raise SpecError(key, "no FMU variable of that name", _close(name, list(variables)))
            for match in matches:
                if table == "random.ranges" and variables[match].type != "Real":
                    raise SpecError(key, f"{match} is a {variables[match].type}: draws are real numbers",
                                    "draw Real variables; list the values of others under [parameters]")
                _check_settable(key, variables[match], values, spec.warm_start)
            for match in matches:
                earlier = next((n for n, ms in spec.expanded.items() if match in ms), None)
                if earlier is not None:
                    raise SpecError(key, f"{match} is already swept by {earlier!r}", "sweep each variable under one name")
            spec.expanded[name] = matches
    for name in spec.outputs:
        if name not in variables:
            raise SpecError("outputs", f"{_show(name)} is no FMU variable", _close(name, list(variables)))
        if variables[name].type != "Real":
            raise SpecError("outputs", f"{name!r} is a {variables[name].type}, not a Real", "record Real variables")


def _check_settable(key, v, values, warm_start):
    if v.causality not in ("parameter", "input"):
        raise SpecError(key, f"{v.name} is an {v.causality}, not a parameter or an input",
                        "sweep parameters and inputs; record outputs under outputs = [...]")
    if warm_start and v.variability == "fixed":
        raise SpecError(key, f"{v.name} is a fixed parameter: it cannot change after warm_start's settling run",
                        "remove warm_start, or this parameter")
    low, high = _range(v)
    for value in values:
        ok = isinstance(value, TYPES[v.type]) and (v.type == "Boolean" or not isinstance(value, bool))
        if not ok:
            raise SpecError(key, f"{v.name} is a {v.type}, got {_show(value)}",
                            {"Real": "write numbers, e.g. 500.0", "Integer": "write integers, e.g. 1",
                             "Boolean": "write true or false"}[v.type])
        if v.type != "Boolean" and not low <= value <= high:
            source = "from the model description" if v.min is not None or v.max is not None else "a 32-bit fmi2Integer"
            raise SpecError(key, f"{v.name} = {_show(value)} is outside its range [{low}, {high}] ({source})",
                            "give values in that range")


def _range(v):
    """The values a variable takes: its model description's min/max, within 32 bits for an Integer."""
    if v.type == "Real":
        low, high, number = -math.inf, math.inf, float
    else:
        (low, high), number = INT32, int
    if v.min is not None:
        low = max(low, number(v.min))
    if v.max is not None:
        high = min(high, number(v.max))
    return low, high


class Samples:
    """Every sample as {column: value}, in a fixed order, computed on demand: the grid's
    product in the order the spec lists the names (the last name varying fastest), or n
    seeded uniform draws with the held values. Draw i is the i-th row of
    `default_rng(seed).random((n, len(ranges)))`."""

    def __init__(self, spec: Spec):
        self.spec = spec
        self.n = spec.runs()
        if spec.random:
            self.held = {k: v[0] for k, v in spec.lists().items()}
            self.generator = np.random.default_rng(spec.random["seed"])
            self.start = self.generator.bit_generator.state

    def __len__(self):
        return self.n

    def __getitem__(self, index):
        if not 0 <= index < self.n:
            raise IndexError(index)
        if not self.spec.random:
            sample = {}
            for name, values in reversed(self.spec.lists().items()):
                index, at = divmod(index, len(values))
                sample[name] = values[at]
            return dict(reversed(sample.items()))
        ranges = self.spec.random["ranges"]
        self.generator.bit_generator.state = self.start
        self.generator.bit_generator.advance(index * len(ranges))  # one 64-bit draw per double
        row = self.generator.random(len(ranges))
        return self.held | {name: lo + (hi - lo) * float(x) for (name, (lo, hi)), x in zip(ranges.items(), row)}

    def __iter__(self):
        return (self[i] for i in range(self.n))


def samples(spec: Spec) -> Samples:
    return Samples(spec)


def fmu_values(spec: Spec, sample: dict) -> dict:
    """The FMU variables a sample sets (patterns expanded)."""
    return {var: sample[name] for name in spec.expanded for var in spec.expanded[name]}


def scene_values(spec: Spec, sample: dict) -> dict:
    return {path: sample[path] for path in spec.scene_parameters}
