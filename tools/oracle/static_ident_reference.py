#!/usr/bin/env python3
"""Independent reference for twinloop's static identification (seed 004, eq 8-9).

The same fit as `twinloop identify static`, written independently: Pinocchio
computes every link's world placement per pose (the CoM regressor's columns), and
scipy.optimize.least_squares solves the bounded problem in a different
parametrisation, (m, c) instead of (m, m c), with the mass equality as a heavily
weighted residual:

    minimise |A x(m, c) - b|^2 + lambda^2 |S^-1 (x(m, c) - x0)|^2 + w^2 (sum m - M_free)^2
    subject to m >= m_min, c_lo <= c <= c_hi                        (box bounds)

A x = sum over links of m_l p_l + R_l (m_l c_l), x and y rows per pose, b = M cop.
The definitions shared with twinloop (docs/static-identification.md): identified
links = links with mass > 0; prior scale of a mass = max(m, 0.01 M / L, 1e-3) and of
a first moment = that times the link size max(bbox extent, |c|, 0.05) where the
bbox covers the link's primitive collision shapes (visual if none: box corners,
16-point cylinder rims, sphere poles) and its prior CoM; CoM box = bbox -/+ margin;
m_min = max(0.01 m, 1e-6); lambda = max(M sigma_cop, 1e-7 sqrt(max diag((A S)^T A S))).

    pip install pin scipy numpy
    python3 tools/oracle/static_ident_reference.py --urdf models/unitree_h1/variants/h1_2025-06_a3b70ca.urdf \\
        --poses crates/twinloop-ident/tests/data/h1_poses.csv --total-mass 59.338 \\
        --out crates/twinloop-ident/tests/data/h1_static_reference.json
    ... --bench 20      # time the fit (regressor + solve), median of 20 runs
"""
import argparse
import csv
import json
import math
import time
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import scipy
from scipy.optimize import least_squares


def rpy_matrix(rpy):
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def floats(s, n):
    v = [float(x) for x in s.split()]
    assert len(v) == n, s
    return v


def origin_of(el):
    o = el.find("origin")
    if o is None:
        return np.zeros(3), np.eye(3)
    xyz = floats(o.get("xyz", "0 0 0"), 3)
    rpy = floats(o.get("rpy", "0 0 0"), 3)
    return np.array(xyz), rpy_matrix(rpy)


def shape_points(shape):
    g = shape.find("geometry")
    if g is None or len(g) == 0:
        return []
    g = g[0]
    pts = []
    if g.tag == "box":
        h = np.array(floats(g.get("size"), 3)) / 2
        for sx in (-1, 1):
            for sy in (-1, 1):
                for sz in (-1, 1):
                    pts.append(np.array([sx * h[0], sy * h[1], sz * h[2]]))
    elif g.tag == "cylinder":
        r, l = float(g.get("radius")), float(g.get("length"))
        for k in range(16):
            a = 2 * math.pi * k / 16
            for z in (-l / 2, l / 2):
                pts.append(np.array([r * math.cos(a), r * math.sin(a), z]))
    elif g.tag == "sphere":
        r = float(g.get("radius"))
        for k in range(3):
            for s in (-1, 1):
                p = np.zeros(3)
                p[k] = s * r
                pts.append(p)
    else:
        return []
    t, rot = origin_of(shape)
    return [rot @ p + t for p in pts]


def links_of(urdf):
    root = ET.parse(urdf).getroot()
    out = []
    for link in root.findall("link"):
        inertial = link.find("inertial")
        if inertial is None:
            continue
        m = float(inertial.find("mass").get("value"))
        if m <= 0:
            continue
        c, _ = origin_of(inertial)
        pts = [p for s in link.findall("collision") for p in shape_points(s)]
        if not pts:
            pts = [p for s in link.findall("visual") for p in shape_points(s)]
        out.append({"name": link.get("name"), "m": m, "c": c, "pts": pts})
    return out


def read_poses(path, model):
    with open(path) as f:
        rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
    head = rows[0]
    col = {h: i for i, h in enumerate(head)}
    qs, cops = [], []
    base = ["base.x", "base.y", "base.z", "base.qx", "base.qy", "base.qz", "base.qw"]
    for r in rows[1:]:
        v = [float(x) for x in r]
        q = np.zeros(model.nq)
        q[0:7] = [v[col["q:" + b]] for b in base]
        for jid in range(2, model.njoints):
            name = model.names[jid]
            q[model.joints[jid].idx_q] = v[col["q:" + name]]
        qs.append(q)
        cops.append([v[col["cop.x"]], v[col["cop.y"]]])
    return qs, np.array(cops)


def regressor(model, data, frames, qs):
    """Rows x, y per pose; columns (m, h_x, h_y, h_z) per identified link."""
    a = np.zeros((2 * len(qs), 4 * len(frames)))
    for n, q in enumerate(qs):
        pin.framesForwardKinematics(model, data, q)
        for k, fid in enumerate(frames):
            x = data.oMf[fid]
            for r in range(2):
                a[2 * n + r, 4 * k] = x.translation[r]
                a[2 * n + r, 4 * k + 1 : 4 * k + 4] = x.rotation[r, :]
    return a


def fit(model, data, links, frames, qs, cops, total, cop_sigma, margin):
    L = len(links)
    a = regressor(model, data, frames, qs)
    b = (total * cops).reshape(-1)
    x0 = np.concatenate([[l["m"], *(l["m"] * l["c"])] for l in links])
    scale, lo, hi, mmin = [], [], [], []
    for l in links:
        sm = max(l["m"], 0.01 * total / L, 1e-3)
        pts = l["pts"] + [l["c"]]
        blo = np.min(pts, axis=0)
        bhi = np.max(pts, axis=0)
        size = max(np.max(bhi - blo), np.linalg.norm(l["c"]), 0.05)
        scale += [sm, sm * size, sm * size, sm * size]
        lo.append(blo - margin)
        hi.append(bhi + margin)
        mmin.append(max(0.01 * l["m"], 1e-6))
    scale = np.array(scale)
    a_s = a * scale
    gram = a_s.T @ a_s
    lam = max(total * cop_sigma, 1e-7 * math.sqrt(np.max(np.diag(gram))))
    m_free = total  # every link with mass is identified: none is kept fixed
    w = 1e4 * math.sqrt(np.max(np.diag(gram))) / max(scale[0::4])

    def params(y):
        x = np.empty(4 * L)
        for k in range(L):
            m = y[4 * k]
            x[4 * k] = m
            x[4 * k + 1 : 4 * k + 4] = m * y[4 * k + 1 : 4 * k + 4]
        return x

    def residual(y):
        x = params(y)
        return np.concatenate([a @ x - b, lam * (x - x0) / scale, [w * (np.sum(y[0::4]) - m_free)]])

    def jacobian(y):
        # d x / d y: x = (m, m c) per link.
        dx = np.zeros((4 * L, 4 * L))
        for k in range(L):
            m, c = y[4 * k], y[4 * k + 1 : 4 * k + 4]
            dx[4 * k, 4 * k] = 1.0
            dx[4 * k + 1 : 4 * k + 4, 4 * k] = c
            dx[4 * k + 1 : 4 * k + 4, 4 * k + 1 : 4 * k + 4] = m * np.eye(3)
        eq = np.zeros((1, 4 * L))
        eq[0, 0::4] = w
        return np.vstack([a @ dx, (lam / scale)[:, None] * dx, eq])

    k0 = m_free / np.sum(x0[0::4])
    y0 = np.concatenate([[k0 * l["m"], *l["c"]] for l in links])
    lb = np.concatenate([[mmin[k], *lo[k]] for k in range(L)])
    ub = np.concatenate([[np.inf, *hi[k]] for k in range(L)])
    y0 = np.clip(y0, lb, ub)
    sol = least_squares(
        residual, y0, jac=jacobian, bounds=(lb, ub), method="trf", x_scale="jac",
        ftol=1e-15, xtol=1e-15, gtol=1e-15, max_nfev=10000,
    )
    return sol, params(sol.x), lam


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--urdf", required=True)
    ap.add_argument("--poses", required=True)
    ap.add_argument("--total-mass", type=float, required=True)
    ap.add_argument("--cop-sigma", type=float, default=0.001)
    ap.add_argument("--com-margin", type=float, default=0.03)
    ap.add_argument("--out")
    ap.add_argument("--bench", type=int, default=0, help="repeat the fit N times and print the median time (s)")
    args = ap.parse_args()
    # A URDF with its own floating root joint (COMAN) gets no extra free flyer.
    root = ET.parse(args.urdf).getroot()
    if any(j.get("type") == "floating" for j in root.findall("joint")):
        model = pin.buildModelFromUrdf(args.urdf)
    else:
        model = pin.buildModelFromUrdf(args.urdf, pin.JointModelFreeFlyer())
    data = model.createData()
    links = links_of(args.urdf)
    frames = [model.getFrameId(l["name"], pin.BODY) for l in links]
    qs, cops = read_poses(args.poses, model)
    sol, x, lam = fit(model, data, links, frames, qs, cops, args.total_mass, args.cop_sigma, args.com_margin)
    result = {
        "schema": "twinloop-static-reference/1",
        "generator": "tools/oracle/static_ident_reference.py",
        "pinocchio_version": pin.__version__,
        "scipy_version": scipy.__version__,
        "urdf": args.urdf,
        "poses": args.poses,
        "total_mass": args.total_mass,
        "cop_sigma": args.cop_sigma,
        "com_margin": args.com_margin,
        "lambda": lam,
        "least_squares": {"status": int(sol.status), "nfev": int(sol.nfev), "cost": float(sol.cost)},
        "links": [
            {"name": l["name"], "mass": float(x[4 * k]), "com": [float(v) for v in x[4 * k + 1 : 4 * k + 4] / x[4 * k]]}
            for k, l in enumerate(links)
        ],
    }
    if args.bench:
        times = []
        for _ in range(args.bench):
            t0 = time.perf_counter()
            fit(model, data, links, frames, qs, cops, args.total_mass, args.cop_sigma, args.com_margin)
            times.append(time.perf_counter() - t0)
        times.sort()
        result["fit_seconds_median"] = times[len(times) // 2]
        print(json.dumps({"fit_seconds_median": times[len(times) // 2], "links": len(links), "poses": len(qs)}))
    if args.out:
        with open(args.out, "w") as f:
            json.dump(result, f, indent=1)
            f.write("\n")
        print(f"wrote {args.out}")
    elif not args.bench:
        print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
