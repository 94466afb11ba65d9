#!/usr/bin/env bash
# triangulate_cli.sh MODE TESSERA [DATA]: `tessera triangulate` end to end.
#   data DATA   every polygon of DATA/polygons (cdt/*.txt, earcut/*.json but
#               expected.json, which is not a polygon and must be refused
#               cleanly) through --check with both methods, and with -q 25
#               for the Delaunay method; skipped (77) without the data.
#   roundtrip   Triangle's .node/.ele/.poly written and read back by our
#               reader; .obj and .ply read back by assimp.
# The check (tsr_triangulation_check) is the oracle: it is independent of
# the triangulator (exact predicates, expected area and Euler characteristic
# from the input alone).
set -u
mode=$1 tessera=$2 data=${3:-}
dir=$(mktemp -d "${TMPDIR:-/tmp}/tsr-tricli-XXXXXX")
trap 'rm -rf "$dir"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

# json_num FILE KEY: the first number after "KEY": in a JSON file
json_num() { grep -o "\"$2\":[[:space:]]*[-0-9.e+]*" "$1" | head -1 | sed 's/.*:[[:space:]]*//'; }

case "$mode" in
data)
  if [ -z "$data" ] || [ ! -d "$data/polygons/cdt" ] || [ ! -d "$data/polygons/earcut" ]; then
    echo "skipped: no shared data (polygons) at '${data}'"
    exit 77
  fi
  # one run: FILE OPTS -> "ok ..." or "FAIL ..." in the file RESULT
  one() {
    local f=$1 opts=$2 result=$3 name rc why
    name=$(basename "$f")
    # shellcheck disable=SC2086
    timeout 600 "$tessera" triangulate "$f" --check --quiet $opts > "$result.out" 2> "$result.err"
    rc=$?
    if [ $rc -eq 0 ] && grep -q "^check: PASS" "$result.out"; then
      echo "ok   $name [$opts]" > "$result"
    else
      why=$(grep "^check: FAIL" "$result.out" | head -1)
      [ -n "$why" ] || why="exit $rc: $(head -c 400 "$result.err")"
      echo "FAIL $name [$opts]: $why" > "$result"
    fi
  }
  jobs_max=$(nproc 2>/dev/null || echo 2)
  runs=0
  for f in "$data"/polygons/cdt/*.txt "$data"/polygons/earcut/*.json; do
    name=$(basename "$f")
    if [ "$name" = expected.json ]; then
      runs=$((runs + 1))
      "$tessera" triangulate "$f" --check > "$dir/exp.out" 2> "$dir/exp.err"
      rc=$?
      if [ $rc -ne 1 ] || [ "$(wc -l < "$dir/exp.err")" -ne 1 ] || ! grep -q "not a polygon" "$dir/exp.err" ||
         [ -s "$dir/exp.out" ]; then
        printf 'FAIL expected.json: exit %s, stderr: %s\n' "$rc" "$(cat "$dir/exp.err")" > "$dir/r.$(printf %04d $runs)"
      else
        printf 'ok   expected.json refused: %s\n' "$(cat "$dir/exp.err")" > "$dir/r.$(printf %04d $runs)"
      fi
      continue
    fi
    for opts in "--method delaunay" "--method quadtree" "--method delaunay -q 25"; do
      runs=$((runs + 1))
      while [ "$(jobs -rp | wc -l)" -ge "$jobs_max" ]; do wait -n; done
      one "$f" "$opts" "$dir/r.$(printf %04d $runs)" &
    done
  done
  wait
  cat "$dir"/r.[0-9][0-9][0-9][0-9]
  failed=$(cat "$dir"/r.[0-9][0-9][0-9][0-9] | grep -c '^FAIL')
  echo "$failed of $runs runs failed"
  [ "$failed" -eq 0 ] || exit 1 ;;
roundtrip)
  command -v assimp > /dev/null || { echo "assimp not installed (tools/install-deps.sh)"; exit 1; }
  # a 10 x 10 square with a 4 x 4 hole (hole seed), an inner segment
  # crossing nothing, and a point on the outer boundary
  cat > "$dir/in.poly" <<'EOF'
# square with a hole
9 2 0 1
1 0 0 1
2 10 0 1
3 10 10 1
4 0 10 1
5 3 3 2
6 7 3 2
7 7 7 2
8 3 7 2
9 5 0 1
10 1
1 1 9 1
2 9 2 1
3 2 3 1
4 3 4 1
5 4 1 1
6 5 6 2
7 6 7 2
8 7 8 2
9 8 5 2
10 3 6 0
1
1 5 5
EOF
  "$tessera" triangulate "$dir/in.poly" -o "$dir/out.ele" --check --json > "$dir/s.json" || fail "triangulate: $(cat "$dir/s.json")"
  for ext in node ele poly; do [ -s "$dir/out.$ext" ] || fail "no out.$ext"; done
  ls -A "$dir" | grep -q tsr-tmp && fail "temporary files left: $(ls -A "$dir")"
  nv=$(json_num "$dir/s.json" vertices) nt=$(json_num "$dir/s.json" triangles)
  ne=$(json_num "$dir/s.json" constrained_edges)
  area=$(json_num "$dir/s.json" area)
  grep -q '"ok":[[:space:]]*true' "$dir/s.json" || fail "check failed: $(grep first_problem "$dir/s.json")"
  awk -v a="$area" 'BEGIN { exit !(a > 83.999999 && a < 84.000001) }' || fail "area $area, not 84"
  # the files' headers
  [ "$(grep -v '^#' "$dir/out.node" | head -1 | awk '{print $1}')" = "$nv" ] || fail ".node count"
  [ "$(grep -v '^#' "$dir/out.ele" | head -1 | awk '{print $1}')" = "$nt" ] || fail ".ele count"
  [ "$(grep -v '^#' "$dir/out.ele" | grep -c .)" -eq $((nt + 1)) ] || fail ".ele lines"
  # the input points keep their numbers (as Triangle keeps them): out.node's
  # points 1..9 are in.poly's, and the Steiner points follow
  [ "$(grep -v '^#' "$dir/out.node" | sed -n 2,10p | awk '{print $1, $2 + 0, $3 + 0}')" = \
    "$(grep -v '^#' "$dir/in.poly" | sed -n 2,10p | awk '{print $1, $2 + 0, $3 + 0}')" ] ||
    fail "out.node does not keep the input numbers: $(sed -n 1,12p "$dir/out.node")"
  # a point given twice keeps its number too (no triangle uses it) and the
  # triangles use the first
  printf '5 2 0 0\n1 0 0\n2 4 0\n3 4 4\n4 4 0\n5 0 4\n' > "$dir/dup.node"
  "$tessera" triangulate "$dir/dup.node" -o "$dir/dupout.node" --quiet || fail "dup.node"
  [ "$(grep -v '^#' "$dir/dupout.node" | sed -n 5p)" = "4 4 0 1" ] || fail "duplicate's number: $(cat "$dir/dupout.node")"
  grep -v '^#' "$dir/dupout.ele" | sed 1d | awk '$2 == 4 || $3 == 4 || $4 == 4 {exit 1}' ||
    fail "a triangle uses the duplicate: $(cat "$dir/dupout.ele")"
  # a 0-based input gives 0-based output, as Triangle keeps its numbering:
  # the same square, numbered from 0, gives the same triangles less one
  printf '5 2 0 0\n0 0 0\n1 4 0\n2 4 4\n3 4 0\n4 0 4\n' > "$dir/dup0.node"
  "$tessera" triangulate "$dir/dup0.node" -o "$dir/dup0out.node" --quiet || fail "dup0.node"
  [ "$(grep -v '^#' "$dir/dup0out.node" | sed -n 2p | awk '{print $1}')" = 0 ] || fail "0-based .node output: $(cat "$dir/dup0out.node")"
  grep -v '^#' "$dir/dupout.ele" | sed 1d | awk '{ print $1 - 1, $2 - 1, $3 - 1, $4 - 1 }' > "$dir/dup1.ele"
  grep -v '^#' "$dir/dup0out.ele" | sed 1d | awk '{ print $1, $2, $3, $4 }' > "$dir/dup0.ele"
  cmp -s "$dir/dup1.ele" "$dir/dup0.ele" || fail "0-based .ele differs from the 1-based one less one: $(cat "$dir/dup0.ele")"
  printf '3 2 0 0\n0 0 0\n1 1 0\n2 0 1\n3 0\n0 0 1\n1 1 2\n2 2 0\n1\n0 5 5\n' > "$dir/tri0.poly"
  "$tessera" triangulate "$dir/tri0.poly" -o "$dir/tri0out.poly" --quiet || fail "tri0.poly"
  [ "$(grep -v '^#' "$dir/tri0out.poly" | awk 'NR >= 3 && NF == 4 { printf "%s;", $1 " " $2 " " $3 } NF == 3 { print "hole " $1 }')" = \
    "0 0 1;1 1 2;2 2 0;hole 0" ] || fail "0-based .poly output: $(cat "$dir/tri0out.poly")"
  # the .poly (0 points: they are in out.node) back through our reader:
  # same points and constrained edges, and triangulating them again with
  # the hole seed gives the same number of triangles and the same area
  "$tessera" triangulate "$dir/out.poly" --check --json > "$dir/back.json" || fail "reading out.poly back: $(cat "$dir/back.json")"
  [ "$(json_num "$dir/back.json" points)" = "$nv" ] || fail "read back $(json_num "$dir/back.json" points) points, wrote $nv"
  [ "$(json_num "$dir/back.json" segments)" = "$ne" ] || fail "read back $(json_num "$dir/back.json" segments) segments, wrote $ne"
  [ "$(json_num "$dir/back.json" holes)" = 1 ] || fail "hole seed not written"
  [ "$(json_num "$dir/back.json" triangles)" = "$nt" ] || fail "re-triangulated: $(json_num "$dir/back.json" triangles) triangles, first $nt"
  grep -q '"ok":[[:space:]]*true' "$dir/back.json" || fail "check of the re-triangulation failed"
  echo "ok .node/.ele/.poly: $nv vertices, $nt triangles, $ne constrained edges; read back alike"
  # the same .poly after a UTF-8 byte order mark (as Windows editors save it)
  { printf '\357\273\277'; cat "$dir/in.poly"; } > "$dir/bom.poly"
  "$tessera" triangulate "$dir/bom.poly" --check --json > "$dir/bom.json" || fail "bom.poly: $(cat "$dir/bom.json")"
  [ "$(json_num "$dir/bom.json" triangles)" = "$nt" ] || fail "bom.poly: $(json_num "$dir/bom.json" triangles) triangles"
  { printf '\357\273\277'; printf '[[[0,0],[10,0],[10,10],[0,10]]]'; } > "$dir/bom.json"
  "$tessera" triangulate "$dir/bom.json" --check --quiet > "$dir/bomj.txt" || fail "bom.json: $(cat "$dir/bomj.txt")"
  echo "ok a byte order mark is skipped (.poly, .json)"
  # the .node alone: the hull of the same points
  "$tessera" triangulate "$dir/out.node" --check --quiet > "$dir/hull.txt" || fail "out.node: $(tail -1 "$dir/hull.txt")"
  echo "ok out.node read back (hull): $(tail -1 "$dir/hull.txt")"
  # meshes through assimp
  for fmt in obj ply; do
    "$tessera" triangulate "$dir/in.poly" -o "$dir/m.$fmt" --quiet || fail "write $fmt"
    info=$(assimp info "$dir/m.$fmt" 2>&1) || fail "assimp could not read $fmt: $info"
    got_f=$(printf '%s\n' "$info" | awk '/^Faces:/ {print $2; exit}')
    [ "$got_f" = "$nt" ] || fail "$fmt: assimp reads $got_f faces, wrote $nt"
    echo "ok $fmt: assimp reads $got_f faces"
  done
  # attributes and markers carried through. a1 = 1 + 2x + 3y (affine: the
  # linear interpolation must give it exactly at every Steiner point), a2 =
  # x y (kept at the input points); the bottom side's segments marked 5, the
  # other sides' 0 (so 1 on the boundary), the hole's 7, point 9 marked 9
  awk 'BEGIN {
    n = split("0 0 10 0 10 10 0 10 3 3 7 3 7 7 3 7 5 0", c, " ");
    print "9 2 2 1";
    for (i = 1; i <= 9; i++) { x = c[2 * i - 1]; y = c[2 * i]; printf "%d %s %s %.17g %.17g %d\n", i, x, y, 1 + 2 * x + 3 * y, x * y, i == 9 ? 9 : 0 }
    print "9 1"; print "1 1 9 5"; print "2 9 2 5"; print "3 2 3 0"; print "4 3 4 0"; print "5 4 1 0";
    print "6 5 6 7"; print "7 6 7 7"; print "8 7 8 7"; print "9 8 5 7"; print "1"; print "1 5 5" }' > "$dir/attr.poly"
  "$tessera" triangulate "$dir/attr.poly" -o "$dir/attr.1.node" -q 30 -a 1 --quiet || fail "attr.poly"
  grep -v '^#' "$dir/attr.1.node" | awk -v in_file="$dir/attr.poly" '
    BEGIN { while ((getline l < in_file) > 0) { split(l, f, " "); if (++k >= 2 && k <= 10) a2[f[1]] = f[5] } }
    NR == 1 { if ($2 != 2 || $3 != 2 || $4 != 1) { print "header " $0; bad = 1 }; n = $1; next }
    {
      x = $2; y = $3; d = $4 - (1 + 2 * x + 3 * y); if (d < 0) d = -d;
      if (d > 1e-9 * (1 + 2 * 10 + 3 * 10)) { print "a1 at " x, y ": " $4; bad = 1 }
      if ($1 <= 9 && $5 != a2[$1]) { print "a2 of input point " $1 ": " $5 " not " a2[$1]; bad = 1 }
      hole_side = x >= 3 && x <= 7 && y >= 3 && y <= 7 && (x == 3 || x == 7 || y == 3 || y == 7);
      want = $1 == 9 ? 9 : y == 0 ? 5 : (x == 0 || x == 10 || y == 10) ? 1 : hole_side ? 7 : 0;
      if ($6 != want) { print "marker of " $1 " (" x ", " y "): " $6 " not " want; bad = 1 }
      if ($1 > 9) steiner++
    }
    END { if (steiner < 50) { print "only " steiner " Steiner points"; bad = 1 }; exit bad }' ||
    fail "attributes or markers in attr.1.node"
  # the .poly: every edge on the bottom side marked 5, on the hole 7, else 1
  grep -v '^#' "$dir/attr.1.node" | sed 1d | awk '{ print $1, $2, $3 }' > "$dir/attr.xy"
  grep -v '^#' "$dir/attr.1.poly" | sed -n '2,$p' | awk -v xy="$dir/attr.xy" '
    BEGIN { while ((getline l < xy) > 0) { split(l, f, " "); X[f[1]] = f[2]; Y[f[1]] = f[3] } }
    NR == 1 { n = $1; next } NR > n + 1 { exit }
    { y0 = Y[$2]; y1 = Y[$3]; want = (y0 == 0 && y1 == 0) ? 5 : (X[$2] >= 3 && X[$2] <= 7 && Y[$2] >= 3 && Y[$2] <= 7) ? 7 : 1;
      if ($4 != want) { print "segment " $0 ": marker " $4 " not " want; bad = 1 } }
    END { exit bad }' || fail "segment markers in the output .poly"
  # --z-attribute 1 to a mesh: a TIN whose every vertex has z = a1 (float32)
  "$tessera" triangulate "$dir/attr.poly" -o "$dir/attr.obj" -q 30 -a 1 --z-attribute 1 --quiet || fail "--z-attribute"
  awk '$1 == "v" { n++; d = $4 - (1 + 2 * $2 + 3 * $3); if (d < 0) d = -d; if (d > 1e-4) { print "z at " $2, $3 ": " $4; bad = 1 } }
       END { if (n < 60) bad = 1; exit bad }' "$dir/attr.obj" || fail "z of --z-attribute 1"
  # a point given again with another attribute: a warning naming both
  printf '4 2 1 0\n1 0 0 1\n2 4 0 2\n3 0 4 3\n4 0 0 99\n' > "$dir/dupz.node"
  warn=$("$tessera" triangulate "$dir/dupz.node" -o "$dir/dupz.1.node" --quiet 2>&1) || fail "dupz.node: $warn"
  printf '%s\n' "$warn" | grep -q "warning: .*dupz.node: 1 point repeats an earlier point with other attributes (the first: point 4 repeats point 1)" ||
    fail "no warning for a repeated point's other attribute: '$warn'"
  # a constant attribute stays exact, and values near the largest double
  # stay finite (each value is kept within those it interpolates)
  printf '4 2 2 0\n1 0 0 0.1 1.7976931348623157e308\n2 7 0 0.1 1.7976931348623157e308\n3 7 5 0.1 1.7976931348623157e308\n4 0 5 0.1 1.7976931348623157e308\n' > "$dir/const.node"
  "$tessera" triangulate "$dir/const.node" -o "$dir/const.1.node" -q 30 -a 0.05 --quiet || fail "const.node"
  grep -v '^#' "$dir/const.1.node" | awk 'NR > 1 { n++; if ($4 != 0.1 || $5 != "1.7976931348623157e+308") { print; bad = 1 } }
    END { if (n < 100) bad = 1; exit bad }' || fail "a constant attribute changed at a Steiner point"
  expect_z=$("$tessera" triangulate "$dir/const.node" -o "$dir/const.obj" --z-attribute 2 2>&1)
  [ $? -eq 1 ] && printf '%s\n' "$expect_z" | grep -q "z-attribute 2: .* is beyond float32" && [ ! -e "$dir/const.obj" ] ||
    fail "a z beyond float32: '$expect_z'"
  echo "ok attributes interpolated (affine exact, constants exact), markers by Triangle's rules, --z-attribute"
  # regional attributes and areas: two rooms split at x = 5 (attributes
  # 10 left, 20 right; maximum area 0.5 right only); each triangle's
  # attribute by its centroid's side, and with --region-areas the right
  # room's triangles within 0.5 while the left room stays coarse
  printf '6 2 0 0\n1 0 0\n2 5 0\n3 10 0\n4 10 4\n5 5 4\n6 0 4\n7 1\n1 1 2 0\n2 2 3 0\n3 3 4 0\n4 4 5 0\n5 5 6 0\n6 6 1 0\n7 2 5 0\n0\n2\n1 2 2 10\n2 8 2 20 0.5\n' > "$dir/rooms.poly"
  note=$("$tessera" triangulate "$dir/rooms.poly" -o "$dir/rooms.1.node" -q 25 2>&1) || fail "rooms.poly: $note"
  printf '%s\n' "$note" | grep -q "note: .*rooms.poly gives regions maximum areas; --region-areas applies them" ||
    fail "no note on the unused regional areas: $note"
  "$tessera" triangulate "$dir/rooms.poly" -o "$dir/rooms.2.node" -q 25 --region-areas --check --quiet > "$dir/rooms.check" ||
    fail "--region-areas: $(cat "$dir/rooms.check")"
  for k in 1 2; do
    grep -v '^#' "$dir/rooms.$k.node" | sed 1d | awk '{ print $1, $2, $3 }' > "$dir/rooms.xy"
    grep -v '^#' "$dir/rooms.$k.ele" | awk -v xy="$dir/rooms.xy" -v k=$k '
      BEGIN { while ((getline l < xy) > 0) { split(l, f, " "); X[f[1]] = f[2]; Y[f[1]] = f[3] } }
      NR == 1 { if ($3 != 1) { print "no triangle attribute: " $0; bad = 1 }; next }
      { cx = (X[$2] + X[$3] + X[$4]) / 3; cy = (Y[$2] + Y[$3] + Y[$4]) / 3;
        a = ((X[$3] - X[$2]) * (Y[$4] - Y[$2]) - (Y[$3] - Y[$2]) * (X[$4] - X[$2])) / 2;
        want = cx < 5 ? 10 : 20; if ($5 != want) { print "triangle " $1 " at " cx ", " cy ": " $5 " not " want; bad = 1 }
        if (cx > 5 && k == 2 && a > 0.5 * (1 + 1e-9)) { print "triangle " $1 " of area " a " above 0.5"; bad = 1 }
        if (cx > 5) { nr++; if (a > big) big = a } else nl++ }
      END { if (k == 1 && big <= 0.5) { print "refined without --region-areas"; bad = 1 }
            if (k == 2 && (nr < 40 || nl > nr / 2)) { print nl " left and " nr " right triangles"; bad = 1 }; exit bad }' ||
      fail "regions in rooms.$k.ele"
  done
  grep -q "check: 0 triangles above their area bound" "$dir/rooms.check" || fail "the check of the regions' areas: $(cat "$dir/rooms.check")"
  echo "ok regional attributes on every triangle; --region-areas refines each room to its own bound"
  # JSON rings: the same square with its hole, even-odd by default
  printf '[[[0,0],[10,0],[10,10],[0,10],[0,0]],[[3,3],[7,3],[7,7],[3,7]]]' > "$dir/ring.json"
  "$tessera" triangulate "$dir/ring.json" --check --json > "$dir/ring.out" || fail "ring.json"
  [ "$(json_num "$dir/ring.out" rings)" = 2 ] && [ "$(json_num "$dir/ring.out" points)" = 8 ] || fail "ring.json counts"
  grep -q '"region":[[:space:]]*"evenodd"' "$dir/ring.out" || fail "ring.json region"
  grep -q '"expected_euler":[[:space:]]*0' "$dir/ring.out" || fail "ring.json Euler"
  echo "ok ring.json: closing point dropped, even-odd region, Euler 0" ;;
*) fail "unknown mode $mode" ;;
esac
exit 0
