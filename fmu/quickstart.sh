#!/usr/bin/env bash
# Builds the default FMU (the embedded prism2 scene, with the portable glibc 2.28 binary)
# and runs it with fmpy.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash tests/setup.sh
cargo build --release --workspace
bash fmu/build-binary.sh   # the portable binary (glibc 2.28) that the FMU ships
fmu=$(./target/release/tensegrity-fmu build -o prism2.fmu)
echo "== built $fmu"
.venv/bin/fmpy info "$fmu" | sed -n "1,20p"
.venv/bin/fmpy simulate "$fmu" --output-file prism2-out.csv \
  --output-variables node[7].x node[7].z cable[1].tension constraint.length_error energy.total
echo "== wrote prism2-out.csv:"
head -3 prism2-out.csv; echo "..."; tail -1 prism2-out.csv
