#!/usr/bin/env bash
# writers.sh TESSERA NODE_MODULES: every mesh format read back by an
# independent reader. assimp (Debian assimp-utils) must agree on vertex and
# face counts for OBJ, PLY and glb (faces for STL, which has no shared
# vertices); the Khronos glTF validator must report no errors and no
# warnings for .glb.
set -u
tessera=$1 modules=$2
dir=$(mktemp -d "${TMPDIR:-/tmp}/tsr-writers-XXXXXX")
trap 'rm -rf "$dir"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
command -v assimp >/dev/null || { echo "assimp not installed (tools/install-deps.sh)"; exit 1; }

"$tessera" generate --width 41 --height 29 --seed 3 -o "$dir/t.png" 2>/dev/null || fail generate
# a no-data hole, so unreferenced vertices and inner boundaries are covered
for n in "" "--normals"; do
  for step in "grid --step 1" "grid --step 3" delaunay quadtree; do
    for fmt in obj ply stl glb; do
      # shellcheck disable=SC2086
      "$tessera" mesh "$dir/t.png" -o "$dir/m.$fmt" --method $step $n --dx 10 --stats "$dir/s.json" --quiet || fail "mesh $fmt"
      want_v=$(grep -o '"vertices":[[:space:]]*[0-9]*' "$dir/s.json" | grep -o '[0-9]*$')
      want_f=$(grep -o '"triangles":[[:space:]]*[0-9]*' "$dir/s.json" | grep -o '[0-9]*$')
      info=$(assimp info "$dir/m.$fmt" 2>&1) || fail "assimp could not read $fmt: $info"
      got_v=$(printf '%s\n' "$info" | awk '/^Vertices:/ {print $2; exit}')
      got_f=$(printf '%s\n' "$info" | awk '/^Faces:/ {print $2; exit}')
      [ "$got_f" = "$want_f" ] || fail "$fmt step $step $n: assimp reads $got_f faces, wrote $want_f"
      if [ "$fmt" != stl ]; then
        [ "$got_v" = "$want_v" ] || fail "$fmt step $step $n: assimp reads $got_v vertices, wrote $want_v"
      fi
      echo "ok $fmt step $step $n: $got_v vertices, $got_f faces"
    done
    TSR_NODE_MODULES="$modules" node "$(dirname "$0")/gltf_validate.mjs" --strict "$dir/m.glb" || fail "glTF validator"
  done
done
