#!/usr/bin/env bash
# Every packed-bed validation run in turn (about 6 min on 2 cores; 45 before the speed work), then copies the plots to
# docs/img/ (with --update-docs).
source "$(dirname "$0")/common.sh"
here=$(dirname "$0")
bash "$here/packing.sh"
bash "$here/janssen.sh"
bash "$here/vibrate.sh"
bash "$here/thermal_cycle.sh"
if [ "${1:-}" = "--update-docs" ]; then
  mkdir -p "$root/docs/img"
  cp "$out/packing_frictional/packing_profile.png" "$root/docs/img/packing_frictional.png"
  cp "$out/packing_frictionless/packing_profile.png" "$root/docs/img/packing_frictionless.png"
  cp "$out/janssen/janssen_up.png" "$out/janssen/janssen_down.png" "$out/janssen/janssen_stress.png" "$root/docs/img/"
  cp "$out/vibrate/vibrate_profile.png" "$root/docs/img/"
  cp "$out/thermal_cycle/thermal_cycle.png" "$root/docs/img/"
fi
