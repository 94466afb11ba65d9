#!/usr/bin/env bash
# formats.sh TESSERA: every input format, written by an independent tool
# (oiiotool from Debian's openimageio-tools) with a known linear ramp, read
# back by `tessera info --json`. A vertical fill from top T to bottom B over
# the rows is exact at both ends and has mean (T+B)/2.
set -u
tessera=$1
dir=$(mktemp -d "${TMPDIR:-/tmp}/tsr-formats-XXXXXX")
trap 'rm -rf "$dir"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
command -v oiiotool >/dev/null || fail "oiiotool not installed (tools/install-deps.sh)"

field() { grep -o "\"$1\":[[:space:]]*[^,}]*" "$dir/info.json" | sed 's/.*:[[:space:]]*//; s/"//g'; }

# check NAME CHANNELS TYPE TOP BOTTOM WANT_FORMAT WANT_MIN WANT_MAX [tessera options]
check() {
  local name=$1 ch=$2 type=$3 top=$4 bottom=$5 want_fmt=$6 want_min=$7 want_max=$8
  shift 8
  oiiotool --pattern "fill:top=$top:bottom=$bottom" 7x33 "$ch" -d "$type" ${oiio_attrib[@]+"${oiio_attrib[@]}"} \
    -o "$dir/$name" || fail "oiiotool $name"
  "$tessera" info "$dir/$name" --json "$@" > "$dir/info.json" || fail "tessera info $name: $(cat "$dir/info.json")"
  [ "$(field format)" = "$want_fmt" ] || fail "$name: format $(field format), wanted $want_fmt"
  [ "$(field width)" = 7 ] && [ "$(field height)" = 33 ] || fail "$name: size $(field width)x$(field height)"
  awk -v a="$(field min)" -v b="$want_min" 'BEGIN { exit !(a == b) }' || fail "$name: min $(field min), wanted $want_min"
  awk -v a="$(field max)" -v b="$want_max" 'BEGIN { exit !(a == b) }' || fail "$name: max $(field max), wanted $want_max"
  # integer samples are rounded ramp values: the mean is within half a unit
  local tol=0.5; [ "$type" = float ] && tol=0
  awk -v a="$(field mean)" -v b="$want_min" -v c="$want_max" -v t="$tol" 'BEGIN { m = (b + c) / 2; d = a - m; if (d < 0) d = -d; exit !(d <= t + 1e-6 * (1 + (m < 0 ? -m : m))) }' \
    || fail "$name: mean $(field mean)"
  echo "ok $name: $want_fmt $(field min)..$(field max)"
}

check a8.png 1 uint8 0 1 "png uint8" 0 255
check a16.png 1 uint16 0 1 "png uint16" 0 65535
check a16.tif 1 uint16 0 1 "tiff uint16" 0 65535
check a8.tif 1 uint8 0 1 "tiff uint8" 0 255
check af.tif 1 float -12.5 3000 "tiff float" -12.5 3000
check af.exr 1 float -5 100 "openexr float" -5 100
check grey-as-rgb.png 3 uint8 0 1 "png uint8" 0 255
# grey and alpha stored as given (alpha a mask, not a factor on the
# heights): tessera reads the grey as stored, and alpha 0 as no-data
oiio_attrib=(--attrib oiio:UnassociatedAlpha 1)
check grey-with-alpha.png 2 uint16 0,0.5 1,1 "png uint16" 0 65535
oiiotool --pattern fill:top=0.2,0:bottom=0.8,1 7x33 2 -d uint16 --attrib oiio:UnassociatedAlpha 1 -o "$dir/ga0.png"
"$tessera" info "$dir/ga0.png" --json > "$dir/info.json" || fail "alpha 0 row"
[ "$(field nodata)" = 7 ] || fail "grey with alpha 0 on the top row: nodata $(field nodata), wanted 7"
echo "ok alpha 0 is no-data: $(field nodata) samples"
oiio_attrib=()
check a8.pgm 1 uint8 0 1 "pgm uint8" 0 255
# (no 16-bit PGM here: OpenImageIO 2.4 writes corrupt 16-bit PNM samples,
# as its own reader confirms; tests/terrain/test_heightfield.c writes one
# by hand instead)

# a colour image is refused unless decoded as Terrain-RGB
oiiotool --pattern fill:top=0.2,0.5,0.1:bottom=1,1,1 7x33 3 -d uint8 -o "$dir/colour.png"
"$tessera" info "$dir/colour.png" 2> "$dir/err" && fail "colour image accepted"
grep -q "terrain-rgb" "$dir/err" || fail "no hint: $(cat "$dir/err")"
# Terrain-RGB decoding of a constant colour: (R*65536 + G*256 + B)*0.1 - 10000
oiiotool --pattern constant:color=0.0039216,0.5294118,0.1960784 4x4 3 -d uint8 -o "$dir/trgb.png"  # 1,135,50
"$tessera" info "$dir/trgb.png" --decode terrain-rgb --json > "$dir/info.json" || fail "terrain-rgb"
awk -v a="$(field min)" 'BEGIN { w = (1*65536 + 135*256 + 50) * 0.1 - 10000; d = a - w; exit !(d < 0.001 && d > -0.001) }' \
  || fail "terrain-rgb decoded $(field min)"
echo "ok terrain-rgb decoding: $(field min)"

# a GeoTIFF reads as a TIFF, and a saved heightfield reads back the same
"$tessera" generate --size 33 --seed 9 -o "$dir/g.tif" 2>/dev/null || fail "generate tif"
"$tessera" generate --size 33 --seed 9 -o "$dir/g.exr" 2>/dev/null || fail "generate exr"
"$tessera" info "$dir/g.tif" --json > "$dir/a.json" && "$tessera" info "$dir/g.exr" --json > "$dir/b.json" || fail "read back"
[ "$(grep -E 'min|max|mean' "$dir/a.json")" = "$(grep -E 'min|max|mean' "$dir/b.json")" ] || fail "tif and exr differ"
echo "ok tif and exr agree"
