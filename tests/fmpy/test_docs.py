"""The user's guide holds: README.md and docs/*.md are short, name only files that exist,
and every shell command they show runs.

- README.md has at most 300 lines; no doc tells the development history (no "the Nth
  round", no issue numbers, no commit hashes).
- Every relative link, and every repository path written in backticks, names a file or
  folder of the repository (outputs live under out/, which the commands create).
- Every command in a fenced ```sh or ```bash block runs with exit status 0, in a scratch
  folder that mirrors the repository with symlinks, unless it ends with the marker
  `# not run: REASON`. The blocks of one page run in order in one folder, as a reader
  would type them, so a command may use what an earlier one wrote.
"""

import os
import re
import subprocess
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
PAGES = [README] + sorted((ROOT / "docs").glob("*.md"))
LINKED = PAGES + [ROOT / "CHANGELOG.md"]
README_MAX_LINES = 300
COMMAND_TIMEOUT_S = 120

# Written by the set-up commands or by the documented commands themselves, not tracked.
GENERATED = ("out", "target", ".venv")
SKIPPED_DIRS = {".git", "target", ".venv", "out", "__pycache__", ".pytest_cache", "node_modules"}

ORDINAL = (r"first|second|third|fourth|fifth|sixth|seventh|eighth|ninth|tenth|next|last|"
           r"this|that|previous|same|[0-9]+(?:st|nd|rd|th)")
HISTORY = {
    "a development round": re.compile(rf"\b(?:{ORDINAL})\s+round\b|\bround's\b|\bround\s+[0-9]+\b", re.I),
    "an issue number": re.compile(r"\bissues?\s*#?\s*[0-9]+", re.I),
    "a commit hash": re.compile(r"\b(?=[0-9a-f]*[a-f])(?=[0-9a-f]*[0-9])[0-9a-f]{7,12}\b"),
}
NOT_RUN = re.compile(r"#\s*not run:\s*\S")
FENCE = re.compile(r"^```(\w*)\s*$")
HEREDOC = re.compile(r"<<-?\s*['\"]?(\w+)['\"]?")
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
PATH_CHARS = re.compile(r"^[\w.+-]+(?:/[\w.+-]*)+$")
HAS_EXTENSION = re.compile(r"\.[A-Za-z0-9]+$")


def rel(path):
    return path.relative_to(ROOT).as_posix()


def strip_fences(text):
    """The text outside fenced blocks (inline code in prose is what names files)."""
    out, fenced = [], False
    for line in text.splitlines():
        if FENCE.match(line.strip()) or line.strip().startswith("```"):
            fenced = not fenced
            continue
        out.append("" if fenced else line)
    return "\n".join(out)


def shell_blocks(text):
    """[(first line number, [lines])] of every ```sh / ```bash block."""
    blocks, current, start, lang = [], None, 0, None
    for number, line in enumerate(text.splitlines(), 1):
        stripped = line.strip()
        if current is None:
            m = FENCE.match(stripped)
            if m:
                lang, current, start = m.group(1), [], number + 1
        elif stripped.startswith("```"):
            if lang in ("sh", "bash", "shell"):
                blocks.append((start, current))
            current = None
        else:
            current.append(line)
    return blocks


def commands(lines):
    """Split a block into commands: `\\` continues a line, a here-document runs to its
    terminator. Comment-only and empty lines are dropped."""
    out, i = [], 0
    while i < len(lines):
        line = lines[i]
        i += 1
        if not line.strip() or line.strip().startswith("#"):
            continue
        command = [line]
        while command[-1].rstrip().endswith("\\") and i < len(lines):
            command.append(lines[i])
            i += 1
        m = HEREDOC.search(command[0])
        if m:
            while i < len(lines):
                command.append(lines[i])
                i += 1
                if lines[i - 1].strip() == m.group(1):
                    break
        out.append("\n".join(command))
    return out


def history_problems(text):
    problems = []
    for what, pattern in HISTORY.items():
        for m in pattern.finditer(text):
            line = text.count("\n", 0, m.start()) + 1
            problems.append(f"line {line}: {what}: {m.group(0)!r}")
    return problems


def nested_dir_names():
    """Folder names found below the top level (src/model, fmu/examples, ...)."""
    names = set()
    for dirpath, dirnames, _ in os.walk(ROOT):
        dirnames[:] = [d for d in dirnames if d not in SKIPPED_DIRS and not d.startswith(".")]
        if Path(dirpath) != ROOT:
            names.update(dirnames)
    return names - {p.name for p in ROOT.iterdir()}


def path_problems(page, text):
    """Links and backticked repository paths that name nothing in the repository."""
    problems = []
    top = {p.name for p in ROOT.iterdir()}
    nested = nested_dir_names()
    prose = strip_fences(text)
    for m in LINK.finditer(prose):
        target = m.group(1).split("#")[0]
        if not target or re.match(r"^[a-z]+:", target):
            continue
        resolved = (page.parent / target).resolve()
        if not resolved.is_relative_to(ROOT):
            problems.append(f"link {target}: outside the repository")
        elif not resolved.exists() and rel(resolved).split("/")[0] not in GENERATED:
            problems.append(f"link {target}: no such file")
    for m in re.finditer(r"`([^`\n]+)`", prose):
        token = m.group(1).strip()
        if not PATH_CHARS.match(token) or not (token.endswith("/") or HAS_EXTENSION.search(token)):
            continue
        if token.startswith("../") or token.startswith("/"):
            problems.append(f"`{token}`: outside the repository")
            continue
        token = token.removeprefix("./")
        first = token.split("/")[0]
        if first in GENERATED:
            continue
        if first in top:
            if not (ROOT / token).exists():
                problems.append(f"`{token}`: no such file in the repository")
        elif first in nested:
            problems.append(f"`{token}`: write the path from the repository root")
    return problems


@pytest.fixture(scope="module")
def cli():
    path = ROOT / "target" / "release" / "tensegrity-fmu"
    assert path.is_file(), "build the CLI first (tests/run.sh does: cargo build --release --workspace)"
    return path


def mirror(folder):
    """A folder whose entries are symlinks to the repository's, with a real out/."""
    for entry in ROOT.iterdir():
        if entry.name not in (".git", "out"):
            (folder / entry.name).symlink_to(entry)
    (folder / "out").mkdir()
    return folder


def test_readme_is_short():
    lines = README.read_text().count("\n")
    assert lines <= README_MAX_LINES, f"README.md has {lines} lines, at most {README_MAX_LINES}"


def test_the_guide_has_its_pages():
    for name in ("scenes", "fmu", "accuracy", "analysis", "sweeps", "benchmarks", "design"):
        assert (ROOT / "docs" / f"{name}.md").is_file(), f"docs/{name}.md is missing"
    assert (ROOT / "CHANGELOG.md").is_file()


@pytest.mark.parametrize("page", PAGES, ids=rel)
def test_no_development_history(page):
    problems = history_problems(page.read_text())
    assert not problems, f"{rel(page)} tells the development history:\n" + "\n".join(problems)


@pytest.mark.parametrize("page", LINKED, ids=rel)
def test_named_files_exist(page):
    problems = path_problems(page, page.read_text())
    assert not problems, f"{rel(page)} names files the repository does not have:\n" + "\n".join(problems)


def test_the_checks_catch_what_they_are_for():
    """Each check fails on the kind of text it exists for, and passes a plain guide."""
    diary = "In the seventh round (issue 14, commit a4af9e3) the step took 14.0 µs.\n"
    assert len(history_problems(diary)) == 3
    plain = "Round-off stays at 2.2e-16; `bench --rounds 5`; the shortest round trip; 0000000.\n"
    assert history_problems(plain) == []
    bad = ("See [notes](../shared/design/analysis.md), `src/analysis/tangent.rs`, "
           "`model/reactions/lanes.rs` and `../shared/design/analysis.md`.\n")
    assert len(path_problems(README, bad)) == 4
    good = ("See [fmu](docs/fmu.md), `src/scene/mod.rs`, `fmu/examples/`, `out/prism2.fmu`, "
            "`documentation/index.html` (in the FMU) and `node[i].x/y/z`.\n")
    assert path_problems(README, good) == []
    block = ["cat > out/a.py <<'PY'", "print(1)", "PY", "echo a \\", "  b  # not run: slow", "# note", ""]
    assert commands(block) == ["cat > out/a.py <<'PY'\nprint(1)\nPY", "echo a \\\n  b  # not run: slow"]


@pytest.mark.parametrize("page", PAGES, ids=rel)
def test_shell_commands_run(page, cli, tmp_path):
    to_run = [(start, c) for start, lines in shell_blocks(page.read_text()) for c in commands(lines)
              if not NOT_RUN.search(c.splitlines()[0])]
    if not to_run:
        pytest.skip(f"{rel(page)} has no command to run")
    folder = mirror(tmp_path)
    env = dict(os.environ, MPLBACKEND="Agg")
    failures = []
    for start, command in to_run:  # all of them: one report names every command that fails
        began = time.monotonic()
        try:
            done = subprocess.run(["bash", "-o", "pipefail", "-c", command], cwd=folder, env=env,
                                  capture_output=True, text=True, timeout=COMMAND_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            failures.append(f"block at line {start}: `{command}` took more than {COMMAND_TIMEOUT_S} s; "
                            "shorten it or mark it `# not run: REASON`")
            continue
        if done.returncode != 0:
            failures.append(f"block at line {start}: `{command}` exited with {done.returncode} after "
                            f"{time.monotonic() - began:.1f} s\n{done.stdout[-1500:]}\n{done.stderr[-1500:]}")
    assert not failures, f"{rel(page)}: {len(failures)} command(s) failed:\n" + "\n".join(failures)
