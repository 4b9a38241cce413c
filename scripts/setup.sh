#!/usr/bin/env bash
# Installs what fovea needs on a fresh Debian or Ubuntu machine. Idempotent and quiet; safe to run again.
# - a Rust toolchain (cargo >= 1.87, the workspace's rust-version) and a C compiler for crates with build scripts;
# - for the Vulkan backend: the SPIR-V tools (spirv-val, spirv-opt), a Vulkan loader, Mesa's drivers (lavapipe
#   runs the kernel on the CPU where there is no GPU), vulkaninfo and the validation layers;
# - for `fovea view`'s tests: Xvfb (an X server without a screen) and xauth, which xvfb-run needs;
# - the pinned nightly that rust-gpu builds the kernel with (see docs/architecture.md, "GPU build").
set -euo pipefail

NIGHTLY=nightly-2026-08-15
MIN_RUST=1.87
NIGHTLY_COMPONENTS=(rust-src rustc-dev llvm-tools)

# --- apt packages -----------------------------------------------------------------------------------------
# xvfb and xauth: an X server for the tests of `fovea view`'s window (xvfb-run), where no desktop runs.
apt_packages=(gcc g++ pkg-config spirv-tools mesa-vulkan-drivers libvulkan1 vulkan-tools vulkan-validationlayers
  xvfb xauth)
need_apt=()
for pkg in "${apt_packages[@]}"; do
  if command -v dpkg-query >/dev/null 2>&1; then
    dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || need_apt+=("$pkg")
  fi
done
if ! command -v dpkg-query >/dev/null 2>&1; then
  # Not Debian-like: only check the commands the build itself runs.
  for cmd in cc pkg-config spirv-val spirv-opt; do
    command -v "$cmd" >/dev/null 2>&1 || need_apt+=("$cmd")
  done
fi
if [ ${#need_apt[@]} -gt 0 ]; then
  if command -v apt-get >/dev/null 2>&1; then
    SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    echo "setup: installing ${need_apt[*]}"
    $SUDO apt-get update -qq >/dev/null
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${need_apt[@]}" >/dev/null
  else
    echo "setup: please install: ${need_apt[*]}" >&2
    exit 1
  fi
fi

# --- lavapipe from Mesa 25 on Debian 12 -------------------------------------------------------------------
# Debian 12's own lavapipe (Mesa 22.3) masks every branch, both sides of every `if` always run, and renders
# fovea's kernel about 3x slower than Mesa 25.0 from bookworm-backports, which skips branches no lane takes
# (docs/performance.md, "lavapipe against the CPU host"). So on bookworm, lavapipe comes from backports (it needs only a
# newer libdrm; other Mesa packages are left alone). FOVEA_SYSTEM_LAVAPIPE=1 keeps the distribution's version.
if [ "${FOVEA_SYSTEM_LAVAPIPE:-0}" != 1 ] && command -v apt-get >/dev/null 2>&1 &&
  grep -q '^VERSION_CODENAME=bookworm' /etc/os-release 2>/dev/null; then
  lvp_version=$(dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null || true)
  case "$lvp_version" in
    2[5-9].*) ;;
    *)
      SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
      backports=/etc/apt/sources.list.d/fovea-bookworm-backports.list
      if ! grep -rqs 'bookworm-backports' /etc/apt/sources.list /etc/apt/sources.list.d/; then
        echo "deb http://deb.debian.org/debian bookworm-backports main" | $SUDO tee "$backports" >/dev/null
      fi
      echo "setup: installing lavapipe (mesa-vulkan-drivers) from bookworm-backports"
      $SUDO apt-get update -qq >/dev/null
      DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
        -t bookworm-backports mesa-vulkan-drivers >/dev/null ||
        { echo "setup: installing mesa-vulkan-drivers from bookworm-backports failed" >&2; exit 1; }
      ;;
  esac
fi

# --- stable Rust ------------------------------------------------------------------------------------------
if ! command -v cargo >/dev/null 2>&1; then
  if [ -x "$HOME/.cargo/bin/cargo" ]; then
    export PATH="$HOME/.cargo/bin:$PATH"
  else
    echo "setup: cargo not found. Install Rust ${MIN_RUST} or newer (https://rustup.rs) and run again." >&2
    exit 1
  fi
fi
# The workspace's `rust-version`: an older cargo would stop with a less direct message.
cargo_version=$(cargo --version | awk '{print $2}')
if [ "$(printf '%s\n%s\n' "$MIN_RUST" "${cargo_version%%-*}" | sort -V | head -1)" != "$MIN_RUST" ]; then
  echo "setup: cargo ${cargo_version} is older than ${MIN_RUST}, which fovea needs; run 'rustup update stable'." >&2
  exit 1
fi

# --- the kernel's nightly ---------------------------------------------------------------------------------
# FOVEA_CPU_ONLY=1 (scripts/render-default.sh): a build without the Vulkan backend needs no nightly.
if [ "${FOVEA_CPU_ONLY:-0}" = 1 ]; then
  echo "setup: $(cargo --version); CPU only (FOVEA_CPU_ONLY=1): the kernel's nightly is not installed"
  exit 0
fi
if command -v rustup >/dev/null 2>&1; then
  if ! rustup toolchain list | grep -q "^${NIGHTLY}"; then
    echo "setup: installing Rust ${NIGHTLY} (${NIGHTLY_COMPONENTS[*]}) for the GPU kernel"
    rustup toolchain install "$NIGHTLY" --profile minimal \
      --component "$(IFS=,; echo "${NIGHTLY_COMPONENTS[*]}")" >/dev/null 2>&1 ||
      { echo "setup: rustup toolchain install ${NIGHTLY} failed" >&2; exit 1; }
  fi
  installed=$(rustup component list --installed --toolchain "$NIGHTLY")
  missing=()
  for c in "${NIGHTLY_COMPONENTS[@]}"; do
    grep -q -e "^${c}\$" -e "^${c}-" <<<"$installed" || missing+=("$c")
  done
  if [ ${#missing[@]} -gt 0 ]; then
    echo "setup: adding ${missing[*]} to ${NIGHTLY}"
    rustup component add --toolchain "$NIGHTLY" "${missing[@]}" >/dev/null 2>&1 ||
      { echo "setup: rustup component add failed" >&2; exit 1; }
  fi
else
  echo "setup: rustup not found; the Vulkan backend needs Rust ${NIGHTLY} with ${NIGHTLY_COMPONENTS[*]}" >&2
fi

echo "setup: $(cargo --version); kernel toolchain ${NIGHTLY}"
