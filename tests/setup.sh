#!/usr/bin/env bash
# Installs what the build and the tests need: libclang (bindgen in fmi-sys) and a Python
# venv with the packages in tests/requirements.txt (fmpy, libcosimpy, and cargo-zigbuild with
# zig for the portable FMU binary of fmu/build-binary.sh). Safe to run again.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

if ! dpkg -s libclang-dev >/dev/null 2>&1; then
  echo "== installing libclang-dev (needed by fmi-sys's bindgen)"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq libclang-dev >/dev/null
fi

# Headless Chromium and its WebDriver for tests/fmpy/test_html_viewer.py (the HTML viewer).
if ! dpkg -s chromium chromium-driver >/dev/null 2>&1; then
  echo "== installing chromium and chromium-driver (the HTML viewer's browser test)"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq chromium chromium-driver >/dev/null
fi

if [ ! -x .venv/bin/python ]; then
  echo "== creating .venv"
  python3 -m venv .venv
fi
.venv/bin/pip install -q --disable-pip-version-check -r tests/requirements.txt
