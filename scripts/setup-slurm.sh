#!/usr/bin/env bash
# Installs what the Slurm recipe's test needs (cli/tests/split.rs, scripts/slurm/local-cluster.sh):
# Debian's Slurm 22.05 controller, node daemon and client, and munge. scripts/test.sh runs it, so CI
# tests the recipe on a real one-node Slurm; FOVEA_SKIP_SLURM=1 skips it (the test then notes that
# it did not run). The packages' own services are not used: local-cluster.sh starts private daemons
# in a temporary folder.
set -euo pipefail
if [ "${FOVEA_SKIP_SLURM:-0}" = 1 ]; then
  echo "setup-slurm: skipped (FOVEA_SKIP_SLURM=1)"
  exit 0
fi
packages=(slurmctld slurmd slurm-client munge)
missing=()
for pkg in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
done
[ ${#missing[@]} -eq 0 ] && exit 0
# The test starts slurmd, which needs root: a developer's own account (not root, not CI) is not changed.
if [ "$(id -u)" -ne 0 ] && [ "${CI:-}" != true ]; then
  echo "setup-slurm: not root, so the Slurm test will skip; to run it: sudo apt-get install ${missing[*]}"
  exit 0
fi
if ! command -v apt-get >/dev/null 2>&1; then
  echo "setup-slurm: not a Debian-like system; install ${missing[*]} (Slurm and munge) to run the Slurm test" >&2
  exit 0
fi
SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
echo "setup-slurm: installing ${missing[*]}"
# Where systemd runs, Debian enables the packages' services: slurmctld and slurmd find no
# /etc/slurm/slurm.conf and stop; munged runs with its own key. The test uses none of them.
# A failed install is a warning: the test then skips (and fails under CI=true, which names it).
if ! { $SUDO apt-get update -qq >/dev/null &&
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null; }; then
  echo "setup-slurm: warning: installing ${missing[*]} failed; the Slurm test will not run" >&2
fi
