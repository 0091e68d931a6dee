#!/usr/bin/env bash
# Installs the peer DEM codes used by bench/peer_compare.py (not part of scripts/install.sh):
#   lammps   -> /usr/bin/lmp       (Debian's build includes the GRANULAR package)
#   liggghts -> /usr/bin/liggghts  (LIGGGHTS-PUBLIC 3.8)
# Also the OpenMPI launcher (mpirun) that LIGGGHTS uses for its 2-rank runs.
set -euo pipefail
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO=sudo; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update
$SUDO apt-get install -y --no-install-recommends lammps liggghts openmpi-bin
# grep reads all of lmp's help (no -q): under pipefail, -q would stop early and lmp's
# SIGPIPE would fail the check on a good install
lmp -h 2>&1 | grep -w 'granular' >/dev/null || { echo "error: this lmp has no GRANULAR package (pair_style granular)" >&2; exit 1; }
command -v liggghts >/dev/null || { echo "error: liggghts not installed" >&2; exit 1; }
echo "peers installed: $(command -v lmp) $(command -v liggghts)"
