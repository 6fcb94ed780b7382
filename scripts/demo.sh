#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The main demo: install what is missing, build, run the scenes, draw their pictures.
# Output (CSV, PNG, VTK frames for ParaView) goes to ./out/demo.
#   1. sphere_indent: a sphere presses into a soft cube fixed at its base, holds, and lets go
#      (MICA solver, tool contact); the force the tissue puts on the sphere over time and
#      against depth.
#      The cube itself at the sphere's deepest, cut through the sphere, coloured by von Mises stress.
#   2. cantilever_sag: a block clamped at one end sags under its own weight.
#   3. haptic_loop: a 60 Hz simulation thread and a 1 kHz servo thread.
#   4. nidus_press: the nidus (a lesion-like blob) pressed by a forceps tip, drawn as it is at the end.
#   5. incision: a blade cuts 3 cm into the cube while a hook draws one side back; the blade force
#      along the cut and the opened cut. The same into the nidus (incision --nidus).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out="$root/out/demo"
bash "$root/scripts/build.sh"
mkdir -p "$out"

"$root/build/examples_c/sphere_indent" "$out" 300
/usr/bin/python3 "$root/scripts/plot_sphere_indent.py" "$out/sphere_indent.csv" "$out/sphere_indent.png"
/usr/bin/python3 "$root/scripts/plot_tissue.py" "$out/sphere_indent.csv" "$out/sphere_indent_tissue.png" \
  --frames "$out/sphere_indent_{:04d}.vtk" --every 10 --cut --elev 20 --azim -70 \
  --title "A sphere indents a soft cube fixed at its base (libmica, MICA solver)"

"$root/build/examples_c/cantilever_sag" "$out" 300
/usr/bin/python3 "$root/scripts/plot_cantilever.py" "$out/cantilever.csv" "$out/cantilever.png"

# 3. haptic_loop: a 60 Hz simulation thread and a 1 kHz servo thread (simulated stylus unless a Touch is there).
"$root/build/examples_c/haptic_loop" "$out" 2
/usr/bin/python3 "$root/scripts/plot_haptic_loop.py" "$out/haptic_loop.csv" "$out/haptic_loop.png"

"$root/build/examples_c/nidus_press" "$out" "$root/data/nidus/nidus.msh" 60 4
/usr/bin/python3 "$root/scripts/plot_tissue.py" "$out/nidus_press.csv" "$out/nidus_press.png" \
  --vtk "$out/nidus_press.vtk" --elev 45 --azim -60 \
  --title "A forceps tip presses the nidus, held by its lowest fifth (libmica, MICA solver)"

"$root/build/examples_c/incision" "$out"
/usr/bin/python3 "$root/scripts/plot_incision.py" "$out/incision.csv" "$out/incision.vtk" "$out/incision.png" \
  --title "A blade cuts 3 cm into a soft cube while a hook draws one side back (libmica)"
(cd "$root" && build/examples_c/incision --nidus "$out/incision_nidus")
/usr/bin/python3 "$root/scripts/plot_incision.py" "$out/incision_nidus/incision.csv" "$out/incision_nidus/incision.vtk" \
  "$out/incision_nidus.png" --title "A blade cuts 3 cm into the nidus while a hook draws one side back (libmica)"

echo "demo: pictures in $out"
echo "  sphere_indent.png  (tool force over time and against depth; sphere_indent_*.vtk open in ParaView)"
echo "  cantilever.png     (tip deflection against Euler-Bernoulli; cantilever_*.vtk open in ParaView)"
echo "  haptic_loop.png    (raw and rendered device force at 1 kHz over a press and release)"
echo "  sphere_indent_tissue.png  (the cube at the sphere's deepest, cut through it, von Mises stress)"
echo "  nidus_press.png    (the nidus under the forceps tip, von Mises stress; nidus_press.vtk opens in ParaView)"
echo "  incision.png       (the blade force along a 3 cm incision, and the opened cut; incision.vtk opens in ParaView)"
echo "  incision_nidus.png (the same incision into the nidus; incision_nidus/ holds its CSV and VTK)"
