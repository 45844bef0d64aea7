#!/usr/bin/env bash
# Installs what the tests need on top of fmu/install.sh (libclang, .venv with fmpy, numpy,
# matplotlib): headless Chromium and its WebDriver (the HTML viewer's test) and every package
# of tests/requirements.txt (pytest, scipy, vtk, mujoco, libcosimpy, selenium, Dask, and
# cargo-zigbuild with zig for the portable FMU binary of fmu/build-binary.sh), and for the
# other platforms' binaries and their tests: the rustup targets, mingw-w64 and wine64 (win64),
# qemu-user and the arm64 C library (aarch64-linux), LLVM's binary tools (the Mach-O checks).
# Safe to run again; a target it cannot add is named and skipped.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash fmu/install.sh

# chromium: the HTML viewer's browser test; the rest: the other platforms' binaries.
apt_packages=(chromium chromium-driver mingw-w64 wine64 qemu-user libc6-arm64-cross
  libgcc-s1-arm64-cross llvm)
if ! dpkg -s "${apt_packages[@]}" >/dev/null 2>&1; then
  echo "== installing ${apt_packages[*]}"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  for p in "${apt_packages[@]}"; do
    dpkg -s "$p" >/dev/null 2>&1 && continue
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "$p" >/dev/null \
      || echo "warning: apt-get could not install $p; its platform's tests will fail" >&2
  done
fi

# The cross targets of fmu/build-binary.sh (win64, darwin64, aarch64-linux).
for t in x86_64-pc-windows-gnu x86_64-apple-darwin aarch64-apple-darwin aarch64-unknown-linux-gnu; do
  rustup target list --installed 2>/dev/null | grep -qx "$t" && continue
  echo "== rustup target add $t"
  rustup target add "$t" >/dev/null \
    || echo "warning: cannot add the rust target $t; fmu/build-binary.sh will skip it" >&2
done

.venv/bin/pip install -q --disable-pip-version-check -r tests/requirements.txt
