#!/usr/bin/env bash
# check_patches.sh TESSERA [DATA]: `tessera check patches` end to end. The
# check itself is the oracle (tsr_ptess_measure against the patches' own
# evaluation, validation, crack search); here we make sure it runs and
# passes on a generated rational surface, on the teapot and on OpenSubdiv
# cages, that it can fail, and that bad input fails cleanly, naming the
# file. Exits 77 (skipped) after the data-free cases when DATA is absent.
set -u
tessera=$1 data=${2:-}
dir=$(mktemp -d "${TMPDIR:-/tmp}/tsr-check-patches-XXXXXX")
trap 'rm -rf "$dir"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

# expect_ok NAME FILE ARGS...: exit 0, the summary line says no run failed
expect_ok() {
  local name=$1 file=$2
  shift 2
  "$tessera" check patches "$file" "$@" > "$dir/out.txt" 2> "$dir/err.txt"
  local rc=$?
  [ $rc -eq 0 ] || fail "$name: exit $rc: $(grep -h FAIL "$dir/out.txt" | head -3) $(cat "$dir/err.txt")"
  grep -q "^view-independent .* ok$" "$dir/out.txt" || fail "$name: no passing view-independent run"
  grep -q "; 0 of [0-9]* runs failed$" "$dir/out.txt" || fail "$name: $(tail -1 "$dir/out.txt")"
  echo "ok $name: $(tail -1 "$dir/out.txt")"
}

# expect_bad NAME FILE: exit 1 (not a crash, not usage), one message naming the file
expect_bad() {
  local name=$1 file=$2
  "$tessera" check patches "$file" > "$dir/out.txt" 2> "$dir/err.txt"
  local rc=$?
  [ $rc -eq 1 ] || fail "$name: exit $rc, expected 1: $(cat "$dir/err.txt")"
  grep -qF "$file" "$dir/err.txt" || fail "$name: the message does not name the file: $(cat "$dir/err.txt")"
  echo "ok $name refused: $(head -1 "$dir/err.txt")"
}

# The check certifies what `tessera patch` writes: on a cylinder as one
# rational B-spline of four quarter circles (knot spans curved one way,
# which patch cuts across their curve for the bound), the view-independent
# run makes the same triangles as patch (it made 4x as many before)
{
  for z in 0 2; do
    awk -v z=$z 'BEGIN { h = sqrt(2) / 2
      split("1 1 0 -1 -1 -1 0 1 1", x, " "); split("0 1 1 1 0 -1 -1 -1 0", y, " ")
      for (i = 1; i <= 9; i++) printf "v %g %g %g %.17g\n", x[i], y[i], z, i % 2 ? 1 : h }'
  done
  echo "cstype rat bspline"; echo "deg 2 1"; echo "surf 0 1 0 1 $(seq -s ' ' 1 18)"
  echo "parm u 0 0 0 0.25 0.25 0.5 0.5 0.75 0.75 1 1 1"; echo "parm v 0 0 1 1"; echo "end"
} > "$dir/cyl.obj"
"$tessera" patch "$dir/cyl.obj" -o "$dir/cyl_out.obj" --stats "$dir/cyl.json" --quiet || fail "patch cyl.obj"
"$tessera" check patches "$dir/cyl.obj" --cameras 0 --json > "$dir/cylc.json" || fail "check cyl.obj"
python3 - "$dir/cyl.json" "$dir/cylc.json" <<'PY' || fail "check and patch tessellate the cylinder differently"
import json, sys
p, c = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
assert p["triangles"] == c["view_independent"]["triangles"], (p["triangles"], c["view_independent"]["triangles"])
print("ok check = patch on a split model: %d triangles" % p["triangles"])
PY

# A rational biquadratic Bezier patch that is exactly a sphere octant: the
# quarter circle (1,0), (1,1), (0,1) with weights 1, sqrt(2)/2, 1 swept
# around z by the same circle, P_ij = (r_j C_i, z_j), w_ij = w_i w_j. Its
# north edge collapses to the pole (0, 0, 1).
octant() { # sx sy sz: the octant mirrored by these signs
  awk -v sx="$1" -v sy="$2" -v sz="$3" 'BEGIN {
    h = sqrt(2) / 2
    cx[0] = 1; cy[0] = 0; cw[0] = 1; cx[1] = 1; cy[1] = 1; cw[1] = h; cx[2] = 0; cy[2] = 1; cw[2] = 1
    r[0] = 1; z[0] = 0; mw[0] = 1; r[1] = 1; z[1] = 1; mw[1] = h; r[2] = 0; z[2] = 1; mw[2] = 1
    for (j = 0; j < 3; j++)
      for (i = 0; i < 3; i++)
        printf "v %.17g %.17g %.17g %.17g\n", sx * r[j] * cx[i], sy * r[j] * cy[i], sz * z[j], cw[i] * mw[j]
  }'
}
{
  echo "# sphere octant, rational Bezier 2x2"
  octant 1 1 1
  echo "cstype rat bezier"
  echo "deg 2 2"
  echo "surf 0 1 0 1 1 2 3 4 5 6 7 8 9"
  echo "parm u 0 1"
  echo "parm v 0 1"
  echo "end"
} > "$dir/octant.obj"
expect_ok "sphere octant" "$dir/octant.obj" --cameras 4
# not vacuous: the octant's error is a good part of the tolerance
awk '/^view-independent/ { for (i = 1; i < NF; i++) if ($i == "max_error") exit !($(i + 1) > 1e-4) }' "$dir/out.txt" \
  || fail "octant: error too small to test anything: $(grep ^view "$dir/out.txt")"

# the whole sphere: eight octants, four of them mirrored, joined along their
# edges and meeting at the poles
{
  for s in "1 1 1" "-1 1 1" "1 -1 1" "-1 -1 1" "1 1 -1" "-1 1 -1" "1 -1 -1" "-1 -1 -1"; do
    # shellcheck disable=SC2086
    octant $s
  done
  echo "cstype rat bezier"
  echo "deg 2 2"
  for k in 0 1 2 3 4 5 6 7; do
    echo "surf 0 1 0 1 $(seq -s ' ' $((9 * k + 1)) $((9 * k + 9)))"
    echo "end"
  done
} > "$dir/sphere.obj"
expect_ok "sphere of 8 octants" "$dir/sphere.obj" --cameras 4 --seed 7

# JSON carries the keys of check terrain where they mean something, and ours
"$tessera" check patches "$dir/octant.obj" --cameras 2 --json > "$dir/out.json" || fail "json check failed"
for k in input pixel_error max_error cameras eye target max_pixel_error watertight conforming triangles seconds \
         view_independent bound vertices patches failures; do
  grep -q "\"$k\"" "$dir/out.json" || fail "no key $k in the JSON"
done
echo "ok json keys"

# the check can fail: a tolerance the depth given cannot reach (the
# default depth would be retried at 12, as tessera patch does)
"$tessera" check patches "$dir/octant.obj" --cameras 0 --max-error 1e-6 --max-level 3 > "$dir/tight.txt" 2>&1
[ $? -eq 1 ] || fail "an unreachable tolerance passed: $(tail -1 "$dir/tight.txt")"
grep -q "FAIL beyond-tolerance" "$dir/tight.txt" || fail "no beyond-tolerance failure: $(cat "$dir/tight.txt")"
echo "ok an unreachable tolerance fails"
# and one below what float positions can hold is refused, as by tessera patch
"$tessera" check patches "$dir/octant.obj" --cameras 0 --max-error 1e-12 > "$dir/tight.txt" 2>&1
[ $? -eq 2 ] && grep -q "below what the float32 mesh can hold" "$dir/tight.txt" ||
  fail "an impossible tolerance not refused: $(cat "$dir/tight.txt")"
echo "ok an impossible tolerance refused"

# T-junctions along patch edges without neighbour are no failure, and only
# those. Two coplanar cage triangles on one edge, 3 4 1 and 3 4 2, overlap
# (catmark_val2_nonman's faces 13 and 14): their shared edge runs the same
# way in both (non-manifold: no neighbour), their other edges are boundary,
# and with the boundary interpolated each limit sheet's open edge from a
# corner to the midpoint of a cage edge runs along the other's median:
# interior vertices of one sheet lie inside the other's open edges. Nothing
# is to be joined there (ptess.h links no such edge), so the check passes
# and reports them apart, as unlinked_edge_t_junctions.
cat > "$dir/overlap.obj" <<'EOF'
v 0.3 0 -0.7
v 0.7 0 -0.7
v 0.3 -0.2 -0.9
v 0.7 -0.2 -0.9
f 3 4 1
f 3 4 2
t interpolateboundary 1/0/0 1
EOF
json_count() { # KEY FILE: the view-independent run's count (its keys come before the cameras')
  grep -o "\"$1\":[[:space:]]*[0-9]*" "$2" | head -1 | grep -o '[0-9]*$'
}
expect_ok "overlapping cage triangles" "$dir/overlap.obj" --cameras 2
"$tessera" check patches "$dir/overlap.obj" --cameras 0 --json > "$dir/overlap.json" || fail "overlap: json check failed"
counted=$(json_count t_junctions "$dir/overlap.json")
discounted=$(json_count unlinked_edge_t_junctions "$dir/overlap.json")
[ "$counted" = 0 ] || fail "overlap: '$counted' T-junctions counted"
[ -n "$discounted" ] && [ "$discounted" -gt 0 ] || fail "overlap: no unlinked-edge T-junction reported: vacuous"
echo "ok overlap: $discounted T-junctions along unlinked edges reported, none counted"
# The other half: the same T-junctions on edges taken as linked, as a crack
# between joined patches would leave them (ptess.h leaves no linked edge
# open, so the check is told to assume the links), all fail.
"$tessera" check patches "$dir/overlap.obj" --cameras 0 --assume-linked > "$dir/linked.txt" 2>&1
[ $? -eq 1 ] || fail "T-junctions on linked edges passed: $(tail -1 "$dir/linked.txt")"
grep -q "^view-independent .* FAIL.* t-junctions $discounted\( \|$\)" "$dir/linked.txt" \
  || fail "linked: not the $discounted T-junctions counted: $(grep ^view "$dir/linked.txt")"
! grep -q "unlinked-edge-t-junctions" "$dir/linked.txt" || fail "linked: T-junctions discounted: $(grep ^view "$dir/linked.txt")"
echo "ok the same T-junctions on linked edges fail:$(grep -o ' FAIL.*' "$dir/linked.txt" | head -1)"

# A T-configuration: a bicubic sheet whose north edge, a cubic curve, is
# the south edge of two patches above, cut at u = 1/2 (de Casteljau). The
# sheet is cut there too and linked to both: the check passes with no gap
# and patch's mesh is one disc. The same with the first patch above raised
# by 1e-4 (more than the link distance, less than the tolerance) leaves a
# crack narrower than the tolerance: the check finds it as gaps and fails.
tcfg() { # RAISE > FILE
  python3 - "$1" <<'PY'
import sys
raise_ = float(sys.argv[1])
cz = [0.0, 0.4, -0.3, 0.2]
def split(c):
    a = c[:]; L = [a[0]]; R = [a[3]]
    for k in range(1, 4):
        a = [0.5 * (a[i] + a[i + 1]) for i in range(len(a) - 1)]
        L.append(a[0]); R.insert(0, a[-1])
    return L, R
L, R = split(cz)
pats = [(0, 2, 0, cz, 0), (0, 1, 1, L, raise_), (1, 2, 1, R, 0)]
print(len(pats))
for x0, x1, y0, zs, dz in pats:
    print("3 3")
    for j in range(4):
        for i in range(4):
            print("%.17g %.17g %.17g" % (x0 + (x1 - x0) * i / 3, y0 + j / 3, zs[i] + (dz if j == 0 else 0)))
PY
}
tcfg 0 > "$dir/tconfig.bpt" && tcfg 1e-4 > "$dir/tcrack.bpt" || fail "python3 could not write the T-configurations"
expect_ok "T-configuration" "$dir/tconfig.bpt" --cameras 2
"$tessera" check patches "$dir/tconfig.bpt" --cameras 0 --json > "$dir/tconfig.json" || fail "tconfig: json check"
[ "$(json_count gaps "$dir/tconfig.json")" = 0 ] || fail "tconfig: gaps $(json_count gaps "$dir/tconfig.json")"
"$tessera" patch "$dir/tconfig.bpt" -o "$dir/tconfig.obj" --quiet || fail "patch tconfig.bpt"
python3 - "$dir/tconfig.obj" <<'PY' || fail "T-configuration: the mesh is not one disc"
import sys
tris = [tuple(int(w.split('/')[0]) for w in l.split()[1:4]) for l in open(sys.argv[1]) if l.startswith('f ')]
edges = {}
for t in tris:
    for k in range(3):
        e = (t[k], t[(k + 1) % 3])
        edges[e] = edges.get(e, 0) + 1
open_ = [e for e in edges if (e[1], e[0]) not in edges]
verts = {v for t in tris for v in t}
# V - E + F with E = (interior half-edges) / 2 + open edges
E = (len(edges) - len(open_)) // 2 + len(open_)
chi = len(verts) - E + len(tris)
sys.exit(0 if chi == 1 and all(c == 1 for c in edges.values()) else 1)
PY
echo "ok T-configuration linked: one disc, no gap"
"$tessera" check patches "$dir/tcrack.bpt" --cameras 0 > "$dir/tcrack.txt" 2>&1
[ $? -eq 1 ] || fail "a crack narrower than the tolerance passed: $(grep ^view "$dir/tcrack.txt")"
grep -q "^view-independent .* FAIL.* gaps [1-9]" "$dir/tcrack.txt" || fail "tcrack: no gaps: $(grep ^view "$dir/tcrack.txt")"
echo "ok a crack narrower than the tolerance fails:$(grep -o ' FAIL.*' "$dir/tcrack.txt" | head -1)"

# a fin on a plate: three bilinear patches along one edge, the plate's half
# split at u = 0.3 and the fin at v = 0.7 so that they sample the edge
# differently unless linked all three ways: the check passes, counting the
# edge's mesh edges as three-patch edges (each has three triangles), and no gap
{
  printf 'v 0 0 0\nv 0 0 1\nv 1 0 0\nv 1 0 1\nv 0 1 0\nv 0 1 1\nv -1 -1 0\nv -1 -1 1\n'
  printf 'v 0.3 0 0\nv 0.3 0 1\nv 0 0 0.7\nv -1 -1 0.7\ncstype bspline\ndeg 1 1\n'
  printf 'surf 0 1 0 1 1 9 3 2 10 4\nparm u 0 0 0.3 1 1\nparm v 0 0 1 1\nend\n'
  printf 'surf 0 1 0 1 1 5 2 6\nparm u 0 0 1 1\nparm v 0 0 1 1\nend\n'
  printf 'surf 0 1 0 1 1 7 11 12 2 8\nparm u 0 0 1 1\nparm v 0 0 0.7 1 1\nend\n'
} > "$dir/fin.obj"
expect_ok "a fin on a plate" "$dir/fin.obj" --cameras 1
"$tessera" check patches "$dir/fin.obj" --cameras 0 --json > "$dir/fin.json" || fail "fin: json check"
python3 - "$dir/fin.json" <<'PY' || fail "fin: $(cat "$dir/fin.json" | head -c 600)"
import json, sys
v = json.load(open(sys.argv[1]))["view_independent"]
assert v["three_patch_edges"] >= 2 and v["gaps"] == 0, (v["three_patch_edges"], v["gaps"])
print("ok a fin on a plate: %d three-patch edges, no gap" % v["three_patch_edges"])
PY
# a fin along a closed cylinder's seam: two of the three patch edges are
# sides of one patch (u = 0 and u = 4), which the check counted as no
# three-patch edge (a reviewer's case)
{
  for z in 0 1; do
    awk -v z=$z 'BEGIN { h = sqrt(2) / 2
      split("1 1 0 -1 -1 -1 0 1 1", x, " "); split("0 1 1 1 0 -1 -1 -1 0", y, " ")
      for (i = 1; i <= 9; i++) printf "v %g %g %g %.17g\n", x[i], y[i], z, i % 2 ? 1 : h }'
  done
  echo "cstype rat bspline"; echo "deg 2 1"; echo "surf 0 4 0 1 $(seq -s ' ' 1 18)"
  echo "parm u 0 0 0 1 1 2 2 3 3 4 4 4"; echo "parm v 0 0 1 1"; echo "end"
  printf 'v 1 0 0\nv 2 0 0\nv 1 0 1\nv 2 0 1\ncstype bezier\ndeg 1 1\nsurf 0 1 0 1 19 20 21 22\nend\n'
} > "$dir/cyl_fin.obj"
expect_ok "a fin along a cylinder's seam" "$dir/cyl_fin.obj" --cameras 1

# two unit squares side by side, each trimmed by its own border given to
# 1e-6 (as CAD files give it): the loops' points that near the border go
# onto it, so the faces meet without a sliver between them
cat > "$dir/trimmed_pair.obj" <<'OBJ'
v 0 0 0
v 1 0 0
v 0 1 0
v 1 1 0
v 1 0 0
v 2 0 0
v 1 1 0
v 2 1 0
vp 0.000001 -0.000001
vp 1.000001 0.000001
vp 0.999999 1.000001
vp -0.000001 0.999999
vp 0.000001 -0.000001
cstype bspline
deg 1
curv2 1 2 3 4 5
parm u 0 0 0.25 0.5 0.75 1 1
end
cstype bezier
deg 1 1
surf 0 1 0 1 1 2 3 4
trim 0 1 1
end
surf 0 1 0 1 5 6 7 8
trim 0 1 1
end
OBJ
"$tessera" check patches "$dir/trimmed_pair.obj" --cameras 0 > "$dir/tp.txt" 2>&1 ||
  fail "faces trimmed by their own borders to 1e-6: $(cat "$dir/tp.txt")"
echo "ok faces trimmed by their own borders to 1e-6 meet"

# a rational cylinder under a square lid trimmed by a circle: the trim
# curve is not joined to the cylinder's rim (ptess.h), so both sides of
# that seam are unjoined gaps, reported and not failed; patch notes them
{
  circle="1 0|1 1|0 1|-1 1|-1 0|-1 -1|0 -1|1 -1|1 0"
  for z in 0 2; do
    k=0; IFS='|'
    for p in $circle; do
      w=1; [ $((k % 2)) -eq 1 ] && w=0.70710678118654757
      echo "v $p $z $w"; k=$((k + 1))
    done; unset IFS
  done
  printf 'cstype rat bspline\ndeg 2 1\nsurf 0 1 0 1 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18\n'
  printf 'parm u 0 0 0 0.25 0.25 0.5 0.5 0.75 0.75 1 1 1\nparm v 0 0 1 1\nend\n'
  k=0; IFS='|'
  for p in $circle; do
    w=1; [ $((k % 2)) -eq 1 ] && w=0.70710678118654757
    echo "vp $p $w"; k=$((k + 1))
  done; unset IFS
  printf 'cstype rat bspline\ndeg 2\ncurv2 1 2 3 4 5 6 7 8 9\nparm u 0 0 0 0.25 0.25 0.5 0.5 0.75 0.75 1 1 1\nend\n'
  printf 'v -1 -1 2\nv 1 -1 2\nv -1 1 2\nv 1 1 2\n'
  printf 'cstype bezier\ndeg 1 1\nsurf -1 1 -1 1 19 20 21 22\nparm u -1 1\nparm v -1 1\ntrim 0 1 1\nend\n'
} > "$dir/cyl_cap.obj"
"$tessera" check patches "$dir/cyl_cap.obj" --cameras 0 > "$dir/cc.txt" 2>&1 ||
  fail "a trimmed cap under a cylinder: $(cat "$dir/cc.txt")"
grep -q "^view-independent .*unjoined-gaps [1-9][0-9]*  ok" "$dir/cc.txt" || fail "cyl_cap: $(grep ^view "$dir/cc.txt")"
"$tessera" patch "$dir/cyl_cap.obj" -o "$dir/cc.ply" 2> "$dir/cc.err" || fail "patch cyl_cap: $(cat "$dir/cc.err")"
grep -q "note: [0-9]* open edges lie along a trimmed patch's boundary" "$dir/cc.err" && ! grep -q warning "$dir/cc.err" ||
  fail "patch cyl_cap: $(cat "$dir/cc.err")"
echo "ok a trim-curve seam is reported as unjoined on both sides"

# bad input fails cleanly, naming the file
expect_bad "missing file" "$dir/missing.bpt"
: > "$dir/empty.obj"
expect_bad "empty file" "$dir/empty.obj"
: > "$dir/empty.bpt"
expect_bad "empty bpt" "$dir/empty.bpt"
head -c 4096 /dev/urandom > "$dir/garbage.bpt"
expect_bad "garbage bpt" "$dir/garbage.bpt"
head -c 4096 /dev/urandom > "$dir/garbage.obj"
expect_bad "garbage obj" "$dir/garbage.obj"
printf 'v 0 0 0\nv 1 0 0\nf 1 2 9\n' > "$dir/badface.obj"
expect_bad "cage with a bad index" "$dir/badface.obj"
printf 'hello\n' > "$dir/notes.txt"
expect_bad "unknown format" "$dir/notes.txt"
# bad usage: exit 2
for args in "--max-error 0" "--tile 3" "--max-level 13" "--camera 1,2,3" "--scheme loop" "--cameras -1"; do
  # shellcheck disable=SC2086
  "$tessera" check patches "$dir/octant.obj" $args > /dev/null 2>&1
  rc=$?
  [ $rc -eq 2 ] || fail "'$args' gave exit $rc, expected 2"
done
echo "ok bad usage"

if [ -z "$data" ] || [ ! -d "$data/patches" ]; then
  echo "teapot and cages skipped: no shared data"
  exit 77
fi

expect_ok teapot "$data/patches/teapot.bpt"
# a .bpt cut in the middle of a patch
head -n 200 "$data/patches/teapot.bpt" > "$dir/truncated.bpt"
expect_bad "truncated bpt" "$dir/truncated.bpt"

for shape in catmark_cube catmark_cube_creases1 catmark_gregory_test1 catmark_fan catmark_hole_test1 bilinear_cube \
             catmark_val2_nonman; do
  expect_ok "$shape" "$data/patches/osd/$shape.obj" --cameras 3
done
# the scheme can be forced: the cube's cage as a bilinear surface is the cage itself
expect_ok "catmark_cube as bilinear" "$data/patches/osd/catmark_cube.obj" --cameras 1 --scheme bilinear
grep -q "cage-bilinear" "$dir/out.txt" || fail "--scheme bilinear not used: $(head -1 "$dir/out.txt")"
