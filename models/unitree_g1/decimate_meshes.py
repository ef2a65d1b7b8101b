"""Decimate the G1 visual meshes for the viewer's browser test: the upstream STL files
(meshes/, 19 MB, not in this repository) reduced by vertex clustering (Rossignac and
Borrel 1993: snap every vertex to a CELL-metre grid, merge those in one cell at their
mean, drop the triangles that collapse), written as binary STL to meshes_decimated/,
and g1_29dof_rev_1_0.decimated.urdf pointing at them.

    python3 models/unitree_g1/decimate_meshes.py UPSTREAM_DIR

UPSTREAM_DIR holds g1_29dof_rev_1_0.urdf and meshes/ as in unitreerobotics/unitree_ros
robots/g1_description (see SOURCE.md). The silhouette moves by at most a cell.
"""
import os
import re
import struct
import sys

import numpy as np

CELL = 0.01

here = os.path.dirname(os.path.abspath(__file__))


def read_stl(path):
    data = open(path, "rb").read()
    n = struct.unpack_from("<I", data, 80)[0]
    if 84 + 50 * n == len(data):
        rec = np.frombuffer(data, dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]), count=n, offset=84)
        return rec["v"].astype(np.float64).reshape(-1, 3)
    # ASCII
    v = re.findall(rb"vertex\s+(\S+)\s+(\S+)\s+(\S+)", data)
    return np.array(v, dtype=np.float64)


def decimate(corners):
    keys = np.floor(corners / CELL).astype(np.int64)
    uniq, inverse = np.unique(keys, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    sums = np.zeros((len(uniq), 3))
    np.add.at(sums, inverse, corners)
    counts = np.bincount(inverse, minlength=len(uniq))[:, None]
    verts = sums / counts
    tris = inverse.reshape(-1, 3)
    keep = (tris[:, 0] != tris[:, 1]) & (tris[:, 1] != tris[:, 2]) & (tris[:, 0] != tris[:, 2])
    tris = tris[keep]
    tris = np.unique(np.sort(tris, axis=1), axis=0, return_index=True)[1]
    return verts, inverse.reshape(-1, 3)[keep][np.sort(tris)]


def write_stl(path, verts, tris):
    p = verts[tris]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    with open(path, "wb") as f:
        f.write(b"twinloop: decimated by vertex clustering".ljust(80, b" "))
        f.write(struct.pack("<I", len(tris)))
        for k in range(len(tris)):
            f.write(struct.pack("<12fH", *n[k], *p[k].reshape(-1), 0))


def main():
    upstream = sys.argv[1]
    urdf = open(os.path.join(upstream, "g1_29dof_rev_1_0.urdf")).read()
    before = after = 0
    for name in sorted(set(re.findall(r'filename="meshes/([^"]+)"', urdf))):
        corners = read_stl(os.path.join(upstream, "meshes", name))
        verts, tris = decimate(corners)
        write_stl(os.path.join(here, "meshes_decimated", name), verts, tris)
        before += len(corners) // 3
        after += len(tris)
    out = urdf.replace('filename="meshes/', 'filename="meshes_decimated/')
    out = out.replace("<robot", "<!-- g1_29dof_rev_1_0.urdf with its meshes decimated by decimate_meshes.py -->\n<robot", 1)
    open(os.path.join(here, "g1_29dof_rev_1_0.decimated.urdf"), "w").write(out)
    print("%d triangles -> %d" % (before, after))


if __name__ == "__main__":
    main()
