#!/usr/bin/env bash
# Janssen silo (pipe wall up) and piston (pipe wall down) in the 4 cm pipe with 3 mm glass beads
# (Walton Figs. 9 and 10). One fill, six bed heights per direction. About 3 min on 2 quiet
# cores (10 MPa), then 8 min (100 MPa).
source "$(dirname "$0")/common.sh"
cd "$root"
timed janssen "$bin" bed janssen examples/beds/janssen.toml --count 6 --speed 0.02 --travel-up 1e-3 --travel-down 3e-3 --quiet --out "$out/janssen" "$@"
# The same with a 10x stiffer modulus (100 MPa, dt = 4 us; 2.5x the cost): the largest overlaps
# in the tallest piston test drop from 13% to about 3% of the radius, and mu k should not change.
timed janssen_stiff "$bin" bed janssen examples/beds/janssen.toml --count 6 --speed 0.02 --travel-up 1e-3 --travel-down 3e-3 \
  --set material.glass.youngs_modulus=1e8 --set material.acrylic.youngs_modulus=1e8 --set simulation.dt=4e-6 \
  --quiet --out "$out/janssen_stiff" "$@"
