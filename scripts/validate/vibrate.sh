#!/usr/bin/env bash
# Vibrational densification and the piston force of the denser bed: a 1.3-diameter bed
# (vibrate.toml, about 2 min on 2 cores), then the tall bed.
source "$(dirname "$0")/common.sh"
cd "$root"
timed vibrate "$bin" bed vibrate examples/beds/vibrate.toml --amplitude 5e-4 --frequency 30 --cycles 30 --quiet --out "$out/vibrate" "$@"
# The same on the tall bed of janssen.toml (H/R about 6: the exponential of Eq. 16 amplifies the
# change of mu k). About 8 min on 2 cores.
timed vibrate_tall "$bin" bed vibrate examples/beds/janssen.toml --amplitude 5e-4 --frequency 30 --cycles 30 --quiet --out "$out/vibrate_tall" "$@"
