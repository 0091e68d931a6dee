#!/usr/bin/env bash
# Runs every example case (examples/**/*.toml), shortened by the overrides on its
# "# test-args:" line, and checks that it finishes and writes its outputs. Also runs
# `cohdem check` on each, `cohdem run` with no case (the embedded default, shortened), and
# each example's fills at their full size (no time step: the shortened runs use fewer
# particles, and a fill of the full count can jam where a smaller one does not; the ring
# shear examples make their samples in their own procedure, run elsewhere).
set -u
bin=$1; src=$2
fail=0; n=0
work=$(mktemp -d)
run_one() {  # label, then cohdem arguments
  local label=$1; shift
  n=$((n + 1))
  local out="$work/out_$n"
  if ! "$bin" run "$@" --out "$out" --quiet > "$work/log_$n" 2>&1; then
    echo "FAIL $label: exit status $?"; tail -5 "$work/log_$n"; fail=$((fail + 1)); return
  fi
  if [ ! -s "$out/summary.json" ] || [ "$(wc -l < "$out/series.csv")" -lt 2 ]; then
    echo "FAIL $label: summary.json or series.csv missing"; fail=$((fail + 1)); return
  fi
  echo "ok   $label"
}
while IFS= read -r f; do
  args=$(sed -n 's/^# test-args: //p' "$f" | head -1)
  if [ -z "$args" ]; then echo "FAIL $f: no '# test-args:' line"; fail=$((fail + 1)); n=$((n + 1)); continue; fi
  pushd "$(dirname "$f")" > /dev/null
  # shellcheck disable=SC2086
  "$bin" check "$(basename "$f")" $args > "$work/check.txt" 2>&1 || {
    echo "FAIL check $f"; cat "$work/check.txt"; fail=$((fail + 1)); }
  # shellcheck disable=SC2086
  run_one "${f#$src/}" "$(basename "$f")" $args
  popd > /dev/null
done < <(find "$src/examples" -name '*.toml' | sort)
while IFS= read -r f; do
  grep -q '^\[ring_shear\]' "$f" && continue
  n=$((n + 1))
  pushd "$(dirname "$f")" > /dev/null
  if "$bin" run "$(basename "$f")" --set simulation.duration=1e-12 --threads 1 --out "$work/fill_$n" --quiet \
       > "$work/fill_$n.log" 2>&1; then
    echo "ok   ${f#$src/}: fills at full size"
  else
    echo "FAIL ${f#$src/}: fills at full size"; tail -3 "$work/fill_$n.log"; fail=$((fail + 1))
  fi
  popd > /dev/null
done < <(find "$src/examples" -name '*.toml' | sort)
default_args=$(sed -n 's/^# test-args: //p' "$src/examples/default.toml" | head -1)
# shellcheck disable=SC2086
run_one "embedded default case" $default_args
rm -rf "$work"
echo "$((n - fail)) passed, $fail failed"
[ $fail = 0 ]
