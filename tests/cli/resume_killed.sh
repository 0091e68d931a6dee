#!/usr/bin/env bash
# A run killed without warning (SIGKILL: no clean-up, no buffered output flushed) and resumed
# from its last periodic checkpoint gives the same series.csv, byte for byte, as a run that
# was never interrupted: the checkpoint carries the state bit for bit, and every series row up
# to the checkpoint is on disk before the checkpoint is (rows still in the writer's buffer when
# the checkpoint was written would otherwise be missing from the resumed series).
set -u
bin=$1; src=$2
work=$(mktemp -d); trap 'kill -9 $pid 2>/dev/null; rm -rf "$work"' EXIT
pid=0
case_args=(--set insert.0.count=300 --set simulation.duration=0.1 --set output.series_interval=2e-5
           --set output.vtk=false --quiet)
"$bin" run "$src/examples/box_pour.toml" "${case_args[@]}" --out "$work/ref" > /dev/null 2>&1 ||
  { echo "FAIL reference run"; exit 1; }

"$bin" run "$src/examples/box_pour.toml" "${case_args[@]}" --set output.checkpoint_interval=0.002 \
  --out "$work/o" > /dev/null 2>&1 &
pid=$!
for _ in $(seq 200); do [ -f "$work/o/checkpoint.bin" ] && break; sleep 0.02; done
sleep 0.3  # the run goes on writing rows, and checkpoints every 2 ms of wall time (each fsynced)
if ! kill -9 $pid 2>/dev/null; then echo "SKIP the run ended before it could be killed (machine too fast)"; exit 0; fi
wait $pid 2>/dev/null
[ -f "$work/o/checkpoint.bin" ] || { echo "FAIL no checkpoint written before the kill"; exit 1; }
ck_step=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['step'])" "$work/o/checkpoint.json")
"$bin" run "$src/examples/box_pour.toml" "${case_args[@]}" --out "$work/o" --resume "$work/o/checkpoint.bin" \
  > "$work/log" 2>&1 || { echo "FAIL resume"; cat "$work/log"; exit 1; }
if cmp -s "$work/ref/series.csv" "$work/o/series.csv"; then
  echo "killed at a checkpoint of step $ck_step, resumed: series.csv identical to the uninterrupted run"
  echo "1 passed, 0 failed"
else
  echo "FAIL series.csv differs from the uninterrupted run (killed after the checkpoint of step $ck_step)"
  diff <(cut -d, -f1-2 "$work/ref/series.csv") <(cut -d, -f1-2 "$work/o/series.csv") | head -5
  echo "0 passed, 1 failed"; exit 1
fi
