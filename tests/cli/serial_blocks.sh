#!/usr/bin/env bash
# The diagnostic COHDEM_SERIAL_BLOCKS=1 (SimConfig::serial_blocks): on two threads the force
# loop's blocks are swept one after another on one thread, with the threads' split and
# hand-off. The run must end as the one-thread and two-thread runs do, to the last digit
# (series and final energies), count its calls in series (summary.json's
# thread_sweep.serial_calls; none without the variable), turn step pairs off, and say so in
# its log.
set -u
bin=$1; src=$2
fail=0; n=0
work=$(mktemp -d)
cd "$work"
run() {  # out, threads, then environment assignments
  local out=$1 t=$2; shift 2
  env "$@" "$bin" run "$src/examples/periodic_gas.toml" --set simulation.duration=0.004 \
    --set simulation.threads=$t --set simulation.parallel_min=0 --out "$out" > "$out.log" 2>&1
}
field() { python3 -c "import json,sys; j=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))" "$1/summary.json" "$2"; }
energy() { field "$1" "repr(j['kinetic_energy']) + ' ' + str(j['contacts'])"; }
n=$((n + 1))
if ! run one 1 X=0 || ! run two 2 X=0 || ! run ser 2 COHDEM_SERIAL_BLOCKS=1; then
  echo "FAIL: a run failed"; cat one.log two.log ser.log; fail=$((fail + 1))
else
  calls=$(field ser "j['thread_sweep']['serial_calls']")
  plain=$(field two "j['thread_sweep']['serial_calls']")
  on=$(field ser "j['thread_sweep']['serial_blocks']")
  pairs=$(field ser "j['step_pairs']['pairs']")
  if ! cmp -s one/series.csv ser/series.csv || ! cmp -s two/series.csv ser/series.csv ||
     [ "$(energy one)" != "$(energy ser)" ] || [ "$(energy two)" != "$(energy ser)" ]; then
    echo "FAIL: blocks in series differ: $(energy one) / $(energy two) / $(energy ser)"; fail=$((fail + 1))
  elif [ "$calls" -lt 100 ] || [ "$plain" != 0 ] || [ "$on" != True ] || [ "$pairs" != 0 ]; then
    echo "FAIL: serial_calls $calls (two threads: $plain), serial_blocks $on, step pairs $pairs"; fail=$((fail + 1))
  elif ! grep -q "one after another on one thread (COHDEM_SERIAL_BLOCKS=1" ser.log ||
       grep -q "one after another" two.log; then
    echo "FAIL: the log does not say (only) where the blocks ran in series"; fail=$((fail + 1))
  else
    echo "ok   blocks in series: $calls calls, the same series and energies as 1 and 2 threads ($(energy ser))"
  fi
fi
rm -rf "$work"
echo "$((n - fail)) passed, $fail failed"
[ $fail = 0 ]
