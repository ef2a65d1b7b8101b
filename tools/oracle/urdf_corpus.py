#!/usr/bin/env python3
"""The URDF corpus measurement: every URDF of example-robot-data (and of
pybullet_data when `pybullet` is installed) through twinloop and Pinocchio.

Run from the repository root after `cargo build -p twinloop-cli`:

    pip install example-robot-data pin     # pybullet optional
    python3 tools/oracle/urdf_corpus.py [--twinloop target/debug/twinloop]

For every file Pinocchio loads (free-flyer root, mimic joints independent),
twinloop must load it for dynamics (`model info --joints`) or refuse it with a
message; for the loaded ones it compares the number of joint DoFs, the total mass
(1e-9 relative) and the generalised gravity at the neutral configuration
(`dynamics inverse` on one row, matched by joint name; base wrench included; 1e-9
relative to the largest entry). Prints one line per disagreement or refusal and a
summary. This is a measurement for docs/mjcf.md, not a test: the corpus is not
committed (it is large and under its own licences).
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import subprocess
import tempfile

import numpy as np
import pinocchio as pin

TOL = 1e-9


def corpus() -> list[str]:
    files = []
    prefix = os.path.join(os.path.dirname(pin.__file__), "..", "..", "..", "..")
    for root in glob.glob(os.path.join(prefix, "**", "share", "example-robot-data"), recursive=True):
        files += glob.glob(os.path.join(root, "**", "*.urdf"), recursive=True)
    try:
        import pybullet_data

        files += glob.glob(os.path.join(pybullet_data.getDataPath(), "**", "*.urdf"), recursive=True)
    except ImportError:
        pass
    return sorted(set(os.path.realpath(f) for f in files))


def twinloop(exe: str, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([exe, *args], capture_output=True, text=True, timeout=120)


def pin_gravity(model) -> dict[str, float]:
    data = model.createData()
    q = pin.neutral(model)
    g = pin.computeGeneralizedGravity(model, data, q)
    out = {f"base.{k}": g[i] for i, k in enumerate(["fx", "fy", "fz", "tx", "ty", "tz"])}
    for j in range(2, model.njoints):
        if model.joints[j].nv == 1:
            out[model.names[j]] = g[model.joints[j].idx_v]
    return out


def check(exe: str, path: str, tmp: str) -> tuple[str, str]:
    """('agree' | 'refused' | 'differs' | 'skipped', detail)."""
    try:
        model = pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer(), mimic=False)
    except Exception as e:  # Pinocchio itself refuses: not part of the corpus
        return "skipped", f"Pinocchio: {str(e).splitlines()[0] if str(e) else type(e).__name__}"
    info = twinloop(exe, "model", "info", "--joints", "--json", "-", path)
    if info.returncode != 0:
        return "refused", info.stderr.strip().splitlines()[0] if info.stderr.strip() else "no message"
    d = json.loads(info.stdout)
    dof = model.nv - 6
    if d["dof"] != dof:
        return "differs", f"dof {d['dof']} vs Pinocchio {dof}"
    mass = sum(i.mass for i in model.inertias)
    if abs(d["total_mass"] - mass) > TOL * max(mass, 1.0):
        return "differs", f"mass {d['total_mass']} vs Pinocchio {mass}"
    header = d["state_header"].split(",")
    qcols = [c for c in header if c.startswith("q:")]
    row = {c: 0.0 for c in qcols}
    row["q:base.qw"] = 1.0
    vcols = ["v:" + c[2:] for c in qcols if c not in ("q:base.qx", "q:base.qy", "q:base.qz", "q:base.qw")]
    vcols = [c.replace("v:base.x", "v:base.vx").replace("v:base.y", "v:base.vy").replace("v:base.z", "v:base.vz") for c in vcols]
    vcols = vcols[:3] + ["v:base.wx", "v:base.wy", "v:base.wz"] + vcols[3:]
    acols = ["a:" + c[2:] for c in vcols]
    cols = ["t"] + qcols + vcols + acols
    values = [0.0] + [row[c] for c in qcols] + [0.0] * (len(vcols) + len(acols))
    csv_in = os.path.join(tmp, "in.csv")
    csv_out = os.path.join(tmp, "out.csv")
    with open(csv_in, "w") as f:
        f.write(",".join(cols) + "\n" + ",".join(repr(v) for v in values) + "\n")
    inv = twinloop(exe, "dynamics", "inverse", "--robot", path, "--trajectory", csv_in, "--out", csv_out)
    if inv.returncode != 0:
        return "refused", "dynamics inverse: " + inv.stderr.strip().splitlines()[0]
    with open(csv_out) as f:
        names = f.readline().strip().split(",")
        got = dict(zip(names, map(float, f.readline().strip().split(","))))
    want = pin_gravity(model)
    scale = max(1.0, max(abs(v) for v in want.values()))
    for name, w in want.items():
        ours = got.get(f"tau:{name}")
        if ours is None:
            return "differs", f"no tau:{name}"
        if abs(ours - w) > TOL * scale:
            return "differs", f"gravity tau:{name} {ours} vs Pinocchio {w}"
    return "agree", ""


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--twinloop", default=os.path.join(os.environ.get("CARGO_TARGET_DIR", "target"), "debug", "twinloop"))
    exe = ap.parse_args().twinloop
    counts = {"agree": 0, "refused": 0, "differs": 0, "skipped": 0}
    with tempfile.TemporaryDirectory() as tmp:
        for path in corpus():
            verdict, detail = check(exe, path, tmp)
            counts[verdict] += 1
            if verdict != "agree":
                print(f"{verdict}: {path}: {detail}")
    n = counts["agree"] + counts["refused"] + counts["differs"]
    print(
        f"{n} URDFs Pinocchio loads: {counts['agree']} agree ({100 * counts['agree'] / max(n, 1):.1f} %), "
        f"{counts['refused']} refused, {counts['differs']} differ; {counts['skipped']} skipped (Pinocchio refuses)"
    )


if __name__ == "__main__":
    main()
