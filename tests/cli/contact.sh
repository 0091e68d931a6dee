#!/usr/bin/env bash
# The `cohdem contact` contract: columns, one row per path row, and the MEPA closed forms
# for n = 1 (k1 = 1e5, k2 = 5e5, kadh = 2e5 N/m, loaded to dmax = 1e-4 m):
#   dp = dmax (1 - k1/k2) = 8e-5 m; largest tensile force -kadh k2 dp/(k2 + kadh) = -11.428571 N
#   at dmin = k2 dp/(k2 + kadh) = 5.7142857e-5 m (derivation: docs/contact-models.md).
# SDS rolling's moment on a bending path against its closed form (below). Bad input (unknown
# parameter, unknown column) must fail with status 2 naming it.
set -u
bin=$1; src=$2
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
python3 -c "
n=200
print('delta,xi')
for k in range(n+1): print(f'{1e-4*k/n:.12e},{0:.1e}')
dmin=1e-4*0.8*5/7
for k in range(1,2*n+1):
  d=1e-4*(1-k/n); dprev=1e-4*(1-(k-1)/n)
  if d < dmin < dprev: print(f'{dmin:.15e},{1e-6*(k-0.5)/n:.12e}')  # the exact extreme point
  print(f'{d:.12e},{1e-6*k/n:.12e}')
" > "$work/path.csv"
"$bin" contact --model mepa --set k1=1e5 --set k2=5e5 --set kadh=2e5 --set n=1 --set mu=0.5 \
  --ri 1e-3 --path "$work/path.csv" --out "$work/o" > /dev/null 2>&1 || { echo "0 passed, 1 failed: run"; exit 1; }
python3 - "$work/o/response.csv" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
fails = []
need = ["delta", "fn", "ft", "mb", "mt", "dp", "branch"]
missing = [c for c in need if c not in rows[0]]
if missing: fails.append(f"missing columns {missing}")
if len(rows) != 602: fails.append(f"{len(rows)} rows, expected 602")
dp = float(rows[300]["dp"])
if abs(dp - 8e-5) > 1e-12: fails.append(f"dp {dp}")
fmin = min(float(r["fn"]) for r in rows)
if abs(fmin + 11.428571428571) > 1e-8: fails.append(f"fmin {fmin}")  # path contains dmin exactly; CSV keeps 10 digits
d_at = float(min(rows, key=lambda r: float(r["fn"]))["delta"])
if abs(d_at - 5.7142857142857e-5) > 1e-14: fails.append(f"delta at fmin {d_at}")
print("ok" if not fails else fails)
sys.exit(1 if fails else 0)
PY
ok=$?
n=1; fail=$ok
"$bin" contact --model mepa --set k1=1e5 --set k3=1 --ri 1e-3 --path "$work/path.csv" --out "$work/o2" 2> "$work/e1"
rc=$?; n=$((n+1)); if [ $rc = 2 ] && grep -q "key 'k3': not a parameter of contact model 'mepa'" "$work/e1"; then :; else echo "FAIL unknown parameter: $rc $(cat "$work/e1")"; fail=$((fail+1)); fi
printf 'delta,zeta\n0,0\n' > "$work/bad.csv"
"$bin" contact --model mepa --set k1=1e5 --set k2=5e5 --set kadh=0 --set mu=0.5 --ri 1e-3 --path "$work/bad.csv" --out "$work/o3" 2> "$work/e2"
rc=$?; n=$((n+1)); if [ $rc = 2 ] && grep -q "bad.csv:1: key 'zeta': unknown column" "$work/e2"; then :; else echo "FAIL unknown column: $rc $(cat "$work/e2")"; fail=$((fail+1)); fi
# SDS rolling (LAMMPS's `rolling sds`) on a bending path at a fixed overlap, quasi-static:
# the rolling displacement is R* theta (R* = 5e-4 m for two spheres of 1e-3 m), the moment
# R* k_r R* theta = 2.5e-3 N m/rad x theta (k_r = 1e4 N/m) up to the limit mu_r R* F_n =
# 0.1 x 5e-4 x 10 N = 5e-4 N m (linear law, kn = 1e6 N/m at 1e-5 m: F_n = 10 N), reached at
# theta = 0.2 rad; unloading by 0.1 rad from there takes 2.5e-4 N m off (elastic again).
printf 'delta,theta\n1e-5,0\n1e-5,0.1\n1e-5,0.3\n1e-5,0.2\n' > "$work/roll.csv"
"$bin" contact --model linear --rolling sds --set kn=1e6 --set e=0.5 --set mu=0.5 --set k_r=1e4 --set mu_r=0.1 \
  --ri 1e-3 --path "$work/roll.csv" --out "$work/o4" --no-plot > /dev/null 2>&1
n=$((n+1))
python3 - "$work/o4/response.csv" <<'PY' || fail=$((fail+1))
import csv, sys
mb = [float(r["mb"]) for r in csv.DictReader(open(sys.argv[1]))]
ref = [0.0, 2.5e-4, 5e-4, 2.5e-4]  # elastic, at the limit, back by 0.1 rad
bad = [(m, r) for m, r in zip(mb, ref) if abs(m - r) > 1e-12 + 1e-9 * abs(r)]
if len(mb) != 4 or bad: print("FAIL sds rolling moments", mb, "expected", ref); sys.exit(1)
PY
echo "$((n - fail)) passed, $fail failed"
[ $fail = 0 ]
