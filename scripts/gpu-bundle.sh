#!/usr/bin/env bash
# Prepares, on this machine, everything one short run on a bare Linux x86-64 machine with an NVIDIA driver
# needs (no Rust, no package registry there): folder `gpu/` (git-ignored) with
#   gpu/fovea   the release binary for a portable x86-64 level (x86-64-v3: AVX2; the repository's
#               `target-cpu=native` build may not run on another CPU), both kernel modules embedded;
#   gpu/debs/   the Vulkan loader (Debian's libvulkan1) and the GL vendor-neutral libraries (libglvnd)
#               that the NVIDIA driver's Vulkan ICD links against, unpacked there by scripts/gpu-run.sh
#               when the machine lacks them (with the loader alone, the loader found "no compatible
#               driver" on an H200 container).
# Lost Empire travels with the repository (assets/). Then, with the `device` tool (see
# /work/.library/device/README.md): run `bash scripts/gpu-run.sh` there with `carry: ["gpu"]`.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
export PATH="$HOME/.cargo/bin:$PATH"
mkdir -p gpu/debs
echo "gpu-bundle: building the release binary for x86-64-v3 (target/portable)"
# RUSTFLAGS replaces the repository's `target-cpu=native`; the kernel's nested build ignores both.
RUSTFLAGS="-C target-cpu=x86-64-v3" cargo build --release -q -p fovea-cli --target-dir target/portable
cp target/portable/release/fovea gpu/fovea
strip --strip-debug gpu/fovea  # line tables are not needed there; keeps the carried tree small
echo "gpu-bundle: downloading the Vulkan loader and libglvnd (amd64)"
apt_opts=(-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/fovea-amd64-lists)
mkdir -p /tmp/fovea-amd64-lists/partial
apt-get "${apt_opts[@]}" update -qq >/dev/null
(cd gpu/debs && rm -f ./*.deb && apt-get "${apt_opts[@]}" download libvulkan1 libglvnd0 libglx0 libegl1 libgl1 libgles2 libopengl0 >/dev/null)
du -sh gpu/fovea gpu/debs
echo "gpu-bundle: ready; on the GPU machine: bash scripts/gpu-run.sh (carry gpu/)"
