#!/usr/bin/env python3
"""Writes the initial state of the poured-packing benchmark as a LAMMPS data file (atom_style
sphere: id type diameter density x y z; Velocities), read by LAMMPS and LIGGGHTS directly
and turned into a cohdem case by bench/lammps_data_to_case.py with bench/packing.toml.

  python3 bench/gen_packing.py N OUT.data [--spacing 1.02] [--seed 1]

N spheres of diameter 1 and density 1 on a square-based cubic lattice (about N^(1/3) per
side, spacing 1.02 d, jitter +-0.005 d, the lowest layer 0.01 d above the floor z = 0),
periodic in x and y, with random velocities uniform in [-0.5, 0.5] per component: a dense
granular gas that collapses onto the floor under gravity 1 (-z).

  python3 bench/gen_packing.py N OUT.data --bed [--spacing 0.999]

--bed writes a packed bed at rest instead (bench/bed.toml, bench/peers/in.bed): round(N^(1/3))^3
spheres on a simple cubic lattice of spacing s < d, no jitter, periodic in x, y and z (box side
s per sphere), velocities uniform in [-0.01, 0.01]: every sphere presses on its six neighbours
with an overlap of d - s (0.001 d by default), so every list entry is a contact and every
contact lasts the whole run (the random velocities move a sphere by about 1e-5 d), the opposite
of the gas, where about 0.1 contacts a particle come and go. Python 3 stdlib only.
"""
import argparse
import math
import random
import sys


def write_data(path, title, box, atoms, vel):
    """A LAMMPS data file (atom_style sphere, one atom type) of the box [0, box) and its atoms'
    and velocities' lines."""
    with open(path, "w") as f:
        f.write(f"{title}\n\n{len(atoms)} atoms\n\n1 atom types\n\n")
        f.write("".join(f"0 {b:.9f} {d}lo {d}hi\n" for b, d in zip(box, "xyz")) + "\n")
        f.write("Atoms\n\n" + "\n".join(atoms) + "\n\nVelocities\n\n" + "\n".join(vel) + "\n")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("n", type=int)
    ap.add_argument("out")
    ap.add_argument("--spacing", type=float, default=None, help="1.02 (the gas), 0.999 (--bed)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--bed", action="store_true", help="a compressed periodic lattice at rest")
    a = ap.parse_args()
    rng = random.Random(a.seed)
    if a.bed:
        return bed(a, rng)
    if a.spacing is None:
        a.spacing = 1.02
    side = max(2, round(a.n ** (1.0 / 3.0)))
    nz = math.ceil(a.n / (side * side))
    s = a.spacing
    L = side * s
    atoms, vel = [], []
    for k in range(a.n):
        iz, rem = divmod(k, side * side)
        iy, ix = divmod(rem, side)
        j = lambda: rng.uniform(-0.005, 0.005)
        x = (ix + 0.5) * s + j()
        y = (iy + 0.5) * s + j()
        z = 0.51 + iz * s + abs(j())
        atoms.append(f"{k + 1} 1 1.0 1.0 {x:.9f} {y:.9f} {z:.9f}")
        vel.append(f"{k + 1} " + " ".join(f"{rng.uniform(-0.5, 0.5):.9f}" for _ in range(3)) + " 0 0 0")
    zhi = 0.51 + nz * s + 1.0
    write_data(a.out, f"poured packing benchmark: {a.n} spheres, lattice {side}x{side}x{nz}, spacing {s} (bench/gen_packing.py)",
               (L, L, zhi), atoms, vel)
    print(f"{a.out}: {a.n} spheres, box {L:.4f} x {L:.4f} (periodic) x {zhi:.4f}")


def bed(a, rng):
    s = 0.999 if a.spacing is None else a.spacing
    if not 0.9 <= s < 1.0:
        sys.exit(f"gen_packing.py: --bed --spacing {s}: expected 0.9 <= spacing < 1 (a sphere's diameter is 1)")
    side = max(3, round(a.n ** (1.0 / 3.0)))
    n = side ** 3
    L = side * s
    atoms, vel = [], []
    for k in range(n):
        iz, rem = divmod(k, side * side)
        iy, ix = divmod(rem, side)
        atoms.append(f"{k + 1} 1 1.0 1.0 {(ix + 0.5) * s:.9f} {(iy + 0.5) * s:.9f} {(iz + 0.5) * s:.9f}")
        vel.append(f"{k + 1} " + " ".join(f"{rng.uniform(-0.01, 0.01):.9f}" for _ in range(3)) + " 0 0 0")
    write_data(a.out, f"packed bed benchmark: {n} spheres, lattice {side}^3, spacing {s} (bench/gen_packing.py --bed)",
               (L, L, L), atoms, vel)
    print(f"{a.out}: {n} spheres, box {L:.4f} (periodic in x, y, z)")


if __name__ == "__main__":
    main()
