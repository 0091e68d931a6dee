#!/usr/bin/env bash
# Vibrational densification and the piston force of the denser bed. About 5 min on 2 cores.
source "$(dirname "$0")/common.sh"
cd "$root"
timed vibrate "$bin" bed vibrate examples/beds/vibrate.toml --amplitude 5e-4 --frequency 30 --cycles 30 --quiet --out "$out/vibrate" "$@"
