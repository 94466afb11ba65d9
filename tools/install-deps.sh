#!/usr/bin/env bash
# Installs, from Debian 12 packages only, everything Tessera's build, tests
# and demo need. Idempotent: when every package is present it does nothing
# (no apt-get update, no network). Works as root, or through sudo otherwise.
# The npm test and benchmark tools (gltf-validator, and the peer meshers
# delatin and @mapbox/martini) go into build/node_modules, not the system,
# so the script never needs network when they are already there.
set -euo pipefail

PKGS=(
  build-essential cmake pkg-config make git ca-certificates
  libopenimageio-dev openimageio-tools
  libosd-dev
  libglfw3-dev
  libvulkan-dev mesa-vulkan-drivers vulkan-tools vulkan-validationlayers
  glslc
  xvfb xauth
  libcjson-dev
  libgdal-dev libtiff-dev
  libmeshoptimizer-dev
  assimp-utils
  nodejs npm
  clang libclang-rt-14-dev
)

missing=()
for p in "${PKGS[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

# Node and npm may come from outside Debian's packaging on some machines
# (they are on PATH already); accept those rather than fight them.
if command -v node >/dev/null 2>&1 && command -v npm >/dev/null 2>&1; then
  tmp=()
  for p in "${missing[@]}"; do
    [[ "$p" == nodejs || "$p" == npm ]] || tmp+=("$p")
  done
  missing=("${tmp[@]+"${tmp[@]}"}")
fi

if ((${#missing[@]})); then
  echo "install-deps: installing ${missing[*]}" >&2
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
      echo "install-deps: need root or sudo to install: ${missing[*]}" >&2; exit 1
    fi
  fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# Test and benchmark npm tools, installed into the build tree (not
# committed): the Khronos glTF validator (the tests check every .glb with
# it), and the peer meshers of `tessera bench mesh --peers` and its test,
# delatin (the JavaScript port of hmm, Garland-Heckbert) and
# @mapbox/martini (RTIN). Optional for the demo.
here=$(cd "$(dirname "$0")/.." && pwd)
npm_pkgs=()
[ -f "$here/build/node_modules/gltf-validator/package.json" ] || npm_pkgs+=(gltf-validator@2.0.0-dev.3.10)
[ -f "$here/build/node_modules/delatin/package.json" ] || npm_pkgs+=(delatin@0.2.0)
[ -f "$here/build/node_modules/@mapbox/martini/package.json" ] || npm_pkgs+=(@mapbox/martini@0.2.0)
if [ "${TSR_SKIP_NPM:-0}" != 1 ] && [ ${#npm_pkgs[@]} -gt 0 ]; then
  echo "install-deps: installing npm ${npm_pkgs[*]} into build/node_modules" >&2
  mkdir -p "$here/build"
  (cd "$here/build" && { [ -f package.json ] || echo '{"private":true}' > package.json; } \
     && npm install --no-audit --no-fund --silent "${npm_pkgs[@]}" >/dev/null)
fi
exit 0
