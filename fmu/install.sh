#!/usr/bin/env bash
# Installs what building an FMU and running it from Python need, nothing more: libclang
# (fmi-sys's bindgen, when the FMU binary is compiled) and a .venv with fmpy, numpy and
# matplotlib at the versions pinned in tests/requirements.txt. Used by fmu/quickstart.sh and
# tests/setup.sh; safe to run again.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

if ! command -v cargo >/dev/null; then
  echo "error: cargo not found: install Rust from https://rustup.rs, then run this again" >&2
  exit 2
fi

if ! dpkg -s libclang-dev >/dev/null 2>&1; then
  echo "== installing libclang-dev (needed by fmi-sys's bindgen)"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq libclang-dev >/dev/null
fi

if [ ! -x .venv/bin/python ]; then
  echo "== creating .venv"
  python3 -m venv .venv
fi
# One list of pins: the lines of tests/requirements.txt for these three packages.
pins=$(grep -E '^(fmpy|numpy|matplotlib)==' tests/requirements.txt | sed 's/[[:space:]]*#.*//')
[ "$(echo "$pins" | wc -l)" -eq 3 ] || { echo "error: tests/requirements.txt must pin fmpy, numpy and matplotlib" >&2; exit 2; }
# shellcheck disable=SC2086  # one argument per pin
.venv/bin/pip install -q --disable-pip-version-check $pins
