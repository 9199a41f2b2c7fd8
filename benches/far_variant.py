#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Writes an OFF mesh moved far from the origin, as OBJ, for the benches' far-from-origin runs.

    python3 benches/far_variant.py MESH.off OUT.obj [FACTOR]

Each coordinate is first rounded to single precision (impact::load_mesh reads through assimp's
float), then moved by FACTOR * (1, -1/2, 1/4) times the mesh's bounding-box diagonal (default
FACTOR 1e6, the "knight-far" variant of docs/particles.md), in double, and written with 17
significant digits. Standard library only."""
import math
import struct
import sys


def f32(x):
    return struct.unpack("f", struct.pack("f", x))[0]


def main():
    if len(sys.argv) not in (3, 4):
        sys.exit(__doc__)
    factor = float(sys.argv[3]) if len(sys.argv) == 4 else 1e6
    words = open(sys.argv[1]).read().split()
    if not words or words[0] != "OFF":
        sys.exit("far_variant.py: not an OFF file: " + sys.argv[1])
    nv, nf = int(words[1]), int(words[2])
    at = 4
    verts = []
    for _ in range(nv):
        verts.append([f32(float(x)) for x in words[at:at + 3]])
        at += 3
    faces = []
    for _ in range(nf):
        n = int(words[at])
        faces.append([int(i) for i in words[at + 1:at + 1 + n]])
        at += 1 + n
    diag = math.sqrt(sum((max(v[k] for v in verts) - min(v[k] for v in verts)) ** 2 for k in range(3)))
    offset = (factor * diag, -0.5 * factor * diag, 0.25 * factor * diag)
    with open(sys.argv[2], "w") as out:
        for v in verts:
            out.write("v %r %r %r\n" % tuple(v[k] + offset[k] for k in range(3)))
        for f in faces:
            out.write("f " + " ".join(str(i + 1) for i in f) + "\n")


if __name__ == "__main__":
    main()
