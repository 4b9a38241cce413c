#!/usr/bin/env bash
# Sets up the machine, then renders the bundled Lost Empire foveated at 1920x1080 on the CPU.
# Extra arguments go to `fovea render` (e.g. --uniform, --resolution 3840x2160).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
export PATH="$HOME/.cargo/bin:$PATH"
mkdir -p out
cargo run --release -q -p fovea-cli -- render --output out/lost_empire.png \
  --regions-overlay out/lost_empire_regions.png --stats out/lost_empire.json "$@"
