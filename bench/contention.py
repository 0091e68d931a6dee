#!/usr/bin/env python3
"""cohdem against LAMMPS with and without a memory-bandwidth hog on the other core.

  python3 bench/contention.py                          # linear chute, 2 rounds x (quiet, hog), 5 runs each
  python3 bench/contention.py --problems chute,chute_hmr --rounds 3 --runs 3

A busy host slows every code, but not necessarily alike: a code whose step waits more on
memory should lose more when another process streams through memory beside it. This script
tests that directly on a machine with two or more cores. bench/peer_compare.py runs pinned
to one core (the last this process may use), alternating with and without a "hog" on another
core: a STREAM-like triad over three 256 MiB arrays (written here in C and compiled with the
system's C compiler into OUT), which takes as much of the memory bandwidth and of the shared
cache as one core can. The invocations alternate quiet, hog, quiet, hog, ... so that a slow
spell of the host falls on both modes. Printed per problem and invocation: each code's median
particle-steps/s, the paired ratio cohdem/peer, and per code the ratio of its median rates
with and without the hog (over all rounds). Physics is checked by peer_compare.py in every
invocation. Python 3 standard library only.
"""
import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import time

HOG_C = r"""
#include <stdio.h>
#include <stdlib.h>
int main(void) {
  const size_t n = (size_t)32 << 20; /* 32 Mi doubles, 256 MiB per array */
  double *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b), *c = malloc(n * sizeof *c);
  if (!a || !b || !c) return 1;
  for (size_t i = 0; i < n; ++i) { a[i] = 0; b[i] = 1; c[i] = 2; }
  for (unsigned long it = 0;; ++it) {
    for (size_t i = 0; i < n; ++i) a[i] = b[i] + 1.5 * c[i];
    if (a[it % n] < 0) puts("");  /* keeps the loop */
  }
}
"""


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--problems", default="chute", help="peer_compare.py problems (comma-separated)")
    ap.add_argument("--peers", default="lammps", help='peer codes for peer_compare.py ("" for cohdem alone)')
    ap.add_argument("--chute-data", default=None, help="LAMMPS chute data file (peer_compare.py's default otherwise)")
    ap.add_argument("--rounds", type=int, default=2, help="pairs of invocations (quiet, hog)")
    ap.add_argument("--runs", type=int, default=5, help="runs per code in each invocation")
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--cohdem", default=os.path.join(here, "..", "build", "cohdem"))
    ap.add_argument("--out", default=os.path.join(here, "..", "build", "bench", "contention"))
    a = ap.parse_args()
    if a.rounds < 1 or a.runs < 1 or a.steps < 1:
        sys.exit("error: --rounds, --runs and --steps must be >= 1")
    cores = sorted(os.sched_getaffinity(0))
    if len(cores) < 2:
        sys.exit("error: needs two cores (one for the runs, one for the hog); this process may use %d" % len(cores))
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        sys.exit("error: no C compiler (cc or gcc) to build the hog")
    os.makedirs(a.out, exist_ok=True)
    src, hog = os.path.join(a.out, "hog.c"), os.path.join(a.out, "hog")
    with open(src, "w") as f:
        f.write(HOG_C)
    subprocess.run([cc, "-O2", "-o", hog, src], check=True)
    run_core, hog_core = cores[-1], cores[0]
    print(f"bench/peer_compare.py pinned to core {run_core}; the hog on core {hog_core}", flush=True)

    rows = []  # (problem, mode, round, cohdem median, peer median, paired)
    for r in range(a.rounds):
        for mode in ("quiet", "hog"):
            out = os.path.join(a.out, f"{mode}{r + 1}")
            hp = None
            if mode == "hog":
                hp = subprocess.Popen([hog], preexec_fn=lambda: os.sched_setaffinity(0, {hog_core}))
                time.sleep(2)  # the arrays written once: the hog streams from here on
            try:
                cmd = [sys.executable, os.path.join(here, "peer_compare.py"), "--problems", a.problems, "--peers",
                       a.peers, "--runs", str(a.runs), "--steps", str(a.steps), "--cohdem", a.cohdem, "--out", out]
                if a.chute_data:
                    cmd += ["--chute-data", a.chute_data]
                with open(out + ".log", "w") as log:
                    subprocess.run(cmd, check=True, stdout=log, stderr=subprocess.STDOUT,
                                   preexec_fn=lambda: os.sched_setaffinity(0, {run_core}))
            finally:
                if hp is not None:
                    hp.kill()
                    hp.wait()
            res = json.load(open(os.path.join(out, "results.json")))["results"]
            for prob, pr in res.items():
                codes = pr["codes"]
                c = codes["cohdem"]["median"]
                peers = [p for p in a.peers.split(",") if p in codes] or [None]
                for peer in peers:
                    if peer is not None and not codes[peer].get("physics_ok"):
                        sys.exit(f"error: {prob}: physics check failed against {peer} ({out}.log)")
                    pm = codes[peer]["median"] if peer else float("nan")
                    paired = codes[peer]["ratio_paired"] if peer else float("nan")
                    rows.append((prob, peer, mode, r + 1, c, pm, paired))
                    line = f"  {prob:10s} {mode:5s} round {r + 1}: cohdem {c:.3e}"
                    if peer:
                        line += f", {peer} {pm:.3e}, cohdem/{peer} {paired:.2f}x paired"
                    print(line, flush=True)

    print()
    print("| problem | peer | mode | cohdem particle-steps/s (median of the invocations' medians) | peer | cohdem / peer (paired, each invocation) |")
    print("|---|---|---|---:|---:|---|")
    summary = {}
    for prob in dict.fromkeys(x[0] for x in rows):
        for peer in dict.fromkeys(x[1] for x in rows if x[0] == prob):
            for mode in ("quiet", "hog"):
                sel = [x for x in rows if x[0] == prob and x[1] == peer and x[2] == mode]
                c = statistics.median(x[4] for x in sel)
                p = statistics.median(x[5] for x in sel) if peer else float("nan")
                summary[(prob, peer, mode)] = (c, p)
                print(f"| {prob} | {peer or '-'} | {mode} | {c:.3e} | " + (f"{p:.3e}" if peer else "-") + " | "
                      + (", ".join(f"{x[6]:.2f}x" for x in sel) if peer else "-") + " |")
    print()
    for (prob, peer, mode), (c, p) in summary.items():
        if mode != "hog":
            continue
        cq, pq = summary[(prob, peer, "quiet")]
        line = f"{prob}: with the hog cohdem runs at {c / cq:.2f}x its quiet rate"
        if peer:
            line += f", {peer} at {p / pq:.2f}x"
        print(line)
    print(f"logs and results in {a.out}")


if __name__ == "__main__":
    main()
