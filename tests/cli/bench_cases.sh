#!/usr/bin/env bash
# The benchmark inputs stay valid as the code changes (issue 6: "keep the benchmark script
# working"): every bench/ case is built from its data as bench/peer_compare.py and
# bench/model_cost.py build it, passes `cohdem check` (time-step audit included), runs a few
# steps (the packed bed: its contacts and momentum by construction), model_cost.py prints its four rows, instructions.py counts a small packing,
# contact_instructions.py the force loop's instructions per contact of two laws,
# scaling.py gives its table for a small gas (with --ceiling and --per-core) and a small bed,
# peer_compare.py pins its rounds to the cores, contention.py runs it beside a memory hog,
# ab.py pairs two binaries' runs (an A/A control), and targets.py measures and judges issue
# 6's targets (its --quick run, with scaling.py --lammps through a stand-in lmp, and its verdicts
# on figures at the bounds).
# LAMMPS's chute data comes from ../shared beside the repository (as in CI). Speed itself is
# measured by the scripts, not here.
set -u
bin=$1; src=$2
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
data=""
for d in "$src/../shared" "$src/../../shared"; do
  [ -f "$d/peers/lammps-chute/data.chute" ] && { data="$d/peers/lammps-chute/data.chute"; break; }
done
[ -n "$data" ] || { echo "FAIL ../shared/peers/lammps-chute/data.chute not found beside $src"; exit 1; }
fail=0; pass=0
check_case() {  # name case.toml : check, then 3 steps
  local name=$1 case=$2
  if ! "$bin" check "$case" > "$work/$name.check" 2>&1; then echo "FAIL check $name"; cat "$work/$name.check"; fail=$((fail+1)); return; fi
  if ! "$bin" run "$case" --set simulation.duration=3e-4 --out "$work/o_$name" --quiet > "$work/$name.run" 2>&1; then
    echo "FAIL run $name"; tail -5 "$work/$name.run"; fail=$((fail+1)); return; fi
  python3 - "$work/o_$name/summary.json" "$name" "$work/$name.check" <<'PY' && pass=$((pass+1)) || fail=$((fail+1))
import json, math, re, sys
s = json.load(open(sys.argv[1]))
ok = s["steps"] == 3 and s["particles"] > 0 and math.isfinite(s["kinetic_energy"]) and s["particle_steps_per_s"] > 0
# The rate is particles x steps over the step loop's time; the final checkpoint is timed apart.
ok = ok and 0 < s["loop_time_s"] <= s["wall_time_s"] and s["final_checkpoint_s"] >= 0 and \
    abs(s["particle_steps_per_s"] * s["loop_time_s"] - s["particles"] * s["steps"]) <= 1e-6 * s["particles"] * s["steps"]
# `cohdem check`'s memory estimate against the time loop's measured peak (resident memory,
# the kernel's count): an upper estimate for a dense bed (the chutes start dense), so the
# measured peak lies below it, within 10 % over for the allocator's and the kernel's
# granularity, and above 0.6 of it (the estimate counts the lists' entries and contacts
# of a bed at random close packing; a chute's 3 first steps hold 3.5 entries and 0.5-1
# contacts a particle).
check = open(sys.argv[3]).read()
m = re.search(r"memory estimate: ([0-9.]+) MiB", check)
est = float(m.group(1)) * 1048576 if m else float("nan")
ratio = s["peak_rss_run_bytes"] / est
if sys.argv[2].startswith("chute"):
    ok = ok and 0.6 <= ratio <= 1.1
# These cases list their particles as [[particle]] tables: above 10,000 of them the check
# points to [[particles]] CSV files (the chutes' 32,000), below it says nothing (the packing's 2000).
ok = ok and ("are [[particle]] tables" in check) == (s["particles"] > 10000)
print(("ok   " if ok else "FAIL ") + sys.argv[2], s["particles"], "particles,", s["steps"], "steps, KE", s["kinetic_energy"],
      f"memory {s['peak_rss_run_bytes'] / 1048576:.1f} MiB, {ratio:.2f} of the estimate")
sys.exit(0 if ok else 1)
PY
}
for c in chute chute_epsd chute_hmr chute_hm_epsd chute_mepa; do
  python3 "$src/bench/lammps_data_to_case.py" "$data" "$src/bench/$c.toml" -o "$work/$c.toml" > /dev/null || { echo "FAIL convert $c"; fail=$((fail+1)); continue; }
  check_case "$c" "$work/$c.toml"
done
python3 "$src/bench/gen_packing.py" 2000 "$work/packing.data" > /dev/null &&
  python3 "$src/bench/lammps_data_to_case.py" "$work/packing.data" "$src/bench/packing.toml" -o "$work/packing.toml" \
    --frozen "" --box xy > /dev/null && check_case packing "$work/packing.toml" || { echo "FAIL packing input"; fail=$((fail+1)); }
# The packed bed (bench/gen_packing.py --bed, bench/bed.toml, scaling.py --bed): 10^3 spheres
# on a simple cubic lattice of spacing 0.999 d, periodic in x, y and z. By construction each
# sphere overlaps its six neighbours by 0.001 d and the random velocities (|v| <= 0.01) move
# it by under 1e-6 d in 3 steps, so the run holds exactly 3 contacts a sphere (no more: the
# next neighbours are sqrt(2) d apart); with no gravity and no walls the momentum is
# conserved, so the mean velocity stays the data file's to rounding (1e-12 of the mean
# speed, 0.005).
if python3 "$src/bench/gen_packing.py" 1000 "$work/bed.data" --bed > /dev/null &&
   python3 "$src/bench/lammps_data_to_case.py" "$work/bed.data" "$src/bench/bed.toml" -o "$work/bed.toml" \
     --frozen "" --box xyz > /dev/null; then
  check_case bed "$work/bed.toml"
  if python3 - "$work/o_bed/summary.json" "$work/bed.data" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
lines = open(sys.argv[2]).read().split("Velocities")[1].split("\n")
v = [list(map(float, l.split()[1:4])) for l in lines if l.strip()]
mean = [sum(c) / len(v) for c in zip(*v)]
ok = len(v) == 1000 and s["particles"] == 1000 and s["contacts"] == 3000
ok = ok and all(abs(a - b) <= 1e-12 * 0.005 for a, b in zip(s["mean_velocity"], mean))
print(("ok   " if ok else "FAIL ") + f"bed: {s['contacts']} contacts (3000 by construction), mean velocity {s['mean_velocity']} against {mean}")
sys.exit(0 if ok else 1)
PY
  then pass=$((pass+1)); else fail=$((fail+1)); fi
  # --bed --spacing outside [0.9, 1): a clear error, no file.
  if python3 "$src/bench/gen_packing.py" 1000 "$work/bad.data" --bed --spacing 1.0 > "$work/bad.log" 2>&1 ||
     [ -e "$work/bad.data" ] || ! grep -q "expected 0.9 <= spacing < 1" "$work/bad.log"; then
    echo "FAIL gen_packing.py --bed --spacing 1.0 accepted"; fail=$((fail+1))
  else pass=$((pass+1)); echo "ok   gen_packing.py --bed --spacing 1.0 refused"; fi
else echo "FAIL bed input"; fail=$((fail+1)); fi
# --csv: the same packing with its particles in a CSV file ([[particles]], one group: the
# same order) runs 3 steps to the same state, to the last digit of the energies.
if python3 "$src/bench/lammps_data_to_case.py" "$work/packing.data" "$src/bench/packing.toml" -o "$work/packing_csv.toml" \
     --frozen "" --box xy --csv > /dev/null && [ -f "$work/packing_csv.grain.csv" ] &&
   "$bin" run "$work/packing_csv.toml" --set simulation.duration=3e-4 --out "$work/o_packing_csv" --quiet > /dev/null 2>&1 &&
   python3 -c "
import json, sys
a, b = (json.load(open(f'$work/{o}/summary.json')) for o in ('o_packing', 'o_packing_csv'))
keys = ('particles', 'steps', 'kinetic_energy', 'rotational_energy', 'contacts')
sys.exit(0 if all(a[k] == b[k] for k in keys) else 1)"; then pass=$((pass+1)); echo "ok   packing --csv: the same state"; else echo "FAIL packing --csv"; fail=$((fail+1)); fi
# model_cost.py end to end (one run of 3 steps per law): four rows with positive rates.
if python3 "$src/bench/model_cost.py" --runs 1 --steps 3 --cohdem "$bin" --chute-data "$data" --out "$work/mc" > "$work/mc.log" 2>&1 &&
   python3 -c "
import json, sys
t = json.load(open('$work/mc/results.json'))
ok = set(t) == {'linear', 'linear+epsd', 'hertz_mindlin+epsd', 'mepa+epsd'} and all(r['median'] > 0 and r['contacts_per_particle'] > 0 for r in t.values())
sys.exit(0 if ok else 1)"; then pass=$((pass+1)); echo "ok   model_cost.py"; else echo "FAIL model_cost.py"; tail -5 "$work/mc.log"; fail=$((fail+1)); fi
# instructions.py end to end (cohdem only, a 2000-sphere packing, runs of 2 and 5 steps under
# callgrind): a positive count per particle-step, most of it in the force loop.
if python3 "$src/bench/instructions.py" --problems packing --packing-n 2000 --codes cohdem --base 2 --steps 3 \
     --cohdem "$bin" --out "$work/ins" > "$work/ins.log" 2>&1 &&
   python3 -c "
import json, math, sys
r = json.load(open('$work/ins/instructions.json'))['results']['packing']['codes']['cohdem']
n = r['instructions_per_particle_step']
# The force loop: the kernel and, on AVX2 machines, its screening (screen_avx2; screen_avx512 where AVX-512 runs).
loop = lambda f: any(s in f for s in ('ContactModelImpl', 'screen_avx2', 'screen_avx512'))
top = r['top_functions'][0]
in_loop = sum(t['per_particle_step'] for t in r['top_functions'] if loop(t['function']))
ok = math.isfinite(n) and n > 0 and loop(top['function']) and in_loop > 0.5 * n
sys.exit(0 if ok else 1)"; then pass=$((pass+1)); echo "ok   instructions.py"; else echo "FAIL instructions.py"; tail -5 "$work/ins.log"; fail=$((fail+1)); fi
# contact_instructions.py end to end (one timed force-loop call per law under callgrind): a
# positive count per contact for each law, the MEPA + EPSD law above the plain linear one
# (it does strictly more per contact: the hysteresis branches and the rolling spring).
bench_bin="$(dirname "$bin")/cohdem_bench"
if [ -x "$bench_bin" ]; then
  if python3 "$src/bench/contact_instructions.py" --models 'linear,mepa+epsd' --iters 1 --bench "$bench_bin" \
       --json "$work/ci.json" > "$work/ci.log" 2>&1 &&
     python3 -c "
import json, math, sys
c = json.load(open('$work/ci.json'))['instructions_per_contact']
ok = all(math.isfinite(v) and v > 0 for v in c.values()) and c['mepa+epsd'] > c['linear']
sys.exit(0 if ok else 1)"; then pass=$((pass+1)); echo "ok   contact_instructions.py"; else echo "FAIL contact_instructions.py"; tail -5 "$work/ci.log"; fail=$((fail+1)); fi
else
  echo "skip contact_instructions.py ($bench_bin not built: COHDEM_BUILD_BENCH=OFF)"
fi
# scaling.py end to end (a 1000-sphere gas, 3 steps, 1 and 2 threads, --ceiling's two
# one-thread runs at once and --per-core's one-thread runs pinned to each core): a row per
# thread count, positive rates and bytes per particle, the two runs' summed rate recorded
# against the one-thread run, a one-thread rate per core (the first two this process may
# use), and no run folder left holding its final checkpoint. With cohdem_bench built,
# --placement: the cost of a line written by the other core read before and after the
# two-thread run (two positive readings, the run counted in one class, its speed-up given
# for that class when near or far).
placement=()
[ -x "$bench_bin" ] && placement=(--placement "$bench_bin")
if python3 "$src/bench/scaling.py" --sizes 1000 --threads 1,2 --steps 3 --repeat 1 --ceiling --per-core --cohdem "$bin" \
     "${placement[@]}" --out "$work/sc" > "$work/sc.log" 2>&1 &&
   python3 -c "
import json, math, os, sys
rows = json.load(open('$work/sc/scaling.json'))['rows']
ok = [r['threads'] for r in rows] == [1, 2] and all(r['particle_steps_per_s'] > 0 and r['peak_rss_run_bytes'] > 0 for r in rows)
c = rows[1]['two_runs_at_once']
ok = ok and c is not None and len(c) == 1 and math.isfinite(c[0]) and c[0] > 0
per = rows[1].get('one_thread_per_core', {})
cores = sorted(os.sched_getaffinity(0))[:2]
ok = ok and sorted(map(int, per)) == cores and all(math.isfinite(v) and v > 0 for v in per.values())
mean = sum(per.values()) / len(per)
ok = ok and abs(rows[1]['speedup_mean_core'] - rows[1]['median_particle_steps_per_s'] / mean) < 1e-9 * rows[1]['speedup_mean_core']
ok = ok and abs(rows[1]['ceiling_mean_core'] - c[0] / mean) < 1e-9 * rows[1]['ceiling_mean_core']
runs = [d for d in os.listdir('$work/sc') if d.startswith('run_')]
ok = ok and len(runs) == 4 + len(cores) and not any(os.path.exists(os.path.join('$work/sc', d, 'checkpoint.bin')) for d in runs)
if os.access('$bench_bin', os.X_OK):
    P = rows[1]['placement']
    ok = ok and len(P['remote_line_ns']) == 1 and all(math.isfinite(x) and x > 0 for x in P['remote_line_ns'][0])
    ok = ok and sum(P['runs'].values()) == 1
    for c in ('near', 'far'):
        ok = ok and (P['speedup_' + c] is None) == (P['runs'][c] == 0)
        ok = ok and (P['runs'][c] == 0 or abs(P['speedup_' + c] - rows[1]['speedup_mean_core']) < 1e-9)
sys.exit(0 if ok else 1)"; then pass=$((pass+1)); echo "ok   scaling.py --ceiling --per-core ${placement[*]:+--placement}"; else echo "FAIL scaling.py"; tail -5 "$work/sc.log"; fail=$((fail+1)); fi
# scaling.py --bed end to end (the packed bed of 10^3 spheres, 3 steps, one thread): its own
# cases (keys b<N>), one row of 1,000 spheres holding 3 contacts each (by construction).
if python3 "$src/bench/scaling.py" --bed --sizes 1000 --threads 1 --steps 3 --repeat 1 --cohdem "$bin" \
     --out "$work/scb" > "$work/scb.log" 2>&1 &&
   python3 -c "
import json, os, sys
rows = json.load(open('$work/scb/scaling.json'))['rows']
ok = len(rows) == 1 and rows[0]['particles'] == 1000 and rows[0]['contacts'] == 3000 and rows[0]['particle_steps_per_s'] > 0
ok = ok and os.path.exists('$work/scb/b1000.toml') and not os.path.exists('$work/scb/p1000.toml')
sys.exit(0 if ok else 1)"; then pass=$((pass+1)); echo "ok   scaling.py --bed"; else echo "FAIL scaling.py --bed"; tail -5 "$work/scb.log"; fail=$((fail+1)); fi
# peer_compare.py's pinning without peers (cohdem alone, the chute, 2 rounds of 3 steps):
# round r ran on core r mod (cores this process may use), recorded per run; each run's peak
# resident memory recorded, and bytes per particle between 100 B (less than the particles'
# own state) and 100 kB.
if python3 "$src/bench/peer_compare.py" --peers "" --problems chute --runs 2 --steps 3 --cohdem "$bin" \
     --chute-data "$data" --out "$work/pc" > "$work/pc.log" 2>&1 &&
   python3 -c "
import json, os, sys
r = json.load(open('$work/pc/results.json'))['results']['chute']['codes']['cohdem']
cores = sorted(os.sched_getaffinity(0))
ok = r['cpu'] == [cores[k % len(cores)] for k in range(2)] and len(r['rate']) == 2 and all(x > 0 for x in r['rate'])
ok = ok and r['particles'] == 32000 and len(r['peak_rss_bytes']) == 2 and 100 < r['bytes_per_particle'] < 1e5
ok = ok and 100 < r['run_bytes_per_particle'] <= r['bytes_per_particle']
sys.exit(0 if ok else 1)"; then pass=$((pass+1)); echo "ok   peer_compare.py pinning, memory"; else echo "FAIL peer_compare.py"; tail -5 "$work/pc.log"; fail=$((fail+1)); fi
# peer_compare.py's physics check through a stand-in `lmp` first on the PATH (CI has no
# LAMMPS): it prints cohdem's own final energies and velocity (read from the round's cohdem
# summary, written just before) with the rotational energy scaled by COHDEM_STUB_ROT, and a
# step-0 row. The translational energy and velocity then agree exactly, so the rotational
# energy alone decides: 0.5 % off passes, 2 % off fails (ROT_TOL, 1 %), and the gain since
# step 0 is reported.
mkdir -p "$work/pcstub"
cat > "$work/pcstub/lmp" <<'PY'
#!/usr/bin/env python3
import json, os, sys
a = sys.argv[1:]
n = int({a[i + 1]: a[i + 2] for i, x in enumerate(a) if x == "-var"}["nsteps"])
j = json.load(open(os.path.join("chute.cohdem.out", "summary.json")))
ke, rot, v = j["translational_energy"], j["rotational_energy"], j["mean_velocity"][0]
print("   Step   Atoms   KinEng   c_1   v_vx")
print(f"  0 32000 {ke - 1.0!r} {rot!r} {v!r}")
print(f"  {n} 32000 {ke!r} {rot * float(os.environ['COHDEM_STUB_ROT'])!r} {v!r}")
print(f"Loop time of 1.0 on 1 procs for {n} steps with 32000 atoms")
PY
chmod +x "$work/pcstub/lmp"
pc_phys() {  # factor on the rotational energy -> physics_ok, rel_diff_ke_rot, rel_diff_ke, gain
  COHDEM_STUB_ROT=$1 PATH="$work/pcstub:$PATH" python3 "$src/bench/peer_compare.py" --peers lammps --problems chute \
    --runs 1 --steps 3 --cohdem "$bin" --chute-data "$data" --out "$work/pcs$1" > "$work/pcs$1.log" 2>&1 &&
  python3 -c "
import json
r = json.load(open('$work/pcs$1/results.json'))['results']['chute']['codes']['lammps']
print(r['physics_ok'], r['rel_diff_ke_rot'], r['rel_diff_ke'], r['rel_diff_ke_gain'])"
}
if p1=$(pc_phys 1.005) && p2=$(pc_phys 1.02) && python3 -c "
a, b = '$p1'.split(), '$p2'.split()
ok = a[0] == 'True' and abs(float(a[1]) - 0.005 / 1.005) < 1e-9 and float(a[2]) == 0 and float(a[3]) == 0
ok = ok and b[0] == 'False' and abs(float(b[1]) - 0.02 / 1.02) < 1e-9 and float(b[2]) == 0
raise SystemExit(0 if ok else 1)"; then pass=$((pass+1)); echo "ok   peer_compare.py judges the rotational energy ($p1 / $p2)"
else echo "FAIL peer_compare.py rotational energy ($p1 / $p2)"; tail -5 "$work/pcs1.02.log"; fail=$((fail+1)); fi
# contention.py end to end (cohdem alone, one round of one run of 3 steps; it needs two
# cores, as CI has): both invocations pinned to the last core this process may use, the hog
# stopped afterwards (no process of it left), and the summary line for the problem printed.
if [ "$(python3 -c 'import os; print(len(os.sched_getaffinity(0)))')" -ge 2 ]; then
  if python3 "$src/bench/contention.py" --peers "" --rounds 1 --runs 1 --steps 3 --cohdem "$bin" \
       --chute-data "$data" --out "$work/ct" > "$work/ct.log" 2>&1 &&
     ! pgrep -f "$work/ct/hog" > /dev/null &&
     grep -q "^chute: with the hog cohdem runs at" "$work/ct.log" &&
     python3 -c "
import json, os, sys
last = sorted(os.sched_getaffinity(0))[-1]
cpus = [json.load(open('$work/ct/' + m + '/results.json'))['results']['chute']['codes']['cohdem']['cpu'] for m in ('quiet1', 'hog1')]
sys.exit(0 if cpus == [[last], [last]] else 1)"; then
    pass=$((pass+1)); echo "ok   contention.py"
  else
    echo "FAIL contention.py"; tail -5 "$work/ct.log"; fail=$((fail+1))
  fi
fi
# peer_compare.py's memory of an MPI job, without mpirun (not installed in CI): two "ranks"
# under its RANK_WRAPPER, each touching 60 MB, started together by a shell; sh() sums the
# ranks' own peaks (each above 60 MB, so the sum above 120 MB, and below 2 x 200 MB); a
# missing rank and a failing rank's exit status are errors.
if python3 - "$src/bench" "$work" <<'PY'
import os, sys
sys.path.insert(0, sys.argv[1])
import peer_compare as pc
work = sys.argv[2]
d = os.path.join(work, "rank_rss")
rank = f"{sys.executable} -c \"{pc.RANK_WRAPPER}\" {d} {sys.executable} -c 'b = bytearray(60_000_000); b[::4096] = b\"x\" * len(b[::4096])'"
_, rss = pc.sh(["sh", "-c", f"{rank} & {rank}; wait"], work, os.path.join(work, "ranks.log"), rank_dir=d, ranks=2)
ok = len(os.listdir(d)) == 2 and 120e6 < rss < 400e6
try:  # a rank that recorded nothing is an error, not a smaller sum
    pc.sh(["sh", "-c", rank], work, os.path.join(work, "ranks1.log"), rank_dir=d, ranks=2)
    ok = False
except RuntimeError:
    pass
try:
    pc.sh(["sh", "-c", f"{sys.executable} -c \"{pc.RANK_WRAPPER}\" {d} false"], work, os.path.join(work, "ranks2.log"), rank_dir=d)
    ok = False
except RuntimeError:
    pass
print("ranks' memory", rss, "bytes")
sys.exit(0 if ok else 1)
PY
then pass=$((pass+1)); echo "ok   peer_compare.py: MPI ranks' memory summed"; else echo "FAIL peer_compare.py MPI ranks' memory"; fail=$((fail+1)); fi
# targets.py end to end (--quick: a 1000/2000/4000-sphere gas and the chute, 5 steps; the
# force-loop counts and times of two laws; no peer comparison): the table has its three rows,
# every problem's two-thread run ended as the one-thread run did (the thread-identity target,
# checked on the runs' own final energies), and the counted MEPA + EPSD law costs more than
# the linear one. Its scaling runs time LAMMPS on the same gases (scaling.py --lammps) through
# a stand-in `lmp` first on the PATH (CI has no LAMMPS), whose loop time is set so that it runs
# 1e8 / (1 + N / 1000) particle-steps/s, 20 ns per particle-step at 1000 spheres and 50 at
# 4000, and whose final energy is wrong: its 4000-over-1000 ratio must come out 2.5x, cohdem's
# lead the rates' quotient, and the physics check must fail.
mkdir -p "$work/stub"
cat > "$work/stub/lmp" <<'PY'
#!/usr/bin/env python3
import re, sys
a = sys.argv[1:]
var = {a[i + 1]: a[i + 2] for i, x in enumerate(a) if x == "-var"}
n = int(var["nsteps"])
m = int(re.search(r"(\d+)\s+atoms", open(var["data"]).read()).group(1))
print("   Step   Atoms   KinEng   c_1   v_vz")
print(f"  0 {m} 1 0 0")
print(f"  {n} {m} 1.0 0.5 -1.0")
print(f"Loop time of {m * n / (1e8 / (1 + m / 1000)):.15g} on 1 procs for {n} steps with {m} atoms")
PY
chmod +x "$work/stub/lmp"
if [ -x "$bench_bin" ]; then tg_only=scaling,contacts; tg_rows=3; else tg_only=scaling; tg_rows=2; fi
if PATH="$work/stub:$PATH" python3 "$src/bench/targets.py" --quick --only "$tg_only" --cohdem "$bin" --bench "$bench_bin" \
     --chute-data "$data" --out "$work/tg" > "$work/tg.log" 2>&1 &&
   python3 -c "
import json, sys
t = json.load(open('$work/tg/targets.json'))
S = t['figures']['scaling']
ok = len(t['table']) == $tg_rows and len(S['identical']) == 4 and all(v['identical'] for v in S['identical'].values())
ok = ok and all(v['ceiling_mean_core'] > 0 for v in S['speedup'].values())
C = t['figures'].get('contacts')
ok = ok and (C is None or (1.0 < C['count_ratio'] < 3.0 and 0.5 < C['time_ratio'] < 3.0 and C['blocks'] > 0
                           and C['lanes'] in (0, 4, 8)
                           and all(0.5 < C[k] < 2.0 for k in ('control_linear', 'control_mepa_epsd'))
                           and all(0.5 < C[k] < 3.0 for k in ('time_ratio_mepa', 'time_ratio_linear_epsd', 'time_ratio_mepa_epsd_eta0',
                                                              'time_ratio_sliding', 'control_linear_sliding'))))
L, FL = json.load(open('$work/tg/scaling/scaling.json'))['lammps'], S['flatness']['lammps']
close = lambda x, y: abs(x - y) <= 1e-9 * abs(y)
ok = ok and close(FL['ratio_median'], 2.5) and close(FL['ns_small'], 20) and close(FL['ns_large'], 50)
ok = ok and close(FL['lead_small'], L['p1000']['runs'][0]['cohdem_rate'] / 5e7) and not FL['physics_ok']
ok = ok and 'LAMMPS on the same gases in the same repeats 2.50x' in t['table'][1]['measured']
sys.exit(0 if ok else 1)"; then pass=$((pass+1)); echo "ok   targets.py --quick (LAMMPS stand-in)"; else echo "FAIL targets.py --quick"; tail -5 "$work/tg.log"; fail=$((fail+1)); fi
# targets.py's verdicts at the bounds (figures made up): >= 2x paired with the physics
# agreeing, >= 1.8x at every size with identical results, <= 1.2x flatness, <= 1.3x in the
# count and in CPU time; just past each bound, or with the physics or identity failing, or a
# control of the CPU-time measurement (a law against itself) off by more than 3 %, not met;
# a size missed where two independent runs also stayed below 1.8x is named as such; LAMMPS's
# own flatness, shown beside the verdict, does not change it.
if python3 - "$src/bench" <<'PY'
import sys
sys.path.insert(0, sys.argv[1])
import targets
def peers(a, b, phys=True):
    r = lambda x: {"paired": x, "median": x, "best": x, "round_by_round": [x], "physics_ok": phys}
    return {"peers": {"chute": r(a), "chute_hmr": r(b)}}
def scaling(sp, same=True, flat=1.2, ceiling=2.0):
    return {"scaling": {"speedup": {"10,000": {"speedup_mean_core": sp, "ceiling_mean_core": ceiling},
                                    "32,000 (chute)": {"speedup_mean_core": 1.9}},
                        "identical": {"10,000": {"identical": True}, "32,000 (chute)": {"identical": same}},
                        "flatness": {"small": 10000, "large": 1000000, "ns_small": 20, "ns_large": 20 * flat,
                                     "ratio_median": flat, "ratio_best": flat}}}
def contacts(count, time, control=1.0):
    return {"contacts": {"count_ratio": count, "time_ratio": time, "instructions_linear": 100,
                         "instructions_mepa_epsd": 100 * count, "time_linear_s": 1e-3, "time_mepa_epsd_s": time * 1e-3,
                         "time_ratio_quartiles": [time, time], "control_linear": control, "control_mepa_epsd": 1.0}}
def status(got, row=0):
    return targets.table(got)[row][2]
met = lambda s: s.startswith("**met**")
checks = [met(status(peers(2.0, 3.0))), not met(status(peers(1.99, 3.0))), not met(status(peers(2.5, 2.5, False))),
          met(status(scaling(1.8))), not met(status(scaling(1.79))), "NOT MET" in status(scaling(2.0, same=False)),
          "two independent" in status(scaling(1.7, ceiling=1.75)), "two independent" not in status(scaling(1.7)),
          met(status(scaling(1.8, flat=1.2), 1)), not met(status(scaling(1.8, flat=1.21), 1)),
          met(status(contacts(1.3, 1.3))), not met(status(contacts(1.25, 1.31))),
          "in CPU time: not met" in status(contacts(1.25, 1.31)), len(targets.table({})) == 0,
          met(status(contacts(1.25, 1.25, control=0.971))), met(status(contacts(1.25, 1.25, control=1.029))),
          not met(status(contacts(1.25, 1.25, control=1.031))),
          "not trusted" in targets.table(contacts(1.25, 1.25, control=0.969))[0][1]]
# LAMMPS's figures beside the flatness verdict do not move it: cohdem's 1.21x stays not met
# with a flat LAMMPS, 1.2x met with a steep one.
def with_lammps(flat, lmp):
    g = scaling(1.8, flat=flat)
    g["scaling"]["flatness"]["lammps"] = {"ratio_median": lmp, "ns_small": 40, "ns_large": 40 * lmp,
                                          "lead_small": 2.0, "lead_large": 2.0, "physics_ok": True}
    return g
checks += [not met(status(with_lammps(1.21, 1.0), 1)), met(status(with_lammps(1.2, 2.9), 1)),
           "LAMMPS on the same gases in the same repeats 2.90x" in targets.table(with_lammps(1.2, 2.9))[1][1]]
sys.exit(0 if all(checks) else 1)
PY
then pass=$((pass+1)); echo "ok   targets.py verdicts at the bounds"; else echo "FAIL targets.py verdicts"; fail=$((fail+1)); fi
# ab.py end to end: a binary against itself (an A/A control) on the packing of the cases
# above, 3 steps a run, alternated and together (the latter needs two cores): both end with
# the same bits; an environment the binary honours (COHDEM_SIMD=0, the scalar screening and
# laws, the same results by design) keeps them too; a missing binary is refused by name.
ab_ok=1
python3 "$src/bench/ab.py" "$work/packing.toml" --a "$bin" --duration 3e-4 --rounds 2 > "$work/ab1.log" 2>&1 &&
  grep -q "^B/A paired: median" "$work/ab1.log" && grep -q "^same bits .*: yes$" "$work/ab1.log" || ab_ok=0
python3 "$src/bench/ab.py" "$work/packing.toml" --a "$bin" --env-b "COHDEM_SIMD=0" --duration 3e-4 --rounds 1 > "$work/ab2.log" 2>&1 &&
  grep -q "^same bits .*: yes$" "$work/ab2.log" || ab_ok=0
if [ "$(python3 -c 'import os; print(len(os.sched_getaffinity(0)))')" -ge 2 ]; then
  python3 "$src/bench/ab.py" "$work/packing.toml" --a "$bin" --b "$bin" --together --duration 3e-4 --rounds 4 > "$work/ab3.log" 2>&1 &&
    grep -q "^B/A over whole cycles" "$work/ab3.log" && grep -q "^same bits .*: yes$" "$work/ab3.log" || ab_ok=0
fi
python3 "$src/bench/ab.py" "$work/packing.toml" --a "$work/no_such_cohdem" --rounds 1 > "$work/ab4.log" 2>&1 && ab_ok=0
grep -q "no_such_cohdem' is not an executable file" "$work/ab4.log" || ab_ok=0
if [ "$ab_ok" -eq 1 ]; then pass=$((pass+1)); echo "ok   ab.py"; else echo "FAIL ab.py"; tail -3 "$work"/ab*.log; fail=$((fail+1)); fi
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
