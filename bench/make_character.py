#!/usr/bin/env python3
"""A sculpted character as a sculpting tool exports it: every subtool its own surface, stuck
through the others, none merged (issue 35's sculpted class).

Usage: bench/make_character.py OUT_DIR [--level L] [--seed S]
Writes character_L.stl (binary STL): a displaced body (an icosphere of L subdivisions, default
6), a head, eyes sunk into it, two curved horns tapering to sharp tips, arms and legs as closed
tubes, five fingers per hand a third of a base cell apart (at --base-size 1 %), 80 strands of
hair as open tubes a quarter of a base cell thick that cross each other and the head, and an
open skirt (one sheet) partly through the body and partly a fraction of a cell off it.
Deterministic (Python's own `random`, fixed seed); about 330k triangles at level 6.
"""
import argparse
import math
import os
import random

from make_scan_classes import icosphere, unit
from mesh_files import write_stl


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


class Model:
    def __init__(self):
        self.points, self.triangles = [], []

    def add(self, points, triangles):
        o = len(self.points)
        self.points += points
        self.triangles += [(a + o, b + o, c + o) for a, b, c in triangles]

    def blob(self, level, centre, radii, bump=None):
        v, f = icosphere(level)
        pts = []
        for p in v:
            s = 1 + (bump(p) if bump else 0)
            pts.append(tuple(centre[i] + radii[i] * s * p[i] for i in range(3)))
        self.add(pts, f)

    def tube(self, curve, radius_at, sides, closed=True):
        """A tube along the polyline `curve`, radius_at(t) for t in [0, 1], frames carried along
        (no twist); closed: fans to a point past each end (a tip where the radius runs out)."""
        n = len(curve)
        tangents = [unit(sub(curve[min(i + 1, n - 1)], curve[max(i - 1, 0)])) for i in range(n)]
        helper = (0.0, 0.0, 1.0) if abs(tangents[0][2]) < 0.9 else (1.0, 0.0, 0.0)
        u = unit(cross(tangents[0], helper))
        pts = []
        for i in range(n):
            t = tangents[i]
            u = unit(sub(u, tuple(t[k] * sum(u[j] * t[j] for j in range(3)) for k in range(3))))
            w = cross(t, u)
            r = radius_at(i / (n - 1))
            for s in range(sides):
                a = 2 * math.pi * s / sides
                pts.append(tuple(curve[i][k] + r * (math.cos(a) * u[k] + math.sin(a) * w[k]) for k in range(3)))
        tris = []
        for i in range(n - 1):
            for s in range(sides):
                a, b = i * sides + s, i * sides + (s + 1) % sides
                tris += [(a, b, b + sides), (a, b + sides, a + sides)]
        if closed:
            for end, ring, sign in ((0, 0, -1), (n - 1, (n - 1) * sides, 1)):
                r = radius_at(end / (n - 1))
                tip = tuple(curve[end][k] + sign * tangents[end][k] * max(r, 1e-4) for k in range(3))
                pts.append(tip)
                c = len(pts) - 1
                for s in range(sides):
                    a, b = ring + s, ring + (s + 1) % sides
                    tris.append((c, b, a) if sign < 0 else (c, a, b))
        self.add(pts, tris)


def curve(a, b, bend, samples):
    """From a to b, bowed by `bend` at the middle."""
    return [tuple(a[k] + (b[k] - a[k]) * t + bend[k] * 4 * t * (1 - t) for k in range(3))
            for t in (i / (samples - 1) for i in range(samples))]


def character(level, rng):
    m = Model()
    waves = [(tuple(rng.gauss(0, 1) * 2 ** o for _ in range(3)), rng.uniform(0, 6.28)) for o in range(5)
             for _ in range(4)]

    def bumps(p):
        return sum(0.03 * math.sin(sum(p[i] * k[i] for i in range(3)) + ph) for k, ph in waves) / 4

    m.blob(level, (0, 0, 1.05), (0.3, 0.22, 0.5), bumps)  # body
    m.blob(level - 1, (0, 0.02, 1.68), (0.17, 0.17, 0.19), bumps)  # head, through the body's top
    for x in (-0.06, 0.06):
        m.blob(3, (x, 0.16, 1.72), (0.03, 0.03, 0.03))  # eyes, half sunk into the head
        # horns: curved, tapering from the head to a sharp tip
        m.tube(curve((x * 1.5, 0.0, 1.8), (x * 4.5, -0.05, 2.05), (x * 0.8, -0.02, 0.02), 40),
               lambda t: 0.035 * (1 - t) + 0.0005, 16)
    for side in (-1, 1):
        hand = (side * 0.55, 0.05, 0.8)
        m.tube(curve((side * 0.22, 0.0, 1.35), hand, (side * 0.05, 0.03, 0.0), 40), lambda t: 0.05, 20)  # arm
        m.blob(3, hand, (0.045, 0.03, 0.05))  # palm
        for f in range(5):  # fingers 0.02 thick, 0.008 apart: a third of a base cell
            y = hand[1] + (f - 2) * 0.028
            base = (hand[0] + side * 0.02, y, hand[2] - 0.03)
            tip = (hand[0] + side * 0.05, y + 0.004 * (f - 2), hand[2] - 0.17)
            m.tube(curve(base, tip, (side * 0.012, 0.0, 0.0), 24), lambda t: 0.01 * (1 - 0.3 * t), 10)
        m.tube(curve((side * 0.13, 0.0, 0.75), (side * 0.18, 0.02, 0.02), (0.0, 0.04, 0.0), 50), lambda t: 0.08, 24)
    for _ in range(80):  # hair: open tubes from the crown down the back, crossing
        a = rng.uniform(-1.2, 1.2)
        start = (0.15 * math.sin(a), 0.15 * math.cos(a) - 0.05, 1.82)
        end = (0.3 * math.sin(a) + rng.uniform(-0.05, 0.05), -0.25 + rng.uniform(-0.05, 0.05), 1.3 + rng.uniform(-0.1, 0.1))
        m.tube(curve(start, end, (rng.uniform(-0.05, 0.05), -0.12, 0.05), 60), lambda t: 0.006, 6, closed=False)
    # the skirt: one open sheet, a cone around the hips
    rows, cols = 30, 160
    pts = []
    for j in range(rows + 1):
        z = 0.62 + 0.3 * j / rows
        for i in range(cols):
            a = 2 * math.pi * i / cols
            r = 1.0 + 0.25 * (0.92 - z) + 0.03 * math.sin(7 * a)
            pts.append((0.3 * r * math.cos(a), 0.22 * r * math.sin(a), z))
    tris = []
    for j in range(rows):
        for i in range(cols):
            a, b = j * cols + i, j * cols + (i + 1) % cols
            tris += [(a, b, b + cols), (a, b + cols, a + cols)]
    m.add(pts, tris)
    return m


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out_dir")
    ap.add_argument("--level", type=int, default=6)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    os.makedirs(a.out_dir, exist_ok=True)
    m = character(a.level, random.Random(a.seed))
    path = os.path.join(a.out_dir, f"character_{a.level}.stl")
    write_stl(path, m.points, m.triangles)
    print(path, len(m.triangles), "triangles")


if __name__ == "__main__":
    main()
