#!/bin/sh
# demo.sh — what `make demo` runs: the main job on the scene the repository ships
# (data/cornell/scene.xml), with its output under out/demo/.
set -eu
cd "$(dirname "$0")/.."
scene=data/cornell/scene.xml
out=out/demo
mkdir -p "$out"
echo "== idmr devices"
bin/idmr devices
echo
echo "== idmr info $scene"
bin/idmr info "$scene"
bin/idmr info --json "$scene" > "$out/info.json.tmp"
mv "$out/info.json.tmp" "$out/info.json"
echo
echo "== idmr importance $scene -o $out/importance --iterations 20"
bin/idmr importance "$scene" -o "$out/importance" --iterations 20
echo
echo "demo: outputs in $out/:"
echo "  info.json                      the scene summary"
echo "  importance/importance.png      what the camera sees, coloured by importance"
echo "  importance/importance/*.ply    each mesh with per-vertex importance (any mesh viewer)"
echo "  importance/report.json         timings, per-mesh importance, convergence"
