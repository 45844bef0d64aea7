#!/usr/bin/env bash
# The macOS linker of fmu/build-binary.sh, called by rustc through a link named `rust-lld`
# (so that rustc drives it as ld64.lld): rustup's rust-lld against the libSystem stubs that
# zig ships, since zig's own Mach-O linker has no export list. It keeps fmu/build.rs's list
# of exports (`-Wl,` options unwrapped) and drops rustc's, which names every `#[no_mangle]`
# function of every crate; the stubs' folder is $FMU_LD64_STUBS.
set -euo pipefail
lld="$(rustc --print sysroot)/lib/rustlib/$(rustc -vV | sed -n 's/^host: //p')/bin/rust-lld"
args=()
list=0
add() {
  if [ "$list" = 1 ]; then
    list=0
    if [[ $1 == *fmi2-exports.txt ]]; then args+=(-exported_symbols_list "$1"); fi
  elif [ "$1" = -exported_symbols_list ]; then
    list=1
  else
    args+=("$1")
  fi
}
for a in "$@"; do
  if [[ $a == -Wl,* ]]; then
    IFS=, read -ra parts <<<"${a#-Wl,}"
    for p in "${parts[@]}"; do add "$p"; done
  else
    add "$a"
  fi
done
[ "${args[0]:-}" = -flavor ] || args=(-flavor darwin "${args[@]}")
exec "$lld" "${args[@]}" -L "$FMU_LD64_STUBS"
