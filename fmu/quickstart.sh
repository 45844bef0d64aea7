#!/usr/bin/env bash
# Builds the default FMU (the embedded prism2 scene, with the portable glibc 2.28 binary),
# runs it with fmpy while a force input pushes the top, and renders the run.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash tests/setup.sh
cargo build --release --workspace
bash fmu/build-binary.sh   # the portable binary (glibc 2.28) that the FMU ships
fmu=$(./target/release/tensegrity-fmu build -o prism2.fmu)
echo "== built $fmu"
.venv/bin/fmpy info "$fmu" | sed -n "1,20p"
# A 10 N push on node 7 along x and y from 0.2 s to 0.4 s (fmpy: a repeated time is a step);
# the other inputs keep their start values.
cat > prism2-push.csv <<'CSV'
time,node[7].fx,node[7].fy
0,0,0
0.2,0,0
0.2,10,10
0.4,10,10
0.4,0,0
3,0,0
CSV
.venv/bin/fmpy simulate "$fmu" --input-file prism2-push.csv --stop-time 3 \
  --output-interval 0.02 --output-file prism2-out.csv 2>&1 | grep -v "missing input for variable" || true
echo "== wrote prism2-out.csv (every output, every 20 ms); node 7 moves:"
.venv/bin/python - <<'PY'
import csv
rows = list(csv.DictReader(open("prism2-out.csv")))
shown = rows[:: len(rows) // 6]
shown += [] if shown[-1] is rows[-1] else [rows[-1]]
for r in shown:
    print(f"t = {float(r['time']):4.2f} s  node[7].x = {float(r['node[7].x']):+.4f} m  "
          f"cable[1].tension = {float(r['cable[1].tension']):7.3f} N  energy = {float(r['energy.total']):.4f} J")
PY
./target/release/tensegrity-fmu render prism2 --csv prism2-out.csv -o prism2-out.gif --fps 25 >/dev/null
./target/release/tensegrity-fmu render prism2 --csv prism2-out.csv -o prism2-out.html >/dev/null
echo "== the run, rendered: prism2-out.gif (animation) and prism2-out.html (open it in a browser: orbit, scrub, hover)"
