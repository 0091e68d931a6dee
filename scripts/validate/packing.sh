#!/usr/bin/env bash
# Packing between two walls ten diameters apart (Walton Fig. 13): frictional (mu = 0.5) and
# frictionless spheres, three seeds each. About 2-4 min per seed on 2 cores.
# Usage: scripts/validate/packing.sh [seeds, default 1,2,3]
source "$(dirname "$0")/common.sh"
seeds=${1:-1,2,3}
cd "$root"
timed packing_frictional "$bin" bed packing examples/beds/packing.toml --seeds "$seeds" --quiet --out "$out/packing_frictional"
timed packing_frictionless "$bin" bed packing examples/beds/packing.toml --seeds "$seeds" --set contact.mu=0 --quiet --out "$out/packing_frictionless"
