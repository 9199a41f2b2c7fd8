#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Renders an OBJ written by impact-cloth-bench --write-final (objects "cloth...", obstacles, the
ground as a large quad) into a small PNG for docs/cloth.md, with matplotlib's 3D polygons and a
simple Lambert shading. Needs Debian's python3-matplotlib (and numpy); not needed by the tests.

    python3 benches/plot_cloth.py FINAL.obj OUT.png [--title TEXT] [--elev DEG] [--azim DEG]
                                  [--size W H] [--dpi D]

The view is fitted to the cloth (the ground quad is clipped to it)."""
import argparse
import sys

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402


def read_obj(path):
    """Returns {object name: (V (n x 3), F (m x 3, 0-based, global indices into V_all))}, V_all."""
    verts, objects, name = [], {}, "default"
    with open(path) as f:
        for line in f:
            p = line.split()
            if not p:
                continue
            if p[0] == "o":
                name = p[1] if len(p) > 1 else "unnamed"
                objects.setdefault(name, [])
            elif p[0] == "v":
                verts.append([float(x) for x in p[1:4]])
            elif p[0] == "f":
                objects.setdefault(name, []).append([int(x.split("/")[0]) - 1 for x in p[1:4]])
    return np.array(verts), {k: np.array(v, dtype=int).reshape(-1, 3) for k, v in objects.items()}


def shade(tris, base, light=np.array([0.4, -0.5, 0.8])):
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
    lam = np.abs(n @ (light / np.linalg.norm(light)))  # two-sided: cloth has no outside
    c = np.outer(0.35 + 0.65 * lam, np.array(base))
    return np.clip(c, 0, 1)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("obj")
    ap.add_argument("png")
    ap.add_argument("--title", default="")
    ap.add_argument("--elev", type=float, default=28)
    ap.add_argument("--azim", type=float, default=-60)
    ap.add_argument("--size", type=float, nargs=2, default=[4.0, 3.2])
    ap.add_argument("--dpi", type=int, default=90)
    a = ap.parse_args()

    V, objects = read_obj(a.obj)
    cloth = [k for k in objects if k.startswith("cloth")]
    if not cloth:
        sys.exit("plot_cloth.py: no object named cloth... in " + a.obj)
    cv = V[np.unique(np.concatenate([objects[k].ravel() for k in cloth]))]
    lo, hi = cv.min(axis=0), cv.max(axis=0)
    centre, half = (lo + hi) / 2, max((hi - lo).max() / 2, 1e-3) * 1.1

    fig = plt.figure(figsize=a.size, dpi=a.dpi)
    ax = fig.add_subplot(111, projection="3d")
    palette = [(0.85, 0.35, 0.25), (0.25, 0.45, 0.85), (0.3, 0.7, 0.35), (0.85, 0.7, 0.2)]
    # One collection for everything, so that matplotlib sorts the triangles by depth one by one.
    all_tris, all_colors = [], []
    for name, F in objects.items():
        if len(F) == 0:
            continue
        tris = V[F]
        if name.startswith("cloth"):
            base = palette[cloth.index(name) % len(palette)]
        else:
            base = (0.72, 0.72, 0.75)
            if name == "ground":  # the big quad, as small tiles of the view's square at its height
                z = tris[:, :, 2].mean()
                k = 16
                g = np.linspace(-half, half, k + 1)
                tiles = []
                for i in range(k):
                    for j in range(k):
                        x0, x1, y0, y1 = centre[0] + g[i], centre[0] + g[i + 1], centre[1] + g[j], centre[1] + g[j + 1]
                        tiles.append([[x0, y0, z], [x1, y0, z], [x1, y1, z]])
                        tiles.append([[x0, y0, z], [x1, y1, z], [x0, y1, z]])
                tris = np.array(tiles)
                base = (0.82, 0.82, 0.8)
            else:  # keep only obstacle triangles near the cloth
                keep = np.all(np.abs(tris.mean(axis=1) - centre) < 1.5 * half, axis=1)
                tris = tris[keep]
        if len(tris) == 0:
            continue
        all_tris.append(tris)
        all_colors.append(shade(tris, base))
    colors = np.concatenate(all_colors)  # edges in the face colour hide the anti-aliasing seams
    pc = Poly3DCollection(np.concatenate(all_tris), facecolors=colors, edgecolors=colors, linewidths=0.3)
    ax.add_collection3d(pc)
    for d, set_lim in enumerate((ax.set_xlim, ax.set_ylim, ax.set_zlim)):
        set_lim(centre[d] - half, centre[d] + half)
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=a.elev, azim=a.azim)
    ax.set_axis_off()
    if a.title:
        ax.set_title(a.title, fontsize=9)
    fig.subplots_adjust(left=0, right=1, bottom=0, top=0.93 if a.title else 1)
    fig.savefig(a.png, dpi=a.dpi)


if __name__ == "__main__":
    main()
