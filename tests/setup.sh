#!/usr/bin/env bash
# Installs what the tests need on top of fmu/install.sh (libclang, .venv with fmpy, numpy,
# matplotlib): headless Chromium and its WebDriver (the HTML viewer's test) and every package
# of tests/requirements.txt (pytest, scipy, vtk, mujoco, libcosimpy, selenium, Dask, and
# cargo-zigbuild with zig for the portable FMU binary of fmu/build-binary.sh). Safe to run again.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash fmu/install.sh

if ! dpkg -s chromium chromium-driver >/dev/null 2>&1; then
  echo "== installing chromium and chromium-driver (the HTML viewer's browser test)"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq chromium chromium-driver >/dev/null
fi

.venv/bin/pip install -q --disable-pip-version-check -r tests/requirements.txt
