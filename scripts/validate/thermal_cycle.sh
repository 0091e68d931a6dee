#!/usr/bin/env bash
# Three thermal cycles of a bed under a spring-loaded lid. About 8 min on 2 cores.
source "$(dirname "$0")/common.sh"
cd "$root"
timed thermal_cycle "$bin" bed thermal-cycle examples/beds/thermal_cycle.toml --start 0.5 --period 0.8 --quiet --out "$out/thermal_cycle" "$@"
