# Sourced by the scripts that run Mitsuba 3 beside fovea (bench-peer.sh, bench-rays.sh), from the
# repository root: sets KIT (the peer kit, ../shared/peer) and PEER_WORK (default ./peer-work), installs the
# kit's venv and generates its scenes on first use, and points Dr.Jit at the kit's kernel cache and at
# libLLVM 19 as the kit's run.sh does.
KIT="$(cd ../shared/peer && pwd)"
export PEER_WORK="${PEER_WORK:-$PWD/peer-work}"
[ -x "$PEER_WORK/venv/bin/python" ] || bash "$KIT/run.sh" setup
[ -f "$PEER_WORK/scenes/big/big.obj" ] || bash "$KIT/run.sh" scenes
export DRJIT_CACHE_DIR="$PEER_WORK/drjit_cache"
if [ -z "${DRJIT_LIBLLVM_PATH:-}" ]; then
  for f in /usr/lib/*/libLLVM.so.19* /usr/lib/*/libLLVM-19.so* /usr/lib/llvm-19/lib/libLLVM*.so*; do
    if [ -f "$f" ]; then export DRJIT_LIBLLVM_PATH="$f"; break; fi
  done
fi
# The kit's camera (camera.json) and integrator (max_depth 4 = 3 bounces) as fovea options, uniform sampling.
PEER_FOVEA_VIEW=(--uniform --eye 0,0,2.8 --target 0,0,-1 --fov 45 --depth 3)
# The kit's materials: its purely diffuse MTL materials are Mitsuba `diffuse`, so Lambertian in fovea too
# (separate from the view, so that scripts/bench-ab.sh can still run builds older than the option).
PEER_FOVEA_MATERIALS=(--mtl-diffuse lambert)
