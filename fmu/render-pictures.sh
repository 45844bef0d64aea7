#!/usr/bin/env bash
# Regenerates the pictures of the README and docs/ in fmu/pictures/ with `tensegrity-fmu render`:
# each built-in scene at its start, and the dropped icosahedron coming to rest.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
cargo build --release --workspace
render=./target/release/tensegrity-fmu
mkdir -p fmu/pictures
for scene in prism2 prism2-elastic icosahedron tower20; do
  "$render" render "$scene" -o "fmu/pictures/$scene.png"
done
"$render" render fmu/scenes/icosahedron-dropped.toml --time 3 --fps 15 \
  -o fmu/pictures/icosahedron-dropped.gif
"$render" render fmu/scenes/icosahedron-dropped.toml --at 0.3 --labels \
  -o fmu/pictures/icosahedron-dropped-impact.png
"$render" render fmu/scenes/icosahedron-step.toml --at 0.6 --contacts \
  -o fmu/pictures/icosahedron-step-contacts.png
