"""The layout shows the architecture: the top-level modules of src/ form layers without a
circle, no two modules import each other, the physics never names the FMI side, and no
source file grows past about 500 lines. Edges come from the `crate::`/`super::` paths and a
module's own `mod` children named in each file (tests left out); a parent declaring its
children (`mod x;`) is not an edge, a child naming its parent's items is."""

import os
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SRC = ROOT / "src"
MAX_LINES = 500
PATH = re.compile(
    r"\b(crate|super)((?:::[A-Za-z_]\w*)+)(?:::\{([^;{}]*(?:\{[^{}]*\}[^;{}]*)*)\})?"
)


def module_of(path: Path) -> str:
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    if parts[-1] in ("mod", "lib", "main"):
        parts = parts[:-1]
    return "::".join(parts)


def module_files() -> dict:
    files = {module_of(p): p for p in SRC.rglob("*.rs")}
    return {m: f for m, f in files.items() if "tests" not in m.split("::")}


def code_of(path: Path) -> str:
    text = path.read_text()
    cut = text.find("#[cfg(test)]\nmod tests {")
    text = text if cut < 0 else text[:cut]
    return re.sub(r"//[^\n]*", "", text)


def edges() -> set:
    files = module_files()
    known = set(files)

    def resolve(parts):
        for k in range(len(parts), -1, -1):
            name = "::".join(parts[:k])
            if name in known:
                return name
        return None

    found = set()
    for module, path in files.items():
        code = code_of(path)
        base = module.split("::") if module else []
        for keyword, tail, group in PATH.findall(code):
            head = [p for p in tail.split("::") if p]
            prefix = []
            if keyword == "super":
                prefix = base[:-1]
                while head and head[0] == "super":
                    prefix, head = prefix[:-1], head[1:]
            items = [s.strip().split("::")[0] for s in re.split(r",(?![^{]*\})", group)] if group else [""]
            for item in items:
                target = resolve(prefix + head + ([item] if item and item != "self" else []))
                if target is not None and target != module:
                    found.add((module or "crate", target or "crate"))
        for child in re.findall(r"^\s*(?:pub(?:\([^)]*\))?\s+)?mod\s+(\w+)\s*;", code, re.M):
            for tail, group in re.findall(
                r"(?<![\w:])" + child + r"((?:::[A-Za-z_]\w*)*)(?:::\{([^;{}]*)\})?", code
            ):
                head = [p for p in tail.split("::") if p]
                items = [x.strip().split("::")[0] for x in group.split(",")] if group else [""]
                for item in items:
                    target = resolve(base + [child] + head + ([item] if item and item != "self" else []))
                    if target and target != module:
                        found.add((module or "crate", target))
    return found


def related(a: str, b: str) -> bool:
    return "crate" in (a, b) or b.startswith(a + "::") or a.startswith(b + "::")


def cycles(graph_edges: set) -> list:
    graph = {}
    for a, b in graph_edges:
        graph.setdefault(a, set()).add(b)
        graph.setdefault(b, set())
    index, low, stack, on_stack, groups, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                groups.append(sorted(group))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return groups


def test_the_edges_are_found():
    found = edges()
    top = {(a.split("::")[0], b.split("::")[0]) for a, b in found}
    # Known edges of the data flow, so an empty result can't pass the checks below.
    for edge in [("sim", "integrator"), ("model", "linalg"), ("fmi", "sim")]:
        assert edge in top, edge
    assert ("fmi::snapshot", "fmi::state") in found
    assert ("render::labels", "render::view") in found


def test_top_level_modules_form_layers():
    top = {(a.split("::")[0], b.split("::")[0]) for a, b in edges()}
    top = {(a, b) for a, b in top if a != b and "crate" not in (a, b)}
    assert cycles(top) == []


def test_no_two_modules_import_each_other():
    found = {(a, b) for a, b in edges() if not related(a, b)}
    both_ways = sorted((a, b) for a, b in found if (b, a) in found and a < b)
    assert both_ways == []
    assert cycles(found) == []


def test_the_physics_knows_nothing_of_fmi():
    outside = {"fmi", "cli", ""}
    named = sorted(a for a, b in edges() if b.split("::")[0] == "fmi" and a.split("::")[0] not in outside)
    assert named == []


def test_no_source_file_past_the_limit():
    long = []
    for folder in (SRC, ROOT / "fmu" / "src", ROOT / "modelDescription" / "src"):
        for path in folder.rglob("*.rs"):
            lines = len(path.read_text().splitlines())
            if lines > MAX_LINES:
                long.append(f"{path.relative_to(ROOT)}: {lines}")
    assert long == []
