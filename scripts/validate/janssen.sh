#!/usr/bin/env bash
# Janssen silo (pipe wall up) and piston (pipe wall down) in the 4 cm pipe with 3 mm glass beads
# (Walton Figs. 9 and 10). One fill, six bed heights per direction. About 35 s on 2 cores
# (10 MPa), then 85 s (100 MPa); docs/packed-beds.md, section 4.5.
source "$(dirname "$0")/common.sh"
cd "$root"
timed janssen "$bin" bed janssen examples/beds/janssen.toml --count 6 --speed 0.02 --travel-up 1e-3 --travel-down 3e-3 --quiet --out "$out/janssen" "$@"
# The same with a 10x stiffer modulus (100 MPa, dt = 4 us; 2.5x the cost): the largest overlaps
# in the tallest piston test drop from 12% to about 3.4% of the radius; mu k wall up stays within
# 7%, the piston direction's rises (0.252 -> 0.285, section 4.5).
timed janssen_stiff "$bin" bed janssen examples/beds/janssen.toml --count 6 --speed 0.02 --travel-up 1e-3 --travel-down 3e-3 \
  --set material.glass.youngs_modulus=1e8 --set material.acrylic.youngs_modulus=1e8 --set simulation.dt=4e-6 \
  --quiet --out "$out/janssen_stiff" "$@"
