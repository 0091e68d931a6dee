#!/usr/bin/env bash
# Ring shear checkpoints: a run stopped by --max-wall-time 0 ends after its first stage (fill
# and consolidation) with exit status 75 and a checkpoint; resumed with --resume (and stopped
# and resumed again part-way), it must give exactly what an uninterrupted run gives: the same
# series.csv (every sample, bit for bit as printed) and the same shear points and yield locus.
# Also: a checkpoint refuses a case with other ring shear settings, and the plain runner
# refuses a ring shear checkpoint, each with exit status 2 and the key named.
set -u
bin=$1; src=$2
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
case=$src/examples/default.toml
args=$(sed -n 's/^# test-args: //p' "$case" | head -1)
pass=0; fail=0
ok() { echo "ok   $1"; pass=$((pass + 1)); }
bad() { echo "FAIL $1"; fail=$((fail + 1)); }

"$bin" run "$case" $args --out "$work/a" --quiet > "$work/a.log" 2>&1 || { echo "FAIL uninterrupted run"; cat "$work/a.log"; exit 1; }

# The tester makes its particles from [ring_shear].size, so it must apply the default Verlet
# skin itself: with a skin of 0 the lists would be rebuilt at every step (as they were before
# 2026-11-24). With 0.2 r_max of skin a build lasts tens to thousands of steps here.
python3 - "$work/a/summary.json" <<'PY' && ok "neighbor lists rebuilt rarely (skin applied)" || bad "neighbor lists rebuilt too often"
import json, sys
j = json.load(open(sys.argv[1]))
print(f"     {j['neighbor_builds']} builds in {j['steps']} steps")
sys.exit(0 if j["neighbor_builds"] * 10 < j["steps"] else 1)
PY

"$bin" run "$case" $args --out "$work/b" --quiet --max-wall-time 0 > "$work/b1.log" 2>&1; rc=$?
if [ $rc = 75 ] && [ -f "$work/b/checkpoint.bin" ] && [ ! -f "$work/b/summary.json" ]; then ok "stopped after the first stage (exit 75)"
else bad "first stop: exit $rc, expected 75 with a checkpoint and no summary"; cat "$work/b1.log"; fi
grep -q "stopped after stage 1 of" "$work/b1.log" && ok "stop message names the stage" || bad "stop message"

"$bin" run "$case" $args --out "$work/b" --quiet --max-wall-time 0 --resume "$work/b/checkpoint.bin" > "$work/b2.log" 2>&1; rc=$?
[ $rc = 75 ] && grep -q "stopped after stage 2 of" "$work/b2.log" && ok "resumed, stopped again after stage 2" || { bad "second stop: exit $rc"; cat "$work/b2.log"; }

"$bin" run "$case" $args --out "$work/b" --quiet --resume "$work/b/checkpoint.bin" > "$work/b3.log" 2>&1; rc=$?
[ $rc = 0 ] && ok "resumed to the end" || { bad "final resume: exit $rc"; cat "$work/b3.log"; }

if cmp -s "$work/a/series.csv" "$work/b/series.csv"; then ok "series.csv identical to the uninterrupted run"
else bad "series.csv differs from the uninterrupted run"; fi
if cmp -s "$work/a/shear_points.csv" "$work/b/shear_points.csv"; then ok "shear points identical"
else bad "shear points differ"; fi
python3 - "$work/a/summary.json" "$work/b/summary.json" <<'PY' && ok "summary.json identical apart from timings" || bad "summary.json differs"
import json, sys
a, b = (json.load(open(f)) for f in sys.argv[1:])
for j in (a, b):
    for k in ("wall_time_s", "cpu_time_s", "particle_steps_per_s"): j.pop(k, None)
sys.exit(0 if a == b else 1)
PY

# A checkpoint refuses other settings, naming the key; the plain runner refuses it.
"$bin" run "$case" $args --set ring_shear.sigma_pre=40000 --out "$work/b" --quiet --resume "$work/b/checkpoint.bin" > /dev/null 2> "$work/e1"; rc=$?
[ $rc = 2 ] && grep -q "ring_shear.sigma_pre" "$work/e1" && ok "other sigma_pre refused (exit 2, key named)" || { bad "other settings: exit $rc"; cat "$work/e1"; }
"$bin" run "$src/examples/box_pour.toml" --out "$work/c" --quiet --resume "$work/b/checkpoint.bin" > /dev/null 2> "$work/e2"; rc=$?
[ $rc = 2 ] && grep -q "checkpoint" "$work/e2" && ok "plain run refuses a ring shear checkpoint (exit 2)" || { bad "plain runner: exit $rc"; cat "$work/e2"; }

echo "$pass passed, $fail failed"
[ $fail = 0 ]
