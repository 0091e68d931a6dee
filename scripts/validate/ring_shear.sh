#!/usr/bin/env bash
# Ring shear validation: runs ring shear cases for several random fillings (seeds), a few at a
# time (one thread each), then tabulates every seed's yield-locus results with the median and
# the scatter:
#   OUT/CASE_NAME/seed_S/          the run's report (summary.json, series.csv, PNG plots) and
#                                  case.toml, the copy of the case it ran
#   OUT/CASE_NAME/results.csv      one row per seed
#   OUT/CASE_NAME/summary.txt      median, min, max and standard deviation over the seeds
# Usage:
#   scripts/validate/ring_shear.sh [-s "1 2 3"] [-j 2] [-o out/validate/ring_shear] [--table-only] CASE.toml... [-- --set key=value ...]
# Example (docs/ring-shear.md):
#   scripts/validate/ring_shear.sh -s "1 2 3" examples/ring_shear/copper_ore_5pct.toml examples/ring_shear/copper_ore_8pct.toml
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${COHDEM_BIN:-$root/build/cohdem}
seeds="1 2 3"; jobs=2; out=$root/out/validate/ring_shear; table_only=0
cases=(); extra=()
while [ $# -gt 0 ]; do
  case $1 in
    -s) seeds=$2; shift 2 ;;
    -j) jobs=$2; shift 2 ;;
    -o) out=$2; shift 2 ;;
    --table-only) table_only=1; shift ;;
    --) shift; extra=("$@"); break ;;
    *) cases+=("$1"); shift ;;
  esac
done
[ ${#cases[@]} -gt 0 ] || { sed -n '2,11p' "$0"; exit 2; }
[ -x "$bin" ] || { echo "no cohdem binary at $bin (build first: bash scripts/build.sh)"; exit 2; }

run_one() {  # case seed dir
  local c=$1 seed=$2 dir=$3 t0=$SECONDS
  mkdir -p "$dir"
  # Run a copy kept with the results: the report stays tied to the case it came from, and
  # editing the example during an hour-long run cannot affect the runs still queued.
  cp "$c" "$dir/case.toml"
  if "$bin" run "$dir/case.toml" --set simulation.seed="$seed" --set simulation.threads=1 ${extra[@]+"${extra[@]}"} \
       --out "$dir" --quiet > "$dir/log.txt" 2>&1; then
    echo "seed $seed of $(basename "$c"): done in $((SECONDS - t0)) s"
  else
    echo "seed $seed of $(basename "$c"): FAILED (see $dir/log.txt)"
  fi
}

if [ $table_only = 0 ]; then
  for c in "${cases[@]}"; do
    name=$(basename "$c" .toml)
    for seed in $seeds; do
      while [ "$(jobs -rp | wc -l)" -ge "$jobs" ]; do sleep 5; done
      run_one "$c" "$seed" "$out/$name/seed_$seed" &
    done
  done
  wait
fi

for c in "${cases[@]}"; do
  name=$(basename "$c" .toml)
  python3 - "$out/$name" $seeds <<'PY'
import json, math, os, statistics, sys
d, seeds = sys.argv[1], sys.argv[2:]
cols = ["seed", "phi_lin_deg", "cohesion_Pa", "sigma_1_Pa", "sigma_c_Pa", "ffc", "phi_e_deg", "phi_sf_deg",
        "preshear_sigma_Pa", "preshear_tau_Pa", "bulk_density", "particles", "steps", "wall_time_s", "cpu_time_s", "particle_steps_per_s"]
rows = []
for s in seeds:
    f = os.path.join(d, "seed_" + s, "summary.json")
    if not os.path.exists(f):
        continue
    j = json.load(open(f))
    # the evaluation of the measured shear points (the default), in any summary.json format
    if "yield_locus_raw" in j or j.get("normalized_points"):
        # older reports (measured points under yield_locus_raw) or normalize_points = true: the
        # other evaluation holds phi_lin, c, sigma_c, ffc only; sigma_1 = ffc sigma_c
        y = dict(j.get("yield_locus_raw") or j["yield_locus_measured_points"])
        if "error" not in y:
            finite = isinstance(y["ffc"], (int, float))  # not "inf", not null
            sp, tp = j["pre_shear"]["sigma"], j["pre_shear"]["tau"]
            y.update(sigma_1=y["ffc"] * y["sigma_c"] if finite else math.nan, phi_e_deg=math.nan,
                     phi_sf_deg=math.degrees(math.atan2(tp, sp)))
    else:
        y = j["yield_locus"]
    if "error" in y:
        print(f"seed {s}: evaluation failed: {y['error']}")
        continue
    # null (no steady-state circle: sigma_2 < 0, steady_state_error) counts as not a number;
    # the locus, sigma_c and phi_sf are still given then
    num = lambda v: math.nan if v is None else v
    ffc = math.inf if isinstance(y["ffc"], str) else num(y["ffc"])
    if "steady_state_error" in y:
        print(f"seed {s}: {y['steady_state_error']}")
    rows.append([s, y["phi_lin_deg"], y["cohesion"], num(y["sigma_1"]), y["sigma_c"], ffc, num(y["phi_e_deg"]), y["phi_sf_deg"],
                 j["pre_shear"]["sigma"], j["pre_shear"]["tau"], j["bulk_density_preshear"], j["particles"], j["steps"],
                 j["wall_time_s"], j.get("cpu_time_s", math.nan), j["particle_steps_per_s"]])
with open(os.path.join(d, "results.csv"), "w") as f:
    f.write(",".join(cols) + "\n")
    for r in rows:
        f.write(",".join(f"{x:.6g}" if isinstance(x, float) else str(x) for x in r) + "\n")
lines = [f"{os.path.basename(d)}: {len(rows)} seeds ({' '.join(r[0] for r in rows)})"]
for k in ["phi_lin_deg", "cohesion_Pa", "sigma_1_Pa", "sigma_c_Pa", "ffc", "phi_e_deg", "phi_sf_deg", "preshear_tau_Pa",
          "bulk_density", "wall_time_s", "cpu_time_s"]:
    i = cols.index(k)
    v = [float(r[i]) for r in rows if math.isfinite(float(r[i]))]
    if not v:
        lines.append(f"  {k}: no finite values"); continue
    sd = statistics.stdev(v) if len(v) > 1 else 0.0
    lines.append(f"  {k}: mean {statistics.mean(v):.4g}, median {statistics.median(v):.4g}, min {min(v):.4g}, "
                 f"max {max(v):.4g}, std {sd:.3g} (n = {len(v)})")
open(os.path.join(d, "summary.txt"), "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
PY
done
