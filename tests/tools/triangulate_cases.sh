#!/usr/bin/env bash
# triangulate_cases.sh TESSERA MAKE_FIXTURES CASE: one bad-input case of
# `tessera triangulate`. Every failing case must exit 1 (or 2 for bad
# usage) -- never a crash or a sanitizer report -- print exactly one line
# naming the file, the line (or JSON position) and the problem, and leave
# no output file behind.
set -u
tessera=$1 fixtures=$2 case=$3
# shellcheck source=cli_harness.sh
. "$(dirname "$0")/cli_harness.sh"

# tri FILE [options]: triangulate FILE into $dir/out.node with --check
tri() { local f=$1; shift; "$tessera" triangulate "$f" -o "$dir/out.node" --check "$@"; }

# a good square, for the option cases
printf '4 2 0 0\n1 0 0\n2 1 0\n3 1 1\n4 0 1\n' > "$dir/square.node"

case "$case" in
tri_missing_file)
  for ext in node poly json txt; do
    expect_error 1 "nope\.$ext: No such file" -- tri "$dir/nope.$ext"
  done
  # a .poly of 0 points reads the .node of its name, which is not there
  printf '0 2 0 0\n0 0\n0\n' > "$dir/lonely.poly"
  expect_error 1 "lonely\.poly:1: 0 points, meaning they are in .*lonely\.node, which does not exist" -- tri "$dir/lonely.poly" ;;
tri_empty_file)
  for ext in node poly json txt; do
    : > "$dir/empty.$ext"
    expect_error 1 "empty\.$ext: empty file" -- tri "$dir/empty.$ext"
  done
  printf '# only a comment\n\n' > "$dir/blank.node"
  expect_error 1 "blank\.node: no header line" -- tri "$dir/blank.node"
  printf '0 2 0 0\n' > "$dir/zero.node"
  expect_error 1 "zero\.node:1: no points" -- tri "$dir/zero.node"
  printf '[]' > "$dir/norings.json"
  expect_error 1 "norings\.json: no points" -- tri "$dir/norings.json" ;;
tri_random_bytes)
  for ext in node poly txt; do
    cp "$dir/random.png" "$dir/random.$ext"
    expect_error 1 "random\.$ext:[0-9]+: .*(is not a|expected)" -- tri "$dir/random.$ext"
  done
  cp "$dir/random.png" "$dir/random.json"
  expect_error 1 "random\.json:1:1: not valid JSON" -- tri "$dir/random.json" ;;
tri_truncated)
  printf '4 2 0 0\n1 0 0\n2 1 0\n3 1 1\n' > "$dir/short.node"
  expect_error 1 "short\.node:5: the file ends after 3 of 4 points" -- tri "$dir/short.node"
  printf '4 3\n0 0\n1 0\n1 1\n0 1\n0 1\n1 2\n' > "$dir/short.txt"
  expect_error 1 "short\.txt:8: the file ends after 2 of 3 edges" -- tri "$dir/short.txt"
  printf '3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n3 0\n1 1 2\n2 2 3\n3 3 1\n' > "$dir/noholes.poly"
  expect_error 1 "noholes\.poly:9: the file ends before the hole count" -- tri "$dir/noholes.poly"
  printf '[[[0,0],[1,0],[1,1]' > "$dir/short.json"
  expect_error 1 "short\.json:1:[0-9]+: not valid JSON" -- tri "$dir/short.json" ;;
tri_non_numeric)
  printf '3 2 0 0\n1 0 0\n2 1 zero\n3 0 1\n' > "$dir/word.node"
  expect_error 1 "word\.node:3: y 'zero' is not a number" -- tri "$dir/word.node"
  printf '3 1\n0 0\n1 0\n0 1\n0 x\n' > "$dir/word.txt"
  expect_error 1 "word\.txt:5: vertex index 'x' is not a non-negative integer" -- tri "$dir/word.txt"
  printf '3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n1 0\n1 1 two\n0\n' > "$dir/word.poly"
  expect_error 1 "word\.poly:6: point index 'two' is not a non-negative integer" -- tri "$dir/word.poly"
  printf '3 2 0 0\n1 0 0\n2 0x10 0\n3 0 1\n' > "$dir/hex.node"
  expect_error 1 "hex\.node:3: x '0x10' is not a number" -- tri "$dir/hex.node"
  printf '[[[0,0],[1,"a"],[0,1]]]' > "$dir/word.json"
  expect_error 1 'word\.json: \$\[0\]\[1\]: ring 0, point 1 is an array of other than two numbers' -- tri "$dir/word.json" ;;
tri_count_mismatch)
  printf '3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n4 1 1\n' > "$dir/more.node"
  expect_error 1 "more\.node:5: more points than the 3 the header gives" -- tri "$dir/more.node"
  printf '3 0\n0 0\n1 0\n0 1\n5 5\n' > "$dir/more.txt"
  expect_error 1 "more\.txt:5: more lines than the 3 points and 0 edges" -- tri "$dir/more.txt"
  printf '3 2 0 1\n1 0 0\n2 1 0 7\n3 0 1 0\n' > "$dir/fields.node"
  expect_error 1 "fields\.node:2: expected 4 values \(index x y marker\), found 3" -- tri "$dir/fields.node"
  printf '3 2 0 0\n1 0 0\n3 1 0\n2 0 1\n' > "$dir/order.node"
  expect_error 1 "order\.node:3: point numbered 3, expected 2" -- tri "$dir/order.node"
  printf '3 2 0 0\n5 0 0\n6 1 0\n7 0 1\n' > "$dir/base.node"
  expect_error 1 "base\.node:2: the first point is numbered 5; numbering starts at 0 or 1" -- tri "$dir/base.node" ;;
tri_index_out_of_range)
  printf '3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n2 0\n1 1 2\n2 2 9\n0\n' > "$dir/far.poly"
  expect_error 1 "far\.poly:7: segment 2 names point 9; points are 1 to 3" -- tri "$dir/far.poly"
  printf '3 2 0 0\n0 0 0\n1 1 0\n2 0 1\n1 0\n0 0 3\n0\n' > "$dir/zero_based.poly"
  expect_error 1 "zero_based\.poly:6: segment 0 names point 3; points are 0 to 2" -- tri "$dir/zero_based.poly"
  printf '3 1\n0 0\n1 0\n0 1\n0 3\n' > "$dir/far.txt"
  expect_error 1 "far\.txt:5: edge 0 names vertex 3; there are 3" -- tri "$dir/far.txt" ;;
tri_nan_coordinate)
  printf '3 2 0 0\n1 0 0\n2 nan 0\n3 0 1\n' > "$dir/nan.node"
  expect_error 1 "nan\.node:3: x 'nan' is not a finite number" -- tri "$dir/nan.node"
  printf '3 0\n0 0\n1 -inf\n0 1\n' > "$dir/inf.txt"
  expect_error 1 "inf\.txt:3: y '-inf' is not a finite number" -- tri "$dir/inf.txt"
  printf '3 0\n0 0\n1 1e999\n0 1\n' > "$dir/big.txt"
  expect_error 1 "big\.txt:3: y '1e999' is not a finite number" -- tri "$dir/big.txt"
  printf '[[[0,0],[1e999,0],[0,1]]]' > "$dir/inf.json"
  expect_error 1 'inf\.json: \$\[0\]\[1\]: ring 0, point 1 has a non-finite coordinate' -- tri "$dir/inf.json"
  printf '3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n0 0\n1\n1 NaN 0.5\n' > "$dir/nanhole.poly"
  expect_error 1 "nanhole\.poly:7: x 'NaN' is not a finite number" -- tri "$dir/nanhole.poly" ;;
tri_huge_count)
  printf '4000000000 2 0 0\n1 0 0\n2 1 0\n3 0 1\n' > "$dir/huge.node"
  expect_error 1 "huge\.node:1: 4000000000 points cannot fit in the 18 bytes left in the file" -- tri "$dir/huge.node"
  printf '3 4000000000\n0 0\n1 0\n0 1\n' > "$dir/huge.txt"
  expect_error 1 "huge\.txt:1: 4000000003 points and edges cannot fit" -- tri "$dir/huge.txt"
  printf '3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n4294967295 0\n0\n' > "$dir/huge.poly"
  expect_error 1 "huge\.poly:5: 4294967295 segments cannot fit" -- tri "$dir/huge.poly"
  printf '99999999999 2 0 0\n' > "$dir/over.node"
  expect_error 1 "over\.node:1: point count '99999999999' is beyond 4294967295" -- tri "$dir/over.node"
  printf '3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n0 0\n2000000000\n' > "$dir/holes.poly"
  expect_error 1 "holes\.poly:6: 2000000000 holes cannot fit" -- tri "$dir/holes.poly" ;;
tri_json_not_polygon)
  printf '{"triangles": {"earcut": 548}}' > "$dir/expected.json"
  expect_error 1 'expected\.json: \$: not a polygon: expected an array of rings, found an object' -- tri "$dir/expected.json"
  printf '[[[0,0],[1,0],[0,1]], 7]' > "$dir/ring.json"
  expect_error 1 'ring\.json: \$\[1\]: ring 1 is a number, not an array' -- tri "$dir/ring.json"
  printf '[[[0,0,0],[1,0,0],[0,1,0]]]' > "$dir/xyz.json"
  expect_error 1 'xyz\.json: \$\[0\]\[0\]: ring 0, point 0 is an array of other than two numbers' -- tri "$dir/xyz.json"
  printf '[[[0,0],[1,0],[0,1]]]\n{\n' > "$dir/trailing.json"
  expect_error 1 "trailing\.json:2:1: unexpected data after the JSON value" -- tri "$dir/trailing.json"
  printf '[\n  [[0,0],[1,0],\n   [0,1],]\n]' > "$dir/syntax.json"
  expect_error 1 "syntax\.json:3:[0-9]+: not valid JSON" -- tri "$dir/syntax.json" ;;
tri_dimension)
  printf '3 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n' > "$dir/three.node"
  expect_error 1 "three\.node:1: dimension 3; only 2 is supported" -- tri "$dir/three.node"
  printf '3 2 0 2\n1 0 0 1 1\n' > "$dir/marks.node"
  expect_error 1 "marks\.node:1: marker count 2; it is 0 or 1" -- tri "$dir/marks.node"
  printf '3 2 0 1\n1 0 0 1\n2 1 0 1.5\n3 0 1 0\n' > "$dir/halfmark.node"
  expect_error 1 "halfmark\.node:3: marker '1\.5' is not an integer" -- tri "$dir/halfmark.node"
  printf '3 2 0 1\n1 0 0 -2147483648\n2 1 0 2147483647\n3 0 1 0\n' > "$dir/extrememarks.node"
  tri "$dir/extrememarks.node" --quiet > /dev/null || fail "the int32 extremes as markers refused"
  printf '3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n1 1\n1 1 2 3e10\n0\n' > "$dir/bigmark.poly"
  expect_error 1 "bigmark\.poly:6: marker '3e10' is not an integer from -2147483648 to 2147483647" -- tri "$dir/bigmark.poly"
  printf '3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n0 0\n0\n1\n1 0.2 0.2\n' > "$dir/shortregion.poly"
  expect_error 1 "shortregion\.poly:8: expected 4 to 5 values \(index x y attribute \[maximum-area\]\), found 3" -- tri "$dir/shortregion.poly"
  printf '3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n0 0\n0\n2\n1 0.2 0.2 1\n' > "$dir/fewregions.poly"
  expect_error 1 "fewregions\.poly:[0-9]+: the file ends after 1 of 2 regions" -- tri "$dir/fewregions.poly"
  printf '3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n0 0\n0\n1\n1 0.2 0.2 1 nan\n' > "$dir/nanregion.poly"
  expect_error 1 "nanregion\.poly:8: maximum area 'nan' is not a finite number" -- tri "$dir/nanregion.poly"
  printf '3 2 65 0\n' > "$dir/attrs.node"
  expect_error 1 "attrs\.node:1: 65 attributes per point; at most 64 are read" -- tri "$dir/attrs.node" ;;
tri_bad_options)
  sq="$dir/square.node"
  expect_error 2 "-q 70: the minimum angle must be" -- "$tessera" triangulate "$sq" --check -q 70
  expect_error 2 "-q abc: the minimum angle must be" -- "$tessera" triangulate "$sq" --check -q abc
  expect_error 2 "missing value for '-q'" -- "$tessera" triangulate "$sq" --check -q
  expect_error 2 "-a -1: the maximum area must be a positive number" -- "$tessera" triangulate "$sq" --check -a -1
  expect_error 2 "--method fast: unknown method" -- "$tessera" triangulate "$sq" --check --method fast
  expect_error 2 "--region inside: unknown region" -- "$tessera" triangulate "$sq" --check --region inside
  expect_error 2 "--format svg: unknown input format" -- "$tessera" triangulate "$sq" --check --format svg
  expect_error 2 "no output: give -o OUT, --check or --json" -- "$tessera" triangulate "$sq"
  expect_error 2 "out\.xyz: unknown output format" -- "$tessera" triangulate "$sq" -o "$dir/out.xyz"
  cp "$sq" "$dir/square.dat"
  expect_error 2 "square\.dat: unknown input format" -- "$tessera" triangulate "$dir/square.dat" --check
  expect_error 2 "--conforming applies to --method delaunay only" -- "$tessera" triangulate "$sq" --check --conforming --method quadtree
  expect_error 2 "unknown option '--frobnicate'" -- "$tessera" triangulate "$sq" --frobnicate
  expect_error 2 "one input at a time" -- "$tessera" triangulate "$sq" "$sq" --check
  expect_error 2 "--z-attribute 1: .*square\.node has 0 attributes per point" -- "$tessera" triangulate "$sq" -o "$dir/z.obj" --z-attribute 1
  printf '3 2 2 0\n1 0 0 5 6\n2 1 0 5 6\n3 0 1 5 6\n' > "$dir/two_attr.node"
  expect_error 2 "--z-attribute 3: .*two_attr\.node has only 2 attributes per point" -- "$tessera" triangulate "$dir/two_attr.node" -o "$dir/z.obj" --z-attribute 3
  expect_error 2 "--z-attribute 0: must be an attribute number from 1 to 64" -- "$tessera" triangulate "$sq" -o "$dir/z.obj" --z-attribute 0
  # Triangle's three output files never replace the input (they share OUT's base name)
  printf '3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n3 0\n1 1 2\n2 2 3\n3 3 1\n0\n' > "$dir/tri.poly"
  cp "$dir/tri.poly" "$dir/tri.poly.orig"
  expect_error 2 "the input .*tri\.poly and the output .*tri\.poly name the same file" -- "$tessera" triangulate "$dir/tri.poly" -o "$dir/tri.ele"
  expect_error 2 "the input .*square\.node and the output .*square\.node name the same file" -- "$tessera" triangulate "$sq" -o "$dir/square.poly"
  cmp -s "$dir/tri.poly" "$dir/tri.poly.orig" || fail "tri.poly was overwritten"
  # a .poly with points of its own reads no .node: an output of that name is fine
  cp "$dir/tri.poly" "$dir/own.dat"
  "$tessera" triangulate "$dir/own.dat" --format poly -o "$dir/own.ele" --quiet || fail "own.dat --format poly -o own.ele"
  # but one whose points are in a .node of its name may not replace it
  printf '0 2 0 0\n3 0\n1 1 2\n2 2 3\n3 3 1\n0\n' > "$dir/pts.dat"
  printf '3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n' > "$dir/pts.node"
  expect_error 2 "the points' file .*pts\.node and the output .*pts\.node name the same file" -- "$tessera" triangulate "$dir/pts.dat" --format poly -o "$dir/pts.ele"
  [ ! -e "$dir/tri.node" ] && [ ! -e "$dir/tri.ele" ] || fail "output files written beside tri.poly"
  expect_error 2 "--region-areas: .*square\.node gives no region a maximum area" -- "$tessera" triangulate "$sq" --check --region-areas
  expect_error 2 "--z-attribute applies to a mesh output" -- "$tessera" triangulate "$dir/two_attr.node" -o "$dir/z.node" --z-attribute 1
  # --format overrides the extension
  "$tessera" triangulate "$dir/square.dat" --format node --check --quiet > /dev/null || fail "--format node"
  echo "ok [$case]: --format node reads square.dat" ;;
tri_unwritable_output)
  expect_error 1 "/no/such/dir/x\.node: cannot write" -- "$tessera" triangulate "$dir/square.node" -o /no/such/dir/x.node
  expect_error 1 "/no/such/dir/x\.obj: cannot write" -- "$tessera" triangulate "$dir/square.node" -o /no/such/dir/x.obj
  if [ "$(id -u)" -ne 0 ]; then
    mkdir "$dir/ro" && chmod 500 "$dir/ro"
    expect_error 1 "ro/x\.node: cannot write" -- "$tessera" triangulate "$dir/square.node" -o "$dir/ro/x.ele"
    [ -z "$(ls -A "$dir/ro")" ] || fail "files left in a read-only folder"
  fi ;;
tri_no_triangle)
  # points on one line (a segment among them or not): no triangle can
  # exist; said, nothing written (an empty region of a valid polygon is
  # not this: earcut's empty-square.json triangulates to nothing, exit 0)
  printf '3 1\n0 0\n1 1\n3 3\n0 2\n' > "$dir/line.txt"
  expect_error 1 "line\.txt: no triangle: the points are all on one line" -- tri "$dir/line.txt"
  printf '2 2 0 0\n1 0 0\n2 5 1\n' > "$dir/two.node"
  expect_error 1 "two\.node: no triangle: fewer than 3 distinct points" -- tri "$dir/two.node" ;;
tri_refinement_bounds)
  # a maximum area asking for more than 5e7 triangles (no --max-steiner):
  # refused before it runs out of memory, naming the region's area
  expect_error 1 "square\.node: a maximum triangle area of 1e-09 over the region's area of 1 asks for more than" \
    -- tri "$dir/square.node" -a 1e-9
  # bounds not met (the Steiner limit stops -q 50): written, exit 3, a
  # warning even with --quiet
  "$tessera" triangulate "$dir/square.node" -q 50 --max-steiner 3 -o "$dir/lim.node" --quiet 2>"$dir/lim.err"
  rc=$?
  [ $rc -eq 3 ] || fail "Steiner-limited: exit $rc: $(cat "$dir/lim.err")"
  grep -q "warning: .*square\.node: the bounds asked for (-q) are not met everywhere: [0-9]* triangles\{0,1\} or edges\{0,1\} left, refinement stopped at the Steiner limit" \
    "$dir/lim.err" || fail "Steiner-limited: '$(cat "$dir/lim.err")'"
  [ -s "$dir/lim.node" ] && [ -s "$dir/lim.ele" ] || fail "Steiner-limited: not written"
  "$tessera" triangulate "$dir/square.node" -q 20 -o "$dir/ok.node" --quiet || fail "-q 20: exit $?"
  echo "ok [$case]: $(cat "$dir/lim.err")" ;;
*) fail "unknown case" ;;
esac
exit 0
