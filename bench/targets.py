#!/usr/bin/env python3
"""Issue 6's four targets, measured in one invocation and judged, with every figure's source.

  python3 bench/targets.py                  # all four, about 20 minutes on the 2-core development VM
  python3 bench/targets.py --only scaling   # some of them: peers, scaling, contacts (comma-separated)
  python3 bench/targets.py --quick          # the script end to end in about a minute (small sizes, few
                                            # steps: the figures then say nothing about the targets)

The targets and how each is measured (by the scripts beside this one, whose logs and JSON files
stay in OUT):

  1. One thread at least 2x LAMMPS's particle-steps per second on both chute problems (LAMMPS's
     chute, linear spring-dashpot with history; the same chute with Hertz-Mindlin + rolling).
     bench/peer_compare.py, runs interleaved and pinned round by round to one core; the ratio
     is the paired one (median over the rounds of cohdem's rate over LAMMPS's in the same
     round), and the physics check (kinetic energy, mean flow velocity) must pass.
  2. Two threads at least 1.8x one thread, with results identical to one thread.
     bench/scaling.py --per-core --ceiling on the gas at 10^4, 10^5 and 10^6 particles and on
     the chute: the two-thread median over the mean of the two cores' one-thread medians (on a VM whose
     cores differ in speed, an unpinned one-thread run measures where it landed), beside what
     two independent one-thread runs started together gave on the same scale (--ceiling: the
     most any two-thread code could reach on this machine at that moment). Identical:
     the last one- and two-thread runs of each problem end with the same kinetic energies, to
     every digit. --serial-blocks too: the blocks swept one after another on one thread
     (COHDEM_SERIAL_BLOCKS=1), where the problem takes plain steps, splits the two-thread loss
     into the split's own work and what the second core adds. --placement too (with
     cohdem_bench): the cost of a line written by the other core, read before and after each
     two-thread run, gives the speed-ups apart for the host's two placements of the vCPUs
     (shown beside the verdict, which is on all runs).
  3. Cost per particle-step flat within 20 % from 10^4 to 10^6 particles: the one-thread
     median rates of the same scaling runs, 10^4 over 10^6. Where LAMMPS is installed, the
     scaling runs also time it on the same gases (scaling.py --lammps): its own 10^6-over-10^4
     ratio on this machine, and cohdem's lead at each size, go beside the verdict (the verdict
     is cohdem's alone).
  4. MEPA n = 3/2 with EPSD rolling resistance at most 1.3x the linear model, on identical
     contacts (the force loop of cohdem_bench's BM_Force lattice): counted instructions per
     contact (bench/contact_instructions.py, callgrind: the same on any machine, of the four
     AVX2 lanes, since valgrind presents a CPU without AVX-512) and CPU time (of the lanes the
     machine runs: eight in AVX-512 where it has them, said beside the figure;
     cohdem_bench's BM_ForceAlternate: the two force loops alternated in blocks of a few
     calls inside one process, the ratio paired block by block; the median of its repetitions).
     Each law alternated with a second lattice of itself is the method's control: its ratio
     must come out within 3 % of 1, or the CPU-time figure is not trusted (not met). Each
     block starts from the same histories (sticking contacts, as in a packing at rest); the
     verdict is on these. Beside it, for the reader: MEPA without rolling, the linear law
     with EPSD, and MEPA + EPSD without EPSD's viscous part (eta_r = 0, the ring shear cases'
     setting), each over the linear law; and the target's pair with every contact sliding
     (BM_ForceAlternateSliding: a bed that shears), with its linear control.

Each target is judged on this invocation's figures only: "met" or "not met". Timings on a
shared VM move from run to run (docs/performance.md quotes several invocations); the JSON
file OUT/targets.json keeps the figures. Exit status: 0 when every measurement ran (met or
not), 1 when one failed. Needs build/cohdem and build/cohdem_bench, LAMMPS (bench/install-peers.sh)
for the first target and valgrind for the fourth. Python 3 standard library only.
"""
import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)


def run(cmd, log):
    """Runs one of the bench scripts, its output into log; returns whether it succeeded."""
    shown = cmd[1:] if cmd[0] == sys.executable else cmd
    print(f"  {' '.join(os.path.relpath(c, REPO) if c.startswith(REPO) else c for c in shown)}", flush=True)
    t0 = time.time()
    with open(log, "w") as f:
        rc = subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT).returncode
    print(f"    {'done' if rc == 0 else 'FAILED (rc %d)' % rc} in {time.time() - t0:.0f} s, log {log}", flush=True)
    return rc == 0


def peers(a, out):
    """Target 1 from peer_compare.py's results.json."""
    d = os.path.join(out, "peers")
    cmd = [sys.executable, os.path.join(HERE, "peer_compare.py"), "--problems", "chute,chute_hmr", "--peers", "lammps",
           "--runs", str(a.runs), "--steps", str(a.steps), "--cohdem", a.cohdem, "--out", d]
    if a.chute_data:
        cmd += ["--chute-data", a.chute_data]
    if not run(cmd, os.path.join(out, "peers.log")):
        return None
    res = json.load(open(os.path.join(d, "results.json")))["results"]
    rows = {}
    for prob in ("chute", "chute_hmr"):
        c = res[prob]["codes"]
        lmp = c["lammps"]
        rows[prob] = {"paired": lmp["ratio_paired"], "median": lmp["ratio_median"], "best": lmp["ratio_best"],
                      "round_by_round": [x / y for x, y in zip(c["cohdem"]["rate"], lmp["rate"])],
                      "cohdem_median": c["cohdem"]["median"], "lammps_median": lmp["median"],
                      "physics_ok": lmp["physics_ok"], "rel_diff_ke": lmp["rel_diff_ke"], "rel_diff_v": lmp["rel_diff_v"],
                      "rel_diff_ke_rot": lmp.get("rel_diff_ke_rot")}
    return rows


def scaling(a, out):
    """Targets 2 and 3 from scaling.py's scaling.json and its last runs' summaries."""
    d = os.path.join(out, "scaling")
    sizes = [a.small, a.mid, a.large]
    cmd = [sys.executable, os.path.join(HERE, "scaling.py"), "--sizes", ",".join(map(str, sizes)), "--threads", "1,2",
           "--repeat", str(a.repeat), "--steps", str(a.steps), "--chute", "--per-core", "--ceiling", "--serial-blocks",
           "--cohdem", a.cohdem,
           "--out", d]
    if a.chute_data:
        cmd += ["--chute-data", a.chute_data]
    if shutil.which("lmp"):
        cmd += ["--lammps"]
    if os.path.exists(a.bench):  # the host's placement of the two vCPUs around each two-thread run
        cmd += ["--placement", a.bench]
    if not run(cmd, os.path.join(out, "scaling.log")):
        return None
    js = json.load(open(os.path.join(d, "scaling.json")))
    rows = js["rows"]
    keys = [(f"p{n}", f"{n:,}") for n in sizes] + [("chute", "32,000 (chute)")]
    speed, same = {}, {}
    for key, label in keys:
        one = next(r for r in rows if r["problem"] == label and r["threads"] == 1)
        two = next(r for r in rows if r["problem"] == label and r["threads"] == 2)
        # scaling.py's own figures (--per-core, --ceiling): the two-thread median and what two
        # independent one-thread runs started together gave (the most any two-thread code could
        # reach here), each over the mean of the cores' one-thread medians.
        speed[label] = {k: two[k] for k in ("one_thread_per_core", "speedup_mean_core", "ceiling_mean_core")}
        # Where the two threads' time went (summary.json's thread_sweep, through scaling.py).
        for k in ("sweeps_over_one_thread_step", "step_minus_longest_sweep_us", "imbalance_us", "handed_over_per_call",
                  "serial_sweeps_over_one_thread_step", "sweeps_over_serial_sweeps"):
            if k in two:
                speed[label][k] = two[k]
        speed[label]["speedup_unpinned"] = two["median_particle_steps_per_s"] / one["median_particle_steps_per_s"]
        if two.get("placement"):
            speed[label]["placement"] = two["placement"]
        # The last run of each thread count (scaling.py keeps each one's output folder).
        s1, s2 = (json.load(open(os.path.join(d, f"run_{key}_{t}", "summary.json"))) for t in (1, 2))
        fields = ("steps", "kinetic_energy", "translational_energy", "rotational_energy", "contacts")
        same[label] = {f: [repr(s1[f]), repr(s2[f])] for f in fields}
        same[label]["identical"] = all(s1[f] == s2[f] for f in fields)
    lo = next(r for r in rows if r["problem"] == f"{a.small:,}" and r["threads"] == 1)
    hi = next(r for r in rows if r["problem"] == f"{a.large:,}" and r["threads"] == 1)
    flat = {"small": a.small, "large": a.large,
            "ns_small": 1e9 / lo["median_particle_steps_per_s"], "ns_large": 1e9 / hi["median_particle_steps_per_s"],
            "ratio_median": lo["median_particle_steps_per_s"] / hi["median_particle_steps_per_s"],
            "ratio_best": lo["particle_steps_per_s"] / hi["particle_steps_per_s"]}
    L = js.get("lammps")
    if L and "flatness" in L:  # LAMMPS on the same gases, in the same repeats
        small, large = L[f"p{a.small}"], L[f"p{a.large}"]
        flat["lammps"] = {"ratio_median": L["flatness"]["lammps"], "ns_small": 1e9 / small["lammps_median"],
                          "ns_large": 1e9 / large["lammps_median"], "lead_small": small["ratio_paired"],
                          "lead_large": large["ratio_paired"],
                          "physics_ok": all(v["physics_ok"] for k, v in L.items() if k != "flatness")}
    return {"speedup": speed, "identical": same, "flatness": flat}


CONTROL_TOL = 0.03  # BM_ForceAlternate of a law against itself: within 3 % of 1


def contacts(a, out):
    """Target 4 from contact_instructions.py (counts) and BM_ForceAlternate (CPU time)."""
    ci = os.path.join(out, "contact_instructions.json")
    fa = os.path.join(out, "force_alternate.json")
    ok = run([sys.executable, os.path.join(HERE, "contact_instructions.py"), "--models", "linear,mepa+epsd",
              "--iters", str(a.iters), "--bench", a.bench, "--json", ci], os.path.join(out, "contact_instructions.log"))
    ok = run([a.bench, "--benchmark_filter=BM_ForceAlternate(Sliding)?/", f"--benchmark_min_time={a.min_time}",
              f"--benchmark_repetitions={a.rounds}", "--benchmark_enable_random_interleaving=true",
              f"--benchmark_out={fa}"],
             os.path.join(out, "force_alternate.log")) and ok
    if not ok:
        return None
    ipc = json.load(open(ci))["instructions_per_contact"]
    reps = {}  # "a/b" (sticking) or "sliding:a/b" -> the iteration runs (one per repetition)
    for b in json.load(open(fa))["benchmarks"]:
        if b.get("run_type", "iteration") == "iteration" and "ratio" in b:
            parts = b["name"].split("/")
            key = ("sliding:" if parts[0].endswith("Sliding") else "") + "/".join(parts[1:3])
            reps.setdefault(key, []).append(b)
    med = lambda key, field: statistics.median(r[field] for r in reps[key])
    return {"instructions_linear": ipc["linear"], "instructions_mepa_epsd": ipc["mepa+epsd"],
            "count_ratio": ipc["mepa+epsd"] / ipc["linear"],
            "time_linear_s": med("linear/mepa+epsd", "a_ms") * 1e-3,
            "time_mepa_epsd_s": med("linear/mepa+epsd", "b_ms") * 1e-3,
            "time_ratio": med("linear/mepa+epsd", "ratio"),
            "time_ratio_repetitions": [r["ratio"] for r in reps["linear/mepa+epsd"]],
            "time_ratio_quartiles": [med("linear/mepa+epsd", "ratio_q1"), med("linear/mepa+epsd", "ratio_q3")],
            "blocks": sum(int(r["blocks"]) for r in reps["linear/mepa+epsd"]),
            "lanes": int(reps["linear/mepa+epsd"][0].get("lanes", 0)),  # 8 (AVX-512), 4 (AVX2), 0 (scalar)
            "control_linear": med("linear/linear", "ratio"),
            "control_mepa_epsd": med("mepa+epsd/mepa+epsd", "ratio"),
            # for the reader: which part of the law costs what, over the linear law
            "time_ratio_mepa": med("linear/mepa", "ratio"),
            "time_ratio_linear_epsd": med("linear/linear+epsd", "ratio"),
            "time_ratio_mepa_epsd_eta0": med("linear/mepa+epsd0", "ratio"),
            # every contact sliding (a shearing bed): the same pair and the linear control
            "time_ratio_sliding": med("sliding:linear/mepa+epsd", "ratio"),
            "control_linear_sliding": med("sliding:linear/linear", "ratio")}


def verdict(ok):
    return "**met**" if ok else "not met"


def table(got):
    """The targets table from the figures of the measurements that ran: (target, measured, status)
    rows, each judged against issue 6's bound."""
    rows = []
    P = got.get("peers")
    if P:
        names = {"chute": "linear chute", "chute_hmr": "Hertz-Mindlin + rolling chute"}
        meas = "; ".join(f"{names[p]} **{r['paired']:.2f}x** paired (round by round "
                         f"{min(r['round_by_round']):.2f}-{max(r['round_by_round']):.2f}x; median {r['median']:.2f}x, "
                         f"best {r['best']:.2f}x), physics {'ok' if r['physics_ok'] else 'DIFFERS'}"
                         + (f" (KE {r['rel_diff_ke']:.1e}, v {r['rel_diff_v']:.1e}"
                            + (f", KE_rot {r['rel_diff_ke_rot']:.1e}" if r.get('rel_diff_ke_rot') is not None else "")
                            + ")" if "rel_diff_ke" in r else "")
                         for p, r in P.items())
        ok = all(r["paired"] >= 2.0 and r["physics_ok"] for r in P.values())
        rows.append(("1 thread >= 2x LAMMPS on both chutes", meas, verdict(ok)))
    S = got.get("scaling")
    if S:
        sp = S["speedup"]
        same = [v["identical"] for v in S["identical"].values()]
        ident = all(same)
        def one(k, v):
            c = v.get("ceiling_mean_core")
            return f"{k} **{v['speedup_mean_core']:.2f}x**" + (f" (two runs at once {c:.2f}x)" if c else "")
        meas = ("; ".join(one(k, v) for k, v in sp.items()) +
                f" (over the mean core's one-thread median); final state identical on {sum(same)} of {len(same)} problems")
        # Where the time went, on the problems that ran their force loop on two threads (a
        # gas below parallel_min runs it on one): both threads' sweeps over the one-thread
        # step (the work the split adds), and the step beyond the longer sweep (waits, joins).
        parts = [f"{k} {v['sweeps_over_one_thread_step']:.2f}x, {v['step_minus_longest_sweep_us']:.0f} us"
                 + (f", {v['imbalance_us']:.0f} us" if "imbalance_us" in v else "")
                 for k, v in sp.items() if "sweeps_over_one_thread_step" in v]
        if parts:
            meas += ("; the two threads' sweeps over the one-thread step, a step beyond the longest sweep"
                     " and the calls' imbalance: " + "; ".join(parts))
        # The blocks swept in series on one thread (scaling.py --serial-blocks; plain steps
        # only): the split's own work over the one-thread step, and what the second core added.
        ser = [f"{k} {v['serial_sweeps_over_one_thread_step']:.2f}x and {v['sweeps_over_serial_sweeps']:.2f}x"
               for k, v in sp.items() if "serial_sweeps_over_one_thread_step" in v]
        if ser:
            meas += ("; the blocks swept in series on one thread over the one-thread step (the split's own work),"
                     " and the two threads' sweeps over those in series (what the second core adds): " + "; ".join(ser))
        # The same runs apart by the host's placement of the two vCPUs (scaling.py --placement:
        # a line written by the other core, read before and after each run); the verdict is on
        # all the runs.
        def placed(v, c):
            P = v.get("placement") or {}
            x, m = P.get(f"speedup_{c}"), (P.get("runs") or {}).get(c, 0)
            return f"{x:.2f}x ({m})" if x is not None else f"- ({m})"
        if any(v.get("placement") for v in sp.values()):
            split = next(v["placement"]["split_ns"] for v in sp.values() if v.get("placement"))
            meas += (f"; the same runs by the host's placement of the vCPUs (a line written by the other core, before "
                     f"and after each run, below {split:g} ns both times: near; above: far; runs in brackets): near "
                     + " / ".join(placed(v, "near") for v in sp.values()) + ", far "
                     + " / ".join(placed(v, "far") for v in sp.values()))
        ok = ident and all(v["speedup_mean_core"] >= 1.8 for v in sp.values())
        status = verdict(ok)
        if not ok:
            met = [k for k, v in sp.items() if v["speedup_mean_core"] >= 1.8]
            status += f" (identical: {'met' if ident else 'NOT MET'}; 1.8x at {', '.join(met) if met else 'no size'}"
            low = [k for k, v in sp.items() if v["speedup_mean_core"] < 1.8 and v.get("ceiling_mean_core", 9) < 1.8]
            if low:
                status += f"; two independent one-thread runs reached less than 1.8x too at {', '.join(low)}"
            status += ")"
        rows.append(("2 threads >= 1.8x 1 thread, identical results", meas, status))
        F = S["flatness"]
        meas = (f"{F['large']:,} over {F['small']:,} on one thread: **{F['ratio_median']:.2f}x** median, "
                f"{F['ratio_best']:.2f}x best ({F['ns_large']:.0f} against {F['ns_small']:.0f} ns per particle-step)")
        FL = F.get("lammps")
        if FL:
            meas += (f"; LAMMPS on the same gases in the same repeats {FL['ratio_median']:.2f}x ({FL['ns_large']:.0f} "
                     f"against {FL['ns_small']:.0f} ns), cohdem {FL['lead_small']:.2f}x / {FL['lead_large']:.2f}x as fast "
                     f"(paired), physics {'ok' if FL['physics_ok'] else 'DIFFERS'}")
        rows.append(("cost per particle-step flat within 20 % (10^4 to 10^6)", meas, verdict(F["ratio_median"] <= 1.2)))
    C = got.get("contacts")
    if C:
        controls_ok = all(abs(C[k] - 1.0) <= CONTROL_TOL for k in ("control_linear", "control_mepa_epsd"))
        meas = (f"counted **{C['count_ratio']:.3f}x** ({C['instructions_mepa_epsd']:.1f} against "
                f"{C['instructions_linear']:.1f} instructions per contact, the four AVX2 lanes: valgrind has no AVX-512); "
                f"CPU time **{C['time_ratio']:.3f}x** ({str(C['lanes']) + ' lanes' if C.get('lanes') else 'the scalar law'}) "
                f"(the force loops alternated in one process, paired block by block: quartiles "
                f"{C['time_ratio_quartiles'][0]:.2f}-{C['time_ratio_quartiles'][1]:.2f}x; "
                f"{C['time_mepa_epsd_s'] * 1e3:.2f} against {C['time_linear_s'] * 1e3:.2f} ms per force call; "
                f"controls, each law against itself: {C['control_linear']:.3f}, {C['control_mepa_epsd']:.3f}"
                f"{'' if controls_ok else ', OFF by more than %g %%: the CPU time is not trusted' % (100 * CONTROL_TOL)}"
                + (f"; over linear: MEPA alone {C['time_ratio_mepa']:.3f}x, linear + EPSD {C['time_ratio_linear_epsd']:.3f}x, "
                   f"MEPA + EPSD with eta_r = 0 {C['time_ratio_mepa_epsd_eta0']:.3f}x" if "time_ratio_mepa" in C else "")
                + (f"; with every contact sliding {C['time_ratio_sliding']:.3f}x (control "
                   f"{C['control_linear_sliding']:.3f})" if "time_ratio_sliding" in C else "")
                + ")")
        count_ok, time_ok = C["count_ratio"] <= 1.3, C["time_ratio"] <= 1.3 and controls_ok
        status = verdict(count_ok and time_ok)
        if count_ok != time_ok:
            status += f" (in the count: {'met' if count_ok else 'not met'}; in CPU time: {'met' if time_ok else 'not met'})"
        rows.append(("MEPA n = 3/2 + rolling <= 1.3x linear", meas, status))
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--only", default="peers,scaling,contacts", help="which measurements (peers, scaling, contacts)")
    ap.add_argument("--quick", action="store_true", help="small sizes and few steps: checks the script, not the targets")
    ap.add_argument("--runs", type=int, default=5, help="peer comparison: interleaved rounds")
    ap.add_argument("--steps", type=int, default=1000, help="steps of every timed run")
    ap.add_argument("--repeat", type=int, default=3, help="scaling: repeats of each run")
    ap.add_argument("--small", type=int, default=10000)
    ap.add_argument("--mid", type=int, default=100000)
    ap.add_argument("--large", type=int, default=1000000)
    ap.add_argument("--rounds", type=int, default=3, help="BM_ForceAlternate: repetitions")
    ap.add_argument("--min-time", default="2", help="BM_ForceAlternate: --benchmark_min_time per repetition, s")
    ap.add_argument("--iters", type=int, default=6, help="counted force-loop calls (contact_instructions.py)")
    ap.add_argument("--cohdem", default=os.path.join(REPO, "build", "cohdem"))
    ap.add_argument("--bench", default=os.path.join(REPO, "build", "cohdem_bench"))
    ap.add_argument("--out", default=os.path.join(REPO, "build", "bench", "targets"))
    ap.add_argument("--chute-data", default=None, help="LAMMPS's data.chute (default: ../shared/peers/lammps-chute/)")
    a = ap.parse_args()
    if a.quick:
        a.runs, a.steps, a.repeat, a.rounds, a.min_time, a.iters = 1, 5, 1, 1, "0.05", 1
        a.small, a.mid, a.large = 1000, 2000, 4000
    only = {w for w in a.only.split(",") if w}
    unknown = only - {"peers", "scaling", "contacts"}
    if unknown:
        sys.exit(f"--only: unknown {', '.join(sorted(unknown))} (peers, scaling, contacts)")
    if not a.small < a.mid < a.large:
        sys.exit("--small < --mid < --large is required")
    out = os.path.abspath(a.out)
    os.makedirs(out, exist_ok=True)
    when = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    rev = subprocess.run(["git", "-C", REPO, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    print(f"issue 6's targets, {when}, engine {rev or '?'}{' (--quick: the figures say nothing)' if a.quick else ''}",
          flush=True)
    got, failed = {}, []
    for name, fn in (("peers", peers), ("scaling", scaling), ("contacts", contacts)):
        if name in only:
            got[name] = fn(a, out)
            if got[name] is None:
                failed.append(name)

    rows = table(got)
    print(f"\n| target | measured ({when}, engine {rev or '?'}) | status |\n|---|---|---|")
    for t, m, s in rows:
        print(f"| {t} | {m} | {s} |")
    for name in failed:
        print(f"\n{name}: the measurement FAILED (its log is in {out})")
    with open(os.path.join(out, "targets.json"), "w") as f:
        json.dump({"when": when, "engine": rev, "args": vars(a), "figures": got,
                   "table": [{"target": t, "measured": m, "status": s} for t, m, s in rows]}, f, indent=1)
    print(f"\nfigures and logs in {out} (targets.json)")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
