#!/usr/bin/env python3
"""A/B timing of two cohdem binaries (or two environments of one) on one case, the way the
rounds in docs/performance-history.md ("What was changed for speed") measure each change.

  python3 bench/ab.py CASE --a OLD/cohdem --b build/cohdem --duration 0.5 --rounds 10
  python3 bench/ab.py CASE --a build/cohdem --env-b "COHDEM_SIMD=0" --rounds 8
  python3 bench/ab.py CASE --a OLD/cohdem --b build/cohdem --together --rounds 16
  python3 bench/ab.py main --a OLD/cohdem --b build/cohdem --rounds 4    # the main job, whole (about 45 s a run)

This machine's host moves a run's speed by up to 2.5x from minute to minute, so one run of
each says nothing about a change of a few per cent. Two ways to pair the runs:

* alternated (the default): each round runs A and B one after the other, one thread, both
  pinned to the same core (core 0 in even rounds, core 1 in odd ones), A first in even
  rounds and B first in odd ones; the ratio B/A is taken round by round and its median
  quoted, with the medians and the best of each side.
* --together: each round runs A on one core and B on the other at the same time, so the two
  see the same spell of the host. The run started second ends later, with the other core
  idle for its last moments, which can favour it (one A/A control with B always started
  second gave B/A 1.04-1.21, median 1.08): so the start order alternates every round and the
  cores every two rounds, and each cycle of four rounds (both orders on both assignments)
  is combined by its geometric mean; the median of those is quoted. Use a multiple of four
  rounds.

A change is worth a claim only where the pairs agree; with 8-16 rounds a single ratio
within about 3-5 % of 1 is within this machine's noise (run the A/A control, --b equal to
--a, in the same spell to see the spread).

Every run ends with its kinetic energy and contact count in summary.json; the script
reports whether A and B ended with the same bits (as a change that only reorders work must).
Python 3 standard library only; runs are pinned and checked by peer_compare.py's `sh`.
"""
import argparse
import json
import math
import os
import shutil
import statistics
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import peer_compare as pc  # noqa: E402  (sh: a run pinned to a core, its failure raised with its log)


def parse_env(text):
    env = {}
    for kv in (text or "").split():
        if "=" not in kv:
            sys.exit(f"ab.py: --env-a/--env-b: expected KEY=VALUE, got '{kv}'")
        k, v = kv.split("=", 1)
        env[k] = v
    return env


def run(binary, env_extra, case, a, core, out):
    """One run of binary on case (pinned to core unless None): its rate and its final state.
    case "main": the main job, the embedded default case, whole (a ring shear test: its
    final state is its yield locus and shear points)."""
    env = dict(os.environ)
    env.update(env_extra)
    if case == "main":
        cmd = [binary, "run", "--threads", str(a.threads), "--out", out, "--quiet"]
    else:
        cmd = [binary, "run", case, "--set", f"simulation.duration={a.duration!r}", "--threads", str(a.threads),
               "--out", out, "--quiet"]
    pc.sh(cmd, None, out + ".log", cpu=core, env=env)
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    if case == "main":
        return s["particle_steps_per_s"], (json.dumps(s["yield_locus"], sort_keys=True),
                                           json.dumps(s["shear_points"], sort_keys=True))
    return s["particle_steps_per_s"], (s["kinetic_energy"], s["contacts"])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("case", help="a cohdem case file, or 'main': the main job (the embedded default case, whole;"
                                 " --duration does not apply)")
    ap.add_argument("--a", required=True, help="binary A (the reference)")
    ap.add_argument("--b", help="binary B (default: A, with --env-b)")
    ap.add_argument("--env-a", default="", help="environment for A's runs, 'KEY=VALUE ...'")
    ap.add_argument("--env-b", default="", help="environment for B's runs, 'KEY=VALUE ...'")
    ap.add_argument("--duration", type=float, default=0.1, help="simulated seconds per run (simulation.duration)")
    ap.add_argument("--rounds", type=int, default=8)
    ap.add_argument("--threads", type=int, default=1, help="threads per run (pinned only with 1)")
    ap.add_argument("--together", action="store_true", help="A and B at once, one per core, cores swapped each round")
    a = ap.parse_args()
    if a.rounds < 1:
        sys.exit("ab.py: --rounds: expected at least 1")
    if not (a.duration > 0 and math.isfinite(a.duration)):
        sys.exit("ab.py: --duration: expected a positive number of seconds")
    if a.case != "main" and not os.path.isfile(a.case):
        sys.exit(f"ab.py: case file '{a.case}' not found")
    b_bin = a.b or a.a
    for label, path in (("--a", a.a), ("--b", b_bin)):
        if not (os.path.isfile(path) and os.access(path, os.X_OK)):
            sys.exit(f"ab.py: {label}: '{path}' is not an executable file")
    env_a, env_b = parse_env(a.env_a), parse_env(a.env_b)
    if a.together and (os.cpu_count() or 1) < 2:
        sys.exit("ab.py: --together needs two cores")
    pin = a.threads == 1
    work = tempfile.mkdtemp(prefix="cohdem_ab_")
    ra, rb, ratio, same = [], [], [], True
    try:
        for r in range(a.rounds):
            oa, ob = os.path.join(work, "a"), os.path.join(work, "b")
            if a.together:
                # Started one after the other, the second run's loop ends later, with the other
                # core idle for a while: the start order alternates every round, the cores every
                # two rounds.
                ca, cb = (0, 1) if (r // 2) % 2 == 0 else (1, 0)
                jobs = [("a", a.a, env_a, ca, oa), ("b", b_bin, env_b, cb, ob)]
                with ThreadPoolExecutor(2) as ex:
                    fut = {side: ex.submit(run, binary, env, a.case, a, core if pin else None, out)
                           for side, binary, env, core, out in (jobs if r % 2 == 0 else jobs[::-1])}
                (xa, ea), (xb, eb) = fut["a"].result(), fut["b"].result()
                first = "A" if r % 2 == 0 else "B"
                where = f"A core {ca}, B core {cb}, {first} started first" if pin else f"unpinned, {first} first"
            else:
                core = r % 2 if pin else None
                res = {}
                for side in (("a", "b") if r % 2 == 0 else ("b", "a")):
                    binary, env, out = (a.a, env_a, oa) if side == "a" else (b_bin, env_b, ob)
                    res[side] = run(binary, env, a.case, a, core, out)
                (xa, ea), (xb, eb) = res["a"], res["b"]
                where = f"core {core}, {'A' if r % 2 == 0 else 'B'} first" if pin else "unpinned"
            ra.append(xa)
            rb.append(xb)
            ratio.append(xb / xa)
            same = same and ea == eb
            print(f"round {r + 1:2d} ({where}): A {xa:.4g}  B {xb:.4g} particle-steps/s  B/A {xb / xa:.3f}", flush=True)
    except RuntimeError as e:  # a run that failed: its command, exit status and log's end
        sys.exit(f"ab.py: {e}")
    finally:
        shutil.rmtree(work, ignore_errors=True)
    what = "the main job (embedded default case)" if a.case == "main" else f"{a.case}, {a.duration!r} s simulated"
    print(f"\n{what}, {a.threads} thread(s), {a.rounds} rounds"
          f"{' (together)' if a.together else ' (alternated)'}")
    print(f"A: median {statistics.median(ra):.4g}, best {max(ra):.4g} particle-steps/s")
    print(f"B: median {statistics.median(rb):.4g}, best {max(rb):.4g} particle-steps/s")
    print(f"B/A paired: median {statistics.median(ratio):.3f} (rounds {min(ratio):.3f}-{max(ratio):.3f})")
    if a.together and len(ratio) >= 4:
        cyc = [math.prod(ratio[q:q + 4]) ** 0.25 for q in range(0, len(ratio) - 3, 4)]
        print(f"B/A over whole cycles (geometric mean of each four rounds: both start orders on both"
              f" core assignments): median {statistics.median(cyc):.3f} ({' '.join(f'{c:.3f}' for c in cyc)})")
    state = "yield locus and shear points" if a.case == "main" else "kinetic energy and contacts"
    print(f"same bits ({state} of every run): {'yes' if same else 'no'}")


if __name__ == "__main__":
    main()
