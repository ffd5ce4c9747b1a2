#!/usr/bin/env python3
"""Write the STL files of the shipped mesh scenes into scenes/ (binary STL, metres):

- slot_plate.stl: a flat plate 0.2 m wide (x from -0.1 to 0.1) and 0.02 m deep (y from 0 to 0.02,
  one period of hopper_discharge's slab), at z = 0, in 20 x 2 triangles. hopper_discharge places it
  twice, offset by -(0.1 + b/2) and +(0.1 + b/2) along x: a flat floor with a slot of width b.
- kiln_drum.stl: a drum of radius 0.1 m along y (0 to 0.02 m, one period of rotary_kiln's slice),
  72 facets around, with 6 lifters (bars 8 mm high, 3 mm wide, standing on the wall: narrower than
  a bead, so that no lattice site of a fill lies inside one).
- wedge_hopper.stl: one period (x from 0 to 0.037 m, moving_bed_hopper's tube pitch) of a wedge
  hopper: two plates inclined 30 degrees from the vertical that run from a ridge at z = 0.026 m on
  the period's edges down to a 7 mm slot (x from 0.015 to 0.022 m) at z = 0, 6 mm deep in y
  (the slab is 4.2 mm deep between its walls), 8 x 2 triangles each.

Usage: python benchmarks/mesh_scenes/make_meshes.py  (from the repository root)
"""

import math
from pathlib import Path

import numpy as np
import pyvista as pv

OUT = Path(__file__).resolve().parents[2] / "scenes"


def save(name: str, tris: list) -> None:
    pts = np.array([p for t in tris for p in t], float)
    faces = np.hstack([np.full((len(tris), 1), 3), np.arange(3 * len(tris)).reshape(-1, 3)]).ravel()
    pv.PolyData(pts, faces).save(str(OUT / name), binary=True)
    print(name, len(tris), "triangles")


def quad(tris, a, b, c, d):
    tris += [(a, b, c), (a, c, d)]


def slot_plate(width=0.2, depth=0.02, nx=10):
    tris = []
    xs = np.linspace(-width / 2, width / 2, nx + 1)
    for x0, x1 in zip(xs[:-1], xs[1:]):
        quad(tris, (x0, 0, 0), (x1, 0, 0), (x1, depth, 0), (x0, depth, 0))
    save("slot_plate.stl", tris)


def kiln_drum(R=0.1, L=0.02, facets=72, lifters=6, h=0.008, w=0.003):
    tris = []
    for k in range(facets):
        t0, t1 = 2 * math.pi * k / facets, 2 * math.pi * (k + 1) / facets
        p = lambda t, y: (R * math.cos(t), y, R * math.sin(t))
        quad(tris, p(t0, 0), p(t1, 0), p(t1, L), p(t0, L))
    for k in range(lifters):  # three faces of a bar standing on the wall, pointing to the axis
        t = 2 * math.pi * (k * (facets // lifters) + 0.5) / facets  # the middle of a facet
        c, s = math.cos(t), math.sin(t)
        u = (-s, c)

        def at(r, off, y):
            return (r * c + off * u[0], y, r * s + off * u[1])

        r0, r1 = R * math.cos(math.pi / facets), R - h  # the bar's foot on the facet
        quad(tris, at(r0, -w / 2, 0), at(r1, -w / 2, 0), at(r1, -w / 2, L), at(r0, -w / 2, L))
        quad(tris, at(r1, -w / 2, 0), at(r1, w / 2, 0), at(r1, w / 2, L), at(r1, -w / 2, L))
        quad(tris, at(r1, w / 2, 0), at(r0, w / 2, 0), at(r0, w / 2, L), at(r1, w / 2, L))
    save("kiln_drum.stl", tris)


def wedge_hopper(period=0.037, slot=0.007, angle=30.0, y0=-0.001, y1=0.0052, n=8):
    tris = []
    run = period / 2 - slot / 2
    top = run / math.tan(math.radians(angle))
    for x_top, x_low in ((0.0, run), (period, period - run)):  # left plate, right plate
        for k in range(n):
            a, b = k / n, (k + 1) / n
            p = lambda f, y: (x_top + f * (x_low - x_top), y, top * (1 - f))
            quad(tris, p(a, y0), p(b, y0), p(b, y1), p(a, y1))
    save("wedge_hopper.stl", tris)


if __name__ == "__main__":
    slot_plate()
    kiln_drum()
    wedge_hopper()
