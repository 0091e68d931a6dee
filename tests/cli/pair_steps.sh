#!/usr/bin/env bash
# The case-file switch for two steps per sweep ([simulation] pair_steps, pair_min): a small
# periodic gas with pair_min = 1 takes pairs (summary.json's step_pairs.pairs > 0), with
# pair_steps = false none, and both runs write the same series and final energies to the
# last digit (System::step_pair is bit-identical to plain steps: tests/physics/test_step_pair.cpp).
# Run on one thread and on two (there the blocks may be too short for pairs: then the count
# may be 0, and the results must still agree).
set -u
bin=$1; src=$2
fail=0; n=0
work=$(mktemp -d)
cd "$work"
run() {  # out, then overrides
  local out=$1; shift
  "$bin" run "$src/examples/periodic_gas.toml" --set simulation.duration=0.004 "$@" --out "$out" > "$out.log" 2>&1
}
pairs() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['step_pairs']['pairs'])" "$1/summary.json"; }
energy() { python3 -c "import json,sys; j=json.load(open(sys.argv[1])); print(repr(j['kinetic_energy']), j['contacts'])" "$1/summary.json"; }
for t in 1 2; do
  n=$((n + 1))
  if ! run on$t --set simulation.threads=$t --set simulation.parallel_min=0 --set simulation.pair_min=1 ||
     ! run off$t --set simulation.threads=$t --set simulation.parallel_min=0 --set simulation.pair_steps=false; then
    echo "FAIL threads=$t: a run failed"; cat on$t.log off$t.log; fail=$((fail + 1)); continue
  fi
  on=$(pairs on$t); off=$(pairs off$t)
  if [ "$off" != 0 ]; then echo "FAIL threads=$t: pair_steps = false took $off pairs"; fail=$((fail + 1)); continue; fi
  if [ "$t" = 1 ] && [ "$on" -lt 100 ]; then echo "FAIL threads=1: pair_min = 1 took only $on pairs of 400 steps' worth"; fail=$((fail + 1)); continue; fi
  if ! cmp -s on$t/series.csv off$t/series.csv || [ "$(energy on$t)" != "$(energy off$t)" ]; then
    echo "FAIL threads=$t: results differ with and without pairs: $(energy on$t) / $(energy off$t)"; fail=$((fail + 1)); continue
  fi
  if ! grep -q "two steps per sweep off (pair_steps = false)" off$t.log; then
    echo "FAIL threads=$t: the log does not say the pairs are off"; fail=$((fail + 1)); continue
  fi
  echo "ok   threads=$t: $on pairs with pair_min = 1, none with pair_steps = false, same series and energies ($(energy on$t))"
done
rm -rf "$work"
echo "$((n - fail)) passed, $fail failed"
[ $fail = 0 ]
