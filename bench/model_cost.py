#!/usr/bin/env python3
"""What a contact model costs in a whole run: LAMMPS's chute (32,000 spheres) with the linear
model (bench/chute.toml), the linear model + EPSD rolling (bench/chute_epsd.toml),
Hertz-Mindlin + EPSD rolling (bench/chute_hm_epsd.toml) and MEPA n = 3/2 + EPSD rolling
(bench/chute_mepa.toml), run by cohdem in one invocation, interleaved.

  python3 bench/model_cost.py                   # 5 runs of 1000 steps each, 1 thread
  python3 bench/model_cost.py --runs 7 --steps 500 --threads 2

For each case: particle-steps per second (median, best), contacts per particle (mean of
the run's series rows), ns per particle-step and ns per contact-step (loop time over
contacts x steps: the law's own cost is easier to see when the contact counts differ), and
the ratio to the linear model's time per particle-step, and for the laws with rolling
resistance the ratio to the linear model with the same rolling sub-model (like for like:
the normal and tangential laws alone differ). The softer laws leave more particles in
contact than the stiff linear spring (the same bed, other physics), so the chute ratio is
that of a user's choice of model on one problem; the cost of the law alone, on identical
contacts, is BM_Force / BM_Step of cohdem_bench (bench/micro_table.py). Python 3 standard
library only.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys

from peer_compare import HERE, REPO, find_chute_data  # same folder

CASES = [("linear", "chute.toml"), ("linear+epsd", "chute_epsd.toml"), ("hertz_mindlin+epsd", "chute_hm_epsd.toml"),
         ("mepa+epsd", "chute_mepa.toml")]


def mean_contacts(series_csv):
    """Mean of the contacts column of a run's series.csv (every series row of the run)."""
    with open(series_csv) as f:
        head = f.readline().strip().split(",")
        col = head.index("contacts")
        vals = [float(line.split(",")[col]) for line in f if line.strip()]
    return statistics.fmean(vals)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=5, help="runs per case (interleaved)")
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--cohdem", default=os.path.join(REPO, "build", "cohdem"))
    ap.add_argument("--chute-data", default=None)
    ap.add_argument("--out", default=os.path.join(REPO, "build", "bench", "model_cost"))
    a = ap.parse_args()
    data = a.chute_data or find_chute_data()
    if not os.path.exists(data):
        sys.exit(f"{data} not found (--chute-data)")
    if not os.path.exists(a.cohdem):
        sys.exit(f"{a.cohdem} not found: build cohdem first (ninja -C build)")
    os.makedirs(a.out, exist_ok=True)
    for _, case in CASES:
        subprocess.run([sys.executable, os.path.join(HERE, "lammps_data_to_case.py"), data, os.path.join(HERE, case),
                        "-o", os.path.join(a.out, case)], check=True)

    runs = {name: [] for name, _ in CASES}
    for r in range(a.runs):
        for name, case in CASES:
            out = os.path.join(a.out, "run_" + name)
            cmd = [a.cohdem, "run", os.path.join(a.out, case), "--set", f"simulation.duration={a.steps * 1e-4:.10g}",
                   "--threads", str(a.threads), "--out", out, "--quiet"]
            p = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
            if p.returncode != 0:
                sys.exit(f"{' '.join(cmd)} failed ({p.returncode}):\n{p.stderr[-2000:]}")
            s = json.load(open(os.path.join(out, "summary.json")))
            runs[name].append(s)
            print(f"run {r + 1}/{a.runs} {name:20s} {s['particle_steps_per_s']:.3e} particle-steps/s", flush=True)

    print(f"\ncohdem, LAMMPS's chute (32,000 spheres), {a.steps} steps, {a.threads} thread(s), "
          f"{a.runs} interleaved runs each")
    print("| model | particle-steps/s median | best | contacts per particle | ns per particle-step (median) "
          "| ns per contact-step | time per particle-step vs linear (median) | vs linear with the same rolling |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    table = {}
    ns_of = {}
    for name, _ in CASES:
        v = [s["particle_steps_per_s"] for s in runs[name]]
        med, best = statistics.median(v), max(v)
        s0 = runs[name][-1]
        cpp = mean_contacts(os.path.join(a.out, "run_" + name, "series.csv")) / s0["particles"]
        ns = ns_of[name] = 1e9 / med
        base = ns_of["linear"]
        # Like for like: a law with a rolling sub-model against the linear law with the same one.
        roll = name.partition("+")[2]
        same = ns / ns_of["linear+" + roll] if roll and name != "linear+" + roll else None
        table[name] = {"median": med, "best": best, "contacts_per_particle": cpp, "ns_per_particle_step": ns,
                       "ns_per_contact_step": ns / cpp, "vs_linear": ns / base, "vs_linear_same_rolling": same,
                       "kinetic_energy": s0["kinetic_energy"], "runs": v}
        print(f"| {name} | {med:.3e} | {best:.3e} | {cpp:.2f} | {ns:.0f} | {ns / cpp:.0f} | {ns / base:.2f}x "
              f"| {'' if same is None else f'{same:.2f}x'} |")
    json.dump(table, open(os.path.join(a.out, "results.json"), "w"), indent=1)


if __name__ == "__main__":
    main()
