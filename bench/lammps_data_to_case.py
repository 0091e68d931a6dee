#!/usr/bin/env python3
"""Turns a LAMMPS data file (atom_style sphere or LIGGGHTS granular: id type diameter density
x y z [ix iy iz], optional Velocities: id vx vy vz wx wy wz) into a cohdem case: the header
case (everything but the particles) followed by one [[particle]] table per atom (with --csv:
the particles in CSV files, read by [[particles]] tables).

  python3 bench/lammps_data_to_case.py DATA HEADER.toml -o CASE.toml [--types 1=flow,2=base]
      [--frozen 2] [--box xy] [--csv]

Atom types map to the header's materials (by default type k -> the k-th [[material]]);
atoms of the --frozen types get frozen = true (LAMMPS: fix freeze). The material density
must equal the atom's density. --box xy adds a [domain] with the data file's box, periodic
in the listed directions (the header must then have no [domain]). --csv writes the particles
to CSV files beside CASE.toml instead (CASE.MATERIAL.csv, CASE.MATERIAL.frozen.csv for frozen
atoms), read by one [[particles]] table each: a case of 10^5 particles then loads in a
fraction of the time and memory. The particles are then grouped by material and frozen
state, in id order within a group. (Both codes take mass = density * pi d^3 / 6.) Python 3
standard library only.
"""
import argparse
import csv
import os
import sys
import tomllib


def fail(msg):
    sys.exit(f"lammps_data_to_case: {msg}")


def read_data(path):
    """Returns (atoms, velocities, box): atoms[id] = (type, diameter, density, x, y, z),
    box = [(xlo, xhi), (ylo, yhi), (zlo, zhi)]."""
    with open(path) as f:
        lines = [l.split("#")[0].strip() for l in f]
    natoms = None
    box = [None, None, None]
    for l in lines[1:40]:
        if l.endswith(" atoms"):
            natoms = int(l.split()[0])
        for d, c in enumerate("xyz"):
            if l.endswith(f"{c}lo {c}hi"):
                box[d] = (float(l.split()[0]), float(l.split()[1]))
    if natoms is None:
        fail(f"{path}: no 'N atoms' line in the header")
    atoms, vel = {}, {}
    section = None
    for n, l in enumerate(lines, 1):
        if not l:
            continue
        head = l.split()[0]
        if head in ("Atoms", "Velocities", "Masses", "Bonds", "Ellipsoids"):
            section = head
            continue
        if section == "Atoms":
            f = l.split()
            if len(f) not in (7, 10):
                fail(f"{path}:{n}: expected 'id type diameter density x y z [ix iy iz]', got {len(f)} columns")
            atoms[int(f[0])] = (int(f[1]), float(f[2]), float(f[3]), float(f[4]), float(f[5]), float(f[6]))
        elif section == "Velocities":
            f = l.split()
            if len(f) != 7:
                fail(f"{path}:{n}: expected 'id vx vy vz wx wy wz'")
            vel[int(f[0])] = tuple(float(x) for x in f[1:])
        elif section is not None and section != "Atoms" and section != "Velocities":
            fail(f"{path}:{n}: section '{section}' is not supported")
    if len(atoms) != natoms:
        fail(f"{path}: header says {natoms} atoms, the Atoms section has {len(atoms)}")
    return atoms, vel, box


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("data")
    ap.add_argument("header")
    ap.add_argument("-o", "--out", required=True)
    ap.add_argument("--types", default="", help="type=material,... (default: type k -> k-th material)")
    ap.add_argument("--frozen", default="2", help="comma-separated frozen atom types ('' for none)")
    ap.add_argument("--box", default=None, help="add [domain] from the data box, periodic in these of x, y, z")
    ap.add_argument("--csv", action="store_true", help="particles in CSV files read by [[particles]] tables")
    a = ap.parse_args()

    with open(a.header, "rb") as f:
        head = tomllib.load(f)
    if "particle" in head:
        fail(f"{a.header}: the header must not list particles")
    mats = {m["name"]: m for m in head.get("material", [])}
    order = [m["name"] for m in head.get("material", [])]
    tmap = {}
    if a.types:
        for kv in a.types.split(","):
            t, name = kv.split("=")
            tmap[int(t)] = name
    frozen = {int(t) for t in a.frozen.split(",") if t}

    atoms, vel, box = read_data(a.data)
    out = [open(a.header).read().rstrip("\n"), ""]
    if a.box is not None:
        if "domain" in head:
            fail(f"{a.header}: --box given but the header has a [domain]")
        if None in box:
            fail(f"{a.data}: no box (xlo xhi, ylo yhi, zlo zhi lines)")
        per = ", ".join("true" if c in a.box else "false" for c in "xyz")
        out += ["[domain]", f"lo = [{box[0][0]!r}, {box[1][0]!r}, {box[2][0]!r}]",
                f"hi = [{box[0][1]!r}, {box[1][1]!r}, {box[2][1]!r}]", f"periodic = [{per}]", ""]
    out.append(f"# {len(atoms)} particles from {a.data} (bench/lammps_data_to_case.py)")
    groups = {}  # (material, frozen) -> rows, in order of first appearance
    for aid in sorted(atoms):
        t, d, rho, x, y, z = atoms[aid]
        name = tmap.get(t) or (order[t - 1] if 0 < t <= len(order) else None)
        if name not in mats:
            fail(f"atom {aid}: type {t} maps to no [[material]] of {a.header} (use --types)")
        if abs(mats[name].get("density", 0) - rho) > 1e-12 * rho:
            fail(f"atom {aid}: density {rho} differs from material '{name}' density {mats[name].get('density')}")
        v = vel.get(aid, (0.0,) * 6)
        if a.csv:
            groups.setdefault((name, t in frozen), []).append([aid, x, y, z, d / 2, *v])
            continue
        p = [f"[[particle]]", f'material = "{name}"', f"radius = {d / 2!r}",
             f"position = [{x!r}, {y!r}, {z!r}]"]
        if any(v[:3]):
            p.append(f"velocity = [{v[0]!r}, {v[1]!r}, {v[2]!r}]")
        if any(v[3:]):
            p.append(f"omega = [{v[3]!r}, {v[4]!r}, {v[5]!r}]")
        if t in frozen:
            p.append("frozen = true")
        out.append("\n".join(p))
    stem = os.path.splitext(a.out)[0]
    for (name, fz), rows in groups.items():
        path = f"{stem}.{name}{'.frozen' if fz else ''}.csv"
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["id", "x", "y", "z", "radius", "vx", "vy", "vz", "wx", "wy", "wz"])
            w.writerows([r[0]] + [repr(float(c)) for c in r[1:]] for r in rows)
        out += ["[[particles]]", f'file = "{os.path.basename(path)}"', f'material = "{name}"'] + \
               (["frozen = true"] if fz else [])
    with open(a.out, "w") as f:
        f.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
