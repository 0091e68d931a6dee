#!/usr/bin/env python3
"""Documentation figures of a ring shear run from its CSV/JSON report (docs/ring-shear.md):
the shear curve (pre-shear and shear phases, stress axis over the shearing phases) and the
measured shear points with their least-squares yield locus and the mean pre-shear point.
Usage: ring_shear_figures.py RUN_DIR OUT_PREFIX   (writes OUT_PREFIX_curve.png, OUT_PREFIX_locus.png)"""
import csv, json, subprocess, sys, tempfile, os

run, prefix = sys.argv[1], sys.argv[2]
rows = list(csv.DictReader(open(os.path.join(run, "series.csv"))))
pts = list(csv.DictReader(open(os.path.join(run, "shear_points.csv"))))
j = json.load(open(os.path.join(run, "summary.json")))
tmp = tempfile.mkdtemp()
with open(os.path.join(tmp, "s.dat"), "w") as f:
    for r in rows:
        if float(r["phase"]) >= 1:
            f.write(f'{1e3*float(r["shear_displacement"])} {1e-3*float(r["tau"])} {1e-3*float(r["sigma"])}\n')
ymax = max([1e-3 * j["sigma_pre_target"]] + [1e-3 * max(float(r["tau"]), float(r["sigma"])) for r in rows if float(r["phase"]) >= 2])
tau_key = "tau_measured" if "tau_measured" in pts[0] else "tau"
xs = [1e-3 * float(p["sigma"]) for p in pts]
ys = [1e-3 * float(p[tau_key]) for p in pts]
n = len(xs); mx = sum(xs) / n; my = sum(ys) / n
m = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs); c = my - m * mx
with open(os.path.join(tmp, "p.dat"), "w") as f:
    for x, y in zip(xs, ys): f.write(f"{x} {y}\n")
sp, tp = 1e-3 * j["pre_shear"]["sigma"], 1e-3 * j["pre_shear"]["tau"]
import math
gp = f"""
set terminal pngcairo size 1100,500 font ',10' noenhanced
set output '{prefix}_curve.png'
set title 'shear stress and normal stress against shear displacement ({os.path.basename(os.path.dirname(run.rstrip('/')))})'
set xlabel 'shear displacement (mm)'; set ylabel 'stress (kPa)'; set grid
set yrange [0:{1.15*ymax}]
plot '{tmp}/s.dat' u 1:2 w l t 'tau', '' u 1:3 w l t 'sigma'
set output '{prefix}_locus.png'
set terminal pngcairo size 700,500 font ',10' noenhanced
set title sprintf('measured shear points: phi_lin = %.1f deg, c = %.1f kPa', {math.degrees(math.atan(m))}, {c})
set xlabel 'normal stress (kPa)'; set ylabel 'shear stress (kPa)'
set xrange [0:{1.2*sp}]; set yrange [0:{1.3*max(ys+[tp])}]; set key left top
plot '{tmp}/p.dat' w p pt 7 t 'shear points', {m}*x+{c} w l t 'linearized yield locus', '-' w p pt 5 t 'mean pre-shear'
{sp} {tp}
e
"""
subprocess.run(["gnuplot"], input=gp, text=True, check=True)
print(f"phi_lin {math.degrees(math.atan(m)):.2f} deg, c {c:.2f} kPa ->", prefix + "_curve.png", prefix + "_locus.png")
