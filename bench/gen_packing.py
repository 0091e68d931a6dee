#!/usr/bin/env python3
"""Writes the initial state of the poured-packing benchmark as a LAMMPS data file (atom_style
sphere: id type diameter density x y z; Velocities), read by LAMMPS and LIGGGHTS directly
and turned into a cohdem case by bench/lammps_data_to_case.py with bench/packing.toml.

  python3 bench/gen_packing.py N OUT.data [--spacing 1.02] [--seed 1]

N spheres of diameter 1 and density 1 on a square-based cubic lattice (about N^(1/3) per
side, spacing 1.02 d, jitter +-0.005 d, the lowest layer 0.01 d above the floor z = 0),
periodic in x and y, with random velocities uniform in [-0.5, 0.5] per component: a dense
granular gas that collapses onto the floor under gravity 1 (-z). Python 3 stdlib only.
"""
import argparse
import math
import random


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("n", type=int)
    ap.add_argument("out")
    ap.add_argument("--spacing", type=float, default=1.02)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    rng = random.Random(a.seed)
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
    with open(a.out, "w") as f:
        f.write(f"poured packing benchmark: {a.n} spheres, lattice {side}x{side}x{nz}, spacing {s} (bench/gen_packing.py)\n\n")
        f.write(f"{a.n} atoms\n\n1 atom types\n\n0 {L:.9f} xlo xhi\n0 {L:.9f} ylo yhi\n0 {zhi:.9f} zlo zhi\n\n")
        f.write("Atoms\n\n" + "\n".join(atoms) + "\n\nVelocities\n\n" + "\n".join(vel) + "\n")
    print(f"{a.out}: {a.n} spheres, box {L:.4f} x {L:.4f} (periodic) x {zhi:.4f}")


if __name__ == "__main__":
    main()
