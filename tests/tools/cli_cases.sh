#!/usr/bin/env bash
# cli_cases.sh TESSERA MAKE_FIXTURES CASE: one bad-input case of the CLI.
# Every failing case must exit 1 (or 2 for bad usage) -- never a crash or a
# sanitizer report -- print exactly one line naming the file and the
# problem, and leave no output file behind.
set -u
tessera=$1 fixtures=$2 case=$3
# shellcheck source=cli_harness.sh
. "$(dirname "$0")/cli_harness.sh"

out="$dir/out.obj"
case "$case" in
missing_file)
  expect_error 1 "nope\.png: No such file" -- "$tessera" info "$dir/nope.png"
  expect_error 1 "nope\.png: No such file" -- "$tessera" mesh "$dir/nope.png" -o "$out" ;;
empty_file)
  expect_error 1 "empty\.png: empty file" -- "$tessera" mesh "$dir/empty.png" -o "$out" ;;
truncated_png)
  "$tessera" generate --size 64 -o "$dir/good.png" 2>/dev/null || fail "generate failed"
  head -c 600 "$dir/good.png" > "$dir/truncated.png"; rm "$dir/good.png"
  expect_error 1 "truncated\.png: (truncated|not an image)" -- "$tessera" mesh "$dir/truncated.png" -o "$out" ;;
random_bytes_png)
  expect_error 1 "random\.png: not an image" -- "$tessera" mesh "$dir/random.png" -o "$out" ;;
huge_header_png)
  expect_error 1 "huge\.png: image is 1000000x1000000" -- "$tessera" mesh "$dir/huge.png" -o "$out"
  expect_error 1 "huge\.png: image is 1000000x1000000" -- "$tessera" info "$dir/huge.png" ;;
one_by_one_image)
  oiiotool --create 1x1 1 -d uint16 -o "$dir/one.png" || fail "oiiotool failed"
  expect_error 1 "one\.png: image is 1x1; a heightfield needs at least 2x2" -- "$tessera" mesh "$dir/one.png" -o "$out" ;;
nan_height)
  # NaN is no-data: it loads, is counted, and becomes a hole in the mesh
  "$tessera" info "$dir/nan.f32" --raw 4 4 f32 --json > "$dir/info.json" || fail "info failed"
  grep -q '"nodata":[[:space:]]*1' "$dir/info.json" || fail "nodata count: $(cat "$dir/info.json")"
  "$tessera" mesh "$dir/nan.f32" --raw 4 4 f32 -o "$dir/nan.obj" --method grid --quiet || fail "mesh failed"
  # grid: 9 cells, 18 triangles; each of the 4 cells around the NaN sample
  # (column 1, row 1) keeps only the triangle of its other three corners
  [ "$(grep -c '^f ' "$dir/nan.obj")" -eq 14 ] || fail "triangles: $(grep -c '^f ' "$dir/nan.obj")"
  [ "$(grep -c '^v ' "$dir/nan.obj")" -eq 15 ] || fail "vertices"
  ! grep -qi nan "$dir/nan.obj" || fail "NaN written into the mesh"
  # delaunay and quadtree: the cells of four valid samples, none touching
  # the NaN sample's position (1, 1)
  for m in delaunay quadtree; do
    "$tessera" mesh "$dir/nan.f32" --raw 4 4 f32 -o "$dir/nan.obj" --method $m --quiet || fail "mesh $m failed"
    ! grep -qi nan "$dir/nan.obj" || fail "NaN written into the $m mesh"
    ! grep -q '^v 1 1 ' "$dir/nan.obj" || fail "$m mesh has a vertex at the no-data sample"
    [ "$(grep -c '^f ' "$dir/nan.obj")" -ge 2 ] || fail "$m: no triangles"
  done
  echo "ok [$case]" ;;
all_nan_height)
  expect_error 1 "allnan\.f32: every sample is no-data" -- "$tessera" mesh "$dir/allnan.f32" --raw 4 4 f32 -o "$out" ;;
inf_height)
  expect_error 1 "inf\.f32: infinite height at column 1, row 2" -- "$tessera" mesh "$dir/inf.f32" --raw 4 4 f32 -o "$out" ;;
unwritable_output)
  "$tessera" generate --size 16 -o "$dir/g.png" 2>/dev/null || fail "generate failed"
  expect_error 1 "/no/such/dir/x\.obj: cannot write" -- "$tessera" mesh "$dir/g.png" -o /no/such/dir/x.obj
  expect_error 1 "x\.png: cannot write" -- "$tessera" generate --size 16 -o /no/such/dir/x.png
  if [ "$(id -u)" -ne 0 ]; then
    mkdir "$dir/ro" && chmod 500 "$dir/ro"
    expect_error 1 "ro/x\.glb: cannot write" -- "$tessera" mesh "$dir/g.png" -o "$dir/ro/x.glb"
  fi ;;
outputs_checked_first)
  # Every output is checked before the work: an unwritable --stats (or
  # image, or video) fails the command with nothing written, not after the
  # mesh is made and saved (expect_error checks no file appears).
  "$tessera" generate --size 16 -o "$dir/g.png" --quiet || fail "generate failed"
  expect_error 1 "/no/such/dir/s\.json: cannot write" -- "$tessera" mesh "$dir/g.png" -o "$dir/x.ply" --stats /no/such/dir/s.json
  expect_error 1 "--hillshade: /no/such/dir/h\.png: cannot write" -- "$tessera" mesh "$dir/g.png" -o "$dir/x.ply" --hillshade /no/such/dir/h.png
  expect_error 2 "--normal-map: .*n\.xyz: no image writer" -- "$tessera" mesh "$dir/g.png" -o "$dir/x.ply" --normal-map "$dir/n.xyz"
  expect_error 2 "g2\.xyz: unknown heightfield format" -- "$tessera" generate --size 16 -o "$dir/g2.xyz"
  expect_error 1 "/no/such/dir/f\.json: cannot write" -- "$tessera" fly "$dir/g.png" --headless --frames 1 --stats /no/such/dir/f.json
  printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n' > "$dir/quad.obj"
  expect_error 1 "/no/such/dir/p\.json: cannot write" -- "$tessera" patch "$dir/quad.obj" -o "$dir/p.obj" --stats /no/such/dir/p.json
  expect_error 1 "/no/such/dir/b\.json: cannot write" -- "$tessera" bench patch --quick --json /no/such/dir/b.json
  # and the good runs make their outputs; --quiet prints nothing
  "$tessera" mesh "$dir/g.png" -o "$dir/x.ply" --stats "$dir/s.json" --hillshade "$dir/h.png" --quiet 2>"$cap/stderr" \
    || fail "mesh with all outputs failed: $(cat "$cap/stderr")"
  [ -s "$dir/x.ply" ] && [ -s "$dir/s.json" ] && [ -s "$dir/h.png" ] || fail "an output is missing"
  [ ! -s "$cap/stderr" ] || fail "mesh --quiet printed: $(cat "$cap/stderr")"
  "$tessera" generate --size 16 -o "$dir/q.png" --quiet 2>"$cap/stderr" || fail "generate --quiet failed"
  [ -s "$dir/q.png" ] && [ ! -s "$cap/stderr" ] || fail "generate --quiet: no file, or it printed: $(cat "$cap/stderr")"
  echo "ok [$case]: good runs" ;;
random_bytes_every_format)
  for ext in tif tiff exr pgm jpg; do
    cp "$dir/random.png" "$dir/random.$ext"
    expect_error 1 "random\.$ext: not an image" -- "$tessera" mesh "$dir/random.$ext" -o "$out"
  done
  printf 'P5\n100 100\n65535\n\001\002' > "$dir/short.pgm"
  expect_error 1 "short\.pgm: truncated PGM" -- "$tessera" info "$dir/short.pgm"
  printf 'P5\n3 x\n255\n' > "$dir/badhead.pgm"
  expect_error 1 "badhead\.pgm: PGM header" -- "$tessera" info "$dir/badhead.pgm" ;;
raw_wrong_size)
  expect_error 1 "nan\.f32: raw f32 5x4 needs 80 bytes but the file has 64" -- "$tessera" info "$dir/nan.f32" --raw 5 4 f32 ;;
bad_options)
  "$tessera" generate --size 16 -o "$dir/g.png" 2>/dev/null || fail "generate failed"
  expect_error 2 "--dx abc: not a finite number" -- "$tessera" mesh "$dir/g.png" -o "$out" --dx abc
  expect_error 2 "unknown mesh format" -- "$tessera" mesh "$dir/g.png" -o "$dir/out.xyz"
  expect_error 2 "unknown option '--frobnicate'" -- "$tessera" info "$dir/g.png" --frobnicate
  expect_error 2 "unknown command 'nosuch'" -- "$tessera" nosuch ;;
*) fail "unknown case" ;;
esac
exit 0
