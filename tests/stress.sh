#!/usr/bin/env bash
# The stress suite (issue 5) in one command: the library half (tests/stress.rs and
# tests/stress_contact.rs) and the FMU half driven by fmpy (tests/fmpy/test_stress.py), then one table of every case.
# Both halves append to $STRESS_RESULTS (default target/stress/results.jsonl). A failing
# half does not stop the other or the table; the exit status is non-zero if anything failed.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash tests/setup.sh

export STRESS_RESULTS="${STRESS_RESULTS:-$PWD/target/stress/results.jsonl}"
rm -f "$STRESS_RESULTS"
status=0

echo "== cargo build --release --workspace"
cargo build --release --workspace
echo "== library stress cases (cargo test --release --test stress --test stress_contact)"
cargo test --release --test stress --test stress_contact || status=1
if [ -f tests/fmpy/test_stress.py ]; then
  echo "== FMU stress cases (pytest tests/fmpy/test_stress.py)"
  .venv/bin/python -m pytest -q tests/fmpy/test_stress.py || status=1
fi
echo "== stress table"
.venv/bin/python tests/stress_table.py || status=1
exit "$status"
