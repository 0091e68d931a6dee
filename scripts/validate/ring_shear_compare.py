#!/usr/bin/env python3
"""Several ring shear runs side by side (random fillings, cells): a Markdown table of each
run's measured shear points and yield locus, the mean and sample standard deviation of the
friction angle per group, and one figure with every run's shear points and least-squares
locus. A group is the folder above the runs (e.g. out/validate/ring_shear/copper_ore_5pct).
Usage: ring_shear_compare.py [--flow-function FF.png] OUT.png RUN_DIR...
  (RUN_DIR holds summary.json and shear_points.csv). --flow-function also draws each run's
  point of the flow function, the unconfined yield strength sigma_c against the major
  consolidation stress sigma_1 of its evaluation, with the group means and Jenike's ffc lines
  (1, 2, 4, 10); a run without a steady-state circle (no sigma_1) is left out of it.
Example (docs/ring-shear.md):
  ring_shear_compare.py docs/img/ring_shear_5pct_seeds.png out/validate/ring_shear/copper_ore_5pct/seed_* \\
      out/validate/ring_shear/copper_ore_5pct_annulus/seed_1"""
import csv, json, math, os, statistics, subprocess, sys, tempfile

args = sys.argv[1:]
ff_png = None
if len(args) >= 2 and args[0] == "--flow-function":
    ff_png, args = args[1], args[2:]
if len(args) < 2:
    print(__doc__); sys.exit(2)
png, runs = args[0], args[1:]
tmp = tempfile.mkdtemp()
flow = {}  # group -> [(sigma_1, sigma_c) in kPa]
MARK = (7, 5, 9, 11, 13)  # gnuplot's filled point types, one a group; each open one is the type - 1


def measured_locus(j):
    """The evaluation of the measured (not normalized) shear points, in any summary.json format."""
    if "yield_locus_raw" in j:  # reports written before normalize_points existed
        return j["yield_locus_raw"]
    return j["yield_locus_measured_points"] if j.get("normalized_points") else j["yield_locus"]


groups, plots, smax = {}, [], 0.0
print("| run | cell | particles | shear points (sigma, tau), kPa | phi_lin, deg | c, kPa | ffc | pre-shear tau first -> last, kPa | CPU (or wall), min |")
print("|---|---|---:|---|---:|---:|---:|---|---:|")
for k, run in enumerate(runs):
    j = json.load(open(os.path.join(run, "summary.json")))
    pts = list(csv.DictReader(open(os.path.join(run, "shear_points.csv"))))
    xs = [1e-3 * float(p["sigma"]) for p in pts]
    ys = [1e-3 * float(p["tau_measured"]) for p in pts]
    n = len(xs); mx = sum(xs) / n; my = sum(ys) / n
    m = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
    c = my - m * mx
    phi = math.degrees(math.atan(m))
    y = measured_locus(j)
    ffc = "-" if "error" in y or y["ffc"] is None else (y["ffc"] if isinstance(y["ffc"], str) else f'{y["ffc"]:.2f}')
    group = os.path.basename(os.path.dirname(os.path.abspath(run)))
    if "sigma_pre_target" in j:  # the same case run at several consolidation stresses: apart
        group += f" at {1e-3 * j['sigma_pre_target']:.1f} kPa"
    name = f"{group}/{os.path.basename(os.path.abspath(run))}"
    groups.setdefault(group, []).append(phi)
    smax = max(smax, max(xs))
    if "error" not in y and y.get("sigma_1") is not None and y.get("sigma_c") is not None:
        flow.setdefault(group, []).append((1e-3 * y["sigma_1"], 1e-3 * y["sigma_c"]))
    tau_each = j["pre_shear"]["tau_each"]
    print(f"| {name} | {j['cell']} | {j['particles']} | " + " ".join(f"({x:.1f}, {t:.1f})" for x, t in zip(xs, ys)) +
          f" | {phi:.1f} | {c:.1f} | {ffc} | {1e-3*tau_each[0]:.1f} -> {1e-3*tau_each[-1]:.1f} | {(j['cpu_time_s'] if 'cpu_time_s' in j else j['wall_time_s'])/60:.0f} |")
    with open(os.path.join(tmp, f"{k}.dat"), "w") as f:
        for x, t in zip(xs, ys): f.write(f"{x} {t}\n")
    plots.append((k, group, name, m, c, phi))
print()
key = {}  # group -> its key entry in the figure
for g, v in groups.items():
    sd = statistics.stdev(v) if len(v) > 1 else float("nan")
    print(f"{g}: phi_lin mean {statistics.mean(v):.1f} deg, std {sd:.1f} deg, min {min(v):.1f}, max {max(v):.1f} (n = {len(v)})")
    key[g] = f"{g}: phi_lin {statistics.mean(v):.1f}" + (f" +- {sd:.1f}" if len(v) > 1 else "") + f" deg (n = {len(v)})"
xmax = 1.15 * smax
cmds = []
# Up to eight runs of one group: a colour and a key entry each. More runs, or several groups
# (fillings of the reduced cell beside the annulus'): a colour and a point type per group and
# one key entry per group with its mean and spread, so the groups can be told apart.
by_group = len(groups) > 1 or len(plots) > 8
order = list(groups)
titled = set()
for k, g, name, m, c, phi in plots:
    if by_group:
        gi = order.index(g)
        title = f"t '{key[g]}'" if g not in titled else "notitle"
        titled.add(g)
        cmds.append(f"'{tmp}/{k}.dat' w p pt {MARK[gi % 5]} lc {gi + 1} {title}")
        cmds.append(f"{m}*x+{c} w l lc {gi + 1} notitle")
    else:
        cmds.append(f"'{tmp}/{k}.dat' w p pt 7 lc {k+1} t '{name}: {phi:.1f} deg'")
        cmds.append(f"{m}*x+{c} w l lc {k+1} notitle")
gp = f"""set terminal pngcairo size 800,560 font ',10' noenhanced
set output '{png}'
set title 'measured shear points and least-squares yield loci'
set xlabel 'normal stress (kPa)'; set ylabel 'shear stress (kPa)'; set grid; set key right bottom
set xrange [0:{xmax}]; set yrange [0:*]
plot {", ".join(cmds)}
"""
subprocess.run(["gnuplot"], input=gp, text=True, check=True)
print("figure:", png)
if ff_png:
    # The flow function: each run's (sigma_1, sigma_c), a filled marker at each group's mean.
    cmds, top, inline = [], 0.0, ""
    for gi, (g, v) in enumerate(flow.items()):
        with open(os.path.join(tmp, f"ff{gi}.dat"), "w") as f:
            for x, yv in v: f.write(f"{x} {yv}\n")
        mx, my = statistics.mean(x for x, _ in v), statistics.mean(yv for _, yv in v)
        print(f"flow function, {g}: mean sigma_1 {mx:.1f} kPa, mean sigma_c {my:.1f} kPa, ratio {mx / my:.2f} (n = {len(v)})")
        top = max(top, max(x for x, _ in v))
        cmds.append(f"'{tmp}/ff{gi}.dat' w p pt {MARK[gi % 5] - 1} lc {gi + 1} "
                    f"t '{g}: sigma_1 {mx:.0f} kPa, sigma_c {my:.0f} kPa, ffc {mx / my:.2f} (n = {len(v)})'")
        cmds.append(f"'-' w p pt {MARK[gi % 5]} ps 2 lc {gi + 1} notitle")
        inline += f"{mx} {my}\ne\n"  # the mean, read by that '-'

    xr = 1.15 * top
    lines = ", ".join(f"x / {k} w l dt 2 lc rgb 'gray' notitle" for k in (1, 2, 4, 10))
    # Jenike's classes between the lines: ffc < 1 not flowing, 1-2 very cohesive, 2-4 cohesive,
    # 4-10 easy flowing, > 10 free flowing; each line labelled where it leaves the plot.
    labels = "\n".join(f"set label 'ffc = {k}' at {0.97 * xr},{0.97 * xr / k} right offset 0,0.6 tc rgb 'gray'"
                        for k in (2, 4, 10)) + f"\nset label 'ffc = 1' at {0.8 * xr},{0.8 * xr} right offset -1,0 tc rgb 'gray'"
    gp = f"""set terminal pngcairo size 800,560 font ',10' noenhanced
set output '{ff_png}'
set title 'flow function: unconfined yield strength against major consolidation stress'
set xlabel 'major consolidation stress sigma_1 (kPa)'; set ylabel 'unconfined yield strength sigma_c (kPa)'
set grid; set key left top
set xrange [0:{xr}]; set yrange [0:*]
{labels}
plot {", ".join(cmds)}, {lines}
{inline}"""
    if flow:
        subprocess.run(["gnuplot"], input=gp, text=True, check=True)
        print("flow function:", ff_png)
    else:
        print("flow function: no run has a steady-state circle (sigma_1); not drawn")
