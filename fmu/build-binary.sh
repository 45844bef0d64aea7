#!/usr/bin/env bash
# Builds the portable FMU binary: the `tensegrity-fmu-binary` cdylib linked by cargo-zigbuild
# against glibc 2.28 stubs (loads on RHEL 8/9, Ubuntu 20.04 and newer). cargo-zigbuild and
# zig (the `ziglang` package) come from tests/requirements.txt via tests/setup.sh. The result,
# target/x86_64-unknown-linux-gnu/release/libtensegrity_fmu_binary.so, is what
# `tensegrity-fmu build` packages whenever it was built from the same sources as the CLI.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
repo=$PWD
export PATH="$PWD/.venv/bin:$PATH"                       # cargo-zigbuild
export CARGO_ZIGBUILD_PYTHON_PATH="$PWD/.venv/bin/python" # zig as `python -m ziglang`
# Run from fmu/, not from the repository root: zig prints its include folders relative to
# the working directory when they lie below it (.venv/...), cargo-zigbuild hands them to
# bindgen (fmi-sys) as they are, and the build script, run elsewhere, then finds no stddef.h.
cd fmu
cargo zigbuild --release -p tensegrity-fmu-binary --target x86_64-unknown-linux-gnu.2.28 "$@"
echo "$repo/target/x86_64-unknown-linux-gnu/release/libtensegrity_fmu_binary.so"
