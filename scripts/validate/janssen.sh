#!/usr/bin/env bash
# Janssen silo (pipe wall up) and piston (pipe wall down) in the 4 cm pipe with 3 mm glass beads
# (Walton Figs. 9 and 10). One fill, six bed heights per direction. About 10 min on 2 cores.
source "$(dirname "$0")/common.sh"
cd "$root"
timed janssen "$bin" bed janssen examples/beds/janssen.toml --count 6 --speed 0.02 --travel-up 1e-3 --travel-down 3e-3 --quiet --out "$out/janssen" "$@"
