#!/usr/bin/env bash
# Installs, from Debian 12 packages only, everything Tessera's build, tests
# and demo need. Idempotent: when every package is present it does nothing
# (no apt-get update, no network). Works as root, or through sudo otherwise.
# The npm test tool (gltf-validator) goes into build/node_modules, not the
# system, so the script never needs network when it is already there.
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
  libgdal-dev
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

# Test-only npm tool: the Khronos glTF validator, installed into the build
# tree (not committed). Optional for the demo, required by the tests.
here=$(cd "$(dirname "$0")/.." && pwd)
if [ "${TSR_SKIP_NPM:-0}" != 1 ] && [ ! -f "$here/build/node_modules/gltf-validator/package.json" ]; then
  echo "install-deps: installing npm gltf-validator into build/node_modules" >&2
  mkdir -p "$here/build"
  (cd "$here/build" && { [ -f package.json ] || echo '{"private":true}' > package.json; } \
     && npm install --no-audit --no-fund --silent gltf-validator@2.0.0-dev.3.10 >/dev/null)
fi
exit 0
