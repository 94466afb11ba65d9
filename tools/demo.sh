#!/usr/bin/env bash
# demo.sh TESSERA OUTDIR: the main job on the bundled default. Generates the
# project's sample terrain (1025x1025, seed 1, 30 m spacing) as a 16-bit
# PNG, converts it into a mesh within the default error bound (and a
# printable solid), checks the view-dependent tessellation, renders a
# short headless flyover, and tessellates the Utah teapot (from the shared
# data folder, TESSERA_DATA or ../shared/data, when it is there) to a .glb.
set -euo pipefail
tessera=$1 out=$2
mkdir -p "$out"
echo "== Tessera demo =="
"$tessera" generate --size 1025 --seed 1 --relief 1200 -o "$out/terrain.png"
"$tessera" info "$out/terrain.png"
# the fewest triangles within 1.2 m (0.1% of the relief: the default bound),
# with normals and images that light the coarse mesh with full detail
"$tessera" mesh "$out/terrain.png" --dx 30 --normals -o "$out/terrain.glb" --stats "$out/terrain-mesh.json" \
  --normal-map "$out/terrain-normals.png" --hillshade "$out/terrain-hillshade.png"
# a printable solid within 5 m, 100 m thick below the lowest point
"$tessera" mesh "$out/terrain.png" --dx 30 --max-error 5 --base 100 -o "$out/terrain-solid.stl" \
  --stats "$out/terrain-solid.json"
echo
echo "checking the view-dependent tessellation (20 random cameras, 1 px at 1920x1080, 60 degrees)..."
status=0
"$tessera" check terrain "$out/terrain.png" --dx 30 --cameras 20 > "$out/check.txt" || status=$?
echo "  $(tail -n 1 "$out/check.txt")"
echo
echo "rendering a flyover (90 frames at 960x540, headless Vulkan: lavapipe where there is no GPU)..."
if "$tessera" fly "$out/terrain.png" --dx 30 --headless --frames 90 --width 960 --height 540 --out "$out/flyover" \
     --stats "$out/flyover.json" --quiet; then
  echo "  frames: $(cd "$out/flyover" && pwd)/frame_00000.png ... frame_00089.png"
else
  echo "  the flyover failed (is a Vulkan driver installed? tools/install-deps.sh installs lavapipe)"
  status=1
fi
echo
data=${TESSERA_DATA:-../shared/data}
teapot=""
if [ -f "$data/patches/teapot.bpt" ]; then
  echo "tessellating the Utah teapot (32 bicubic patches) within 1e-3 of its size, crack-free..."
  "$tessera" patch "$data/patches/teapot.bpt" --normals -o "$out/teapot.glb" --stats "$out/teapot.json"
  teapot="teapot.glb teapot.json"
else
  echo "no $data/patches/teapot.bpt (set TESSERA_DATA to the shared data folder): the teapot is skipped"
fi
echo
echo "wrote:"
for f in terrain.png terrain.glb terrain-mesh.json terrain-normals.png terrain-hillshade.png terrain-solid.stl \
         terrain-solid.json check.txt flyover.json $teapot; do
  printf '  %-22s %s\n' "$f" "$(du -h "$out/$f" | cut -f1)"
done
echo "in $(cd "$out" && pwd)"
exit "$status"
