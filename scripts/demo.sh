#!/usr/bin/env bash
# The main demo: install what is missing, build, run the scene, draw its pictures.
# Output (CSV, PNG, VTK frames for ParaView) goes to ./out/demo.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out="$root/out/demo"
bash "$root/scripts/build.sh"
mkdir -p "$out"
"$root/build/examples_c/cantilever_sag" "$out" 300
/usr/bin/python3 "$root/scripts/plot_cantilever.py" "$out/cantilever.csv" "$out/cantilever.png"
echo "demo: pictures in $out (cantilever.png; cantilever_*.vtk open in ParaView)"
