#!/usr/bin/env bash
# Builds the fovea binary for cluster nodes: release, for a portable x86-64 level (x86-64-v3: AVX2,
# from 2013 on; the repository's `target-cpu=native` build may not run on another CPU), and without
# the Vulkan backend, so a node needs no Rust, no nightly, no Vulkan loader and no GPU: only glibc and libstdc++.
# Writes slurm-bin/fovea (git-ignored). Usage: scripts/slurm/build-portable.sh [--level x86-64-v2]
set -euo pipefail
cd "$(dirname "$0")/../.."
level=x86-64-v3
if [ "${1:-}" = --level ]; then level=$2; fi
export PATH="$HOME/.cargo/bin:$PATH"
echo "build-portable: building fovea (release, $level, CPU only) into target/portable-cpu"
# RUSTFLAGS replaces the repository's `target-cpu=native`.
RUSTFLAGS="-C target-cpu=$level" cargo build --release -p fovea-cli --no-default-features \
  --target-dir target/portable-cpu
mkdir -p slurm-bin
cp target/portable-cpu/release/fovea slurm-bin/fovea
strip --strip-debug slurm-bin/fovea
echo "build-portable: slurm-bin/fovea ($(du -h slurm-bin/fovea | cut -f1)); needs: $(ldd slurm-bin/fovea | awk '{print $1}' | tr '\n' ' ')"
