#!/usr/bin/env bash
# The project's one test command: set-up, formatting, lints, Rust tests, FMU build (the
# portable binary too) and the fmpy suite (fmpy and libcosim).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash tests/setup.sh

echo "== cargo fmt --check"
cargo fmt --all -- --check
echo "== cargo clippy -D warnings"
cargo clippy --release --workspace --all-targets -- -D warnings
echo "== cargo build (CLI and FMU binary)"
cargo build --release --workspace
echo "== portable FMU binary (cargo-zigbuild, glibc 2.28): what tensegrity-fmu build packages"
bash fmu/build-binary.sh
echo "== cargo test"
cargo test --release --workspace
echo "== pytest (fmpy and libcosim against the built FMUs)"
.venv/bin/python -m pytest -q tests/fmpy
