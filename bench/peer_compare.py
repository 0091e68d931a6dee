#!/usr/bin/env python3
"""Side-by-side benchmark of cohdem against LAMMPS and LIGGGHTS (Debian's `lmp` and
`liggghts`; bench/install-peers.sh installs them), in one invocation, runs interleaved.

  python3 bench/peer_compare.py                      # all problems, 5 runs each, 1 thread
  python3 bench/peer_compare.py --runs 7 --steps 2000 --problems chute,chute_hmr
  python3 bench/peer_compare.py --threads 2 --mpi 2  # cohdem on 2 threads, peers on 2 ranks

Problems (same initial state, same physics, same number of steps in every code; cohdem's
cases read their particles from CSV files, [[particles]], as LAMMPS reads its data file):
  chute      LAMMPS's chute benchmark, 32,000 spheres, gran/hooke/history (in.chute);
             cohdem: bench/chute.toml; LIGGGHTS: hooke/stiffness + tangential history
  chute_hmr  the same chute with Hertz-Mindlin + rolling resistance (in.chute.granular
             -var model hmr: hertz/material, mindlin_rescale/force (bench/peers' default, the
             Mindlin law cohdem has; the shared input's `mindlin`: -var tangential mindlin),
             tsuji, rolling sds); cohdem:
             bench/chute_hmr.toml (SDS rolling, LAMMPS's numbers); LIGGGHTS: hertz +
             rolling_friction epsd2 (its own rolling law: its physics agree roughly only)
  packing    a poured packing of 100,000 spheres (bench/gen_packing.py; bench/packing.toml,
             bench/peers/in.packing[.liggghts])

For every code and problem: particle-steps per second (atoms x steps / loop time; cohdem:
its summary.json, which times the step loop only, as LAMMPS's "Loop time" does), median and
best of the runs, the ratio cohdem/peer, and the physics after the same simulated time:
translational kinetic energy and mean flow velocity of the free particles (x for the chute,
z for the packing) within the problem's tolerance, the rotational energy within 1 % (ROT_TOL),
the gain of translational energy since step 0 (reported only), and the memory: each run's peak resident memory of the whole process
(the kernel's high-water mark; cohdem's own record of it, which also covers the loading of
its case) over the particle count, median of the runs (column B/particle), and cohdem's
time loop alone (summary.json's peak_rss_run_bytes); for the peers on several MPI ranks, the
sum of the ranks' peaks. Results also go to OUT/results.json.
Python 3 standard library only.

Pinning (one thread and one rank, the default): every run of round r is pinned to the same
core, core r mod (cores this process may use), so that within a round every code runs on the
same core, and over the rounds every code gets every core equally. On a virtual machine the
cores need not be equally fast: on the development VM one core ran this code's one-thread
runs 1.35-2x slower than the other for minutes at a time, and an unpinned run lands on either,
so the codes' ratios swung with where the scheduler put them. The core of each run is
printed; `--no-pin` runs unpinned.
"""
import argparse
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)


# For MPI runs each rank runs under this wrapper (its first argument a folder, the rest the
# command). When the rank ends, the wrapper writes the rank's own peak resident memory (its
# process's high-water mark, as for one process) to a file of its own in that folder, and
# sh() sums them. (Printed instead, a rank's last line was lost now and then as mpirun shut
# down.)
RANK_WRAPPER = ("import os, subprocess, sys\n"
                "p = subprocess.Popen(sys.argv[2:])\n"
                "_, st, ru = os.wait4(p.pid, 0)\n"
                "open(os.path.join(sys.argv[1], str(os.getpid())), 'w').write(str(ru.ru_maxrss * 1024))\n"
                "sys.exit(os.waitstatus_to_exitcode(st))\n")


def sh(cmd, cwd, log, cpu=None, rank_dir=None, ranks=1, env=None):
    """Runs cmd (list), output to log; returns the output text and the run's peak resident
    memory in bytes. Raises on failure. cpu: the core the run is pinned to (None: not
    pinned). The memory is the kernel's high-water mark of the process (os.wait4's
    ru_maxrss), the same measure for every code: binary, libraries, input and all. For an
    MPI run whose `ranks` ranks run under RANK_WRAPPER writing to rank_dir, it is the sum of
    the ranks' high-water marks: the job's memory without the launcher (an upper bound when
    the ranks peak at different times). env: the run's environment (None: this process's)."""
    if rank_dir is not None:
        shutil.rmtree(rank_dir, ignore_errors=True)
        os.makedirs(rank_dir)
    pin = None if cpu is None else (lambda: os.sched_setaffinity(0, {cpu}))
    with open(log, "w") as f:
        proc = subprocess.Popen(cmd, cwd=cwd, stdout=f, stderr=subprocess.STDOUT, preexec_fn=pin, env=env)
        _, status, usage = os.wait4(proc.pid, 0)
        proc.returncode = os.waitstatus_to_exitcode(status)
    text = open(log).read()
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({proc.returncode}); see {log}:\n{text[-2000:]}")
    if rank_dir is None:
        return text, usage.ru_maxrss * 1024  # KiB on Linux
    rss = [int(open(os.path.join(rank_dir, r)).read()) for r in os.listdir(rank_dir)]
    if len(rss) != ranks:
        raise RuntimeError(f"{' '.join(cmd)}: {len(rss)} of {ranks} ranks recorded their memory in {rank_dir}")
    return text, sum(rss)


def peer_loop(text):
    """LAMMPS/LIGGGHTS screen output -> (loop time s, steps, atoms) of its 'Loop time' line."""
    m = re.search(r"Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms", text)
    if not m:
        raise RuntimeError("no 'Loop time' line in the output")
    return float(m.group(1)), int(m.group(3)), int(m.group(4))


def parse_peer(text, nsteps):
    """LAMMPS/LIGGGHTS screen output -> (particle-steps/s, KE, KE_rot, v_mean, KE at step 0)."""
    t, steps, atoms = peer_loop(text)
    row = row0 = None
    for line in text.splitlines():
        f = line.split()
        if len(f) == 5 and f[1] == str(atoms):
            if f[0] == str(nsteps):
                row = f
            elif f[0] == "0":
                row0 = f
    if row is None or row0 is None:
        raise RuntimeError(f"no thermo row for step {nsteps} or step 0")
    return atoms * steps / t, float(row[2]), float(row[3]), float(row[4]), float(row0[2])


def find_chute_data():
    """LAMMPS's chute data file in ../shared beside the repository (or beside a worktree's parent)."""
    for up in ("..", os.path.join("..", "..")):
        cand = os.path.normpath(os.path.join(REPO, up, "shared", "peers", "lammps-chute", "data.chute"))
        if os.path.exists(cand):
            return cand
    return os.path.join(REPO, "..", "shared", "peers", "lammps-chute", "data.chute")


PEER_EXE = {"lammps": "lmp", "liggghts": "liggghts"}
DT = 1e-4  # the time step of every problem (its cohdem case and its peer inputs)
# The rotational energy after the same time, judged to 1 %: the translational energy of the
# chute is mostly its initial flow (784,139 of 784,700 after 1000 steps), so its agreement
# says little about the contact laws, while the rotational energy halves in those steps and
# follows the tangential, rolling and damping laws. Same physics in the two codes gives
# 0.1-0.25 % (the linear chute 0.22 %, the packing 0.1 %, Hertz-Mindlin with and without SDS
# rolling 0.25 % and 0.22 %; 0.43 % without rolling against LAMMPS's other Mindlin law,
# `mindlin`); a dashpot 1.42 times LAMMPS's (e = 0.9 integrated exactly against LAMMPS's Tsuji
# fit, docs/contact-models.md) gave 2.6 %.
ROT_TOL = 0.01


class Problem:
    """rot_tol: per peer, the tolerance on the rotational energy (None: reported, not judged,
    where the peer runs another rolling law)."""
    def __init__(self, name, cohdem_case, vel_axis, lammps, liggghts, physics_tol, note="",
                 rot_tol=None):
        self.name, self.cohdem_case, self.vel_axis = name, cohdem_case, vel_axis
        self.lammps, self.liggghts, self.physics_tol, self.note = lammps, liggghts, physics_tol, note
        self.rot_tol = rot_tol or {"lammps": ROT_TOL, "liggghts": ROT_TOL}

    def command(self, code, nsteps, cohdem=None, threads=1, out=None):
        """The command that runs this problem for nsteps in `code`, from the working folder
        (cohdem: the binary, its thread count and output folder)."""
        if code == "cohdem":
            return [cohdem, "run", self.cohdem_case, "--set", f"simulation.duration={nsteps * DT!r}",
                    "--threads", str(threads), "--out", out, "--quiet"]
        return (self.lammps if code == "lammps" else self.liggghts) + ["-var", "nsteps", str(nsteps)]


def cohdem_summary(out, nsteps):
    """summary.json of a cohdem run in folder out, checked to have run nsteps steps."""
    j = json.load(open(os.path.join(out, "summary.json")))
    if j["steps"] != nsteps:
        raise RuntimeError(f"cohdem ran {j['steps']} steps, not {nsteps}")
    return j


def add_input_args(ap, out):
    """The options of every peer script: the cohdem binary, the chute data, the output folder."""
    ap.add_argument("--cohdem", default=os.path.join(REPO, "build", "cohdem"))
    ap.add_argument("--chute-data", default=None,
                    help="LAMMPS chute data file (default: shared/peers/lammps-chute/data.chute beside the repo)")
    ap.add_argument("--out", default=out)


def prepare_inputs(work, problems, chute_data, packing_n):
    """Inputs in one working folder: peer inputs, the data files, the cohdem cases."""
    for f in os.listdir(os.path.join(HERE, "peers")):
        shutil.copy(os.path.join(HERE, "peers", f), work)
    if any(p.startswith("chute") for p in problems):
        if not os.path.exists(chute_data):
            sys.exit(f"{chute_data} not found (--chute-data)")
        shutil.copy(chute_data, os.path.join(work, "data.chute"))
        for case in ("chute", "chute_hmr"):
            subprocess.run([sys.executable, os.path.join(HERE, "lammps_data_to_case.py"), os.path.join(work, "data.chute"),
                            os.path.join(HERE, case + ".toml"), "-o", os.path.join(work, case + ".toml"), "--csv"],
                           check=True)
    if "packing" in problems:
        subprocess.run([sys.executable, os.path.join(HERE, "gen_packing.py"), str(packing_n),
                        os.path.join(work, "packing.data")], check=True, stdout=subprocess.DEVNULL)
        subprocess.run([sys.executable, os.path.join(HERE, "lammps_data_to_case.py"), os.path.join(work, "packing.data"),
                        os.path.join(HERE, "packing.toml"), "-o", os.path.join(work, "packing.toml"), "--frozen", "",
                        "--box", "xy", "--csv"], check=True)


def problem_table():
    """The problems: cohdem case (in the working folder), flow-velocity axis, peer commands,
    physics tolerance, note."""
    return {
        "chute": Problem("chute", "chute.toml", 0,
                         ["lmp", "-in", "in.chute", "-log", "none"],
                         ["liggghts", "-var", "model", "hooke", "-in", "in.chute.liggghts"], 0.02),
        "chute_hmr": Problem("chute_hmr", "chute_hmr.toml", 0,
                             ["lmp", "-var", "model", "hmr", "-in", "in.chute.granular", "-log", "none"],
                             ["liggghts", "-var", "model", "hmr", "-in", "in.chute.liggghts"], 0.02,
                             "cohdem and LAMMPS: SDS rolling with the same numbers and the same dashpot; "
                             "LIGGGHTS: its epsd2 rolling law and the exact dashpot for e = 0.9, so its physics "
                             "agree roughly only (its rotational energy is not judged)",
                             rot_tol={"lammps": ROT_TOL, "liggghts": None}),
        "packing": Problem("packing", "packing.toml", 2,
                           ["lmp", "-in", "in.packing", "-log", "none"],
                           ["liggghts", "-in", "in.packing.liggghts"], 0.02),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=5, help="runs per code and problem (interleaved)")
    ap.add_argument("--steps", type=int, default=1000, help="steps of the chute problems")
    ap.add_argument("--packing-steps", type=int, default=500)
    ap.add_argument("--packing-n", type=int, default=100000)
    ap.add_argument("--problems", default="chute,chute_hmr,packing")
    ap.add_argument("--peers", default="lammps,liggghts")
    ap.add_argument("--threads", type=int, default=1, help="cohdem OpenMP threads")
    ap.add_argument("--mpi", type=int, default=1, help="MPI ranks of the peers (mpirun -np)")
    ap.add_argument("--no-pin", action="store_true",
                    help="do not pin one-thread runs to a core (default: round r on core r mod cores)")
    add_input_args(ap, os.path.join(REPO, "build", "bench", "peers"))
    a = ap.parse_args()

    if a.chute_data is None:
        a.chute_data = find_chute_data()
    problems = [p for p in a.problems.split(",") if p]
    peers = [p for p in a.peers.split(",") if p]
    for p in peers:
        exe = PEER_EXE.get(p)
        if exe is None:
            sys.exit(f"unknown peer '{p}' (lammps, liggghts)")
        if not shutil.which(exe):
            sys.exit(f"{exe} not found: run bench/install-peers.sh (or --peers to leave it out)")
    if not os.path.exists(a.cohdem):
        sys.exit(f"{a.cohdem} not found: build cohdem first (ninja -C build)")
    os.makedirs(a.out, exist_ok=True)
    work = os.path.abspath(a.out)

    prepare_inputs(work, problems, a.chute_data, a.packing_n)

    rank_dir = os.path.join(work, "rank_rss") if a.mpi > 1 else None
    mpi = (["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", str(a.mpi), sys.executable, "-c", RANK_WRAPPER,
            rank_dir] if a.mpi > 1 else [])
    # The cores of the rounds (one thread and one rank only: wider runs need every core).
    cores = sorted(os.sched_getaffinity(0)) if a.threads == 1 and a.mpi == 1 and not a.no_pin else []
    probs = problem_table()
    results = {}
    for pname in problems:
        P = probs[pname]
        nsteps = a.packing_steps if pname == "packing" else a.steps
        codes = ["cohdem"] + peers
        res = {c: {"rate": [], "ke": None, "ke_rot": None, "v": None} for c in codes}
        print(f"\n== {pname}: {nsteps} steps, {a.runs} interleaved runs per code "
              f"(cohdem {a.threads} thread(s), peers {a.mpi} rank(s))", flush=True)
        for run in range(a.runs):
            cpu = cores[run % len(cores)] if cores else None
            for c in codes:
                log = os.path.join(work, f"{pname}.{c}.{run}.log")
                if c == "cohdem":
                    out = os.path.join(work, f"{pname}.cohdem.out")
                    _, rss = sh(P.command(c, nsteps, a.cohdem, a.threads, out), work, log, cpu)
                    j = cohdem_summary(out, nsteps)
                    r = (j["particle_steps_per_s"], j["translational_energy"], j["rotational_energy"],
                         j["mean_velocity"][P.vel_axis], None)
                    atoms = j["particles"]
                    # cohdem resets the kernel's high-water mark once the case is loaded (to
                    # measure its time loop, summary.json's peak_rss_run_bytes), so the
                    # process's maximum is its own record of the peak before the reset.
                    rss = max(rss, j["peak_rss_bytes"])
                    res[c].setdefault("peak_rss_run_bytes", []).append(j["peak_rss_run_bytes"])
                else:
                    text, rss = sh(mpi + P.command(c, nsteps), work, log, cpu, rank_dir, a.mpi)
                    r = parse_peer(text, nsteps)
                    atoms = peer_loop(text)[2]
                res[c]["rate"].append(r[0])
                res[c].setdefault("peak_rss_bytes", []).append(rss)
                res[c]["particles"] = atoms
                res[c].setdefault("cpu", []).append(cpu)
                res[c]["ke"], res[c]["ke_rot"], res[c]["v"] = r[1], r[2], r[3]
                if r[4] is not None:
                    res[c]["ke0"] = r[4]
                where = f" (core {cpu})" if cpu is not None else ""
                print(f"  run {run + 1} {c:8s} {r[0]:10.4g} particle-steps/s{where}", flush=True)
        ax = "xyz"[P.vel_axis]
        # paired: the median over the rounds of cohdem's rate over the peer's in the same round
        # (the same core, minutes apart at most).
        print(f"\n  {'code':9s} {'median':>10s} {'best':>10s}  {'cohdem/peer (median, best, paired)':>35s}  "
              f"{'B/particle':>10s}  {'KE_trans':>12s} {'KE_rot':>10s} {'v_' + ax:>10s}  physics")
        c0 = res["cohdem"]
        for c in codes:
            R = res[c]
            med, best = statistics.median(R["rate"]), max(R["rate"])
            R["median"], R["best"] = med, best
            # Peak resident memory of the whole process over the particle count (median of the runs).
            R["bytes_per_particle"] = statistics.median(R["peak_rss_bytes"]) / R["particles"]
            if "peak_rss_run_bytes" in R:  # cohdem's time loop alone (the case's parse excluded)
                R["run_bytes_per_particle"] = statistics.median(R["peak_rss_run_bytes"]) / R["particles"]
            ratio = ""
            phys = ""
            if c != "cohdem":
                R["ratio_median"] = statistics.median(c0["rate"]) / med
                R["ratio_best"] = max(c0["rate"]) / best
                R["ratio_paired"] = statistics.median(x / y for x, y in zip(c0["rate"], R["rate"]))
                ratio = f"{R['ratio_median']:.2f}x, {R['ratio_best']:.2f}x, {R['ratio_paired']:.2f}x"
                dke = abs(c0["ke"] - R["ke"]) / abs(R["ke"])
                dv = abs(c0["v"] - R["v"]) / max(abs(R["v"]), 1e-12)
                drot = abs(c0["ke_rot"] - R["ke_rot"]) / max(abs(R["ke_rot"]), 1e-300)
                # The change of the translational energy since step 0 (the same initial state in
                # every code: the peer's own step-0 row), reported only: it is the small
                # difference of the gravity's work and the dissipation, so a 1 % difference in
                # the dissipation shows several times larger in it.
                gain_p = R["ke"] - R["ke0"]
                dgain = abs((c0["ke"] - R["ke0"]) - gain_p) / max(abs(gain_p), 1e-300)
                R["rel_diff_ke"], R["rel_diff_v"], R["rel_diff_ke_rot"], R["rel_diff_ke_gain"] = dke, dv, drot, dgain
                rtol = P.rot_tol[c]
                ok = dke <= P.physics_tol and dv <= P.physics_tol and (rtol is None or drot <= rtol)
                R["physics_ok"] = ok
                rot = f"dKE_rot {drot:.2e}" + (f" (tol {rtol:g})" if rtol is not None else " (not judged)")
                phys = (f"dKE {dke:.2e}, dv {dv:.2e} (tol {P.physics_tol:g}), {rot}: {'ok' if ok else 'DIFFERS'}; "
                        f"KE gain since step 0 {dgain:.2e}")
            print(f"  {c:9s} {med:10.4g} {best:10.4g}  {ratio:>35s}  {R['bytes_per_particle']:10.0f}  "
                  f"{R['ke']:12.7g} {R['ke_rot']:10.5g} {R['v']:10.6g}  {phys}")
        print(f"  memory: peak resident memory of the whole process over the particle count (cohdem's "
              f"time loop alone: {c0['run_bytes_per_particle']:.0f} B/particle)")
        if P.note:
            print(f"  note: {P.note}")
        results[pname] = {"steps": nsteps, "runs": a.runs, "threads": a.threads, "mpi": a.mpi, "codes": res}
    with open(os.path.join(work, "results.json"), "w") as f:
        json.dump({"when": time.strftime("%Y-%m-%d %H:%M:%S"), "args": vars(a), "results": results}, f, indent=1)
    print(f"\nlogs and results.json in {work}")


if __name__ == "__main__":
    main()
