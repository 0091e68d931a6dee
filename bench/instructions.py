#!/usr/bin/env python3
"""Instructions per particle-step of cohdem and its peers on the same problems, counted
with valgrind's callgrind: a measure of work that does not move with the machine's load.

  python3 bench/instructions.py                          # chute and chute_hmr, cohdem + LAMMPS
  python3 bench/instructions.py --codes cohdem,lammps,liggghts --steps 200
  python3 bench/instructions.py --problems packing --packing-n 2000 --codes cohdem   # quick

Wall-clock rates on a shared machine move by 15-30 % from run to run (bench/peer_compare.py
interleaves runs and quotes median and best for that reason); the number of instructions a
code executes per particle-step does not. Each code runs each problem twice under callgrind,
for BASE and for BASE + STEPS steps, from the same input as bench/peer_compare.py gives it
(same files, same folder layout), and the difference of the two totals over particles x
STEPS is the cost of a step without the set-up, reading, checks and output that both runs
share. Per function as well (the same difference per symbol): the top ones are printed.

Instructions are not time: a code that executes as many instructions per step but misses the
cache less, or keeps more of them in flight, runs faster. The ratio of the wall-clock ratio
(bench/peer_compare.py) to the instruction ratio is the ratio of instructions per cycle.
cohdem runs on one thread here (callgrind serialises threads anyway), peers on one rank.
Needs valgrind (scripts/install-deps.sh installs it; the peers come from bench/install-peers.sh). Python 3 standard
library only; results also go to OUT/instructions.json.
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import peer_compare as pc  # noqa: E402  (inputs and problem table shared with the timing script)

REPO = pc.REPO


def short_name(fn):
    """callgrind_annotate's 'file:function [object]' -> the function, template arguments
    and parameter lists elided (templates nest, so innermost first)."""
    fn = re.sub(r"\s+\[/[^\]]*\]\s*$", "", fn)           # the object file
    m = re.match(r"^(.*?)(?<!:):(?!:)(.*)$", fn)          # the source file (??? without -g)
    if m and ("/" in m.group(1) or m.group(1) == "???" or m.group(1).startswith(".")):
        fn = m.group(2)
    prev = None
    while prev != fn:
        prev = fn
        fn = re.sub(r"<[^<>]*>", "<>", fn)
    fn = re.sub(r"\([^()]*\)", "()", fn)
    return fn.strip()


def per_function(outfile):
    """Exclusive instruction counts per function (summed over the source files GCC inlined
    into it) and the program total, from a callgrind output file."""
    text = subprocess.run(["callgrind_annotate", "--inclusive=no", "--threshold=100", "--auto=no", outfile],
                          capture_output=True, text=True, check=True).stdout
    total, funcs, table = None, {}, False
    for line in text.splitlines():
        if total is not None and "file:function" in line:
            table = True  # the per-function table follows (a build with -g may annotate sources after it)
            continue
        if table and line.startswith("-- "):
            break
        m = re.match(r"^\s*([\d,]+)\s+(?:\(\s*[\d.]+%\)\s+)?(.*)$", line)
        if not m:
            continue
        n, what = int(m.group(1).replace(",", "")), m.group(2)
        if what.startswith("PROGRAM TOTALS"):
            total = n
        elif table and ":" in what and not what.lstrip().startswith("=>"):
            name = short_name(what)
            funcs[name] = funcs.get(name, 0) + n
    if total is None:
        raise RuntimeError(f"no PROGRAM TOTALS in callgrind_annotate's output for {outfile}")
    return total, funcs


def run_counted(cmd, work, tag):
    """Runs cmd under callgrind in folder work; returns (total, per-function counts, screen output)."""
    out = os.path.join(work, f"callgrind.{tag}.out")
    log = os.path.join(work, f"{tag}.log")
    text = pc.sh(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}"] + cmd, work, log)
    total, funcs = per_function(out)
    return total, funcs, text


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--problems", default="chute,chute_hmr", help="chute, chute_hmr, packing")
    ap.add_argument("--codes", default="cohdem,lammps", help="cohdem, lammps, liggghts")
    ap.add_argument("--steps", type=int, default=100, help="steps counted (the difference of the two runs)")
    ap.add_argument("--base", type=int, default=20, help="steps of the shorter run")
    ap.add_argument("--packing-n", type=int, default=100000)
    ap.add_argument("--top", type=int, default=6, help="functions listed per code and problem")
    pc.add_input_args(ap, os.path.join(REPO, "build", "bench", "instructions"))
    a = ap.parse_args()
    if a.steps < 1 or a.base < 1:
        sys.exit("--steps and --base must be >= 1")

    problems = [p for p in a.problems.split(",") if p]
    codes = [c for c in a.codes.split(",") if c]
    table = pc.problem_table()
    for p in problems:
        if p not in table:
            sys.exit(f"unknown problem '{p}' ({', '.join(table)})")
    for tool in ("valgrind", "callgrind_annotate"):
        if not shutil.which(tool):
            sys.exit(f"{tool} not found: run scripts/install-deps.sh (it installs valgrind)")
    for c in codes:
        exe = a.cohdem if c == "cohdem" else pc.PEER_EXE.get(c)
        if exe is None:
            sys.exit(f"unknown code '{c}' (cohdem, lammps, liggghts)")
        if not (shutil.which(exe) or os.path.exists(exe)):
            sys.exit(f"{exe} not found" + (": build cohdem first" if c == "cohdem" else ": run bench/install-peers.sh"))
    if a.chute_data is None:
        a.chute_data = pc.find_chute_data()
    os.makedirs(a.out, exist_ok=True)
    work = os.path.abspath(a.out)
    pc.prepare_inputs(work, problems, a.chute_data, a.packing_n)

    results = {}
    for pname in problems:
        P = table[pname]
        print(f"\n== {pname}: instructions per particle-step over {a.steps} steps "
              f"(runs of {a.base} and {a.base + a.steps} steps under callgrind)", flush=True)
        res = {}
        for c in codes:
            counted = []
            for n in (a.base, a.base + a.steps):
                tag = f"{pname}.{c}.{n}"
                if c == "cohdem":
                    out = os.path.join(work, f"{pname}.cohdem.out{n}")
                    total, funcs, _ = run_counted(P.command(c, n, os.path.abspath(a.cohdem), 1, out), work, tag)
                    atoms = pc.cohdem_summary(out, n)["particles"]
                else:
                    total, funcs, text = run_counted(P.command(c, n), work, tag)
                    _, steps, atoms = pc.peer_loop(text)
                    if steps != n:
                        raise RuntimeError(f"{c} ran {steps} steps, not {n}; see {tag}.log")
                counted.append((total, funcs, atoms))
            (t0, f0, n0), (t1, f1, n1) = counted
            if n0 != n1:
                raise RuntimeError(f"{c}: particle count changed between the runs ({n0}, {n1})")
            ps = float(n1) * a.steps
            per = (t1 - t0) / ps
            fdiff = {k: (f1.get(k, 0) - f0.get(k, 0)) / ps for k in set(f0) | set(f1)}
            top = sorted(fdiff.items(), key=lambda kv: -kv[1])[:a.top]
            res[c] = {"particles": n1, "instructions_per_particle_step": per,
                      "top_functions": [{"function": k, "per_particle_step": v} for k, v in top]}
            print(f"  {c:9s} {per:8.1f} instructions per particle-step ({n1} particles)", flush=True)
            for k, v in top:
                print(f"      {v:7.1f}  {100 * v / per:5.1f} %  {k[:110]}")
        if "cohdem" in res:
            for c in codes:
                if c != "cohdem":
                    r = res["cohdem"]["instructions_per_particle_step"] / res[c]["instructions_per_particle_step"]
                    res[c]["cohdem_over_peer"] = r
                    print(f"  cohdem / {c}: {r:.3f} of its instructions per particle-step")
        results[pname] = {"steps": a.steps, "base": a.base, "codes": res}
    with open(os.path.join(work, "instructions.json"), "w") as f:
        json.dump({"when": time.strftime("%Y-%m-%d %H:%M:%S"), "args": vars(a), "results": results}, f, indent=1)
    print(f"\ncallgrind files, logs and instructions.json in {work}")


if __name__ == "__main__":
    main()
