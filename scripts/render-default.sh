#!/usr/bin/env bash
# Sets up the machine, then renders the bundled Lost Empire foveated at 1920x1080 on the CPU.
# Extra arguments go to `fovea render` (e.g. --uniform, --resolution 3840x2160).
#
# The binary is built without the Vulkan backend (`--no-default-features`), so the first run needs
# neither the pinned nightly nor the rust-gpu kernel's build: on a fresh 2-core machine the build takes
# about 5 minutes instead of 8 (docs/performance.md, "Split renders, a one-node Slurm, and the first
# render"). `fovea view` and `--backend vulkan` need the full build: `cargo build --release -p fovea-cli`.
set -euo pipefail
cd "$(dirname "$0")/.."
FOVEA_CPU_ONLY=1 bash scripts/setup.sh
export PATH="$HOME/.cargo/bin:$PATH"
mkdir -p out
bin=target/cpu-only/release/fovea
if [ ! -x "$bin" ]; then
  echo "render-default: building fovea (release, CPU backend) for the first time: about 5 minutes on" \
    "2 cores; cargo shows its progress below"
fi
start=$(date +%s)
# A target folder of its own: the full build (with Vulkan) in target/ is not rebuilt back and forth.
cargo build --release -p fovea-cli --no-default-features --target-dir target/cpu-only
took=$(( $(date +%s) - start ))
[ "$took" -ge 10 ] && echo "render-default: built in ${took} s"
"$bin" render --output out/lost_empire.png \
  --regions-overlay out/lost_empire_regions.png --stats out/lost_empire.json "$@"
