#!/usr/bin/env bash
# scripts/validate/same_physics.py tells a change of physics from a change of rounding: the
# same engine with settings that change only the order of operations (a list rebuilt every
# step, skin 1e-9) is judged the same, on a resting cohesive cluster and on a chaotic
# periodic gas (there the rounding baseline grows to 1e-4 radii within the run and the later
# frames are left unjudged); a friction coefficient 2 % higher is judged different, as is
# 2e-7 higher (8.6e3 times the baseline on the cluster when measured); a run that fails
# (bad override) gives exit status 2.
set -u
bin=$1; src=$2
fail=0; n=0
sp() { python3 "$src/scripts/validate/same_physics.py" "$@" --a "$bin"; }
check() {  # expected status, description, arguments
  local want=$1 what=$2; shift 2
  n=$((n + 1))
  out=$(sp "$@" 2>&1); rc=$?
  if [ "$rc" != "$want" ]; then
    echo "FAIL $what: exit $rc, expected $want"; echo "$out" | tail -8; fail=$((fail + 1))
  else
    echo "ok   $what: $(echo "$out" | tail -1)"
  fi
}
cluster=(examples/cohesive/cluster_mepa.toml --duration 0.02 --frames-every 0.001)
cd "$src"
check 0 "cluster, skin 1e-9" "${cluster[@]}" --b-set simulation.skin=1e-9
check 1 "cluster, mu 0.51" "${cluster[@]}" --b-set contact.mu=0.51
check 1 "cluster, mu 0.5000001" "${cluster[@]}" --b-set contact.mu=0.5000001
check 0 "periodic gas, skin 1e-9" examples/periodic_gas.toml --duration 0.1 --frames-every 0.005 --b-set simulation.skin=1e-9
check 2 "a failing run" "${cluster[@]}" --b-set contact.mu=-1
echo "$((n - fail)) of $n passed"
[ $fail = 0 ]
