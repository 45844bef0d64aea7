"""Scene variants: a scene with a sample's `scene_parameters` set, built into its own FMU.

Prestress and cable stiffness are scene keys, not FMU variables (the rest lengths follow
from both when the scene is loaded), so sweeping them means building one FMU per
combination. Variants are written as TOML: the CLI reads TOML numbers correctly rounded,
while its JSON reader (serde_json without `float_roundtrip`) can be one ulp off.
"""

import copy
import dataclasses
import hashlib
import io
import json
import re
import subprocess
import tomllib
import zipfile
from pathlib import Path

import sweep_files
import sweep_spec
from sweep_spec import SpecError, check_scene_name


_SEGMENT = re.compile(r"([A-Za-z_]\w*)(?:\[(\d+|\*)\])?\Z")


def set_scene_key(scene: dict, path: str, value):
    """Sets `prestress.min_tension` or `cables[*].stiffness` (indices from 1, as scene errors
    and FMU names count) in a parsed scene; the key must already be in the scene."""
    key = f'scene_parameters."{sweep_spec.key_name(path)}"'
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
    if path.suffix in (".json", ".toml"):
        try:
            text = path.read_text(encoding="utf-8")
            data = json.loads(text) if path.suffix == ".json" else tomllib.loads(text)
        except FileNotFoundError:
            raise SpecError("scene", f"no such file {path}", "give the path of a scene file (relative to the spec)") from None
        except UnicodeDecodeError as e:
            raise SpecError("scene", f"{path} is not UTF-8 text (byte {e.start})", "give a scene file in UTF-8") from None
        except OSError as e:
            raise SpecError("scene", f"{path} cannot be read ({e.strerror})", "give a readable scene file") from None
        except json.JSONDecodeError as e:
            raise SpecError("scene", f"{path} is not valid JSON (line {e.lineno}, column {e.colno}: {e.msg})",
                            "fix the JSON at that place") from None
        except tomllib.TOMLDecodeError as e:
            raise SpecError("scene", f"{path} is not valid TOML ({e})", "fix the TOML at that line") from None
        except RecursionError:
            raise SpecError("scene", f"{path} nests arrays or objects too deeply to read",
                            "write a scene (docs/scenes.md)") from None
        if not isinstance(data, dict):
            raise SpecError("scene", f"{path} holds a {type(data).__name__}, not a scene table",
                            "write the scene as one object of keys (see docs/scenes.md)")
        if _depth(data) > MAX_SCENE_DEPTH:
            raise SpecError("scene", f"{path} nests arrays or objects more than {MAX_SCENE_DEPTH} deep",
                            "write a scene (docs/scenes.md)")
        return data
    try:
        res = subprocess.run([str(cli), "scene", scene], capture_output=True, text=True)
    except OSError as e:
        raise SpecError("scene", f"the CLI {cli} cannot run ({e.strerror})",
                        "build it with `cargo build --release --workspace`") from None
    if res.returncode != 0:
        raise SpecError("scene", cli_error(res.stderr),
                        "name a built-in scene (`tensegrity-fmu scene` lists them) or a .toml/.json file")
    return tomllib.loads(res.stdout)


MAX_SCENE_DEPTH = 16  # a scene nests 3 deep ([[cables]] of tables of lists)


def _depth(data) -> int:
    """How deeply lists and tables nest, counted without recursion."""
    deepest, stack = 0, [(data, 1)]
    while stack:
        node, depth = stack.pop()
        deepest = max(deepest, depth)
        if depth <= MAX_SCENE_DEPTH:
            children = node.values() if isinstance(node, dict) else node if isinstance(node, list) else ()
            stack.extend((child, depth + 1) for child in children if isinstance(child, (dict, list)))
    return deepest


def variant(spec, sample) -> str:
    """The scene values of a sample as the key of its variant."""
    return json.dumps(sweep_spec.scene_values(spec, sample), sort_keys=True)


def build_variants(spec, out: Path, cli: Path):
    """The FMU of each variant: spec.fmu, or the scene with each combination of the
    scene_parameters, built once into DIR/fmus/ (kept, so a resumed sweep rebuilds nothing).
    Counts the combinations by multiplying, builds them one at a time.

    Returns ({key: fmu bytes}, {variant: key or build error})."""
    if spec.fmu:
        data = read_fmu(spec.fmu)
        key = hashlib.sha256(data).hexdigest()[:16]
        return {key: data}, {"{}": key}
    base = scene_data(spec.scene, cli)
    check_scene_name(f"{spec.scene}: name", base.get("name", "scene"))
    (out / "fmus").mkdir(exist_ok=True)
    sweep_files.remove_leftovers(out / "fmus", ["*.fmu", "*.toml"])
    archives, keys = {}, {}  # a random sweep holds each scene key at one value: one variant
    for combo in sweep_spec.Samples(dataclasses.replace(spec, parameters={}, random=None)):
        keys[variant(spec, combo)] = _build(base, combo, out / "fmus", archives, cli)
    return archives, keys


def read_fmu(path: Path) -> bytes:
    """The bytes of a built FMU, once checked to be a zip holding a modelDescription.xml."""
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise SpecError("fmu", f"no such file {path}", "give the path of a .fmu (relative to the spec)") from None
    except OSError as e:
        raise SpecError("fmu", f"{path} cannot be read ({e.strerror})", "give a readable .fmu file") from None
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as z:
            if "modelDescription.xml" not in z.namelist():
                raise SpecError("fmu", f"{path} is a zip archive without modelDescription.xml, not an FMU",
                                "give an FMU built with `tensegrity-fmu build`")
    except zipfile.BadZipFile:
        raise SpecError("fmu", f"{path} is not an FMU (not a zip archive)",
                        "give an FMU built with `tensegrity-fmu build`") from None
    return data


def _build(base, values, folder, archives, cli):
    scene = copy.deepcopy(base)
    for path, value in values.items():
        set_scene_key(scene, path, value)
    text = dumps(scene)
    # The name only labels the file; check_scene_name has refused any that leaves the folder.
    label = re.sub(r"[^A-Za-z0-9_.-]+", "_", str(scene.get("name", "scene")))[:60]
    stem = f"{label}-{hashlib.sha256(text.encode()).hexdigest()[:12]}"
    fmu = folder / f"{stem}.fmu"
    if not fmu.is_file():
        sweep_files.write_bytes(folder / f"{stem}.toml", text.encode())
        try:
            res = subprocess.run([str(cli), "build", str(folder / f"{stem}.toml"), "-o", str(fmu)],
                                 capture_output=True, text=True)
        except OSError as e:
            raise SpecError("scene", f"the CLI {cli} cannot run ({e.strerror})",
                            "build it with `cargo build --release --workspace`") from None
        if res.returncode != 0:  # this variant's samples become error rows
            return BuildError(cli_error(res.stderr))
    data = fmu.read_bytes()
    key = hashlib.sha256(data).hexdigest()[:16]
    archives[key] = data
    return key


def cli_error(stderr: str) -> str:
    """The CLI's error line (notes it prints before it left out)."""
    errors = [line for line in stderr.splitlines() if line.startswith("error: ")]
    return " ".join((errors[-1] if errors else stderr).split()).removeprefix("error: ")


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
