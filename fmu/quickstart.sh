#!/usr/bin/env bash
# From a fresh clone to a running FMU: installs what building and running an FMU from Python
# needs (fmu/install.sh), builds the CLI and the FMU binary, packages the default scene
# (prism2) as out/prism2.fmu, runs it with fmpy while a force pushes node 7, prints how node 7
# moves and renders the run as out/prism2-out.gif. Everything it writes is under out/
# (git-ignored). The test tools come on top with tests/setup.sh.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash fmu/install.sh
echo "== cargo build --release --workspace (the CLI and the FMU binary)"
cargo build --release --workspace   # the same invocation as tests/run.sh, which reuses it
mkdir -p out
fmu=$(./target/release/tensegrity-fmu build -o out/prism2.fmu)
echo "== built $fmu"
# A 10 N push on node 7 along x and y from 0.2 s to 0.4 s (fmpy: a repeated time is a step);
# the other inputs keep their start values.
cat > out/prism2-push.csv <<'CSV'
time,node[7].fx,node[7].fy
0,0,0
0.2,0,0
0.2,10,10
0.4,10,10
0.4,0,0
3,0,0
CSV
.venv/bin/fmpy simulate "$fmu" --input-file out/prism2-push.csv --stop-time 3 \
  --output-interval 0.02 --output-file out/prism2-out.csv 2>&1 | grep -v "missing input for variable" || true
echo "== wrote out/prism2-out.csv (every output, every 20 ms); node 7 moves:"
.venv/bin/python - <<'PY'
import csv
rows = list(csv.DictReader(open("out/prism2-out.csv")))
shown = rows[:: len(rows) // 6]
shown += [] if shown[-1] is rows[-1] else [rows[-1]]
for r in shown:
    print(f"t = {float(r['time']):4.2f} s  node[7].x = {float(r['node[7].x']):+.4f} m  "
          f"cable[1].tension = {float(r['cable[1].tension']):7.3f} N  energy = {float(r['energy.total']):.4f} J")
PY
./target/release/tensegrity-fmu render prism2 --csv out/prism2-out.csv -o out/prism2-out.gif --fps 25 >/dev/null
echo "== the run, rendered: out/prism2-out.gif"
echo "== next: .venv/bin/python fmu/examples/simulate.py out/prism2.fmu --input 'node[7].fx=2' --plot out/prism2.png"
