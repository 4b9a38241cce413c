#!/usr/bin/env bash
# Sets up FovVideoVDP (Mantiuk et al. 2021, `pyfvvdp` on PyPI) for `fovea report --gaze-trace`, in its
# own virtual environment: $FOVEA_FVVDP_VENV, else $XDG_CACHE_HOME/fovea/fvvdp-venv, else
# ~/.cache/fovea/fvvdp-venv. `fovea report` looks there and says how to run this script if it is missing.
#
# PyTorch comes from Debian's CPU-only `python3-torch` (about 190 MB to download, 1 GB on disk): the
# PyTorch wheel index is not reachable from every machine and PyPI's wheel pulls several GB of CUDA.
# Where `import torch` already works for /usr/bin/python3 the apt step is skipped.
set -euo pipefail
VENV="${FOVEA_FVVDP_VENV:-${XDG_CACHE_HOME:-$HOME/.cache}/fovea/fvvdp-venv}"
PYTHON=/usr/bin/python3

if ! "$PYTHON" -c "import torch, scipy" 2>/dev/null; then
    if ! command -v apt-get >/dev/null; then
        echo "setup-fvvdp: no apt-get; install PyTorch (CPU) and SciPy for $PYTHON, then run this again" >&2
        exit 1
    fi
    SUDO=""
    if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi
    echo "== apt: python3-torch python3-scipy python3-venv (CPU PyTorch from Debian)"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
        python3-torch python3-scipy python3-venv python3-pip >/dev/null
fi

if [ ! -x "$VENV/bin/python" ]; then
    echo "== venv $VENV"
    mkdir -p "$(dirname "$VENV")"
    "$PYTHON" -m venv --system-site-packages "$VENV"
fi
echo "== pip: pyfvvdp 1.2.2"
# --no-deps: pyfvvdp also asks for the unrelated `ffmpeg` package, whose module clashes with
# ffmpeg-python's; torch, numpy and scipy come from the system.
"$VENV/bin/pip" install -q --no-deps pyfvvdp==1.2.2 ffmpeg-python==0.2.0 future
"$VENV/bin/pip" install -q 'imageio>=2.19.5,<3'
"$VENV/bin/python" - <<'PY'
import pyfvvdp, torch
fv = pyfvvdp.fvvdp(display_name="standard_4k", foveated=True, device=torch.device("cpu"), quiet=True)
print("setup-fvvdp: ready:", fv.get_info_string(), "torch", torch.__version__)
PY
echo "setup-fvvdp: done ($VENV)"
