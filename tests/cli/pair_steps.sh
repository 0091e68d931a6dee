#!/usr/bin/env bash
# The case-file switches for several steps per sweep ([simulation] pair_steps, pair_min,
# sweep_steps, sweep_min): a small periodic gas with pair_min = 1 takes sweeps (summary.json's
# step_pairs.pairs > 0; on one thread with sweep_min = 1 of up to four steps, sweep_steps'
# default, two where the growth of the displacements is not known yet; of two with
# sweep_steps = 2), with pair_steps = false none, and all runs write the same series and
# final energies to the last digit (System::step_sweep is bit-identical to plain steps:
# tests/physics/test_step_pair.cpp). Run on one thread and on two (there the blocks may be
# too short for pairs: then the count may be 0, and the results must still agree). The runs
# that count the steps a sweep fix them (sweep_tune = false); one more run on one thread
# leaves the choice between two and four to its timings (sweep_tune's default), which the
# log says, and must write the same series and energies whatever it chose (its summary's
# step_pairs.tuning, where a choice was made, names 2 or 4). A sweep_steps outside 2-4 is
# refused with the key named.
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
field() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['step_pairs'][sys.argv[2]])" "$1/summary.json" "$2"; }
energy() { python3 -c "import json,sys; j=json.load(open(sys.argv[1])); print(repr(j['kinetic_energy']), j['contacts'])" "$1/summary.json"; }
for t in 1 2; do
  n=$((n + 1))
  if ! run on$t --set simulation.threads=$t --set simulation.parallel_min=0 --set simulation.pair_min=1 --set simulation.sweep_min=1 \
         --set simulation.sweep_tune=false ||
     ! run off$t --set simulation.threads=$t --set simulation.parallel_min=0 --set simulation.pair_steps=false; then
    echo "FAIL threads=$t: a run failed"; cat on$t.log off$t.log; fail=$((fail + 1)); continue
  fi
  on=$(pairs on$t); off=$(pairs off$t)
  if [ "$off" != 0 ]; then echo "FAIL threads=$t: pair_steps = false took $off pairs"; fail=$((fail + 1)); continue; fi
  if [ "$t" = 1 ]; then
    swept=$(field on1 steps); per=$(field on1 steps_per_sweep)
    if [ "$per" != 4 ] || [ "$swept" -lt 200 ] || [ "$swept" -le $((2 * on)) ]; then
      echo "FAIL threads=1: pair_min = 1 took $on sweeps, $swept steps in them, up to $per a sweep (expected up to 4, some sweeps of more than two, 200 of 400 steps at least)"
      fail=$((fail + 1)); continue
    fi
    if ! run two1 --set simulation.threads=1 --set simulation.parallel_min=0 --set simulation.pair_min=1 \
         --set simulation.sweep_min=1 --set simulation.sweep_steps=2; then
      echo "FAIL threads=1: the run with sweep_steps = 2 failed"; cat two1.log; fail=$((fail + 1)); continue
    fi
    if [ "$(field two1 steps_per_sweep)" != 2 ] || [ "$(field two1 steps)" != $((2 * $(pairs two1))) ] ||
       ! cmp -s two1/series.csv off1/series.csv || [ "$(energy two1)" != "$(energy off1)" ]; then
      echo "FAIL threads=1: sweep_steps = 2 did not take pairs of steps with the same results"; fail=$((fail + 1)); continue
    fi
    if ! run tuned1 --set simulation.threads=1 --set simulation.parallel_min=0 --set simulation.pair_min=1 \
         --set simulation.sweep_min=1; then
      echo "FAIL threads=1: the run with sweep_tune failed"; cat tuned1.log; fail=$((fail + 1)); continue
    fi
    tuned=$(python3 -c "import json,sys; t=json.load(open(sys.argv[1]))['step_pairs']['tuning']; \
print('none' if t is None else ('ok %d steps, %.3g against %.3g ns' % (t['steps_per_sweep'], t['more_ns'], t['two_ns']) \
      if t['steps_per_sweep'] in (2, 4) and t['choices'] >= 1 and t['more_ns'] > 0 and t['two_ns'] > 0 else 'bad %s' % t))" tuned1/summary.json)
    if ! cmp -s tuned1/series.csv off1/series.csv || [ "$(energy tuned1)" != "$(energy off1)" ] ||
       [ "${tuned%% *}" = bad ] || [ "$(pairs tuned1)" = 0 ] || ! grep -q "2 or 4 steps per sweep" tuned1.log; then
      echo "FAIL threads=1: sweep_tune: $(pairs tuned1) sweeps, tuning $tuned, energies $(energy tuned1) / $(energy off1)"
      fail=$((fail + 1)); continue
    fi
    echo "ok   threads=1: sweep_tune took $(pairs tuned1) sweeps (choice: $tuned), the same series and energies"
  fi
  if ! cmp -s on$t/series.csv off$t/series.csv || [ "$(energy on$t)" != "$(energy off$t)" ]; then
    echo "FAIL threads=$t: results differ with and without pairs: $(energy on$t) / $(energy off$t)"; fail=$((fail + 1)); continue
  fi
  if ! grep -q "several steps per sweep off (pair_steps = false)" off$t.log; then
    echo "FAIL threads=$t: the log does not say the pairs are off"; fail=$((fail + 1)); continue
  fi
  echo "ok   threads=$t: $on sweeps with pair_min = 1, none with pair_steps = false, same series and energies ($(energy on$t))"
done
for bad in 1 5; do
  n=$((n + 1))
  if run bad$bad --set simulation.sweep_steps=$bad; then
    echo "FAIL sweep_steps = $bad was accepted"; fail=$((fail + 1))
  elif ! grep -q "sweep_steps" bad$bad.log; then
    echo "FAIL sweep_steps = $bad: the error does not name the key"; cat bad$bad.log; fail=$((fail + 1))
  else
    echo "ok   sweep_steps = $bad refused: $(grep -m1 sweep_steps bad$bad.log)"
  fi
done
rm -rf "$work"
echo "$((n - fail)) passed, $fail failed"
[ $fail = 0 ]
