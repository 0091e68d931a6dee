#!/usr/bin/env python3
"""A plain `cohdem run` case made from a shear-box ring shear run's consolidated bed, for
scripts/validate/same_physics.py: the consolidated particles (free, the glued base layer as
frozen particles, the lid's layer attached to a lid plane), the lid floating under sigma_pre
(a spring-controlled plane with the sample's mass and the load as preload, as the tester
sets it) and moving at the shear speed, periodic in x and y, with the run's materials and
contact law. Particles start at rest and without contact history (the VTK frame holds
none), so that the first force evaluation is the same in engines that differ in what
System::prepare does with moving contacts.

Usage: ring_shear_bed_case.py RUN_DIR OUT.toml [--duration S] [--frames-every S] [--sigma-fraction F]
RUN_DIR is a ring shear output folder with case.toml (as scripts/validate/ring_shear.sh
keeps it) and particles_consolidated.vtu. Example (docs/ring-shear.md, "Same physics"):
  scripts/validate/ring_shear.sh -s 1 -o /tmp/rs examples/ring_shear/copper_ore_5pct.toml
  scripts/validate/ring_shear_bed_case.py /tmp/rs/copper_ore_5pct/seed_1 /tmp/bed.toml
  scripts/validate/same_physics.py /tmp/bed.toml --b OTHER/build/cohdem"""
import argparse, math, os, re, sys, tomllib

from vtu import read_arrays as read_vtu


def sections(text, names):
    """The text of the case's tables whose header is one of `names` (e.g. [[material]]), in order."""
    out, keep = [], False
    for line in text.splitlines():
        h = re.match(r"^\s*(\[\[?[\w.]+\]\]?)", line)
        if h:
            keep = h.group(1) in names
        if keep:
            out.append(line)
    return "\n".join(out)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run_dir")
    ap.add_argument("out")
    ap.add_argument("--duration", type=float, default=0.009)
    ap.add_argument("--frames-every", type=float, default=0.0005)
    ap.add_argument("--sigma-fraction", type=float, default=1.0,
                    help="the lid's load as a fraction of sigma_pre (0.2: the relief before the lowest shear point)")
    a = ap.parse_args()
    case_path = os.path.join(a.run_dir, "case.toml")
    text = open(case_path).read()
    c = tomllib.loads(text)
    r = c["ring_shear"]
    if r.get("cell", "shear_box") != "shear_box":
        sys.exit("ring_shear_bed_case: %s: only the shear box (periodic) cell is supported" % case_path)
    v = read_vtu(os.path.join(a.run_dir, "particles_consolidated.vtu"))
    walls = read_vtu(os.path.join(a.run_dir, "walls_consolidated.vtu"))["Points"]
    lid_z = max(p[2] for p in walls)  # the lid plane's corners
    L, W = r["length"], r["width"]
    ore = r["material"]
    rho = next(m for m in c["material"] if m["name"] == ore)["density"]
    g = c["simulation"].get("gravity", [0, 0, -9.81])
    free_mass = sum(rho * 4 / 3 * math.pi * rad ** 3 for rad, f in zip(v["radius"], v["flag"]) if f == 0)
    preload = a.sigma_fraction * r["sigma_pre"] * L * W - free_mass * (-g[2])  # the lid's weight counterbalanced (normal -z)
    parts = []
    for k in range(len(v["id"])):
        f = v["flag"][k]
        s = '  { material = "%s", radius = %.17g, position = [%.17g, %.17g, %.17g]' % ((ore, v["radius"][k]) + tuple(v["Points"][k]))
        s += ", frozen = true" if f == 1 else (', attach_to = "lid"' if f == 2 else "")
        parts.append(s + " }")
    body = sections(text, {"[[material]]", "[contact]", "[[contact.pair]]"})
    out = ["# Made by scripts/validate/ring_shear_bed_case.py from %s (consolidated bed)." % os.path.abspath(a.run_dir),
           "particle = [", ",\n".join(parts) + ",", "]",
           "[case]", 'name = "consolidated ring shear bed, sheared (same_physics check)"', 'units = "SI"',
           "[simulation]", "dt = %r" % c["simulation"]["dt"], "duration = %r" % a.duration,
           "gravity = [%r, %r, %r]" % tuple(g), "threads = 1",
           "[domain]", "lo = [0, 0, -1]", "hi = [%r, %r, 1]" % (L, W), "periodic = [true, true, false]",
           body,
           "[[wall]]", 'name = "base"', 'type = "plane"', 'material = "%s"' % r["base_material"],
           "point = [0, 0, 0]", "normal = [0, 0, 1]",
           "[[wall]]", 'name = "lid"', 'type = "plane"', 'material = "%s"' % r["base_material"],
           "point = [%r, %r, %r]" % (L / 2, W / 2, lid_z), "normal = [0, 0, -1]",
           "velocity = [%r, 0, 0]" % r.get("shear_velocity", 0.02),
           'control = "spring"', "mass = %r" % free_mass, "spring_k = 0", "spring_preload = %r" % preload,
           "[output]", 'folder = "out"', "frame_interval = %r" % a.frames_every, "progress_interval = 10", ""]
    open(a.out, "w").write("\n".join(out))
    print("ring_shear_bed_case: %d particles (%d free), lid at z = %.6g m, preload %.6g N -> %s" %
          (len(parts), sum(1 for f in v["flag"] if f == 0), lid_z, preload, a.out))


main()
