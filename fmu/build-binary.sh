#!/usr/bin/env bash
# Builds the FMU binary (the `tensegrity-fmu-binary` cdylib) for every platform with
# cargo-zigbuild, in one release build per target:
#   linux64        x86_64-unknown-linux-gnu, against glibc 2.28 stubs (RHEL 8, Ubuntu 20.04)
#   win64          x86_64-pc-windows-gnu, MinGW runtime linked in statically
#   darwin64       x86_64 + arm64 joined into one universal dylib (cargo-zigbuild's
#                  universal2-apple-darwin), macOS 10.12 / 11 and newer, linked by
#                  fmu/ld64.sh (rust-lld with an export list, which zig's linker lacks)
#   aarch64-linux  aarch64-unknown-linux-gnu, glibc 2.28
# `--linux64-only` builds the first alone (the quickstart); other arguments go to cargo.
# A platform whose rustup target is missing is skipped with a note (tests/setup.sh adds
# them). cargo-zigbuild and zig (the `ziglang` package) come from tests/requirements.txt.
# `tensegrity-fmu build` packages each binary that was built from the same sources as it.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
repo=$PWD
export PATH="$PWD/.venv/bin:$PATH"                       # cargo-zigbuild
export CARGO_ZIGBUILD_PYTHON_PATH="$PWD/.venv/bin/python" # zig as `python -m ziglang`

all=(linux64 win64 darwin64 aarch64-linux)
platforms=("${all[@]}")
args=()
for a in "$@"; do
  if [ "$a" = --linux64-only ]; then platforms=(linux64); else args+=("$a"); fi
done

# platform -> cargo-zigbuild target, rustup targets it needs, the file it writes
target_of() {
  case $1 in
    linux64) echo x86_64-unknown-linux-gnu.2.28 ;;
    win64) echo x86_64-pc-windows-gnu ;;
    darwin64) echo universal2-apple-darwin ;;
    aarch64-linux) echo aarch64-unknown-linux-gnu.2.28 ;;
  esac
}
rustup_targets_of() {
  case $1 in
    darwin64) echo x86_64-apple-darwin aarch64-apple-darwin ;;
    *) target_of "$1" | sed 's/\.2\.28$//' ;;
  esac
}
file_of() {
  case $1 in
    linux64) echo x86_64-unknown-linux-gnu/release/libtensegrity_fmu_binary.so ;;
    win64) echo x86_64-pc-windows-gnu/release/tensegrity_fmu_binary.dll ;;
    darwin64) echo universal2-apple-darwin/release/libtensegrity_fmu_binary.dylib ;;
    aarch64-linux) echo aarch64-unknown-linux-gnu/release/libtensegrity_fmu_binary.so ;;
  esac
}

installed=$(rustup target list --installed 2>/dev/null || rustc --print target-list)
built=()
targets=()
for p in "${platforms[@]}"; do
  missing=""
  for t in $(rustup_targets_of "$p"); do
    grep -qx "$t" <<<"$installed" || missing+=" $t"
  done
  if [ -n "$missing" ]; then
    echo "note: skipping $p: rustup target$missing not installed (bash tests/setup.sh adds it)" >&2
    continue
  fi
  targets+=(--target "$(target_of "$p")")
  built+=("$p")
done

# macOS: rustc drives fmu/ld64.sh as ld64.lld through a link named rust-lld, against zig's
# libSystem stubs (libc, libm and libiconv resolve to it too; nothing of iconv is used).
config=()
if [[ " ${built[*]} " == *" darwin64 "* ]]; then
  stubs=$repo/target/ld64
  zig_darwin=$(.venv/bin/python -c 'import ziglang, os; print(os.path.dirname(ziglang.__file__))')/lib/libc/darwin
  mkdir -p "$stubs"
  ln -sf "$repo/fmu/ld64.sh" "$stubs/rust-lld"
  for l in System c m iconv; do ln -sf "$zig_darwin/libSystem.tbd" "$stubs/lib$l.tbd"; done
  export FMU_LD64_STUBS=$stubs
  for t in x86_64-apple-darwin aarch64-apple-darwin; do
    config+=(--config "target.$t.linker='$stubs/rust-lld'")
  done
fi

# Run from fmu/, not from the repository root: zig prints its include folders relative to
# the working directory when they lie below it (.venv/...), cargo-zigbuild hands them to
# bindgen (fmi-sys) as they are, and the build script, run elsewhere, then finds no stddef.h.
cd fmu
cargo zigbuild --release -p tensegrity-fmu-binary "${targets[@]}" "${config[@]}" "${args[@]}"
for p in "${built[@]}"; do
  echo "$repo/target/$(file_of "$p")"
done
