#!/usr/bin/env bash
# Builds Monado, the open-source OpenXR runtime, once per machine, for `fovea xr`'s test
# (cli/tests/xr.rs): its null compositor and simulated headset run headless, inside the test's
# process, on lavapipe. Debian 12 has the OpenXR loader but no runtime, so the runtime is built from
# the pinned source snapshot in ../shared/vendor (see its README: licence, packages, flags).
# scripts/test.sh runs this; FOVEA_SKIP_MONADO=1 skips it (the test then notes that it did not run,
# and fails under CI=true).
#
# Prints nothing when Monado is already built. The runtime's manifest ends up at
#   ${FOVEA_MONADO_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/fovea/monado}/build/openxr_monado-dev.json
# which the test finds by itself; for your own runs: export XR_RUNTIME_JSON=<that file>
# XRT_COMPOSITOR_NULL=1 (no window) and XDG_RUNTIME_DIR (Monado needs it).
set -euo pipefail
if [ "${FOVEA_SKIP_MONADO:-0}" = 1 ]; then
  echo "setup-monado: skipped (FOVEA_SKIP_MONADO=1)"
  exit 0
fi
root=$(cd "$(dirname "$0")/.." && pwd)
snapshot=f8e58ef6a16d
tarball="${FOVEA_MONADO_TARBALL:-$root/../shared/vendor/monado-$snapshot.tar.gz}"
dest="${FOVEA_MONADO_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/fovea/monado}"
marker="$dest/.built-$snapshot"
[ -f "$marker" ] && [ -f "$dest/build/openxr_monado-dev.json" ] && exit 0

# The packages the vendor README lists, and the loader `fovea xr` opens at run time.
packages=(cmake ninja-build pkg-config g++ libeigen3-dev glslang-tools libvulkan-dev libudev-dev
  libx11-xcb-dev libxrandr-dev libxcb-randr0-dev libhidapi-dev libusb-1.0-0-dev libcjson-dev
  libopenxr-loader1)
missing=()
for pkg in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
done
if [ ${#missing[@]} -gt 0 ]; then
  if ! command -v apt-get >/dev/null 2>&1; then
    echo "setup-monado: not a Debian-like system; install ${missing[*]} to build Monado" >&2
    exit 0
  fi
  # A developer's own account (not root, not CI) is not changed.
  if [ "$(id -u)" -ne 0 ] && [ "${CI:-}" != true ]; then
    echo "setup-monado: not root, so the OpenXR test will skip; to run it: sudo apt-get install ${missing[*]}"
    exit 0
  fi
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  echo "setup-monado: installing ${missing[*]}"
  if ! { $SUDO apt-get update -qq >/dev/null &&
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null; }; then
    echo "setup-monado: warning: installing ${missing[*]} failed; the OpenXR test will not run" >&2
    exit 0
  fi
fi
if [ ! -f "$tarball" ]; then
  echo "setup-monado: warning: no Monado snapshot at $tarball (FOVEA_MONADO_TARBALL names another); the OpenXR test will not run" >&2
  exit 0
fi
echo "setup-monado: building Monado $snapshot in $dest (a few minutes, once)"
rm -rf "$dest"
mkdir -p "$dest"
tar xzf "$tarball" -C "$dest"
src="$dest/monado-$snapshot"
# No service (the runtime runs in the application's process), no tests, no documentation; only the
# runtime and its manifest are built (254 of the 322 steps).
if ! { cmake -S "$src" -B "$dest/build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DXRT_FEATURE_SERVICE=OFF -DBUILD_TESTING=OFF -DBUILD_DOC=OFF >"$dest/cmake.log" 2>&1 &&
  ninja -C "$dest/build" openxr_monado-dev.json >"$dest/ninja.log" 2>&1; }; then
  echo "setup-monado: warning: building Monado failed (see $dest/cmake.log and ninja.log); the OpenXR test will not run" >&2
  exit 0
fi
touch "$marker"
echo "setup-monado: built; its manifest is $dest/build/openxr_monado-dev.json"
