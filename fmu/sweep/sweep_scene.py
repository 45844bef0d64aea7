"""Scene variants: a scene with a sample's `scene_parameters` set, built into its own FMU.

Prestress and cable stiffness are scene keys, not FMU variables (the rest lengths follow
from both when the scene is loaded), so sweeping them means building one FMU per
combination. Variants are written as TOML: the CLI reads TOML numbers correctly rounded,
while its JSON reader (serde_json without `float_roundtrip`) can be one ulp off.
"""

import copy
import hashlib
import json
import re
import subprocess
import tomllib
from pathlib import Path

import sweep_spec
from sweep_spec import SpecError


_SEGMENT = re.compile(r"([A-Za-z_]\w*)(?:\[(\d+|\*)\])?\Z")


def set_scene_key(scene: dict, path: str, value):
    """Sets `prestress.min_tension` or `cables[*].stiffness` (indices from 1, as scene errors
    and FMU names count) in a parsed scene; the key must already be in the scene."""
    key = f'scene_parameters."{path}"'
    targets = [scene]
    segments = path.split(".")
    for depth, segment in enumerate(segments):
        m = _SEGMENT.match(segment)
        if not m:
            raise SpecError(key, f"{segment!r} is no scene key", "write keys like prestress.min_tension or cables[*].stiffness")
        name, index = m.groups()
        last = depth == len(segments) - 1 and index is None
        nxt = []
        for node in targets:
            if not isinstance(node, dict) or name not in node:
                raise SpecError(key, f"the scene has no key {name!r} there",
                                "add the key to the scene file with a start value, or fix its spelling")
            if last:
                _set_leaf(key, node, name, value)
            elif index is None:
                nxt.append(node[name])
            elif not isinstance(node[name], list):
                raise SpecError(key, f"{name} is no list", f"drop the [{index}]")
            elif index == "*":
                nxt.extend(node[name])
            elif not 1 <= int(index) <= len(node[name]):
                raise SpecError(key, f"{name} has {len(node[name])} entries, counted from 1", f"use an index from 1 to {len(node[name])}")
            else:
                nxt.append(node[name][int(index) - 1])
        targets = nxt
    if targets:
        raise SpecError(key, "names a table, not a value", "name a value inside it, e.g. prestress.min_tension")


def _set_leaf(key, node, name, value):
    old = node[name]
    numbers = (int, float)
    same = isinstance(value, numbers) == isinstance(old, numbers) and isinstance(value, bool) == isinstance(old, bool)
    if not same or isinstance(old, (dict, list)) != isinstance(value, (dict, list)):
        raise SpecError(key, f"the scene holds {old!r} there, got {value!r}", "give values of the same kind")
    node[name] = value


def scene_data(scene: str, cli: Path) -> dict:
    """A scene file (TOML or JSON) or a built-in name (printed by `tensegrity-fmu scene`)."""
    path = Path(scene)
    if path.suffix == ".json":
        return json.loads(path.read_text())
    if path.suffix == ".toml":
        return tomllib.loads(path.read_text())
    res = subprocess.run([str(cli), "scene", scene], capture_output=True, text=True)
    if res.returncode != 0:
        raise SpecError("scene", res.stderr.strip().removeprefix("error: "),
                        "name a built-in scene (`tensegrity-fmu scene` lists them) or a .toml/.json file")
    return tomllib.loads(res.stdout)


def build_variants(spec, samples, out: Path, cli: Path):
    """The FMU of each sample: spec.fmu, or the scene with the sample's scene_parameters,
    built once per distinct variant into DIR/fmus/ (kept, so a resumed sweep rebuilds nothing).

    Returns ({key: fmu bytes}, [key or build error per sample])."""
    if spec.fmu:
        if not spec.fmu.is_file():
            raise SpecError("fmu", f"no such file {spec.fmu}", "give the path of a .fmu (relative to the spec)")
        data = spec.fmu.read_bytes()
        key = hashlib.sha256(data).hexdigest()[:16]
        return {key: data}, [key] * len(samples)
    base = scene_data(spec.scene, cli)
    (out / "fmus").mkdir(exist_ok=True)
    archives, built, keys = {}, {}, []
    for sample in samples:
        values = sweep_spec.scene_values(spec, sample)
        text = json.dumps(values, sort_keys=True)
        if text not in built:
            built[text] = _build(base, values, out / "fmus", archives, cli)
        keys.append(built[text])
    return archives, keys


def _build(base, values, folder, archives, cli):
    scene = copy.deepcopy(base)
    for path, value in values.items():
        set_scene_key(scene, path, value)
    text = dumps(scene)
    stem = f"{scene.get('name', 'scene')}-{hashlib.sha256(text.encode()).hexdigest()[:12]}"
    fmu = folder / f"{stem}.fmu"
    if not fmu.is_file():
        (folder / f"{stem}.toml").write_text(text)
        res = subprocess.run([str(cli), "build", str(folder / f"{stem}.toml"), "-o", str(fmu)],
                             capture_output=True, text=True)
        if res.returncode != 0:  # this variant's samples become error rows
            return BuildError(res.stderr.strip().removeprefix("error: "))
    data = fmu.read_bytes()
    key = hashlib.sha256(data).hexdigest()[:16]
    archives[key] = data
    return key


class BuildError(str):
    """The CLI's message for a scene variant it refused to build."""


_BARE = re.compile(r"[A-Za-z0-9_-]+\Z")


def _key(k):
    return k if _BARE.match(k) else json.dumps(k)


def _value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return repr(v)  # the shortest decimal that reads back as the same double
    if isinstance(v, int):
        return str(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)  # a JSON string is a TOML basic string
    if isinstance(v, list):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    return "{ " + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + " }"


def dumps(scene: dict) -> str:
    """A parsed scene back as TOML: plain keys, then tables, then arrays of tables."""
    tables = {k: v for k, v in scene.items() if isinstance(v, dict)}
    arrays = {k: v for k, v in scene.items() if isinstance(v, list) and v and all(isinstance(x, dict) for x in v)}
    lines = [f"{_key(k)} = {_value(v)}" for k, v in scene.items() if k not in tables and k not in arrays]
    for k, table in tables.items():
        lines += ["", f"[{_key(k)}]", *(f"{_key(a)} = {_value(b)}" for a, b in table.items())]
    for k, items in arrays.items():
        for item in items:
            lines += ["", f"[[{_key(k)}]]", *(f"{_key(a)} = {_value(b)}" for a, b in item.items())]
    return "\n".join(lines) + "\n"
