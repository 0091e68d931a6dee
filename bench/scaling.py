#!/usr/bin/env python3
"""Scaling and memory table of cohdem: particle-steps per second and bytes per particle
(peak resident memory of the time loop over the particle count, and of the whole process:
the cases read their particles from CSV files, so the two are about the same) for 10^3 ..
10^6 particles on 1 and 2 threads.

  python3 bench/scaling.py                       # N = 1e3,1e4,1e5,1e6; threads 1,2; best of 3
  python3 bench/scaling.py --sizes 1000,10000 --threads 1 --repeat 5 --steps 300
  python3 bench/scaling.py --sizes 100000 --chute --repeat 5   # + LAMMPS's chute (dense flow)

The problem: bench/gen_packing.py's dense granular gas (spacing 1.01 d, random velocities,
floor, periodic x and y; contact law of the LAMMPS chute, bench/packing.toml), the same
number of steps at every size, so the physics per particle is the same and any change in
cost per particle-step comes from the code (cache, lists, threads). Runs are interleaved
over sizes and thread counts; the table shows the best run and the median. --chute adds
LAMMPS's chute benchmark (32,000 spheres in dense flow, bench/chute.toml), a problem with
4x as many contacts per particle as the gas.

--bed runs a packed bed at rest instead of the gas (bench/gen_packing.py --bed, bench/bed.toml;
LAMMPS: bench/peers/in.bed): spheres on a compressed simple cubic lattice (spacing 0.999 d,
periodic in x, y and z, no gravity), each pressing on its six neighbours for the whole run,
so every list entry is a contact (3 a particle) and the lists are never rebuilt. The gas is
the memory-bound end of the range (0.1 contacts a particle, the particle arrays streamed for
little arithmetic), the bed the contact-bound end (the contacts' records streamed with the
particles, and the contact law evaluated on every entry). Its sizes are cubes: a size N runs
round(N^(1/3))^3 spheres (10,648 for 10^4, 97,336 for 10^5, 10^6 exactly).

--ceiling also measures what the machine gives two runs at once: in each repeat and for
each problem, two independent one-thread runs started together (no shared data, no
synchronisation); the median of their summed rates over the median one-thread rate is the
most any two-thread code can reach here, and the table's last column sets the two-thread
speed-up against it (on a virtual machine whose second core is shared with other work, two
processes can give well under 2x).

--per-core also runs the one-thread case pinned to each core in turn, in every repeat. The
cores of a virtual machine need not be equally fast (on the development VM one core ran
1.35-2x slower than the other for minutes at a time, and an unpinned one-thread run lands on
either), so a two-thread speed-up over "the" one-thread rate depends on where that run
landed. The table then adds, for two threads: the speed-up over the mean of the cores'
one-thread medians (on equal cores, the usual speed-up) and over the fastest core's, and the
efficiency, the two-thread median over the sum of the cores' one-thread medians.

Where two threads' time goes (a table after the first, from each run's summary.json
`thread_sweep`): the one- and two-thread steps, each thread's sweep of its block per step
(waits left out; its time per force call times the calls over the steps, so that a call
that takes two steps in one sweep, as the 10^6 gas's do, counts as two), both sweeps over
the one-thread step (above 1: work the split adds, such as the particles finished across
the block boundary; below 1: each core's own cache),
the two-thread step beyond the longest sweep, call by call (the list builds, the serial parts,
the fork and the join), the imbalance (the longest sweep of a call less the sweep had that
call's work been split so that both threads ended together, each at the rate it swept at in
that call: what the join waits for, which no split made from earlier calls can fully
recover), and the time the threads spend finishing the particles handed across the block
boundaries.

--serial-blocks also runs each problem, in every repeat, with the two threads' blocks swept
one after another on one thread (COHDEM_SERIAL_BLOCKS=1: the split and the hand-off across
the block boundary as on two threads, the same results, but no second core; step pairs off).
The table of where the time goes then adds the blocks' sweeps in series over the one-thread
step (the work the split itself adds: the particles finished across the boundary, the
locality tests) and the two threads' sweeps over those in series (what the second core adds:
lines moved between the cores' caches, a slower core), for the problems whose one- and
two-thread runs took plain steps (no step pairs: at 10^5 and 10^6 particles they take them,
and the comparison would not be like for like).

--placement COHDEM_BENCH reads, before and after each two-thread run, what a cache line
written by the other core costs (cohdem_bench's BM_RemoteLines, a fraction of a second). On
the development VM it takes one of two values, which the host switches between every few tens
of seconds (about 19 and 70 ns on the forty-third round's Zen 3), and every line the two
threads pass at their blocks' boundary pays it, so the two-thread rate follows it while
one-thread runs and two independent runs do not (docs/performance-history.md, forty-third and
forty-fourth rounds). A table then gives the two-thread speed-up apart for the runs with both
readings below --placement-split ns ("near") and both above ("far"); runs with one of each
are counted as mixed.

--lammps also runs LAMMPS (`lmp`, one rank; bench/install-peers.sh) on every size of the gas,
once per repeat, with bench/peers/in.packing on the same data file and for the same number of
steps: what the best-known peer's cost per particle-step does from size to size on this
machine, beside cohdem's. With --per-core, repeat r's LAMMPS run is pinned to core r mod 2 and
paired with cohdem's one-thread run on that core in the same repeat; without it, both are
unpinned. The physics of the last runs is compared as bench/peer_compare.py compares its
packing (translational kinetic energy, mean vertical velocity; same tolerance). Python 3
stdlib only.
"""
import argparse
import json
import shutil
import statistics
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import peer_compare as pc  # noqa: E402  (its run, parse and physics tolerance for the peer runs)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="1000,10000,100000,1000000")
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--cohdem", default=os.path.join(REPO, "build", "cohdem"))
    ap.add_argument("--out", default=os.path.join(REPO, "build", "bench", "scaling"))
    ap.add_argument("--chute", action="store_true", help="add LAMMPS's chute benchmark (32,000 spheres)")
    ap.add_argument("--bed", action="store_true",
                    help="a packed bed at rest (every entry a contact) at every size instead of the gas")
    ap.add_argument("--ceiling", action="store_true",
                    help="also run two independent one-thread runs at once: what two cores give here")
    ap.add_argument("--per-core", action="store_true",
                    help="also run one thread pinned to each core: speed-ups over the mean and the fastest core")
    ap.add_argument("--serial-blocks", action="store_true",
                    help="also run the two threads' blocks one after another on one thread (COHDEM_SERIAL_BLOCKS=1)")
    ap.add_argument("--lammps", action="store_true",
                    help="also run LAMMPS (lmp, one rank) on every size of the gas, once per repeat")
    ap.add_argument("--placement", metavar="COHDEM_BENCH", default=None,
                    help="cohdem_bench: read BM_RemoteLines before and after each two-thread run")
    ap.add_argument("--placement-split", type=float, default=40.0,
                    help="ns a line: below it both times, a two-thread run counts as 'near', above as 'far'")
    ap.add_argument("--chute-data", default=os.path.join(REPO, "..", "shared", "peers", "lammps-chute", "data.chute"))
    a = ap.parse_args()
    sizes = [int(float(x)) for x in a.sizes.split(",")]
    threads = [int(x) for x in a.threads.split(",")]
    if a.lammps and (1 not in threads or not shutil.which("lmp")):
        sys.exit("--lammps needs 1 among --threads (its runs are set against cohdem's one-thread runs) and "
                 "LAMMPS's lmp on the PATH (bench/install-peers.sh)")
    os.makedirs(a.out, exist_ok=True)
    # The gas (keys p<N>) or, with --bed, the packed bed (keys b<N>): generator options, the
    # case's header, its periodic directions, LAMMPS's input.
    pre, gen, header, box, lmp_in = (("b", ["--bed"], "bed.toml", "xyz", "in.bed") if a.bed else
                                     ("p", ["--spacing", "1.01"], "packing.toml", "xy", "in.packing"))
    for n in sizes:
        data, case = os.path.join(a.out, f"{pre}{n}.data"), os.path.join(a.out, f"{pre}{n}.toml")
        # The particles in a CSV file beside the case ([[particles]]): loaded in a fraction of
        # the time and memory of one TOML table each (an older folder's case is redone). LAMMPS
        # reads the data file itself.
        if (not os.path.exists(case) or not os.path.exists(os.path.join(a.out, f"{pre}{n}.grain.csv"))
                or (a.lammps and not os.path.exists(data))):
            subprocess.run([sys.executable, os.path.join(HERE, "gen_packing.py"), str(n), data] + gen,
                           check=True, stdout=subprocess.DEVNULL)
            subprocess.run([sys.executable, os.path.join(HERE, "lammps_data_to_case.py"), data,
                            os.path.join(HERE, header), "-o", case, "--frozen", "", "--box", box, "--csv"],
                           check=True)
    # Problems by key: the gas (or the bed) at each size, then (with --chute) the chute. The
    # bed's label is its own count (a cube).
    probs = [(f"{pre}{n}", f"{(round(n ** (1 / 3)) ** 3 if a.bed else n):,}", os.path.join(a.out, f"{pre}{n}.toml"))
             for n in sizes]
    if a.chute:
        if not os.path.exists(a.chute_data):
            sys.exit(f"{a.chute_data} not found (--chute-data)")
        case = os.path.join(a.out, "chute.toml")
        subprocess.run([sys.executable, os.path.join(HERE, "lammps_data_to_case.py"), a.chute_data,
                        os.path.join(HERE, "chute.toml"), "-o", case, "--csv"], check=True)
        probs.append(("chute", "32,000 (chute)", case))
    cores = sorted(os.sched_getaffinity(0))[:2] if a.per_core else []
    def cmd(case, t, out):
        return [a.cohdem, "run", case, "--set", f"simulation.duration={a.steps * 1e-4!r}", "--threads", str(t),
                "--out", out, "--quiet"]

    def summary(out):
        """A run's summary.json; its final checkpoint, which no table needs, is removed (220 MB at
        10^6 particles, and each size keeps six run folders)."""
        for f in ("checkpoint.bin", "checkpoint.json"):
            if os.path.exists(os.path.join(out, f)):
                os.remove(os.path.join(out, f))
        return json.load(open(os.path.join(out, "summary.json")))

    lmp_dir = os.path.join(a.out, "lammps")
    if a.lammps:
        os.makedirs(lmp_dir, exist_ok=True)
        shutil.copy(os.path.join(HERE, "peers", lmp_in), lmp_dir)
    lmp = {}  # gas key -> one record per repeat

    def lammps_run(key, label, r):
        """LAMMPS on the gas `key` in repeat r, beside cohdem's one-thread run of that repeat
        (the run pinned to the same core with --per-core)."""
        cpu = cores[r % len(cores)] if cores else None
        text, rss = pc.sh(["lmp", "-var", "nsteps", str(a.steps), "-var", "data", os.path.abspath(os.path.join(a.out, f"{key}.data")),
                           "-in", lmp_in, "-log", "none"], lmp_dir, os.path.join(lmp_dir, f"{key}.{r + 1}.log"), cpu)
        rate, ke, ke_rot, vz, _ = pc.parse_peer(text, a.steps)
        ours = allr[(key, f"core{cpu}") if cpu is not None else (key, 1)][-1]
        lmp.setdefault(key, []).append({"rate": rate, "cohdem_rate": ours, "cpu": cpu, "peak_rss_bytes": rss,
                                        "particles": pc.peer_loop(text)[2], "ke": ke, "ke_rot": ke_rot, "vz": vz})
        where = f" on core {cpu}" if cpu is not None else ""
        print(f"  run {r + 1}: {label:>16s}, LAMMPS{where}: {rate:10.4g} particle-steps/s (cohdem {ours:.4g})", flush=True)

    def remote_line_ns():
        """BM_RemoteLines' ns a line now (None where it cannot run: one CPU, no binary)."""
        try:
            r = subprocess.run([a.placement, "--benchmark_filter=BM_RemoteLines", "--benchmark_min_time=0.05",
                                "--benchmark_format=json"], capture_output=True, text=True, timeout=60)
            b = json.loads(r.stdout)["benchmarks"][0]
            return 1e9 * b["ns_per_line"] if "ns_per_line" in b and not b.get("error_occurred") else None
        except (OSError, ValueError, KeyError, IndexError, subprocess.TimeoutExpired):
            return None

    best, allr, pair, steps, serial = {}, {}, {}, {}, {}
    for r in range(a.repeat):
        for key, label, case in probs:
            for t in threads:
                out = os.path.join(a.out, f"run_{key}_{t}")
                probes = [remote_line_ns()] if a.placement and t == 2 else None
                subprocess.run(cmd(case, t, out), check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                if probes:
                    probes.append(remote_line_ns())
                j = summary(out)
                rate = j["particle_steps_per_s"]
                where = (", a remote line " + "/".join("-" if x is None else f"{x:.0f}" for x in probes) + " ns"
                         if probes else "")
                print(f"  run {r + 1}: {label:>16s}, {t} thread(s): {rate:10.4g} particle-steps/s{where}", flush=True)
                k = (key, t)
                allr.setdefault(k, []).append(rate)
                # The step loop's time a step, and on several threads where it went
                # (summary.json's thread_sweep: each thread's sweep per force call, here per
                # step: a call that takes two steps in one sweep counts as two).
                ts = j.get("thread_sweep")
                per_step = ts["force_calls"] / max(1, j["steps"]) if ts else 1.0
                steps.setdefault(k, []).append(
                    {"loop_us": 1e6 * j["loop_time_s"] / max(1, j["steps"]),
                     "sweep_us": [u * per_step for u in ts["sweep_us_per_call"]] if ts else None,
                     "head_us": sum(ts.get("head_us_per_call", [])) if ts else None,
                     # call by call: the longest sweep, and the sweep had the call's work been
                     # split to end together (None from an engine without these counters)
                     "longest_us": ts["longest_sweep_us_per_call"] * per_step
                     if ts and "longest_sweep_us_per_call" in ts else None,
                     "balanced_us": ts["balanced_sweep_us_per_call"] * per_step
                     if ts and "balanced_sweep_us_per_call" in ts else None,
                     "handed": sum(ts["handed_over_per_call"]) if ts else None,
                     "step_pairs": (j.get("step_pairs") or {}).get("pairs", 0),
                     "remote_line_ns": probes})
                if k not in best or rate > best[k]["particle_steps_per_s"]:
                    best[k] = j
            for cpu in cores:
                out = os.path.join(a.out, f"run_{key}_core{cpu}")
                subprocess.run(cmd(case, 1, out), check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                               preexec_fn=lambda c=cpu: os.sched_setaffinity(0, {c}))
                rate = summary(out)["particle_steps_per_s"]
                allr.setdefault((key, f"core{cpu}"), []).append(rate)
                print(f"  run {r + 1}: {label:>16s}, 1 thread on core {cpu}: {rate:10.4g} particle-steps/s", flush=True)
            # (not where this repeat's one-thread run took step pairs: no like-for-like step)
            if a.serial_blocks and 2 in threads and not (steps.get((key, 1)) or [{}])[-1].get("step_pairs"):
                out = os.path.join(a.out, f"run_{key}_serial")
                subprocess.run(cmd(case, 2, out), check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                               env=dict(os.environ, COHDEM_SERIAL_BLOCKS="1"))
                j = summary(out)
                ts = j.get("thread_sweep")
                if ts and ts.get("serial_calls"):
                    # the blocks' sweeps summed, per step
                    sweeps = sum(ts["sweep_us_per_call"]) * ts["force_calls"] / max(1, j["steps"])
                    serial.setdefault(key, []).append(sweeps)
                    print(f"  run {r + 1}: {label:>16s}, 2 blocks in series: {j['particle_steps_per_s']:10.4g} "
                          f"particle-steps/s, blocks' sweeps {sweeps:.1f} us a step", flush=True)
            if a.lammps and key != "chute":
                lammps_run(key, label, r)
            if a.ceiling:
                outs = [os.path.join(a.out, f"run_{key}_pair{q}") for q in (0, 1)]
                procs = [subprocess.Popen(cmd(case, 1, o), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                         for o in outs]
                if any(p.wait() != 0 for p in procs):
                    sys.exit(f"a two-process run of {label} failed")
                rates = [summary(o)["particle_steps_per_s"] for o in outs]
                pair.setdefault(key, []).append(sum(rates))
                print(f"  run {r + 1}: {label:>16s}, two 1-thread runs at once: {rates[0]:10.4g} + {rates[1]:10.4g}"
                      f" = {sum(rates):10.4g} particle-steps/s", flush=True)
    print(f"\n{a.steps} steps, best and median of {a.repeat} runs")
    ceil = a.ceiling and 1 in threads and 2 in threads
    print(f"| particles | threads | particle-steps/s (best) | median | ns per particle-step (best) | "
          f"{threads[-1]} threads / {threads[0]} (best, median) | contacts per particle | peak RSS of the run | bytes per particle |"
          f" bytes per particle, whole process |"
          + (" two runs at once / one (median) | 2 threads / two runs (median) |" if ceil else ""))
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|" + ("---:|---:|" if ceil else ""))
    rows = []
    for key, label, _ in probs:
        for t in threads:
            j = best[(key, t)]
            n = j["particles"]
            rate = j["particle_steps_per_s"]
            med = statistics.median(allr[(key, t)])
            sp = ""
            if t != threads[0] and (key, threads[0]) in best:
                sp = (f"{rate / best[(key, threads[0])]['particle_steps_per_s']:.2f}, "
                      f"{med / statistics.median(allr[(key, threads[0])]):.2f}")
            extra = ""
            if ceil:
                extra = " | |"
                if t == 2 and key in pair:
                    one = statistics.median(allr[(key, 1)])
                    c = statistics.median(pair[key]) / one
                    s2 = med / one
                    extra = f" {c:.2f} | {s2 / c:.2f} |"
            print(f"| {label} | {t} | {rate:.3g} | {med:.3g} | {1e9 / rate:.0f} | {sp} | {j['contacts'] / n:.2f} | "
                  f"{j['peak_rss_run_bytes'] / 2**20:.0f} MiB | {j['run_bytes_per_particle']:.0f} | "
                  f"{j['peak_rss_bytes'] / n:.0f} |" + extra)
            rows.append({"problem": label, "particles": n, "threads": t, "particle_steps_per_s": rate,
                         "median_particle_steps_per_s": med, "contacts": j["contacts"],
                         "peak_rss_run_bytes": j["peak_rss_run_bytes"], "peak_rss_bytes": j["peak_rss_bytes"],
                         "two_runs_at_once": pair.get(key) if t == 2 else None})
    if cores and 2 in threads:
        print(f"\ntwo threads against the cores' one-thread rates (medians of {a.repeat} runs)")
        print("| particles | " + " | ".join(f"1 thread, core {c}" for c in cores) +
              " | 2 threads | 2 threads / mean core | 2 threads / fastest core | efficiency (2 threads / sum) |")
        print("|---:|" + "---:|" * (len(cores) + 4))
        for key, label, _ in probs:
            per = [statistics.median(allr[(key, f"core{c}")]) for c in cores]
            two = statistics.median(allr[(key, 2)])
            mean = sum(per) / len(per)
            print(f"| {label} | " + " | ".join(f"{x:.3g}" for x in per) +
                  f" | {two:.3g} | {two / mean:.2f} | {two / max(per):.2f} | {two / sum(per):.2f} |")
            for row in rows:
                if row["problem"] == label and row["threads"] == 2:
                    row["one_thread_per_core"] = dict(zip(map(str, cores), per))
                    row["speedup_mean_core"] = two / mean
                    if key in pair:  # --ceiling on the same scale: two independent runs at once
                        row["ceiling_mean_core"] = statistics.median(pair[key]) / mean
    if a.placement and 2 in threads:
        # The two-thread runs by the remote line's cost around them (same order as allr's).
        print(f"\ntwo threads by the host's placement of the two vCPUs (BM_RemoteLines before and after each "
              f"run; near: both below {a.placement_split:g} ns a line, far: both above; medians)")
        print("| particles | a remote line (ns, each run) | runs near / far / mixed | 2 threads / "
              + ("mean core" if cores else "1 thread") + ", near | far |")
        print("|---:|---|---:|---:|---:|")
        for key, label, _ in probs:
            one = (sum(statistics.median(allr[(key, f"core{c}")]) for c in cores) / len(cores) if cores
                   else statistics.median(allr[(key, 1)]) if (key, 1) in allr else None)
            cls = {"near": [], "far": [], "mixed": []}
            seen = []
            for x, rate in zip(steps.get((key, 2), []), allr.get((key, 2), [])):
                pr = x.get("remote_line_ns") or []
                if len(pr) != 2 or None in pr:
                    continue
                seen.append(pr)
                c = ("near" if max(pr) < a.placement_split else "far" if min(pr) > a.placement_split else "mixed")
                cls[c].append(rate)
            sp = {c: (statistics.median(v) / one if v and one else None) for c, v in cls.items()}
            fmt = lambda v: f"{v:.2f}" if v is not None else "-"
            print(f"| {label} | " + ", ".join(f"{p:.0f}/{q:.0f}" for p, q in seen) +
                  f" | {len(cls['near'])} / {len(cls['far'])} / {len(cls['mixed'])} | {fmt(sp['near'])} | {fmt(sp['far'])} |")
            for row in rows:
                if row["problem"] == label and row["threads"] == 2:
                    row["placement"] = {"remote_line_ns": seen, "split_ns": a.placement_split,
                                        "runs": {c: len(v) for c, v in cls.items()},
                                        "speedup_near": sp["near"], "speedup_far": sp["far"]}
    if 1 in threads and any(x["sweep_us"] for v in steps.values() for x in v):
        print(f"\nwhere the two threads' time goes (medians of {a.repeat} runs; a sweep: one thread's block and "
              "the head it finishes for the next, per step, waits left out)")
        print("| particles | 1 thread: a step (us) | 2 threads: a step (us) | a thread's sweep (us, mean) | "
              "sweeps / 1-thread step | step - longest sweep (us) | imbalance (us) | particles handed over a call | "
              "finishing them (us a call) |" + (" blocks in series: sweeps / 1-thread step | 2 threads' sweeps / "
                                                "in series |" if serial else ""))
        print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|" + ("---:|---:|" if serial else ""))
        for key, label, _ in probs:
            two = [x for x in steps.get((key, 2), []) if x["sweep_us"]]
            one = steps.get((key, 1), [])
            if not two or not one:
                continue
            one_us = statistics.median(x["loop_us"] for x in one)
            two_us = statistics.median(x["loop_us"] for x in two)
            mean_sweep = statistics.median(sum(x["sweep_us"]) / len(x["sweep_us"]) for x in two)
            work = statistics.median(sum(x["sweep_us"]) / one_us for x in two)
            # The longest sweep call by call where the engine counts it (else the longer of
            # the threads' mean sweeps, which leaves the calls' imbalance in the step's rest).
            longest = [x["longest_us"] if x["longest_us"] is not None else max(x["sweep_us"]) for x in two]
            rest = statistics.median(x["loop_us"] - l for x, l in zip(two, longest))
            imb = [x["longest_us"] - x["balanced_us"] for x in two if x["longest_us"] is not None]
            imbalance = statistics.median(imb) if imb else None
            handed = statistics.median(x["handed"] for x in two)
            head = statistics.median(x["head_us"] or 0.0 for x in two)
            imb_s = f"{imbalance:.1f}" if imbalance is not None else "-"
            ser_s, split_own, second_core = "", None, None
            if serial:
                plain = all(not x.get("step_pairs") for x in one + two)
                if key in serial and plain:
                    ser = statistics.median(serial[key])
                    split_own = ser / one_us
                    second_core = statistics.median(sum(x["sweep_us"]) for x in two) / ser
                    ser_s = f" {split_own:.2f} | {second_core:.2f} |"
                else:
                    ser_s = " - | - |"
            print(f"| {label} | {one_us:.1f} | {two_us:.1f} | {mean_sweep:.1f} | {work:.2f} | {rest:.1f} | {imb_s} | "
                  f"{handed:.0f} | {head:.1f} |" + ser_s)
            for row in rows:
                if row["problem"] == label and row["threads"] == 2:
                    row["step_us_one_thread"], row["step_us"] = one_us, two_us
                    row["sweep_us_mean"], row["sweeps_over_one_thread_step"] = mean_sweep, work
                    row["step_minus_longest_sweep_us"], row["handed_over_per_call"] = rest, handed
                    row["head_us"] = head
                    if split_own is not None:
                        row["serial_sweeps_over_one_thread_step"] = split_own
                        row["sweeps_over_serial_sweeps"] = second_core
                    if imbalance is not None:
                        row["imbalance_us"] = imbalance
    # Issue 6's flatness target: cost per particle-step within 20 % from 10^4 to 10^6 particles.
    ends = [(f"{pre}{n}", threads[0]) for n in (10000, 1000000)]
    if all(k in allr for k in ends):
        lo, hi = ends
        print(f"\ncost per particle-step, 10^6 over 10^4 ({threads[0]} thread(s)): "
              f"{statistics.median(allr[lo]) / statistics.median(allr[hi]):.2f}x median, "
              f"{max(allr[lo]) / max(allr[hi]):.2f}x best (target <= 1.20x)")
    peer = lammps_table(a, probs, lmp) if a.lammps else None
    with open(os.path.join(a.out, "scaling.json"), "w") as f:
        json.dump({"steps": a.steps, "repeat": a.repeat, "rows": rows, "lammps": peer}, f, indent=1)


def lammps_table(a, probs, lmp):
    """--lammps: LAMMPS's rates on the gases beside cohdem's one-thread rates of the same repeats,
    the physics of the last runs, and both codes' 10^6-over-10^4 cost ratio."""
    tol = pc.problem_table()["packing"].physics_tol
    pinned = any(x["cpu"] is not None for v in lmp.values() for x in v)
    print(f"\nLAMMPS on the same {'beds' if a.bed else 'gases'} (one rank, the same data files and steps; "
          f"{'pinned, repeat r on core r mod 2, against cohdem on that core in that repeat' if pinned else 'unpinned'})")
    print("| particles | LAMMPS particle-steps/s (median) | ns per particle-step, LAMMPS | cohdem (one thread) | "
          "cohdem / LAMMPS (paired) | LAMMPS bytes per particle | physics (last runs) |")
    print("|---:|---:|---:|---:|---:|---:|---|")
    out = {}
    for key, label, _ in probs:
        if key not in lmp:
            continue
        R = lmp[key]
        med = statistics.median(x["rate"] for x in R)
        ours = statistics.median(x["cohdem_rate"] for x in R)
        paired = statistics.median(x["cohdem_rate"] / x["rate"] for x in R)
        # cohdem's last one-thread run of this size (every run of a size ends in the same state)
        j = json.load(open(os.path.join(a.out, f"run_{key}_1", "summary.json")))
        last = R[-1]
        dke = abs(j["translational_energy"] - last["ke"]) / abs(last["ke"])
        dv = abs(j["mean_velocity"][2] - last["vz"]) / max(abs(last["vz"]), 1e-12)
        ok = dke <= tol and dv <= tol
        bpp = statistics.median(x["peak_rss_bytes"] for x in R) / last["particles"]
        print(f"| {label} | {med:.3g} | {1e9 / med:.0f} | {1e9 / ours:.0f} ns | {paired:.2f}x | {bpp:.0f} | "
              f"dKE {dke:.1e}, dv {dv:.1e}: {'ok' if ok else 'DIFFERS'} (tol {tol:g}) |")
        out[key] = {"particles": last["particles"], "runs": R, "lammps_median": med, "cohdem_median": ours,
                    "ratio_paired": paired, "lammps_bytes_per_particle": bpp, "rel_diff_ke": dke, "rel_diff_v": dv,
                    "physics_ok": ok}
    gases = sorted(out, key=lambda k: out[k]["particles"])
    if len(gases) > 1:  # the largest gas over the smallest (issue 6: 10^6 over 10^4)
        small, large = out[gases[0]], out[gases[-1]]
        f_l = small["lammps_median"] / large["lammps_median"]
        f_c = small["cohdem_median"] / large["cohdem_median"]
        print(f"\ncost per particle-step, {large['particles']:,} over {small['particles']:,} particles, in the same "
              f"repeats: LAMMPS {f_l:.2f}x, cohdem {f_c:.2f}x (medians)")
        out["flatness"] = {"small": small["particles"], "large": large["particles"], "lammps": f_l, "cohdem": f_c}
    return out


if __name__ == "__main__":
    main()
