#!/usr/bin/env python3
"""Runs the micro-benchmarks (build/cohdem_bench) interleaved, several rounds, and prints the
median CPU time per iteration of each, its particle-steps per CPU-second and its cost
relative to the linear model (the force loop and the whole step each against their linear
counterpart), and, for a law with rolling resistance, relative to the linear model with the
same rolling sub-model (like for like). Interleaving matters on a shared machine: a
neighbour's load then falls on all benchmarks alike instead of on whichever ran at that
moment.

  python3 bench/micro_table.py                   # 5 rounds, the default set
  python3 bench/micro_table.py --rounds 7 --filters 'BM_Force/linear/,BM_Force/mepa\\+epsd/'

Python 3 standard library only.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
DEFAULT = ("BM_Force/linear/,BM_Force/linear\\+epsd/,BM_Force/hertz_mindlin/,BM_Force/hertz_mindlin\\+epsd/,"
           "BM_Force/mepa/,BM_Force/mepa\\+epsd/,BM_Force/walton/,BM_Step/linear/,BM_Step/linear\\+epsd/,"
           "BM_Step/mepa\\+epsd/,"
           "BM_CaseStep/1/,BM_CaseStep/2/,BM_NeighborBuild/,BM_NeighborBuildWithHistory/")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--filters", default=DEFAULT, help="comma-separated --benchmark_filter regexes")
    ap.add_argument("--min-time", default="0.5", help="--benchmark_min_time per run, s")
    ap.add_argument("--bench", default=os.path.join(REPO, "build", "cohdem_bench"))
    ap.add_argument("--json", help="also write each benchmark's times, s per iteration, round by round, to this file")
    a = ap.parse_args()
    if not os.path.exists(a.bench):
        sys.exit(f"{a.bench} not found: build it first (ninja -C build cohdem_bench)")
    filters = [f for f in a.filters.split(",") if f]
    runs = {}
    order = []
    for r in range(a.rounds):
        for f in filters:
            out = subprocess.run([a.bench, f"--benchmark_filter={f}", f"--benchmark_min_time={a.min_time}",
                                  "--benchmark_format=json"], capture_output=True, text=True, cwd=REPO)
            if out.returncode != 0:
                sys.exit(f"{a.bench} --benchmark_filter={f} failed:\n{out.stderr[-2000:]}")
            for b in json.loads(out.stdout)["benchmarks"]:
                if b.get("error_occurred"):
                    print(f"  {b['name']}: skipped ({b.get('error_message', '')})")
                    continue
                scale = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}[b["time_unit"]]
                name = b["name"]
                if name not in runs:
                    runs[name] = []
                    order.append(name)
                # Real time for the multi-threaded case benchmark (CPU time is the main thread's).
                t = (b["real_time"] if "real_time" in name else b["cpu_time"]) * scale
                runs[name].append((t, b.get("items_per_second", 0.0), b))
        print(f"  round {r + 1} of {a.rounds} done", flush=True)

    def med(name):
        return statistics.median(t for t, _, _ in runs[name])

    def ref(n):
        """The linear law's run of the same benchmark and size (BM_Force runs 8^3 and 32^3)."""
        parts = n.split("/")
        if parts[0] not in ("BM_Force", "BM_Step") or len(parts) < 3:
            return None
        r = "/".join([parts[0], "linear"] + parts[2:])
        return r if r in runs else None
    print(f"\nmedian of {a.rounds} interleaved rounds (CPU time; real time for BM_CaseStep)")
    print("| benchmark | ms per iteration | particle-steps per second | vs linear | vs linear with the same rolling "
          "| counters |")
    print("|---|---:|---:|---:|---:|---|")
    for n in order:
        m = med(n)
        rate = statistics.median(ips for _, ips, _ in runs[n])
        kind = n.split("/")[0]
        vs = f"{m / med(ref(n)):.2f}" if ref(n) else ""
        # Like for like: BM_Force/mepa+epsd/32 against BM_Force/linear+epsd/32, when both ran.
        parts = n.split("/")
        roll = parts[1].partition("+")[2] if len(parts) > 2 else ""
        twin = "/".join([kind, "linear+" + roll] + parts[2:]) if roll else ""
        same = f"{m / med(twin):.2f}" if twin in runs and twin != n else ""
        b = runs[n][-1][2]
        counters = ", ".join(f"{k} {b[k]:.3g}" for k in ("contacts_per_particle", "entries_per_particle",
                                                          "live_per_particle") if k in b)
        print(f"| {n} | {m * 1e3:.2f} | {rate:.3g} | {vs} | {same} | {counters} |")
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"rounds": a.rounds, "min_time": a.min_time,
                       "seconds_per_iteration": {n: [t for t, _, _ in runs[n]] for n in order}}, f, indent=1)


if __name__ == "__main__":
    main()
