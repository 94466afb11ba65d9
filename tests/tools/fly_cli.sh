#!/usr/bin/env bash
# fly_cli.sh TESSERA: `tessera fly` end to end on lavapipe (or a GPU).
#  - headless: N numbered PNGs of the viewport's size (oiiotool reads
#    them), frames that differ along the path, --stats with per-frame
#    times, tiles, triangles (the GPU's count equal to the cut's) and
#    uploaded bytes;
#  - --path keyframes; bad path files, bad options and a bad input fail
#    with a message naming the problem and leave no frames behind;
#  - the window: under Xvfb it opens, renders 30 frames and closes cleanly.
# Exits 77 (skipped) when no Vulkan device is available.
set -u
tessera=$1
dir=$(mktemp -d "${TMPDIR:-/tmp}/tsr-flycli-XXXXXX")
trap 'rm -rf "$dir"' EXIT
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$dir}
fail() { echo "FAIL: $*"; exit 1; }

"$tessera" generate --size 257 --seed 3 -o "$dir/t.png" 2>/dev/null || fail generate

out=$("$tessera" fly "$dir/t.png" --dx 20 --headless --frames 6 --width 200 --height 120 --out "$dir/frames" \
       --stats "$dir/s.json" --quiet 2>&1)
rc=$?
if [ $rc -ne 0 ] && echo "$out" | grep -qi 'no Vulkan device\|Vulkan instance\|no usable Vulkan'; then
  echo "skipped: $out"; exit 77
fi
[ $rc -eq 0 ] || fail "headless fly: $out"
n=$(ls "$dir/frames"/frame_*.png | wc -l)
[ "$n" -eq 6 ] || fail "expected 6 frames, got $n"
oiiotool --info "$dir/frames/frame_00000.png" | grep -Eq '200 x +120' || fail "frame size"
cmp -s "$dir/frames/frame_00000.png" "$dir/frames/frame_00003.png" && fail "frames 0 and 3 are identical"
python3 - "$dir/s.json" <<'PY' || fail "stats"
import json, sys
d = json.load(open(sys.argv[1]))
fr = d["frames"]
assert len(fr) == 6, len(fr)
for f in fr:
    for k in ("select_ms", "upload_ms", "record_ms", "draw_ms", "tiles", "triangles", "gpu_triangles",
              "uploaded_bytes", "resident_bytes"):
        assert k in f, k
    assert f["tiles"] > 0 and f["triangles"] > 0
    assert f["gpu_triangles"] == f["triangles"], (f["gpu_triangles"], f["triangles"])
assert fr[0]["uploaded_bytes"] > 0
# the options used, defaults filled in (not 0 for "the default")
assert d["tile"] == 16 and d["pixel_error"] == 2, (d["tile"], d["pixel_error"])
print("ok stats: %d frames, %d tiles, %d triangles in frame 0" % (len(fr), fr[0]["tiles"], fr[0]["triangles"]))
PY
echo "ok headless: 6 frames"

# keyframes
printf '# eye only\n100 100 900\n4000 600 800\n4000 4000 700\n' > "$dir/path.txt"
"$tessera" fly "$dir/t.png" --dx 20 --headless --frames 3 --width 64 --height 48 --out "$dir/p" --path "$dir/path.txt" \
  --quiet || fail "--path"
[ "$(ls "$dir/p" | wc -l)" -eq 3 ] || fail "--path frames"
echo "ok --path"

# one keyframe: a still camera, every frame the same picture; with an eye
# alone it looks at the terrain's centre (the middle of the frame is
# terrain, not sky), and a target beside the terrain shows the sky there
printf '5000 -3000 3000\n' > "$dir/still.txt"
"$tessera" fly "$dir/t.png" --dx 20 --headless --frames 2 --width 64 --height 48 --out "$dir/still" \
  --path "$dir/still.txt" --quiet || fail "one keyframe"
cmp -s "$dir/still/frame_00000.png" "$dir/still/frame_00001.png" || fail "one keyframe: the frames differ"
printf '5000 -3000 3000 5000 -9000 6000\n' > "$dir/sky.txt"
"$tessera" fly "$dir/t.png" --dx 20 --headless --frames 1 --width 64 --height 48 --out "$dir/sky" \
  --path "$dir/sky.txt" --quiet || fail "one keyframe with a target"
# --fog: 0 draws no haze (the picture of a haze too far to see), and the
# default haze (a third of the diagonal) shows at the camera's distance
for fog in 0 1e9; do
  "$tessera" fly "$dir/t.png" --dx 20 --headless --frames 1 --width 64 --height 48 --out "$dir/fog$fog" \
    --path "$dir/still.txt" --fog $fog --quiet || fail "--fog $fog"
  cp "$dir/fog$fog/frame_00000.png" "$dir/fog$fog.png"
done
"$tessera" fly "$dir/t.png" --fog -1 --headless --frames 1 --out "$dir/fogbad" --quiet 2>/dev/null && fail "--fog -1"
for v in still sky fog0 fog1e9; do
  [ -d "$dir/$v" ] || continue
  oiiotool "$dir/$v/frame_00000.png" --cut 30x22+16+12 -o "$dir/$v.centre.png" && oiiotool --stats "$dir/$v.centre.png" |
    grep 'Stats Avg' | head -1 > "$dir/$v.avg"
done
python3 - "$dir/still.avg" "$dir/sky.avg" "$dir/fog0.avg" "$dir/fog1e9.avg" <<'PY' || fail "one keyframe, --fog"
import re, sys
def avg(p):
    return [float(x) for x in re.findall(r"[-0-9.]+", open(p).read().split(":", 1)[1])[:3]]
still, sky, fog0, far = (avg(p) for p in sys.argv[1:5])
assert still != sky, (still, sky)
print("ok one keyframe: centre RGB %s, looking away %s" % (still, sky))
assert max(abs(a - b) for a, b in zip(fog0, far)) < 2, (fog0, far)
assert max(abs(a - b) for a, b in zip(fog0, still)) > 10, (fog0, still)
print("ok --fog 0: centre RGB %s, --fog 1e9 %s, default haze %s" % (fog0, far, still))
PY

# a cut that does not fit the tile cache is drawn coarser, not a failed
# flight: a 1025^2 terrain in tiles of 128 quads (33 kB each, 31 in 1 MB),
# a low camera at 0.15 px needs more; the frame is drawn, its stats give
# the pixel error it was drawn at, and a note says so. With the default
# cache the same frame keeps 0.15 px.
python3 - "$dir/w.f32" <<'PY'
import array, math, sys
n = 1025
a = array.array('f', [300 * math.sin(i * 0.05) * math.cos(j * 0.037) + 100 * math.sin(i * 0.31 + j * 0.23)
                      for j in range(n) for i in range(n)])
with open(sys.argv[1], 'wb') as f:
    a.tofile(f)
PY
printf '1000 1000 600 10000 10000 0\n' > "$dir/low.txt"
for cache in 1 256; do
  err=$("$tessera" fly "$dir/w.f32" --raw 1025 1025 f32 --dx 20 --headless --frames 1 --width 160 --height 120 \
        --tile 128 --pixel-error 0.15 --path "$dir/low.txt" --cache $cache --out "$dir/cache$cache" \
        --stats "$dir/cache$cache.json" 2>&1) || fail "--cache $cache: $err"
  [ -f "$dir/cache$cache/frame_00000.png" ] || fail "--cache $cache: no frame"
  note=$(echo "$err" | grep "needed more tiles than the cache of $cache MB")
  px=$(python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["frames"][0]["pixel_error"])' \
       "$dir/cache$cache.json")
  if [ $cache = 1 ]; then
    [ -n "$note" ] || fail "--cache 1: no note: $err"
    python3 -c "import sys; sys.exit(not float('$px') > 0.15)" || fail "--cache 1: drawn at $px px"
  else
    [ -z "$note" ] || fail "--cache 256: $note"
    [ "$px" = 0.15 ] || fail "--cache 256: drawn at $px px"
  fi
  echo "ok --cache $cache: drawn at $px px"
done

# --show-normals: looking down on the terrain, the frame is the normals as
# colours, (n + 1) / 2: blue (z) near 1 and red, green (x, y) near 1/2 on
# average, which the lit frame of the same view is not
printf '2560 2300 4000 2560 2600 0\n2600 2300 4000 2600 2600 0\n' > "$dir/down.txt"
for mode in lit normals; do
  extra=; [ $mode = normals ] && extra=--show-normals
  "$tessera" fly "$dir/t.png" --dx 20 --headless --frames 1 --width 64 --height 48 --out "$dir/$mode" \
    --path "$dir/down.txt" $extra --quiet || fail "--show-normals ($mode)"
  oiiotool --stats "$dir/$mode/frame_00000.png" | grep 'Stats Avg' | head -1 > "$dir/$mode.avg"
done
python3 - "$dir/lit.avg" "$dir/normals.avg" <<'PY' || fail "--show-normals colours"
import re, sys
def avg(p):
    return [float(x) for x in re.findall(r"[-0-9.]+", open(p).read().split(":", 1)[1])[:3]]
lit, nrm = avg(sys.argv[1]), avg(sys.argv[2])
def normals_like(c):
    return c[2] > 0.9 * 255 and abs(c[0] - 127.5) < 40 and abs(c[1] - 127.5) < 40
assert normals_like(nrm) and not normals_like(lit), (nrm, lit)
print("ok --show-normals: average RGB %s (lit %s)" % (nrm, lit))
PY

# a second, shorter flight into the same folder leaves only its own frames
"$tessera" fly "$dir/t.png" --dx 20 --headless --frames 4 --width 32 --height 24 --out "$dir/re" --quiet ||
  fail "4 frames"
"$tessera" fly "$dir/t.png" --dx 20 --headless --frames 2 --width 32 --height 24 --out "$dir/re" --quiet ||
  fail "2 frames"
[ "$(ls "$dir/re")" = "$(printf 'frame_00000.png\nframe_00001.png')" ] || fail "stale frames: $(ls "$dir/re")"
echo "ok a shorter flight removes the longer one's frames"

# an interrupted flight leaves the folder as it was: the earlier flight's
# frames whole (none overwritten by this run's), no staging folder
( cd "$dir/re" && md5sum frame_*.png ) > "$dir/re.md5"
"$tessera" fly "$dir/t.png" --dx 20 --headless --frames 400 --width 32 --height 24 --out "$dir/re" --wireframe \
  --quiet 2>/dev/null &
pid=$!
for _ in $(seq 1 200); do # until this run has drawn some frames
  [ "$(ls -A "$dir/re"/.tessera-fly-*/ 2>/dev/null | wc -l)" -ge 3 ] && break
  sleep 0.1
done
kill -TERM $pid; wait $pid # (not INT: a background job of a script ignores it)
[ "$(ls -A "$dir/re")" = "$(printf 'frame_00000.png\nframe_00001.png')" ] ||
  fail "interrupted flight: the folder holds $(ls -A "$dir/re")"
( cd "$dir/re" && md5sum --quiet -c "$dir/re.md5" ) || fail "interrupted flight: the earlier frames changed"
echo "ok an interrupted flight leaves the earlier one's frames as they were"

# a terrain a few units across (2.56 x 2.56, 0.1 high) is drawn as the
# same terrain in metres is: its frames show tiles (the near plane and the
# cameras' clearance scale with the terrain); its --stats go inside the
# frames' folder, which does not exist yet (named another way); a run whose
# input fails to load leaves no such folder
"$tessera" fly "$dir/none.png" --headless --out "$dir/small/" --stats "$dir/small/stats.json" --quiet 2>/dev/null &&
  fail "a missing input flew"
[ ! -e "$dir/small" ] || fail "a failed run left the frames' folder"
"$tessera" fly "$dir/t.png" --dx 0.01 --dz 0.0003 --headless --frames 2 --width 64 --height 48 --out "$dir/small/" \
  --stats "$dir/./small/../small//stats.json" --quiet 2>"$dir/small.err" || fail "small terrain: $(cat "$dir/small.err")"
python3 - "$dir/small/stats.json" <<'PY' || fail "small terrain: no tiles drawn"
import json, sys
frames = json.load(open(sys.argv[1]))["frames"]
assert all(f["tiles"] > 0 for f in frames), [f["tiles"] for f in frames]
PY
! grep -q warning "$dir/small.err" || fail "small terrain: $(cat "$dir/small.err")"
# cameras that see none of the terrain: a warning, even with --quiet
printf '0 0 100000 -1000 -1000 200000\n' > "$dir/away.path"
"$tessera" fly "$dir/t.png" --dx 20 --headless --frames 1 --width 64 --height 48 --out "$dir/away" \
  --path "$dir/away.path" --quiet 2>"$dir/away.err" || fail "looking away: $(cat "$dir/away.err")"
grep -q "warning: no frame shows any of the terrain" "$dir/away.err" || fail "looking away: '$(cat "$dir/away.err")'"
echo "ok a small terrain is drawn; cameras looking away get a warning"

# a path whose eye meets its target between keyframes: refused before any
# frame is written, naming the path file
printf '0 0 500 100 0 500\n100 0 500 0 0 500\n' > "$dir/cross.path"
err=$("$tessera" fly "$dir/t.png" --dx 20 --headless --frames 3 --width 32 --height 24 --path "$dir/cross.path" \
      --out "$dir/cr" --quiet 2>&1) && fail "crossing path: exit 0"
echo "$err" | grep -q "cross\.path: frame 1: the camera is degenerate" || fail "crossing path: '$err'"
[ -z "$(ls -A "$dir/cr" 2>/dev/null)" ] || fail "crossing path: frames left: $(ls "$dir/cr")"
echo "ok crossing path: $err"
# --out is for headless runs: refused with a window
err=$("$tessera" fly "$dir/t.png" --out "$dir/nohead" 2>&1) && fail "--out without --headless: exit 0"
echo "$err" | grep -q -- "--out needs --headless" || fail "--out without --headless: '$err'"
echo "ok $err"

# --video: assembled by ffmpeg when it is installed, else a clear failure
# before any frame is rendered
if command -v ffmpeg >/dev/null; then
  "$tessera" fly "$dir/t.png" --dx 20 --headless --frames 4 --width 64 --height 48 --out "$dir/v" \
    --video "$dir/v.mp4" --quiet || fail "--video"
  [ -s "$dir/v.mp4" ] || fail "--video: no file"
  echo "ok --video"
else
  err=$("$tessera" fly "$dir/t.png" --dx 20 --headless --frames 2 --width 64 --height 48 --out "$dir/v" \
        --video "$dir/v.mp4" --quiet 2>&1) && fail "--video without ffmpeg: exit 0"
  echo "$err" | grep -q ffmpeg || fail "--video without ffmpeg: '$err'"
  [ -e "$dir/v.mp4" ] && fail "--video without ffmpeg: left a file"
  [ -z "$(ls -A "$dir/v" 2>/dev/null)" ] || fail "--video without ffmpeg: frames rendered: $(ls "$dir/v")"
  echo "ok --video without ffmpeg: $err"
fi

# bad inputs: a message naming the problem, non-zero exit, no frames
bad() { # name expected-message args...
  local name=$1 msg=$2; shift 2
  rm -rf "$dir/bad"
  local err
  err=$("$tessera" fly "$@" --headless --frames 2 --width 32 --height 32 --out "$dir/bad" --quiet 2>&1)
  local rc=$?
  [ $rc -ne 0 ] || fail "$name: exit 0"
  echo "$err" | grep -q -- "$msg" || fail "$name: message '$err' lacks '$msg'"
  [ -z "$(ls "$dir/bad" 2>/dev/null)" ] || fail "$name: left frames behind"
  echo "ok bad input $name: $err"
}
printf '1 2 3\n4 5\n' > "$dir/short.txt"
printf '1 2 3\n' > "$dir/one.txt"
printf '1 2 x\n4 5 6\n' > "$dir/nan.txt"
: > "$dir/empty.png"
bad path_wrong_count "short.txt:2" "$dir/t.png" --path "$dir/short.txt"
printf '# nothing\n\n' > "$dir/nokey.txt"
bad path_no_keyframe "nokey.txt: no keyframes" "$dir/t.png" --path "$dir/nokey.txt"
: > "$dir/afile"
err=$("$tessera" fly "$dir/t.png" --headless --frames 2 --width 32 --height 32 --out "$dir/afile" --quiet 2>&1) &&
  fail "--out a file: exit 0"
echo "$err" | grep -q -- "--out .*afile: a file of that name is in the way" || fail "--out a file: '$err'"
[ -f "$dir/afile" ] && [ ! -s "$dir/afile" ] || fail "--out a file: the file changed"
echo "ok --out a file: $err"
bad path_not_number "nan.txt:1" "$dir/t.png" --path "$dir/nan.txt"
bad path_missing "nosuch.txt" "$dir/t.png" --path "$dir/nosuch.txt"
mkdir -p "$dir/pathdir"
printf '1 2 \001\377\n4 5 6\n' > "$dir/bin.txt"
printf '0 0 1e300\n1 1 1\n' > "$dir/far.txt"
bad path_folder "pathdir: is a folder" "$dir/t.png" --path "$dir/pathdir"
bad path_binary "bin.txt:1: expected a number, found '??'" "$dir/t.png" --path "$dir/bin.txt"
bad path_far "far.txt:1: 1e+300 is beyond 1e15" "$dir/t.png" --path "$dir/far.txt"
bad tiny_dx "--dx 1e-300: must be between 1e-15 and 1e15" "$dir/t.png" --dx 1e-300
bad huge_dz "--dz 1e300: must be between 1e-15 and 1e15" "$dir/t.png" --dz 1e300
# a path's cameras under the ground are raised, and a note says so
printf '2560 2300 -5000 2560 2600 -5000\n2600 2300 -5000 2600 2600 -5000\n' > "$dir/under.txt"
err=$("$tessera" fly "$dir/t.png" --dx 20 --headless --frames 2 --width 32 --height 24 --path "$dir/under.txt" \
      --out "$dir/under" 2>&1) || fail "under the ground: $err"
echo "$err" | grep -q "note: .*under.txt: 2 of 2 cameras (the first at frame 0) were less than" ||
  fail "under the ground: no note: '$err'"
echo "ok a path under the ground: raised, with a note"
# the ends of --fov's range, as its help gives them, are taken
for fov in 1 170; do
  "$tessera" fly "$dir/t.png" --headless --frames 1 --width 32 --height 24 --fov $fov --out "$dir/fov" --quiet ||
    fail "--fov $fov refused"
done
echo "ok --fov 1 and 170"
bad empty_input "empty.png" "$dir/empty.png"
bad missing_input "nosuch.png" "$dir/nosuch.png"
bad bad_tile "tile" "$dir/t.png" --tile 12
bad bad_device "no Vulkan device matches" "$dir/t.png" --device no-such-gpu

# the window, under a virtual X server
if command -v xvfb-run >/dev/null; then
  err=$(xvfb-run -a -s "-screen 0 640x480x24" "$tessera" fly "$dir/t.png" --dx 20 --frames 30 --width 320 \
        --height 200 --stats "$dir/w.json" 2>&1) || fail "window: $err"
  # 30 frames; the device times known in a window too (frames overlap
  # there, so each is the latest finished frame's) where headless has them
  python3 - "$dir/w.json" "$dir/s.json" <<'PY' || fail "window stats"
import json, sys
w, h = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
assert len(w["frames"]) == 30, len(w["frames"])
if h["mean"]["draw_ms"] > 0:
    assert sum(f["draw_ms"] > 0 for f in w["frames"]) >= 25, [f["draw_ms"] for f in w["frames"]]
PY
  echo "ok window: 30 frames under Xvfb ($err)"
else
  echo "note: xvfb-run not installed; window smoke test not run"
fi
echo "all fly checks passed"
