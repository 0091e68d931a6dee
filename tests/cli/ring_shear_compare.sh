#!/usr/bin/env bash
# scripts/validate/ring_shear_compare.py, on made-up runs whose shear points lie exactly on
# known loci tau = c + tan(phi) sigma: the table gives each run's phi and c back (least
# squares on exact points: to the printed digit), the per-group line gives the mean and the
# sample standard deviation of phi (30, 35, 40 deg: 35.0 and 5.0), and the figure is written
# both ways (one key entry per run for a single small group; per group with two groups).
# scripts/validate/ring_shear.sh --table-only on the same runs and on one whose steady-state
# circle reached into tension (sigma_1, ffc, phi_e null with steady_state_error, the locus
# given): its phi and c are counted, its ffc is not, and the seed is named. --flow-function
# draws the runs' (sigma_1, sigma_c) points, leaving that run out.
set -u
bin=$1; src=$2
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
fail=0
mkrun() {  # group seed phi_deg c_kPa cell [nocircle]
  local d=$work/$1/seed_$2
  mkdir -p "$d"
  python3 - "$d" "$3" "$4" "$5" "${6:-}" <<'EOF'
import json, math, sys
d, phi, c, cell, nocircle = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), sys.argv[4], sys.argv[5]
m = math.tan(math.radians(phi))
sig = [11e3, 22e3, 33e3, 44e3]
with open(d + "/shear_points.csv", "w") as f:
    f.write("sigma,tau_measured,tau_normalized\n")
    for s in sig:
        f.write(f"{s!r},{c * 1e3 + m * s!r},{c * 1e3 + m * s!r}\n")
yl = {"ffc": 1.7, "phi_lin_deg": phi, "cohesion": c * 1e3, "sigma_1": 1e5, "sigma_c": 6e4, "phi_e_deg": 55.0,
      "phi_sf_deg": 41.0}
if nocircle:
    yl.update(ffc=None, sigma_1=None, sigma_2=None, phi_e_deg=None, steady_state_error="sigma_2 < 0 (made up)")
j = {"cell": cell, "particles": 1968, "pre_shear": {"tau_each": [45e3, 48e3], "sigma": 54.8e3, "tau": 46.5e3},
     "cpu_time_s": 180.0, "wall_time_s": 181.0, "steps": 1000, "particle_steps_per_s": 1e7,
     "bulk_density_preshear": 1400.0, "yield_locus": yl}
if cell == "annulus":  # a report that names its consolidation stress: the group says it
    j["sigma_pre_target"] = 54.8e3
json.dump(j, open(d + "/summary.json", "w"))
EOF
}
mkrun box 1 30 18 shear_box; mkrun box 2 35 17 shear_box; mkrun box 3 40 16 shear_box
mkrun ring 1 36 14 annulus
expect() {  # what, pattern, text
  if echo "$3" | grep -qF -- "$2"; then echo "ok   $1"; else echo "FAIL $1: no '$2' in:"; echo "$3"; fail=$((fail + 1)); fi
}
out=$(python3 "$src/scripts/validate/ring_shear_compare.py" "$work/one.png" "$work"/box/seed_* 2>&1) || { echo "FAIL one group: exit $?"; echo "$out"; fail=$((fail + 1)); }
expect "run 1: phi 30.0, c 18.0" "| 30.0 | 18.0 | 1.70 | 45.0 -> 48.0 | 3 |" "$out"
expect "run 3: phi 40.0, c 16.0" "| 40.0 | 16.0 |" "$out"
expect "group mean and standard deviation" "box: phi_lin mean 35.0 deg, std 5.0 deg, min 30.0, max 40.0 (n = 3)" "$out"
[ -s "$work/one.png" ] && echo "ok   figure, one group" || { echo "FAIL no figure (one group)"; fail=$((fail + 1)); }
out=$(python3 "$src/scripts/validate/ring_shear_compare.py" "$work/two.png" "$work"/box/seed_* "$work"/ring/seed_1 2>&1) || { echo "FAIL two groups: exit $?"; echo "$out"; fail=$((fail + 1)); }
expect "second group, with its consolidation stress" "ring at 54.8 kPa: phi_lin mean 36.0 deg, std nan deg, min 36.0, max 36.0 (n = 1)" "$out"
expect "its cell" "| ring at 54.8 kPa/seed_1 | annulus | 1968 |" "$out"
[ -s "$work/two.png" ] && echo "ok   figure, two groups" || { echo "FAIL no figure (two groups)"; fail=$((fail + 1)); }
mkrun box 4 45 25 shear_box nocircle
out=$(COHDEM_BIN="$bin" bash "$src/scripts/validate/ring_shear.sh" --table-only -s "1 2 3 4" -o "$work" box.toml 2>&1) || { echo "FAIL table: exit $?"; echo "$out"; fail=$((fail + 1)); }
expect "the seed without a circle named" "seed 4: sigma_2 < 0 (made up)" "$out"
expect "its phi counted" "phi_lin_deg: mean 37.5, median 37.5, min 30, max 45, std 6.45 (n = 4)" "$out"
expect "its c counted" "cohesion_Pa: mean 1.9e+04, median 1.75e+04, min 1.6e+04, max 2.5e+04, std 4.08e+03 (n = 4)" "$out"
expect "its ffc not" "ffc: mean 1.7, median 1.7, min 1.7, max 1.7, std 0 (n = 3)" "$out"
out=$(python3 "$src/scripts/validate/ring_shear_compare.py" "$work/three.png" "$work"/box/seed_* 2>&1) || { echo "FAIL compare with a null ffc: exit $?"; echo "$out"; fail=$((fail + 1)); }
expect "null ffc shown as -" "| 45.0 | 25.0 | - |" "$out"
out=$(python3 "$src/scripts/validate/ring_shear_compare.py" --flow-function "$work/ff.png" "$work/four.png" "$work"/box/seed_* "$work"/ring/seed_1 2>&1) || { echo "FAIL flow function: exit $?"; echo "$out"; fail=$((fail + 1)); }
expect "flow function drawn" "flow function: $work/ff.png" "$out"
expect "the run without sigma_1 left out of it" "flow function, box: mean sigma_1 100.0 kPa, mean sigma_c 60.0 kPa, ratio 1.67 (n = 3)" "$out"
[ -s "$work/ff.png" ] && echo "ok   flow function figure" || { echo "FAIL no flow function figure"; fail=$((fail + 1)); }
[ $fail = 0 ]
