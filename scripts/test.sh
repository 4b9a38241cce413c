#!/usr/bin/env bash
# Sets up the machine, then runs every check CI runs: formatting, clippy, and all tests.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/setup-slurm.sh
# Monado, the OpenXR runtime `fovea xr`'s test runs against (built once per machine).
bash scripts/setup-monado.sh
export PATH="$HOME/.cargo/bin:$PATH"
echo "== cargo fmt --check"
cargo fmt --all -- --check
# The kernel and its builder are separate workspaces (the builder pins a nightly without rustfmt).
rustfmt --edition 2021 --check gpu-kernel/src/*.rs gpu-kernel/builder/src/*.rs
echo "== cargo clippy"
cargo clippy --workspace --all-targets -q -- -D warnings
# The CPU-only build (scripts/render-default.sh, scripts/slurm/build-portable.sh) has no Vulkan backend.
cargo clippy -p fovea-cli --no-default-features --all-targets -q -- -D warnings
echo "== cargo test"
cargo test --workspace
