#!/usr/bin/env bash
# Each tests/data/bad/*.toml is a malformed case; its first line says what the error must
# say ("# expect: REGEX", matched against stderr) and, optionally, the exit status
# ("# exit: N", default 2 = bad input). The run must also leave no output folder behind.
set -u
bin=$1; src=$2
fail=0; n=0
work=$(mktemp -d)
cd "$work"
for f in "$src"/tests/data/bad/*.toml; do
  n=$((n + 1))
  expect=$(sed -n '1s/^# expect: //p' "$f")
  want=$(sed -n '2s/^# exit: //p' "$f"); want=${want:-2}
  rel="bad/$(basename "$f")"
  mkdir -p bad && cp "$f" "$rel"
  "$bin" run "$rel" --out "$work/out_$n" --quiet > stdout.txt 2> stderr.txt
  rc=$?
  msg=$(cat stderr.txt)
  if [ "$rc" != "$want" ]; then echo "FAIL $rel: exit $rc, expected $want; stderr: $msg"; fail=$((fail+1)); continue; fi
  if ! grep -Eq -- "$expect" stderr.txt; then echo "FAIL $rel: stderr does not match /$expect/: $msg"; fail=$((fail+1)); continue; fi
  if [ -e "$work/out_$n" ]; then echo "FAIL $rel: output folder was created"; fail=$((fail+1)); continue; fi
  echo "ok   $rel: $msg"
done
# --set errors name the override.
"$bin" run bad/01_unknown_key.toml --set simulation.dt=abc --quiet 2> stderr.txt; rc=$?
if [ $rc = 2 ] && grep -q "key 'simulation.dt': expected a number, got a string" stderr.txt; then echo "ok   --set wrong type: $(cat stderr.txt)"; else echo "FAIL --set wrong type: $rc $(cat stderr.txt)"; fail=$((fail+1)); fi
"$bin" run bad/01_unknown_key.toml --set wall.nowall.velocity=[0,0,1] --quiet 2> stderr.txt; rc=$?
if [ $rc = 2 ] && grep -q "^error: --set: key 'wall.nowall.velocity': no element 'nowall'" stderr.txt; then echo "ok   --set unknown wall: $(cat stderr.txt)"; else echo "FAIL --set unknown wall: $rc $(cat stderr.txt)"; fail=$((fail+1)); fi
"$bin" run no_such_case.toml --quiet 2> stderr.txt; rc=$?
if [ $rc = 2 ] && grep -q "no_such_case.toml: cannot open case file" stderr.txt; then echo "ok   missing file"; else echo "FAIL missing file: $rc $(cat stderr.txt)"; fail=$((fail+1)); fi
n=$((n + 3))
rm -rf "$work"
echo "$((n - fail)) passed, $fail failed"
[ $fail = 0 ]
