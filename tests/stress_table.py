#!/usr/bin/env python3
"""Prints the stress suite's results (tests/stress.rs and tests/fmpy/test_stress.py) as
one Markdown table, sorted by case then layer; exits 1 if any row failed.

Reads the JSON-lines file named by $STRESS_RESULTS, default target/stress/results.jsonl
(one object per (case, method): layer, case, method, steps, max_length_error,
max_orthogonality_error, energy_drift, status, note).
"""

import json
import os
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
COLUMNS = ["case", "layer", "method", "steps", "max length error",
           "max orthogonality error", "energy drift", "status", "note"]


def sci(value):
    if value is None:
        return "–"
    try:
        return f"{float(value):.2e}"
    except (TypeError, ValueError):
        return str(value)


def cell(text):
    return str(text).replace("|", "\\|").replace("\n", " ")


def main():
    path = Path(os.environ.get("STRESS_RESULTS") or REPO / "target" / "stress" / "results.jsonl")
    if not path.is_file():
        print(f"no results file at {path}: run tests/stress.sh first", file=sys.stderr)
        return 1
    rows = []
    for number, line in enumerate(path.read_text().splitlines(), 1):
        if not line.strip():
            continue
        try:
            rows.append(json.loads(line))
        except json.JSONDecodeError as e:
            print(f"{path}:{number}: not JSON ({e})", file=sys.stderr)
            return 1
    rows.sort(key=lambda r: (str(r.get("case", "")), str(r.get("layer", ""))))
    print("| " + " | ".join(COLUMNS) + " |")
    print("|" + "|".join(["---"] * len(COLUMNS)) + "|")
    for r in rows:
        values = [
            r.get("case", ""), r.get("layer", ""), r.get("method", ""), r.get("steps", ""),
            sci(r.get("max_length_error")), sci(r.get("max_orthogonality_error")),
            sci(r.get("energy_drift")), r.get("status", ""), r.get("note", ""),
        ]
        print("| " + " | ".join(cell(v) for v in values) + " |")
    failed = [r for r in rows if r.get("status") == "fail"]
    counts = {s: sum(r.get("status") == s for r in rows) for s in ("pass", "rejected", "fail")}
    print(f"\n{len(rows)} rows: {counts['pass']} pass, {counts['rejected']} rejected, "
          f"{counts['fail']} fail")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
