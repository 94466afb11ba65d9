#!/usr/bin/env bash
# mesh_cli.sh TESSERA NODE_MODULES [DATA]: `tessera mesh` end to end.
#  - every method: the stats' measured max_error within --max-error (the
#    stats' figure is the independent measurement), the stats keys present;
#  - --no-flip (plain Delaunay): within the bound, not fewer triangles than
#    the default flips;
#  - --block / --threads: blocks of 32 cells within the bound, the file the
#    same byte for byte on 1 and 3 threads, the stats' block count; the
#    quadtree's file the same on 1 and 3 threads;
#  - budgets: --triangles / --vertices never exceeded, with --base counting
#    the walls and bottom; --base's bottom one plane for every window;
#  - --window: two adjacent windows of a real heightfield (or a generated
#    one without the data) write identical vertices on their shared column
#    and row, read from the OBJ files;
#  - --base: assimp reads the closed solid; --normal-map and --hillshade
#    images have the heightfield's size, or the window's (oiiotool); .glb
#    with normals passes the Khronos validator.
set -u
tessera=$1 modules=$2 data=${3:-}
dir=$(mktemp -d "${TMPDIR:-/tmp}/tsr-meshcli-XXXXXX")
trap 'rm -rf "$dir"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
json_num() { grep -o "\"$2\":[[:space:]]*[-0-9.e+]*" "$1" | head -1 | sed 's/.*:[[:space:]]*//'; }
le() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a <= b) }'; }

"$tessera" generate --width 130 --height 97 --seed 5 -o "$dir/t.png" 2>/dev/null || fail generate
# The same heights as raw float32 (from the grid mesh's vertices, exact),
# for the loops below: a raw input opens no image module, which costs
# every process that reads a PNG some 0.4 s (1.5 s under ASan). Its
# spacing is 1, the PNG's 30: the checks are vertical.
"$tessera" mesh "$dir/t.png" --method grid --dx 1 --dy 1 -o "$dir/grid.obj" --quiet || fail "grid for raw"
python3 - "$dir/grid.obj" "$dir/t.f32" <<'PY' || fail "raw heights"
import struct, sys
W, H = 130, 97
h = [0.0] * (W * H)
n = 0
for line in open(sys.argv[1]):
    if line.startswith('v '):
        x, y, z = (float(w) for w in line.split()[1:4])
        h[int(round(y)) * W + int(round(x))] = z
        n += 1
assert n == W * H
open(sys.argv[2], 'wb').write(struct.pack('<%df' % (W * H), *h))
PY
rm -f "$dir/grid.obj"
raw=("$dir/t.f32" --raw 130 97 f32)

# bound, per method, and the stats keys
for m in delaunay quadtree; do
  for e in 0.5 5 40; do
    "$tessera" mesh "${raw[@]}" --dx 10 --method $m --max-error $e -o "$dir/m.ply" --stats "$dir/s.json" --quiet \
      || fail "mesh $m $e"
    for k in vertices triangles max_error rms_error seconds peak_bytes; do
      [ -n "$(json_num "$dir/s.json" $k)" ] || fail "stats: no $k"
    done
    for k in '"method"' '"input"' '"width"' '"height"' '"min"' '"max"' '"nodata"'; do
      grep -q "$k" "$dir/s.json" || fail "stats: no $k"
    done
    got=$(json_num "$dir/s.json" max_error)
    le "$got" "$e" || fail "$m: measured max error $got > $e"
    echo "ok $m --max-error $e: measured $got, $(json_num "$dir/s.json" triangles) triangles"
  done
done

# no --max-error: the default bound, 0.1 % of the height range (the stats'
# input min and max, times --dz), the same for every method, reported as
# the bound asked for, and held
for m in delaunay quadtree; do
  "$tessera" mesh "${raw[@]}" --dz 2 --method $m -o "$dir/m.ply" --stats "$dir/s.json" --quiet || fail "mesh $m default"
  want=$(awk -v lo="$(json_num "$dir/s.json" min)" -v hi="$(json_num "$dir/s.json" max)" 'BEGIN { print (hi - lo) * 2e-3 }')
  req=$(json_num "$dir/s.json" requested_max_error) got=$(json_num "$dir/s.json" max_error)
  awk -v a="$req" -v b="$want" 'BEGIN { exit !(a - b < 1e-9 * b && b - a < 1e-9 * b) }' ||
    fail "$m: default bound reported as '$req', not 0.1 % of the range x dz = $want"
  le "$got" "$want" || fail "$m: measured max error $got > the default bound $want"
  echo "ok $m default bound $req held (measured $got)"
done

# --no-flip: plain greedy Delaunay, within the bound too, with more
# triangles than the default data-dependent flips; delaunay only
for e in 0.5 5; do
  "$tessera" mesh "${raw[@]}" --dx 10 --max-error $e -o "$dir/m.ply" --stats "$dir/f.json" --quiet || fail "mesh $e"
  "$tessera" mesh "${raw[@]}" --dx 10 --max-error $e --no-flip -o "$dir/m.ply" --stats "$dir/n.json" --quiet \
    || fail "mesh --no-flip $e"
  got=$(json_num "$dir/n.json" max_error)
  le "$got" "$e" || fail "--no-flip: measured max error $got > $e"
  tf=$(json_num "$dir/f.json" triangles) tn=$(json_num "$dir/n.json" triangles)
  [ "$(json_num "$dir/n.json" flips)" = 0 ] && [ "$(json_num "$dir/f.json" flips)" -gt 0 ] || fail "flips in the stats"
  [ "$tf" -le "$tn" ] || fail "--max-error $e: $tf triangles with flips, $tn with --no-flip"
  echo "ok --max-error $e: $tf triangles with flips, $tn with --no-flip (measured $got)"
done
"$tessera" mesh "$dir/t.png" --method quadtree --no-flip -o "$dir/m.ply" 2>/dev/null && fail "--no-flip with quadtree"

# blocks: the same mesh on any number of threads
for t in 1 3; do
  "$tessera" mesh "${raw[@]}" --dx 10 --max-error 2 --block 32 --threads $t -o "$dir/k$t.ply" \
    --stats "$dir/k$t.json" --quiet || fail "mesh --block 32 --threads $t"
  got=$(json_num "$dir/k$t.json" max_error)
  le "$got" 2 || fail "--block 32: measured max error $got > 2"
  [ "$(json_num "$dir/k$t.json" blocks)" = 15 ] || fail "--block 32: $(json_num "$dir/k$t.json" blocks) blocks, not 5 x 3 (129 x 96 cells)"
done
cmp -s "$dir/k1.ply" "$dir/k3.ply" || fail "--block 32: --threads 1 and 3 wrote different meshes"
echo "ok --block 32: the same mesh on 1 and 3 threads, 15 blocks (measured $got)"
"$tessera" mesh "$dir/t.png" --method grid --threads 2 -o "$dir/m.ply" 2>/dev/null && fail "--threads with grid"
"$tessera" mesh "$dir/t.png" --method quadtree --tile 4 --threads 2 -o "$dir/m.ply" 2>/dev/null &&
  fail "--threads with quadtree --tile"
"$tessera" mesh "$dir/t.png" --method delaunay --block 16 --method quadtree -o "$dir/m.ply" 2>/dev/null &&
  fail "--block with quadtree"
# the quadtree's nodes tested on several threads: the same mesh
for t in 1 3; do
  "$tessera" mesh "${raw[@]}" --dx 10 --method quadtree --max-error 0.5 --threads $t -o "$dir/q$t.ply" --quiet ||
    fail "mesh --method quadtree --threads $t"
done
cmp -s "$dir/q1.ply" "$dir/q3.ply" || fail "quadtree: --threads 1 and 3 wrote different meshes"
echo "ok quadtree: the same mesh on 1 and 3 threads"

# budgets
for m in delaunay quadtree grid; do
  for kind in triangles vertices; do
    for n in 50 777 5000; do
      if ! "$tessera" mesh "${raw[@]}" --method $m --$kind $n -o "$dir/b.obj" --stats "$dir/s.json" --quiet 2> "$dir/err"; then
        # only "below the coarsest mesh" may refuse a budget
        grep -q "budget" "$dir/err" || fail "$m --$kind $n: $(cat "$dir/err")"
        [ -e "$dir/b.obj" ] && fail "$m --$kind $n: output left behind"
        echo "ok $m --$kind $n refused: $(cat "$dir/err")"
        continue
      fi
      got=$(json_num "$dir/s.json" $kind)
      [ "$got" -le "$n" ] || fail "$m --$kind $n: $got"
      echo "ok $m --$kind $n: $got"
      rm -f "$dir/b.obj"
    done
  done
done

# budgets with --base cover the solid as written, walls and bottom too
# (counted from the file's own v and f lines; with --normals, the walls'
# and bottom's vertices are written apart from the top's); delaunay comes
# within 10 % of the budget
for m in delaunay quadtree grid; do
  for kind in triangles vertices; do
    for n in 100 3000; do
      for nrm in "" --normals; do
        "$tessera" mesh "${raw[@]}" --method $m --$kind $n --base 20 $nrm -o "$dir/b.obj" --quiet 2> "$dir/err" \
          || fail "$m --$kind $n --base $nrm: $(cat "$dir/err")"
        nv=$(grep -c '^v ' "$dir/b.obj") nf=$(grep -c '^f ' "$dir/b.obj")
        got=$nf; [ $kind = vertices ] && got=$nv
        [ "$got" -le "$n" ] || fail "$m --$kind $n --base $nrm: the file has $got $kind"
        [ $m != delaunay ] || [ $((got * 10)) -ge $((n * 9)) ] || fail "$m --$kind $n --base $nrm: only $got $kind"
      done
      echo "ok $m --$kind $n --base: $got $kind in the file"
    done
  done
done
# the bottom is the same plane for every method and window: DEPTH below
# the whole heightfield's lowest sample
bottoms=$(for args in "--method delaunay" "--method quadtree" "--method grid --step 3" "--window 0,0,60,50" \
  "--window 59,0,71,50" "--window 59,49,71,48"; do
  # shellcheck disable=SC2086
  "$tessera" mesh "${raw[@]}" $args --base 20 -o "$dir/w.obj" --quiet || fail "--base $args"
  awk '$1 == "v" && (n++ == 0 || $4 < lo) {lo = $4} END {print lo}' "$dir/w.obj"
done | sort -u)
[ "$(echo "$bottoms" | wc -l)" -eq 1 ] || fail "--base: bottoms at $(echo $bottoms)"
echo "ok --base: one bottom plane at z = $bottoms for every method and window"

# seams: adjacent windows share a column (vertical seam) or a row
if [ -n "$data" ] && [ -f "$data/terrain/bayhills-14-2625-6369-terrainrgb.png" ]; then
  in=$data/terrain/bayhills-14-2625-6369-terrainrgb.png dec="--decode terrain-rgb" W=512 H=512
else
  # (the generated PNG stores its 30 m spacing: placed 1 apart, as the
  # seams below are found by column and row)
  in=$dir/t.png dec="--dx 1 --dy 1" W=130 H=97
  echo "note: no shared data; seams on a generated heightfield"
fi
sx=$((W / 2 + 7)) sy=$((H / 2 - 3))
for m in delaunay quadtree grid; do
  opt="--max-error 1"
  [ $m = grid ] && opt=""
  # shellcheck disable=SC2086
  "$tessera" mesh "$in" $dec --method $m $opt --window 0,0,$((sx + 1)),$H -o "$dir/a.obj" --quiet || fail "window a"
  # shellcheck disable=SC2086
  "$tessera" mesh "$in" $dec --method $m $opt --window $sx,0,$((W - sx)),$H -o "$dir/b.obj" --quiet || fail "window b"
  # shellcheck disable=SC2086
  "$tessera" mesh "$in" $dec --method $m $opt --window 0,$sy,$W,$((H - sy)) -o "$dir/c.obj" --quiet || fail "window c"
  # shellcheck disable=SC2086
  "$tessera" mesh "$in" $dec --method $m $opt --window 0,0,$W,$((sy + 1)) -o "$dir/d.obj" --quiet || fail "window d"
  awk -v x=$sx '$1 == "v" && $2 == x' "$dir/a.obj" | sort > "$dir/a.seam"
  awk -v x=$sx '$1 == "v" && $2 == x' "$dir/b.obj" | sort > "$dir/b.seam"
  awk -v y=$sy '$1 == "v" && $3 == y' "$dir/c.obj" | sort > "$dir/c.seam"
  awk -v y=$sy '$1 == "v" && $3 == y' "$dir/d.obj" | sort > "$dir/d.seam"
  [ -s "$dir/a.seam" ] && cmp -s "$dir/a.seam" "$dir/b.seam" || fail "$m: vertical seam differs ($(wc -l < "$dir/a.seam") vs $(wc -l < "$dir/b.seam") vertices)"
  [ -s "$dir/c.seam" ] && cmp -s "$dir/c.seam" "$dir/d.seam" || fail "$m: horizontal seam differs"
  cmp -s "$dir/a.obj" "$dir/b.obj" && fail "$m: the windows' meshes are identical"
  echo "ok $m seams: $(wc -l < "$dir/a.seam") and $(wc -l < "$dir/c.seam") shared vertices"
done

# a closed solid, images, glb
"$tessera" mesh "$dir/t.png" --dx 10 --max-error 3 --base 50 -o "$dir/solid.ply" --stats "$dir/s.json" \
  --normal-map "$dir/n.png" --hillshade "$dir/h.tif" --quiet || fail "base"
if command -v assimp >/dev/null; then
  faces=$(assimp info "$dir/solid.ply" 2>&1 | awk '/^Faces:/ {print $2; exit}')
  [ "$faces" = "$(json_num "$dir/s.json" triangles)" ] || fail "assimp reads $faces faces of the solid"
fi
for img in n.png h.tif; do
  oiiotool --info "$dir/$img" | grep -q "130 x  *97" || fail "$img: $(oiiotool --info "$dir/$img")"
done
"$tessera" mesh "$dir/t.png" --dx 10 --normals -o "$dir/m.glb" --quiet || fail "glb"
if [ -f "$modules/gltf-validator/package.json" ]; then
  TSR_NODE_MODULES="$modules" node "$(dirname "$0")/gltf_validate.mjs" --strict "$dir/m.glb" || fail "glTF validator"
  echo "ok glb validated"
fi
# with a normal map the mesh gets texture coordinates that put each vertex
# at the centre of its sample's pixel: the map's normal there is the
# vertex's own (--normals, from the same gradients); v runs up in .obj
"$tessera" mesh "$dir/t.png" --dx 10 --window 10,20,30,40 --normals --normal-map "$dir/wn.png" -o "$dir/uv.obj" \
  --quiet || fail "uvs"
oiiotool --info -v --dumpdata "$dir/wn.png" > "$dir/wn.txt" || fail "uvs: reading the map"
python3 - "$dir/uv.obj" "$dir/wn.txt" 30 40 <<'PY' || fail "uvs"
import re, sys
obj, dump, W, H = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
px = {}
for line in open(dump):
    m = re.match(r"\s*Pixel \((\d+), (\d+)\): (\d+) (\d+) (\d+)", line)
    if m:
        x, y, r, g, b = map(int, m.groups())
        px[(x, y)] = (r, g, b)
assert len(px) == W * H, len(px)
vt, vn = [], []
for line in open(obj):
    f = line.split()
    if f and f[0] == "vt":
        vt.append((float(f[1]), float(f[2])))
    if f and f[0] == "vn":
        vn.append(tuple(map(float, f[1:4])))
assert vt and len(vt) == len(vn), (len(vt), len(vn))
worst = 0
for (u, v), n in zip(vt, vn):
    fx, fy = u * W, (1 - v) * H  # OBJ: v up from the image's bottom
    i, j = int(fx), int(fy)
    assert abs(fx - i - 0.5) < 1e-3 and abs(fy - j - 0.5) < 1e-3, (u, v)  # a pixel's centre
    r, g, b = px[(i, j)]
    m = ((r / 255) * 2 - 1, -((g / 255) * 2 - 1), (b / 255) * 2 - 1)  # green is north, -y
    worst = max(worst, max(abs(a - c) for a, c in zip(m, n)))
assert worst < 0.01, worst
print("ok %d vertices: uv at pixel centres, the map's normal there within %.4f of the vertex's" % (len(vt), worst))
PY
"$tessera" mesh "$dir/t.png" --dx 10 --hillshade "$dir/wh.png" -o "$dir/uv.glb" --quiet || fail "glb uvs"
grep -aq TEXCOORD_0 "$dir/uv.glb" || fail "glb with --hillshade: no TEXCOORD_0"
if [ -f "$modules/gltf-validator/package.json" ]; then
  TSR_NODE_MODULES="$modules" node "$(dirname "$0")/gltf_validate.mjs" --strict "$dir/uv.glb" ||
    fail "glTF validator (uvs)"
  echo "ok glb with texture coordinates validated"
fi
# with --normals the solid's walls and bottom shade flat: a bottom corner's
# normal is -z, a wall corner's horizontal, none shared with the top's
"$tessera" mesh "$dir/t.png" --dx 10 --max-error 3 --base 50 --normals -o "$dir/solid_n.obj" --quiet || fail "base normals"
bad=$(awk '$1 == "v" {z[++n] = $4; if (n == 1 || $4 < lo) lo = $4}
  $1 == "vn" {nz[++m] = $4}
  $1 == "f" {k = 0; for (i = 2; i <= 4; i++) { split($i, a, "/"); v[i] = a[1]; k += z[a[1]] == lo }
    if (k == 3) { for (i = 2; i <= 4; i++) if (nz[v[i]] != -1) b++ }
    else if (k > 0) { for (i = 2; i <= 4; i++) if (nz[v[i]] > 1e-6 || nz[v[i]] < -1e-6) b++ } }
  END {print b + 0}' "$dir/solid_n.obj")
[ "$bad" -eq 0 ] || fail "--base --normals: $bad wall or bottom corners not flat-shaded"
"$tessera" mesh "$dir/t.png" --window 5,6,40,30 --max-error 3 --dz 0.5 -o "$dir/w.ply" --normal-map "$dir/wn.png" \
  --hillshade "$dir/wh.png" --stats "$dir/w.json" --quiet || fail "window images"
# the stats give dz and the window's own range (against the grid mesh's
# vertices: every sample of the window, z = sample * dz)
"$tessera" mesh "$dir/t.png" --window 5,6,40,30 --method grid -o "$dir/wg.obj" --quiet || fail "window grid"
range=$(awk '$1 == "v" {if (n++ == 0 || $4 < lo) lo = $4; if (n == 1 || $4 > hi) hi = $4} END {print lo, hi}' \
  "$dir/wg.obj")
[ "$(json_num "$dir/w.json" dz)" = 0.5 ] || fail "stats: dz $(json_num "$dir/w.json" dz)"
wmin=$(sed -n '/"window"/,/}/p' "$dir/w.json" | grep -o '"min":[[:space:]]*[-0-9.e+]*' | sed 's/.*:[[:space:]]*//')
wmax=$(sed -n '/"window"/,/}/p' "$dir/w.json" | grep -o '"max":[[:space:]]*[-0-9.e+]*' | sed 's/.*:[[:space:]]*//')
awk -v r="$range" -v a="$wmin" -v b="$wmax" 'function off(x, y) { return x > y ? x - y : y - x }
  BEGIN { split(r, z, " "); exit !(off(z[1], a) <= 1e-6 * off(a, 0) && off(z[2], b) <= 1e-6 * off(b, 0)) }' \
  || fail "stats: window range $wmin..$wmax, the window's samples $range"
for img in wn.png wh.png; do
  oiiotool --info "$dir/$img" | grep -q "40 x  *30" || fail "--window: $img: $(oiiotool --info "$dir/$img")"
done
echo "ok solid, images"

# over_limit WHAT FILE INPUT ARGS...: meshes INPUT with -o full.ply and
# --normal-map full.png under an 8 KiB file size limit (as a full disk);
# it must fail naming FILE and leave neither output nor a temporary
over_limit() {
  local what=$1 file=$2 input=$3
  shift 3
  rm -f "$dir"/full.*
  if (trap '' XFSZ; ulimit -f 8; "$tessera" mesh "$input" "$@" --method grid -o "$dir/full.ply" \
      --normal-map "$dir/full.png" --quiet) 2> "$dir/full.err"; then
    fail "$what: written over the file size limit: $(ls -l "$dir"/full.* 2>&1)"
  fi
  grep -q "$file: write failed" "$dir/full.err" || fail "$what: no error naming $file: $(cat "$dir/full.err")"
  local left
  left=$(ls -A "$dir" | grep -c "full\.\(png\|ply\)\|tsr-tmp" || true)
  [ "$left" -eq 0 ] || fail "$what: files left after the failed write: $(ls -A "$dir")"
}
# the image does not fit (the PNG writer did not check its writes)
over_limit "normal map" full.png "$dir/t.png" --dx 10
echo "ok an image over the file size limit fails cleanly"
# the mesh does not fit after a (small, flat) normal map was written: the
# map is removed too, no partial set of outputs left (it was left)
python3 -c "import struct; open('$dir/flat.f32', 'wb').write(struct.pack('<4225f', *([5.0] * 4225)))"
over_limit "mesh" full.ply "$dir/flat.f32" --raw 65 65 f32
echo "ok a mesh over the file size limit removes the normal map written before it"

# --north-up: every vertex (x, y, z) becomes (x, -y, z) with its normal's y
# negated, every triangle still faces up (+z, by the cross product of its
# edges), and a solid stays closed with its volume positive (outward)
for up in "" --north-up; do
  # shellcheck disable=SC2086
  "$tessera" mesh "${raw[@]}" --dx 10 --dy 7 --max-error 3 --normals -o "$dir/up$up.obj" $up --quiet || fail "mesh $up"
  # shellcheck disable=SC2086
  "$tessera" mesh "${raw[@]}" --dx 10 --max-error 3 --base 50 -o "$dir/solid$up.obj" $up --quiet || fail "solid $up"
done
awk '$1 == "v" {print $2, -$3, $4} $1 == "vn" {print "n", $2, -$3, $4}' "$dir/up.obj" > "$dir/up.mirror"
awk '$1 == "v" {print $2, $3 + 0, $4} $1 == "vn" {print "n", $2, $3, $4}' "$dir/up--north-up.obj" > "$dir/north.list"
awk '{ for (i = 1; i <= NF; i++) $i = $i + 0 } 1' "$dir/up.mirror" > "$dir/up.mirror2"
awk '{ for (i = 1; i <= NF; i++) $i = $i + 0 } 1' "$dir/north.list" > "$dir/north.list2"
cmp -s "$dir/up.mirror2" "$dir/north.list2" || fail "--north-up: vertices are not the mirror of the default's"
facing='$1 == "v" {x[++n] = $2; y[n] = $3; z[n] = $4}
  $1 == "f" {split($2, a, "/"); split($3, b, "/"); split($4, c, "/");
    ux = x[b[1]] - x[a[1]]; uy = y[b[1]] - y[a[1]]; uz = z[b[1]] - z[a[1]];
    vx = x[c[1]] - x[a[1]]; vy = y[c[1]] - y[a[1]]; vz = z[c[1]] - z[a[1]];
    nz = ux * vy - uy * vx; if (nz <= 0) down++; faces++;
    vol += x[a[1]] * (y[b[1]] * z[c[1]] - z[b[1]] * y[c[1]]) - y[a[1]] * (x[b[1]] * z[c[1]] - z[b[1]] * x[c[1]]) + z[a[1]] * (x[b[1]] * y[c[1]] - y[b[1]] * x[c[1]])}
  END {print faces + 0, down + 0, vol / 6}'
for up in "" --north-up; do
  read -r faces down vol < <(awk "$facing" "$dir/up$up.obj")
  [ "$faces" -gt 0 ] && [ "$down" -eq 0 ] || fail "mesh $up: $down of $faces triangles do not face up"
  read -r faces down vol < <(awk "$facing" "$dir/solid$up.obj")
  awk -v v="$vol" 'BEGIN { exit !(v > 0) }' || fail "solid $up: signed volume $vol (inward-facing)"
  echo "ok ${up:-default} orientation: $faces solid triangles, volume $vol"
done

# Interrupted while an image is written (SIGINT as Ctrl-C sends it, the
# moment the normal map's or the hillshade's temporary appears): no hidden
# temporary is left, nor the normal map written before the hillshade. The
# images' temporaries are the I/O module's, which the command's signal
# handler did not know of (a GIS audit found .k_n.tsr-tmp-*.png left
# behind, and k_n.png without the rest).
"$tessera" generate --size 1025 --seed 3 -o "$dir/big.tif" --quiet 2>/dev/null ||
  "$tessera" generate --size 1025 --seed 3 -o "$dir/big.tif" > /dev/null || fail "generate big.tif"
for img in n h; do
  mkdir -p "$dir/intr_$img"
  python3 - "$dir/intr_$img" ".k_$img.tsr-tmp" "$tessera" mesh "$dir/big.tif" --max-error 0.5 -o "$dir/intr_$img/k.ply" \
    --normal-map "$dir/intr_$img/k_n.png" --hillshade "$dir/intr_$img/k_h.png" --quiet <<'PY' || fail "interrupted while writing k_$img.png"
import os, signal, subprocess, sys, time
folder, pat, cmd = sys.argv[1], sys.argv[2], sys.argv[3:]
p = subprocess.Popen(cmd, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
def size(f):
    try:
        return os.path.getsize(f)
    except OSError:
        return 0
sent = False
while p.poll() is None:
    # (a temporary with bytes in it: the image being written, not the
    # empty one the output check at the start makes and removes)
    if any(f.startswith(pat) and size(os.path.join(folder, f)) > 0 for f in os.listdir(folder)):
        p.send_signal(signal.SIGINT)
        sent = True
        break
    time.sleep(0.002)
rc = p.wait()
left = os.listdir(folder)  # no temporary, and no part of the set (the normal map before the hillshade)
if not sent:
    sys.exit("the temporary %s* was never seen (rc %d)" % (pat, rc))
if rc != -signal.SIGINT or left:
    sys.exit("rc %d, left behind: %s" % (rc, left))
print("ok interrupted while %s* was written: rc %d, nothing left" % (pat, rc))
PY
done

# A file naming no no-data value whose lowest samples are -9999 far below
# the rest: a warning names the value and --nodata; with --nodata -9999,
# none, and those samples are holes (fewer triangles)
python3 - "$dir/sent.f32" <<'PY' || fail "write sent.f32"
import math, struct, sys
w = h = 40
v = [(-9999.0 if (c - 20) ** 2 + (r - 20) ** 2 < 36 else 100 + 10 * math.sin(c / 5.0) + r * 0.3)
     for r in range(h) for c in range(w)]
open(sys.argv[1], "wb").write(struct.pack("<%df" % len(v), *v))
PY
"$tessera" mesh "$dir/sent.f32" --raw 40 40 f32 -o "$dir/sent.obj" --quiet 2> "$dir/sent.err" || fail "mesh sent.f32"
grep -q "warning: .*sent.f32: [0-9]* samples hold -9999, .*--nodata -9999" "$dir/sent.err" ||
  fail "no sentinel warning: $(cat "$dir/sent.err")"
"$tessera" mesh "$dir/sent.f32" --raw 40 40 f32 --nodata -9999 -o "$dir/sent2.obj" --quiet 2> "$dir/sent2.err" ||
  fail "mesh sent.f32 --nodata"
[ ! -s "$dir/sent2.err" ] || fail "a warning with --nodata given: $(cat "$dir/sent2.err")"
"$tessera" mesh "${raw[@]}" -o "$dir/nosent.obj" --quiet 2> "$dir/nosent.err" || fail "mesh without sentinel"
[ ! -s "$dir/nosent.err" ] || fail "a warning on an ordinary file: $(cat "$dir/nosent.err")"
echo "ok a -9999 the file does not name is warned of: $(head -c 90 "$dir/sent.err")..."
