#!/usr/bin/env bash
# The project's one test command: set-up, formatting, lints, Rust tests, FMU build and
# the fmpy suite.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash tests/setup.sh

echo "== cargo fmt --check"
cargo fmt --all -- --check
echo "== cargo clippy -D warnings"
cargo clippy --release --workspace --all-targets -- -D warnings
echo "== cargo build (CLI and FMU binary)"
cargo build --release --workspace
echo "== cargo test"
cargo test --release --workspace
echo "== pytest (fmpy against the built FMUs)"
.venv/bin/python -m pytest -q tests/fmpy
