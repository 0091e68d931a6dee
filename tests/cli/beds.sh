#!/usr/bin/env bash
# Smoke test of the packed-bed protocols (cohdem bed ...): each runs on its example shortened
# to a few hundred steps and must write its JSON summary, CSV table and PNG plot. The physics
# is checked by the long runs of scripts/validate (docs/packed-beds.md), not here.
set -u
bin=$1; src=$2
fail=0; n=0
work=$(mktemp -d)
cd "$src"
check() {  # label, files..., -- , cohdem arguments
  local label=$1; shift
  local files=()
  while [ "$1" != "--" ]; do files+=("$1"); shift; done
  shift
  n=$((n + 1))
  local out="$work/$n"
  if ! "$bin" bed "$@" --quiet --out "$out" > "$work/log_$n" 2>&1; then
    echo "FAIL $label: exit status $?"; tail -5 "$work/log_$n"; fail=$((fail + 1)); return
  fi
  for f in "${files[@]}"; do
    if [ ! -s "$out/$f" ]; then echo "FAIL $label: $f missing"; fail=$((fail + 1)); return; fi
  done
  echo "ok   $label: $(tail -1 "$work/log_$n")"
}
short="--set simulation.duration=0.01 --set insert.0.count=300"
check packing packing.json packing_profile.csv packing_profile.png -- \
  packing examples/beds/packing.toml $short --seeds 1,2 --band-margin 0
check janssen janssen.json janssen.csv janssen_up.png janssen_down.png janssen_stress.png stress_up.csv -- \
  janssen examples/beds/janssen.toml $short --heights 0.03,0.02 --settle 0.0005 --travel-up 1e-5 --travel-down 1e-5
check vibrate vibrate.json vibrate_profile.png -- \
  vibrate examples/beds/vibrate.toml $short --frequency 2000 --cycles 2 --settle 0.0005 --height 0.03 --travel 1e-5
check thermal-cycle thermal_cycle.json thermal_cycle.csv thermal_cycle.png -- \
  thermal-cycle examples/beds/thermal_cycle.toml --set simulation.duration=0.003 --set insert.0.count=100 --period 0.001
# Errors name the option or key.
"$bin" bed janssen examples/beds/janssen.toml --pipe nopipe $short --quiet --out "$work/e1" 2> "$work/err" ; rc=$?
n=$((n + 1))
if [ $rc = 2 ] && grep -q "key '--pipe': no wall called 'nopipe'" "$work/err"; then echo "ok   unknown pipe: $(cat "$work/err")"
else echo "FAIL unknown pipe: $rc $(cat "$work/err")"; fail=$((fail + 1)); fi
"$bin" bed thermal-cycle examples/beds/janssen.toml --period 1 $short --quiet --out "$work/e2" 2> "$work/err" ; rc=$?
n=$((n + 1))
if [ $rc = 2 ] && grep -q "thermal-cycle needs a case with a \[thermal\] table" "$work/err"; then echo "ok   no thermal: $(cat "$work/err")"
else echo "FAIL no thermal: $rc $(cat "$work/err")"; fail=$((fail + 1)); fi
# A bed still falling when the motions start (fill of 0.03 s): the stress fits cannot be made,
# but the protocol still writes its tables and says why, and the mu k at the edge of the
# search range is labelled as no fit.
"$bin" bed janssen examples/beds/janssen.toml --set simulation.duration=0.03 --set insert.0.count=300 --heights 0.03,0.02 \
  --settle 0.0005 --travel-up 1e-5 --travel-down 1e-5 --quiet --out "$work/u" > "$work/log_u" 2>&1; rc=$?
n=$((n + 1))
if [ $rc = 0 ] && grep -q "not a fit" "$work/log_u" && python3 -c "import json,sys; j=json.load(open(sys.argv[1])); sys.exit(0 if 'skipped' in j['stresses']['up'] else 1)" "$work/u/janssen.json"; then
  echo "ok   unsettled bed: tables written, fits marked"
else echo "FAIL unsettled bed: exit $rc"; tail -3 "$work/log_u"; fail=$((fail + 1)); fi
rm -rf "$work"
echo "$((n - fail)) passed, $fail failed"
[ $fail = 0 ]
