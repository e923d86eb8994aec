#!/bin/sh
# demo.sh — what `make demo` runs: the main job, `idmr reduce`, on the scene the repository
# ships (data/cornell/scene.xml), then a short render of the original and the reduced scene and
# their comparison, with the output under out/demo/.
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
echo "== idmr render: the original and the reduced scene, 8 iterations each"
bin/idmr render "$scene" -o "$out/original.exr" --iterations 8 --quiet
bin/idmr render "$out/reduced/scene.xml" -o "$out/reduced.exr" --iterations 8 --quiet
echo
echo "== idmr compare $out/reduced.exr $out/original.exr"
bin/idmr compare "$out/reduced.exr" "$out/original.exr" --diff "$out/difference.png"
echo
echo "demo: the reduced scene is $out/reduced/scene.xml (Mitsuba XML, meshes in $out/reduced/meshes/)"
echo "  $out/reduced/report.json          vertex counts per mesh, factors, timings, convergence"
echo "  $out/reduced/importance.png       what the camera sees, coloured by importance"
echo "  $out/reduced/importance/NAME.ply  each original mesh with per-vertex importance"
echo "  $out/original.png, $out/reduced.png, $out/difference.png   renders and their difference"
echo "  idmr info $out/reduced/scene.xml  to inspect it"
