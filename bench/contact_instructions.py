#!/usr/bin/env python3
"""Instructions per contact of each contact law in the bulk force loop, counted with
valgrind's callgrind on identical contacts, and each law's cost relative to the linear law
and to the linear law with the same rolling resistance: the instruction-count form of issue 6's "MEPA n = 3/2 with rolling resistance costs at most
1.3x the linear model", repeatable on any machine at any load.

  python3 bench/contact_instructions.py                       # the six laws with lanes
  python3 bench/contact_instructions.py --models 'linear,mepa+epsd' --iters 6 --json out.json

The problem is BM_Force of build/cohdem_bench (bench/micro.cpp): 32,768 spheres in a simple
cubic lattice, slightly compressed, three contacts each in the half list (98,304 contacts,
every one touching), the same for every law; the force loop (screening, contacts, sums and
each particle's finish) runs COHDEM_BENCH_ITERS times after five set-up steps. The count is
the inclusive count of the law's ContactModelImpl::compute (every call: the set-up steps'
and the timed ones', found from the call count callgrind reports) over calls x contacts
(the contacts from the benchmark's own counters).
The AVX2 screening and lanes run where the CPU has AVX2 (as in a run); COHDEM_SIMD=0 in the
environment counts the portable scalar code instead.

valgrind 3.19 (Debian 12) does not decode AVX-512: the benchmark binary must be the
project's portable build (it is: no -march), and the CPU valgrind presents has no AVX-512,
so the count is of the four AVX2 lanes even where a run takes the eight AVX-512 ones. Python 3 standard library only.
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)


def count(bench, model, iters, work):
    """(instructions per contact, calls of compute, contacts) for one BM_Force/<model>."""
    out = os.path.join(work, "callgrind." + re.sub(r"[^a-z0-9]+", "_", model) + ".out")
    filt = "BM_Force/" + re.escape(model) + "/32(/|$)"  # the 32^3 lattice (BM_Force also runs 8^3; /iterations:N may follow)
    env = dict(os.environ, COHDEM_BENCH_ITERS=str(iters))
    r = subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", bench,
                        f"--benchmark_filter={filt}", "--benchmark_format=json"],
                       capture_output=True, text=True, env=env, cwd=REPO)
    try:
        b = json.loads(r.stdout)["benchmarks"][0]
        contacts = round(b["particles"] * b["contacts_per_particle"])  # every one touching
    except (ValueError, KeyError, IndexError):
        b, contacts = None, 0
    if r.returncode != 0 or b is None or contacts <= 0:
        sys.exit(f"{bench} --benchmark_filter={filt} under callgrind failed:\n{r.stderr[-2000:]}")
    # The calls of ContactModelImpl<...>::compute (the region's outlined body is a clone, not
    # counted apart) and their inclusive cost.
    ann = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", "--tree=caller", out],
                         capture_output=True, text=True).stdout
    total, calls = None, 0
    for block in ann.split("\n\n"):  # a function's callers ('<' lines), then the function ('*')
        lines = block.strip().splitlines()
        star = [ln for ln in lines if re.search(r"\)\s+\*\s", ln)]
        if (len(star) != 1 or "[clone" in star[0]
                or not re.search(r"ContactModelImpl<.*>::compute\(cohdem::ForceContext&\) const \[", star[0])):
            continue  # not the law's compute (its region's outlined body is a '[clone ._omp_fn.0]')
        total = int(star[0].split()[0].replace(",", ""))
        calls = sum(int(m.group(1)) for ln in lines if re.search(r"\)\s+<\s", ln)
                    for m in [re.search(r"\((\d+)x\)", ln)] if m)
    if total is None or calls == 0:
        sys.exit(f"no ContactModelImpl::compute with its callers in {out}")
    return total / (calls * contacts), calls, contacts


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--models", default="linear,linear+epsd,hertz_mindlin,hertz_mindlin+epsd,mepa,mepa+epsd",
                    help="comma-separated BM_Force tags (law, or law+rolling)")
    ap.add_argument("--iters", type=int, default=6, help="timed force-loop calls (COHDEM_BENCH_ITERS)")
    ap.add_argument("--bench", default=os.path.join(REPO, "build", "cohdem_bench"))
    ap.add_argument("--json", help="also write the counts to this file")
    a = ap.parse_args()
    if not os.path.exists(a.bench):
        sys.exit(f"{a.bench} not found: build it first (ninja -C build cohdem_bench)")
    models = [m for m in a.models.split(",") if m]
    rows = []
    with tempfile.TemporaryDirectory() as work:
        for m in models:
            ipc, calls, contacts = count(a.bench, m, a.iters, work)
            rows.append((m, ipc, calls))
            print(f"  {m:22s} {ipc:8.1f} instructions per contact ({calls} force-loop calls)", flush=True)
    base = {m: ipc for m, ipc, _ in rows}
    print()
    print(f"{'model':22s} {'instructions/contact':>21s} {'vs linear':>10s} {'vs linear+same rolling':>23s}")
    def ratio(x, ref):
        return f"{x / ref:.3f}x" if ref else "-"
    for m, ipc, _ in rows:
        roll = m.split("+")[1] if "+" in m else None
        like = base.get("linear+" + roll) if roll else base.get("linear")
        print(f"{m:22s} {ipc:21.1f} {ratio(ipc, base.get('linear')):>10s} {ratio(ipc, like):>23s}")
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"contacts": contacts, "iters": a.iters,
                       "instructions_per_contact": {m: ipc for m, ipc, _ in rows}}, f, indent=1)

if __name__ == "__main__":
    main()
