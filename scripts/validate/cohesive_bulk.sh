#!/usr/bin/env bash
# Bulk demonstrations of cohesion, longer runs (minutes): clusters of 67 and 155 spheres
# on a plane with and without MEPA/Walton cohesion (0.3 s), and Walton beds settled with and
# without bending/twisting resistance for several seeds at two sizes (400 spheres in
# 16 r x 16 r, 1600 in 32 r x 32 r), solids fraction at 0.1 s and 0.2 s.
# Physics, parameters and thresholds: tests/physics/test_cohesive_bulk.cpp, docs/cohesive-bulk.md.
#
# Usage: bash scripts/validate/cohesive_bulk.sh [OUT_DIR]     (default out/validate/cohesive_bulk)
# Environment: COHDEM_BULK_SEEDS (default 5), COHDEM_BULK_SIZES (default "400:16,1600:32"),
#              COHDEM_BULK_TIMES (default "0.1,0.2"); UPDATE_DOCS=1 copies the PNGs to docs/img.
# Writes OUT_DIR/clusters.csv, beds.csv, profile_*.csv, cohesive_bulk_*.png, log.txt, summary.txt.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
out=${1:-$root/out/validate/cohesive_bulk}
mkdir -p "$out"
out=$(cd "$out" && pwd)
bin=$root/build/cohdem_tests
[ -x "$bin" ] || { echo "build first: cmake -S . -B build -G Ninja && ninja -C build" >&2; exit 2; }
start=$(date +%s)
COHDEM_BULK_OUT=$out OMP_WAIT_POLICY=passive "$bin" --gtest_also_run_disabled_tests \
  --gtest_filter='CohesiveBulkValidation.*' | tee "$out/log.txt"
grep -q '\[  PASSED  \] 1 test' "$out/log.txt"

# Summary: mean and sample standard deviation of phi per (n, bf, t), and the paired difference.
{
  echo "# cohesive_bulk.sh: $(date -u +%Y-%m-%dT%H:%M:%SZ), $(git -C "$root" rev-parse --short HEAD), $(( $(date +%s) - start )) s"
  echo "clusters (rg, rxy in units of r; kept = fraction of initial contacts still touching at 0.3 s):"
  column -s, -t < "$out/clusters.csv"
  echo
  echo "beds: solids fraction between z = 4 r and z90 - 4 r, over seeds"
  awk -F, 'NR > 1 { k = $1 "," $2 "," $5 "," $4; n[k]++; s[k] += $6; q[k] += $6 * $6;
                    key[$1 "," $2 "," $5 "," $3 "," $4] = $6; seeds[$3] = 1 }
           END {
             printf "%6s %5s %6s %4s %8s %8s %4s\n", "n", "L/r", "t_s", "bf", "mean", "std", "runs";
             for (k in n) { split(k, a, ","); m = s[k] / n[k]; v = n[k] > 1 ? (q[k] - n[k] * m * m) / (n[k] - 1) : 0;
                            printf "%6s %5s %6s %4s %8.4f %8.4f %4d\n", a[1], a[2], a[3], a[4], m, sqrt(v > 0 ? v : 0), n[k] }
           }' "$out/beds.csv" | sort -k1,1n -k3,3n -k4,4nr
  echo
  echo "paired difference phi(bf = 0) - phi(bf = 1), per seed:"
  awk -F, 'NR > 1 { v[$1 "," $2 "," $5 "," $3 "," $4] = $6 }
           END { for (k in v) { split(k, a, ","); if (a[5] == 0) { w = a[1] "," a[2] "," a[3] "," a[4] ",1";
                   printf "n %5s L/r %3s t %4s seed %2s: %.4f\n", a[1], a[2], a[3], a[4], v[k] - v[w] } } }' \
      "$out/beds.csv" | sort -k2,2n -k6,6n -k8,8n
} | tee "$out/summary.txt"

# The user examples at full length, with their no-cohesion / no-moment variants (CLI).
last_col() {  # series.csv, column name: value in the last row
  awk -F, -v c="$2" 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == c) k = i } END { print $k }' "$1"
}
run_example() {  # label, case, extra args...
  local label=$1 case=$2; shift 2
  local o="$out/examples/$label"
  (cd "$root/examples/cohesive" && "$root/build/cohdem" run "$case" --out "$o" --quiet "$@" > "$o.log" 2>&1)
  printf "%-34s coordination %-8.3f bed_height/r %-7.3f wall %.1f s\n" "$label" "$(last_col "$o/series.csv" coordination)" \
    "$(awk -v h="$(last_col "$o/series.csv" bed_height)" 'BEGIN { print h / 1e-3 }')" \
    "$(grep -o '"wall_time_s": [0-9.]*' "$o/summary.json" | cut -d' ' -f2)"
}
mkdir -p "$out/examples"
{
  echo
  echo "examples/cohesive at full length (final row of series.csv; coordination = 2 x pair contacts / particles):"
  run_example cluster_mepa cluster_mepa.toml --set 'output.probes=["coordination","bed_height"]'
  run_example cluster_mepa_kadh0 cluster_mepa.toml --set contact.kadh=0 --set 'output.probes=["coordination","bed_height"]'
  run_example cluster_walton cluster_walton.toml --set 'output.probes=["coordination","bed_height"]'
  run_example cluster_walton_Fc0_0 cluster_walton.toml --set contact.Fc0=0 --set 'output.probes=["coordination","bed_height"]'
  run_example loose_packing_walton loose_packing_walton.toml
  run_example loose_packing_walton_bf0 loose_packing_walton.toml --set contact.bf=0
} | tee -a "$out/summary.txt"

if [ "${UPDATE_DOCS:-0}" = 1 ]; then
  cp "$out"/cohesive_bulk_clusters.png "$out"/cohesive_bulk_profiles.png "$root/docs/img/"
  echo "copied the PNGs to docs/img/"
fi
