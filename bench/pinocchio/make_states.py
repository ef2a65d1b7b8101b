#!/usr/bin/env python3
"""Random robot states in the twinloop trajectory CSV format, for both benchmarks.

    python3 bench/pinocchio/make_states.py MODEL_FILE OUT.csv [--count 1000] [--seed 0]

MODEL_FILE is a URDF (.urdf) or MJCF (.xml). The model is loaded with Pinocchio using the same
floating-base rule as bench_pinocchio (free-flyer root unless the file has its own floating root);
the floating root is written as "base". Columns, in this order:

    t
    q:base.x q:base.y q:base.z q:base.qx q:base.qy q:base.qz q:base.qw
    q:<joint>            one per 1-DoF joint, Pinocchio joint order (angle in rad / position in m)
    v:base.vx v:base.vy v:base.vz v:base.wx v:base.wy v:base.wz   (base frame, linear then angular)
    v:<joint> ...
    a:base.vx ... a:base.wz, a:<joint> ...                        (same names as v)
    tau:base.fx tau:base.fy tau:base.fz tau:base.tx tau:base.ty tau:base.tz, tau:<joint> ...

Values: base position uniform in [-1, 1]^3, base orientation a random unit quaternion (4 normals,
normalised; x, y, z, w), joint positions uniform in [-1.5, 1.5] within the joint limits, v, a, tau
standard normal; drawn per state in that order from numpy.random.default_rng(seed). Continuous
joints are written as an angle (the bench maps it to Pinocchio's cos/sin pair). Floats are
written with repr (shortest string that round-trips), t = state index * 0.001.
"""

from __future__ import annotations

import argparse
import csv
import os
import sys

import numpy as np
import pinocchio as pin


def load_model(path: str):
    ext = os.path.splitext(path)[1].lower()
    if ext == ".urdf":
        model = pin.buildModelFromUrdf(path, mimic=False)
        if not _ff_root(model):
            model = pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer(), mimic=False)
    elif ext == ".xml":
        model = pin.buildModelFromMJCF(path)
        if not _ff_root(model):
            model = pin.buildModelFromMJCF(path, pin.JointModelFreeFlyer(), "root_joint")
            if isinstance(model, tuple):
                model = model[0]
    else:
        sys.exit(f"make_states: model file must end in .urdf or .xml: {path}")
    if not _ff_root(model):
        sys.exit(f"make_states: no floating root after loading {path}")
    return model


def _ff_root(model) -> bool:
    return (model.njoints > 1 and model.parents[1] == 0
            and model.joints[1].shortname() == "JointModelFreeFlyer")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("model")
    ap.add_argument("out")
    ap.add_argument("--count", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)

    model = load_model(args.model)
    joints = []  # (name, kind) for non-root joints
    for j in range(2, model.njoints):
        jm = model.joints[j]
        if jm.nv != 1 or jm.nq not in (1, 2):
            sys.exit(f"make_states: joint {model.names[j]} ({jm.shortname()}) is not 1-DoF")
        joints.append(model.names[j])
    names = [n for n in joints]
    # Joint positions stay within the model's limits (twinloop refuses states beyond
    # them since issue 29): uniform over [-1.5, 1.5] intersected with the limits.
    idx = [model.joints[model.getJointId(n)].idx_q for n in names]
    lo = np.maximum(-1.5, np.array([model.lowerPositionLimit[i] for i in idx]))
    hi = np.minimum(1.5, np.array([model.upperPositionLimit[i] for i in idx]))

    header = ["t"]
    header += [f"q:base.{c}" for c in ("x", "y", "z", "qx", "qy", "qz", "qw")]
    header += [f"q:{n}" for n in names]
    for p in ("v", "a"):
        header += [f"{p}:base.{c}" for c in ("vx", "vy", "vz", "wx", "wy", "wz")]
        header += [f"{p}:{n}" for n in names]
    header += [f"tau:base.{c}" for c in ("fx", "fy", "fz", "tx", "ty", "tz")]
    header += [f"tau:{n}" for n in names]

    rng = np.random.default_rng(args.seed)
    nj, nv = len(names), model.nv
    with open(args.out, "w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(header)
        for k in range(args.count):
            pos = rng.uniform(-1.0, 1.0, 3)
            quat = rng.standard_normal(4)
            quat /= np.linalg.norm(quat)
            qj = rng.uniform(lo, hi, nj)
            v = rng.standard_normal(nv)
            a = rng.standard_normal(nv)
            tau = rng.standard_normal(nv)
            row = [repr(k * 0.001)]
            row += [repr(float(x)) for x in np.concatenate([pos, quat, qj, v, a, tau])]
            w.writerow(row)
    print(f"wrote {args.count} states of {os.path.basename(args.model)} (nv={nv}, "
          f"{nj} joints + base) to {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
