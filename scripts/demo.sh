#!/bin/sh
# demo.sh — what `make demo` runs: the main job, `idmr reduce`, on the scene the repository
# ships (data/cornell/scene.xml), with its output under out/demo/.
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
echo
echo "== idmr reduce $scene --target 0.1 --iterations 20 -o $out/reduced --force"
bin/idmr reduce "$scene" --target 0.1 --iterations 20 -o "$out/reduced" --force
echo
echo "demo: the reduced scene is $out/reduced/scene.xml (Mitsuba XML, meshes in $out/reduced/meshes/)"
echo "  $out/reduced/report.json          vertex counts per mesh, factors, timings, convergence"
echo "  $out/reduced/importance.png       what the camera sees, coloured by importance"
echo "  $out/reduced/importance/NAME.ply  each original mesh with per-vertex importance"
echo "  idmr info $out/reduced/scene.xml  to inspect it"
