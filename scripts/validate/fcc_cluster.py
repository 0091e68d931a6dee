#!/usr/bin/env python3
"""Prints the compact cluster of tests/physics/test_cohesive_bulk.cpp (fcc_cluster) as a TOML
`particle = [...]` array for a case file: the face-centred cubic lattice points (close-packed
layers horizontal) within a ball, cut flat `cut` ball radii below its centre, spheres with
fewer than 4 lattice neighbours pruned, lowest centre at r + gap.

Usage: fcc_cluster.py [--radius 1e-3] [--overlap 0.02] [--ball 2.6] [--cut 0.5] [--gap 0.02]
                      [--material powder]
  --overlap  initial overlap of lattice neighbours, in units of r (spacing 2r - overlap r)
  --ball     ball radius in diameters;  --gap  clearance above z = 0, in units of r
"""
import argparse
import math


def cluster(r, overlap, ball, cut, gap):
    d = 2 * r - overlap * r
    R = ball * 2 * r
    a1 = (d, 0.0, 0.0)
    a2 = (d / 2, d * math.sqrt(3) / 2, 0.0)
    a3 = (d / 2, d * math.sqrt(3) / 6, d * math.sqrt(2 / 3))
    n = int(R / d) + 3
    p = []
    for i in range(-2 * n, 2 * n + 1):
        for j in range(-2 * n, 2 * n + 1):
            for k in range(-n, n + 1):
                x = tuple(i * a1[c] + j * a2[c] + k * a3[c] for c in range(3))
                if math.dist(x, (0, 0, 0)) <= R and x[2] >= -cut * R:
                    p.append(x)
    pruned = True
    while pruned:
        q = [x for x in p if sum(1 for y in p if x != y and math.dist(x, y) < 1.01 * d) >= 4]
        pruned = len(q) != len(p)
        p = q
    zmin = min(x[2] for x in p)
    return [(x[0], x[1], x[2] + r + gap * r - zmin) for x in p]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--radius", type=float, default=1e-3)
    ap.add_argument("--overlap", type=float, default=0.02)
    ap.add_argument("--ball", type=float, default=2.6)
    ap.add_argument("--cut", type=float, default=0.5)
    ap.add_argument("--gap", type=float, default=0.02)
    ap.add_argument("--material", default="powder")
    a = ap.parse_args()
    pts = cluster(a.radius, a.overlap, a.ball, a.cut, a.gap)
    print(f"# {len(pts)} spheres: scripts/validate/fcc_cluster.py --radius {a.radius:g} --overlap {a.overlap:g} "
          f"--ball {a.ball:g} --cut {a.cut:g} --gap {a.gap:g}")
    print("particle = [")
    for x in pts:
        print(f'  {{ material = "{a.material}", radius = {a.radius:g}, '
              f"position = [{x[0]:.9e}, {x[1]:.9e}, {x[2]:.9e}] }},")
    print("]")


if __name__ == "__main__":
    main()
