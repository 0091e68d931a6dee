#!/usr/bin/env bash
# The long stage of the packed-bed protocols (the fill of packing, janssen and vibrate; the
# whole thermal cycling run) checkpoints every [output] checkpoint_interval s of wall time, and
# `cohdem bed ... --resume` continues it bit for bit: a protocol killed without warning
# (SIGKILL) and resumed writes the same tables, byte for byte, as one never interrupted. A
# checkpoint written with other options is refused, naming --resume.
set -u
bin=$1; src=$2
work=$(mktemp -d); pid=0
trap 'kill -9 $pid 2>/dev/null; rm -rf "$work"' EXIT
cd "$src"
fail=0; n=0
# killed OUT CHECKPOINT ARGS...: runs `cohdem bed ARGS` with a checkpoint every 50 ms and kills
# it (SIGKILL) 0.3 s after OUT/CHECKPOINT first appears.
killed() {
  local out=$1 ck=$2; shift 2
  "$bin" bed "$@" --set output.checkpoint_interval=0.05 --quiet --out "$out" > /dev/null 2>&1 &
  pid=$!
  for _ in $(seq 1000); do [ -f "$out/$ck" ] && break; sleep 0.02; done
  sleep 0.3
  if ! kill -9 $pid 2>/dev/null; then echo "note: the run ended before it could be killed"; fi
  wait $pid 2>/dev/null
}
# same LABEL REF OUT FILES...: the files are byte-equal in both folders.
same() {
  local label=$1 ref=$2 out=$3; shift 3
  n=$((n + 1))
  for f in "$@"; do
    if ! cmp -s "$ref/$f" "$out/$f"; then echo "FAIL $label: $f differs from the uninterrupted run"; fail=$((fail + 1)); return; fi
  done
  echo "ok   $label: $* identical to the uninterrupted run"
}

# Thermal cycling (its samples travel with the checkpoint).
tc=(thermal-cycle examples/beds/thermal_cycle.toml --set simulation.duration=0.2 --set insert.0.count=300 --period 0.01)
"$bin" bed "${tc[@]}" --quiet --out "$work/tc_ref" > /dev/null 2>&1 || { echo "FAIL thermal-cycle reference run"; exit 1; }
killed "$work/tc" thermal_cycle_checkpoint.bin "${tc[@]}"
"$bin" bed "${tc[@]}" --resume --quiet --out "$work/tc" > "$work/log_tc" 2>&1 || { echo "FAIL thermal-cycle resume"; tail -3 "$work/log_tc"; exit 1; }
same "thermal-cycle killed and resumed" "$work/tc_ref" "$work/tc" thermal_cycle.csv thermal_cycle.json

# Packing over two seeds, killed during the second seed's fill (the first one's is complete).
pk=(packing examples/beds/packing.toml --set simulation.duration=0.5 --set insert.0.count=300 --seeds 1,2 --band-margin 0)
"$bin" bed "${pk[@]}" --quiet --out "$work/pk_ref" > /dev/null 2>&1 || { echo "FAIL packing reference run"; exit 1; }
killed "$work/pk" seed2_checkpoint.bin "${pk[@]}"
"$bin" bed "${pk[@]}" --resume --quiet --out "$work/pk" > "$work/log_pk" 2>&1 || { echo "FAIL packing resume"; tail -3 "$work/log_pk"; exit 1; }
same "packing killed in seed 2 and resumed" "$work/pk_ref" "$work/pk" packing.json packing_profile.csv

# Janssen resumed after its fill ended: the motions run on the fill taken from the checkpoint.
js=(janssen examples/beds/janssen.toml --set simulation.duration=0.01 --set insert.0.count=300 --heights 0.03,0.02
    --settle 0.0005 --travel-up 1e-5 --travel-down 1e-5)
"$bin" bed "${js[@]}" --quiet --out "$work/js" > /dev/null 2>&1 || { echo "FAIL janssen run"; exit 1; }
mkdir -p "$work/js_ref" && cp "$work/js/janssen.csv" "$work/js/janssen.json" "$work/js_ref/"
"$bin" bed "${js[@]}" --resume --quiet --out "$work/js" > "$work/log_js" 2>&1 || { echo "FAIL janssen resume"; tail -3 "$work/log_js"; exit 1; }
n=$((n + 1))
if grep -q "the stage had ended" "$work/log_js"; then echo "ok   janssen --resume takes the ended fill from its checkpoint"
else echo "FAIL janssen --resume did not take the fill from its checkpoint"; fail=$((fail + 1)); fi
same "janssen resumed after the fill" "$work/js_ref" "$work/js" janssen.csv janssen.json

# Other options than the checkpoint's: refused (exit 2), naming the checkpoint and --resume.
"$bin" bed "${tc[@]}" --set thermal.time_scale=2 --resume --quiet --out "$work/tc" 2> "$work/err"; rc=$?
n=$((n + 1))
if [ $rc = 2 ] && grep -q "thermal_cycle_checkpoint.bin.*--resume.*--set options" "$work/err"; then echo "ok   other options refused: $(cat "$work/err")"
else echo "FAIL other options: exit $rc, $(cat "$work/err")"; fail=$((fail + 1)); fi

# A stage checkpoint given to `cohdem run --resume` is refused, naming what wrote it.
"$bin" run examples/beds/thermal_cycle.toml --set simulation.duration=0.2 --set insert.0.count=300 \
  --resume "$work/tc/thermal_cycle_checkpoint.bin" --quiet --out "$work/r" 2> "$work/err"; rc=$?
n=$((n + 1))
if [ $rc = 2 ] && grep -q "written by a packed-bed protocol" "$work/err"; then echo "ok   run --resume of a stage checkpoint refused: $(cat "$work/err")"
else echo "FAIL run --resume of a stage checkpoint: exit $rc, $(cat "$work/err")"; fail=$((fail + 1)); fi

echo "$((n - fail)) passed, $fail failed"
[ $fail = 0 ]
