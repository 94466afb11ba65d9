#!/usr/bin/env bash
# demo.sh TESSERA OUTDIR: the main job on the bundled default. Generates the
# project's sample terrain (1025x1025, seed 1, 30 m spacing) as a 16-bit
# PNG and converts it into a mesh.
set -euo pipefail
tessera=$1 out=$2
mkdir -p "$out"
echo "== Tessera demo =="
"$tessera" generate --size 1025 --seed 1 --relief 1200 -o "$out/terrain.png"
"$tessera" info "$out/terrain.png"
"$tessera" mesh "$out/terrain.png" --dx 30 --normals -o "$out/terrain.glb" --stats "$out/terrain-mesh.json"
"$tessera" mesh "$out/terrain.png" --dx 30 --step 4 -o "$out/terrain-step4.obj" --stats "$out/terrain-step4.json"
echo
echo "checking the view-dependent tessellation (20 random cameras, 1 px at 1920x1080, 60 degrees)..."
status=0
"$tessera" check terrain "$out/terrain.png" --dx 30 --cameras 20 > "$out/check.txt" || status=$?
echo "  $(tail -n 1 "$out/check.txt")"
echo
echo "wrote:"
for f in terrain.png terrain.glb terrain-mesh.json terrain-step4.obj terrain-step4.json check.txt; do
  printf '  %-22s %s\n' "$f" "$(du -h "$out/$f" | cut -f1)"
done
echo "in $(cd "$out" && pwd)"
exit "$status"
