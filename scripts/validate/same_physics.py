#!/usr/bin/env python3
"""Do two engines (or two settings) compute the same physics on a case? A trajectory test
that sees through chaos.

A granular run is chaotic: a change in the last bit of one force (a sum taken in another
order) grows by orders of magnitude every few thousand steps, so two correct engines that
round differently agree only for a while, and their long-run results are two realizations.
What tells a change of physics from a change of rounding is how the difference starts: a
rounding change starts at about 1e-16 and grows at the system's own rate, while a change in
a force law, a boundary or an integrator shows at once, many orders of magnitude above that.

So the script runs the case three times, writing VTK frames:
  A   with --a (default build/cohdem),
  A'  with --a and the time step changed by one part in 1e13 (the rounding baseline: how a
      last-bit perturbation grows in this case),
  B   with --b (another build, e.g. an older commit) and/or the --b-set overrides,
and compares the particles frame by frame (matched by id): the largest position difference
|x_A - x_B| against the baseline |x_A - x_A'|. B computes the same physics if, at every frame
until the baseline has grown to a micron-scale share of the radius (after that both are
chaos), B's difference stays within a factor --factor (default 1000) of the baseline's, with
a floor of 1e-14 mean radii for the frames where both are still at zero or rounding level.
A change of physics is typically 1e6 times the baseline from the first frames on.

Usage:
  same_physics.py CASE [--a BIN] [--b BIN] [--b-set key=value ...] [--set key=value ...]
                  [--frames-every S] [--duration S] [--out DIR] [--factor F]
Give the case frames close together (or --frames-every): the window before chaos is a few
thousand steps in a dense bed. Exit status 0: same physics; 1: differs; 2: a run failed.
Example (docs/ring-shear.md, "Same physics"): the dense sheared ore bed against an engine of
another commit built in a worktree:
  same_physics.py /tmp/dense/zlong.toml --b /tmp/wb/build/cohdem"""
import argparse, glob, os, subprocess, sys, tempfile, tomllib

from vtu import read_arrays


def read_vtu(path):
    """id -> (x, y, z) of a particles_*.vtu, and the mean radius."""
    v = read_arrays(path)
    radii = v["radius"]
    return dict(zip(v["id"], v["Points"])), sum(radii) / max(len(radii), 1)


def max_diff(p, q, periods):
    """Largest position difference over the particles both frames hold, periodic images taken
    into account (a particle wrapped in one run and not yet in the other)."""
    d = 0.0
    for k, a in p.items():
        c = q.get(k)
        if c is None:
            continue
        for ax in range(3):
            e = abs(a[ax] - c[ax])
            if periods[ax] > 0:
                e = min(e, abs(e - periods[ax]))
            d = max(d, e)
    return d


def time_step_and_periods(case_file, overrides):
    """The case's time step (a simulation.dt override first) and its periodic lengths (0 where
    not periodic), read once."""
    with open(case_file, "rb") as f:
        c = tomllib.load(f)
    dt = float(c["simulation"]["dt"])
    for o in overrides:
        if o.startswith("simulation.dt="):
            dt = float(o.split("=", 1)[1])
    dom = c.get("domain", {})
    per = dom.get("periodic", [False, False, False])
    lo, hi = dom.get("lo", [0, 0, 0]), dom.get("hi", [0, 0, 0])
    return dt, [float(hi[k]) - float(lo[k]) if per[k] else 0.0 for k in range(3)]


def run(binary, case_file, out, overrides):
    cmd = [binary, "run", case_file, "--out", out, "--quiet"]
    for o in overrides:
        cmd += ["--set", o]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.stderr.write("same_physics: run failed: %s\n%s%s" % (" ".join(cmd), r.stdout, r.stderr))
        sys.exit(2)


def main():
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("case")
    ap.add_argument("--a", default=os.path.join(root, "build", "cohdem"))
    ap.add_argument("--b", default=None, help="the engine to check (default: --a, with --b-set)")
    ap.add_argument("--set", action="append", default=[], help="override for all three runs")
    ap.add_argument("--b-set", action="append", default=[], help="override for run B only")
    ap.add_argument("--frames-every", type=float, default=None, help="output.frame_interval, s")
    ap.add_argument("--duration", type=float, default=None, help="simulation.duration, s")
    ap.add_argument("--factor", type=float, default=1000.0)
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    b_bin = a.b or a.a
    if b_bin == a.a and not a.b_set:
        ap.error("give --b (another engine) or --b-set (other settings): B would be A")
    common = list(a.set) + ["output.vtk=true", "simulation.threads=1"]
    if a.frames_every is not None:
        common.append("output.frame_interval=%r" % a.frames_every)
    if a.duration is not None:
        common.append("simulation.duration=%r" % a.duration)
    out = a.out or tempfile.mkdtemp(prefix="same_physics_")
    dt, periods = time_step_and_periods(a.case, common)
    run(a.a, a.case, os.path.join(out, "A"), common)
    run(a.a, a.case, os.path.join(out, "A_perturbed"), common + ["simulation.dt=%.17g" % (dt * (1 + 1e-13))])
    run(b_bin, a.case, os.path.join(out, "B"), common + a.b_set)
    frames = sorted(glob.glob(os.path.join(out, "A", "particles_[0-9]*.vtu")))
    if len(frames) < 3:
        sys.stderr.write("same_physics: fewer than 3 frames: set output.frame_interval (--frames-every)\n")
        sys.exit(2)
    print("A: %s\nB: %s %s\n" % (a.a, b_bin, " ".join("--set " + s for s in a.b_set)))
    print("| frame | max |x_A - x_B|, m | baseline max |x_A - x_A'|, m | ratio |")
    print("|---:|---:|---:|---:|")
    worst, judged = 0.0, 0
    for f in frames:
        name = os.path.basename(f)
        g, h = os.path.join(out, "B", name), os.path.join(out, "A_perturbed", name)
        if not (os.path.exists(g) and os.path.exists(h)):
            break
        pa, rmean = read_vtu(f)
        db = max_diff(pa, read_vtu(g)[0], periods)
        dp = max_diff(pa, read_vtu(h)[0], periods)
        floor = 1e-14 * rmean
        ratio = db / max(dp, floor)
        # Judged while the baseline is still far below the particle scale (1e-4 radii): beyond
        # that the rounding perturbation itself has become a different realization.
        in_window = dp < 1e-4 * rmean
        if in_window:
            worst = max(worst, ratio)
            judged += 1
        print("| %s | %.3e | %.3e | %s |" % (name, db, dp, ("%.3g" % ratio) + ("" if in_window else " (chaos)")))
    print()
    if judged < 2:
        print("same_physics: only %d frame(s) before the baseline reached 1e-4 radii: frames closer together" % judged)
        sys.exit(2)
    verdict = worst <= a.factor
    print("same_physics: %s (largest ratio %.3g over %d frames, limit %g)" %
          ("SAME physics within rounding" if verdict else "DIFFERENT physics", worst, judged, a.factor))
    sys.exit(0 if verdict else 1)


main()
