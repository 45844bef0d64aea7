#!/usr/bin/env bash
# The project's one test command: set-up, formatting, lints, Rust tests, FMU build (every
# platform's binary too) and the fmpy suite (fmpy and libcosim). Every cargo step says why
# cargo rebuilt something it had built before (its fingerprint's "dirty" reason), so a second
# run with nothing changed shows at once if anything recompiles.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash tests/setup.sh
fingerprints=$(mktemp)
trap 'rm -f "$fingerprints"' EXIT

# Runs a cargo command with cargo's fingerprint log, shows its usual output, then lists each
# unit that was rebuilt although built before, with the reason cargo gives.
cargo_step() {
  echo "== $*"
  { RUST_BACKTRACE=0 CARGO_LOG=cargo::core::compiler::fingerprint=info "$@" 2>&1; } \
    | tee "$fingerprints" | awk '
        / INFO / { hide = 1; next }   # the fingerprint log and the tails of its messages
        hide && cause { cause = 0; next }
        hide && $0 == "" { next }
        hide && $0 == "Caused by:" { cause = 1; next }
        hide && /^ +[0-9]+: / { next }
        { hide = 0; print; fflush() }'
  bash tests/rebuilt.sh "$fingerprints"
}

echo "== cargo fmt --check"
cargo fmt --all -- --check
cargo_step cargo clippy --release --workspace --all-targets -- -D warnings
cargo_step cargo build --release --workspace                   # the CLI and the FMU binary
cargo_step bash fmu/build-binary.sh   # every platform's FMU binary (linux64 for glibc 2.28) that `build` packages
cargo_step cargo test --release --workspace
echo "== pytest (fmpy and libcosim against the built FMUs)"
.venv/bin/python -m pytest -q tests/fmpy
# The steps must leave each other's outputs fresh: a build now compiles nothing.
cargo_step cargo build --release --workspace
