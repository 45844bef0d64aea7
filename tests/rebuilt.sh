#!/usr/bin/env bash
# Reads a log of cargo run with CARGO_LOG=cargo::core::compiler::fingerprint=info and prints,
# for each unit cargo rebuilt although it had built it before, the reason cargo gives
# ("dirty: ..."), skipping units rebuilt only because a dependency was newer. A unit whose
# output was last built over another build of a dependency (other features) is named: that
# is how two commands undo each other's work. Prints nothing when everything was fresh or
# built for the first time.
set -euo pipefail
awk '
  /fingerprint dirty for / {
    unit = $0
    sub(/.*fingerprint dirty for /, "", unit)
    sub(/ \(.*\)\//, " ", unit)
    sub(/\/TargetInner.*name: "/, " \"", unit)
    sub(/\/TargetInner.*lib_target\("/, " lib \"", unit)
    sub(/\/TargetInner.*custom_build_target\("/, " build script \"", unit)
    sub(/",.*/, "\"", unit)
    next
  }
  /     dirty: / && unit != "" {
    reason = $0
    sub(/.*     dirty: /, "", reason)
    if (match(reason, /stale: "[^"]*"/))  # a changed file: name it, not its timestamps
      reason = "changed " substr(reason, RSTART + 7, RLENGTH - 7)
    if (reason ~ /StaleDependency/)  # rebuilt or rerun by an earlier cargo command
      reason = "a dependency (or its build script'"'"'s output) is newer: an earlier command rebuilt it"
    if (reason ~ /^UnitDependencyInfoChanged/)  # the same output, last built over another build
      reason = "built against another build of a dependency: other features (a `cargo build -p` of one crate) or a dependency rebuilt"
    if (reason !~ /^FsStatusOutdated\(StaleDepFingerprint/ && !seen[unit reason]++) {
      if (!n++) print "!! cargo rebuilt what it had built before:"
      print "!!   " unit ": " substr(reason, 1, 400)
    }
    unit = ""
  }
' "$1"
