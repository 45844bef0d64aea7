"""The sweep spec (TOML) and its samples.

Reading is in two passes: `load` checks the file's own structure and types; `resolve`
checks the names against the FMU's variables (and a scene's keys) once the FMU is known.
Every mistake is a SpecError naming the key, the reason and the fix.
"""

import difflib
import itertools
import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np


class SpecError(Exception):
    def __init__(self, key, reason, fix):
        super().__init__(f"{key}: {reason}; {fix}")


KNOWN = {"fmu", "scene", "stop_time", "step", "outputs", "warm_start", "parameters",
         "scene_parameters", "random"}


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


def _number(key, value, positive=True):
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SpecError(key, f"must be a number, got {value!r}", f"write e.g. {key} = 1.0")
    if not math.isfinite(value) or (positive and value <= 0):
        raise SpecError(key, f"must be a positive finite number, got {value!r}", f"write e.g. {key} = 1.0")
    return float(value)


def _value_lists(table_key, table):
    if not isinstance(table, dict):
        raise SpecError(table_key, "must be a table of names to lists of values",
                        f'write [{table_key}] then lines like "cable[1].stiffness" = [250.0, 500.0]')
    for name, values in table.items():
        key = f'{table_key}."{name}"'
        if not isinstance(values, list) or not values:
            raise SpecError(key, f"must be a non-empty list of values, got {values!r}",
                            f'write "{name}" = [value, ...] (one value holds it constant)')
    return dict(table)


def load(path) -> Spec:
    path = Path(path)
    try:
        raw = tomllib.loads(path.read_text())
    except FileNotFoundError:
        raise SpecError(str(path), "no such file", "give the path of a sweep spec (.toml)") from None
    except tomllib.TOMLDecodeError as e:
        raise SpecError(str(path), f"not valid TOML ({e})", "fix the TOML syntax at that line") from None
    for key in raw:
        if key not in KNOWN:
            raise SpecError(key, "unknown key", f"use only {', '.join(sorted(KNOWN))}")
    if ("fmu" in raw) == ("scene" in raw):
        raise SpecError("fmu/scene", "exactly one of the two is needed",
                        'write fmu = "tower20.fmu" or scene = "tower20" (a built-in name or a scene file)')
    for key in ("fmu", "scene"):
        if key in raw and not isinstance(raw[key], str):
            raise SpecError(key, f"must be a string, got {raw[key]!r}", f'write {key} = "tower20"')
    for key in ("stop_time", "step", "outputs"):
        if key not in raw:
            raise SpecError(key, "missing", {"outputs": 'write outputs = ["node[61].x"]'}.get(key, f"write {key} = 0.01"))
    outputs = raw["outputs"]
    if not isinstance(outputs, list) or not outputs or not all(isinstance(o, str) for o in outputs):
        raise SpecError("outputs", f"must be a non-empty list of FMU variable names, got {outputs!r}",
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
    if spec.step > spec.stop_time:
        raise SpecError("step", f"{spec.step} is longer than stop_time {spec.stop_time}", "use a step ≤ stop_time")
    if spec.scene_parameters and spec.fmu:
        raise SpecError("scene_parameters", "need a scene to build, not a built FMU", 'name the scene: scene = "tower20"')
    if spec.scene and spec.scene.endswith((".toml", ".json")):  # a file, not a built-in name
        spec.scene = str(path.parent / spec.scene)
    if spec.random:
        for table, lists in (("parameters", spec.parameters), ("scene_parameters", spec.scene_parameters)):
            for name, values in lists.items():
                if len(values) != 1:
                    raise SpecError(f'{table}."{name}"', "a random sweep holds these at one value",
                                    "give one value, or sweep the variable in [random.ranges] with [low, high]")
    return spec


def _random(table):
    if not isinstance(table, dict):
        raise SpecError("random", "must be a table", "write [random] with n, seed and [random.ranges]")
    for key in ("n", "seed", "ranges"):
        if key not in table:
            raise SpecError(f"random.{key}", "missing",
                            {"n": "write n = 20 (samples)", "seed": "write seed = 1 (any integer)",
                             "ranges": '[random.ranges] with lines like "cable[1].stiffness" = [250.0, 1000.0]'}[key])
    for key in ("n", "seed"):
        if isinstance(table[key], bool) or not isinstance(table[key], int) or table[key] < (1 if key == "n" else 0):
            raise SpecError(f"random.{key}", f"must be a {'positive' if key == 'n' else 'non-negative'} integer, got {table[key]!r}",
                            f"write {key} = 20")
    ranges = {}
    for name, bounds in _value_lists("random.ranges", table["ranges"]).items():
        key = f'random.ranges."{name}"'
        if len(bounds) != 2:
            raise SpecError(key, f"must be [low, high], got {bounds!r}", f'write "{name}" = [250.0, 1000.0]')
        low, high = (_number(key, b, positive=False) for b in bounds)
        if not low < high:
            raise SpecError(key, f"low {low} must be below high {high}", "swap or widen the range")
        ranges[name] = (low, high)
    return {"n": table["n"], "seed": table["seed"], "ranges": ranges}


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
            key = f'{table}."{name}"'
            rx = _pattern(name)
            matches = [n for n in variables if rx.match(n)]
            if not matches:
                raise SpecError(key, "no FMU variable of that name", _close(name, list(variables)))
            for match in matches:
                _check_settable(key, variables[match], values, spec.warm_start)
            for match in matches:
                earlier = next((n for n, ms in spec.expanded.items() if match in ms), None)
                if earlier is not None:
                    raise SpecError(key, f"{match} is already swept by {earlier!r}", "sweep each variable under one name")
            spec.expanded[name] = matches
    for name in spec.outputs:
        if name not in variables:
            raise SpecError("outputs", f"{name!r} is no FMU variable", _close(name, list(variables)))
        if variables[name].type != "Real":
            raise SpecError("outputs", f"{name!r} is a {variables[name].type}, not a Real", "record Real variables")


def _check_settable(key, v, values, warm_start):
    if v.causality not in ("parameter", "input"):
        raise SpecError(key, f"{v.name} is an {v.causality}, not a parameter or an input",
                        "sweep parameters and inputs; record outputs under outputs = [...]")
    if warm_start and v.variability == "fixed":
        raise SpecError(key, f"{v.name} is a fixed parameter: it cannot change after warm_start's settling run",
                        "remove warm_start, or this parameter")
    for value in values:
        ok = isinstance(value, TYPES[v.type]) and (v.type == "Boolean" or not isinstance(value, bool))
        if not ok:
            raise SpecError(key, f"{v.name} is a {v.type}, got {value!r}",
                            {"Real": "write numbers, e.g. 500.0", "Integer": "write integers, e.g. 1",
                             "Boolean": "write true or false"}[v.type])


def samples(spec: Spec) -> list:
    """Every sample as {column: value}, in a fixed order: the grid's product in the order
    the spec lists the names, or n random draws (seeded) with the held values."""
    if spec.random:
        held = {k: v[0] for k, v in {**spec.scene_parameters, **spec.parameters}.items()}
        ranges = spec.random["ranges"]
        u = np.random.default_rng(spec.random["seed"]).random((spec.random["n"], len(ranges)))
        return [held | {name: lo + (hi - lo) * float(x) for (name, (lo, hi)), x in zip(ranges.items(), row)}
                for row in u]
    lists = {**spec.scene_parameters, **spec.parameters}
    return [dict(zip(lists, combo)) for combo in itertools.product(*lists.values())]


def fmu_values(spec: Spec, sample: dict) -> dict:
    """The FMU variables a sample sets (patterns expanded)."""
    return {var: sample[name] for name in spec.expanded for var in spec.expanded[name]}


def scene_values(spec: Spec, sample: dict) -> dict:
    return {path: sample[path] for path in spec.scene_parameters}
