#!/usr/bin/env python3
"""The URDF corpus measurement: every URDF of example-robot-data (and of
pybullet_data when `pybullet` is installed) through twinloop and Pinocchio.

Run from the repository root after `cargo build -p twinloop-cli`:

    pip install example-robot-data pin     # pybullet optional
    python3 tools/oracle/urdf_corpus.py [--twinloop target/debug/twinloop]

For every file Pinocchio loads (free-flyer root, mimic joints independent),
twinloop must load it for dynamics (`model info --joints`) or refuse it with a
message; for the loaded ones it compares the number of joint DoFs, the total
mass, and at three seeded random states (base pose, joint angles in [-1.5, 1.5],
v, a, tau standard normal) the centre of mass (`dynamics kinematics`), RNEA
(`dynamics inverse`: base wrench and joint torques) and ABA (`dynamics forward`:
base and joint accelerations), matched by joint name, each to 1e-12 relative to
the largest entry of Pinocchio's vector (files that agree only to 1e-9 are
named). Files with a joint of more than one DoF below the root (URDF `floating`
or `planar`) are skipped, as are those Pinocchio refuses; the summary counts
each reason. Prints one line per disagreement or refusal and a summary. This is a measurement for docs/mjcf.md, not a test: the corpus is not
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

# Agreement: every quantity to STRICT relative (the baseline was
# 1e-13); files within TOL only are counted and named apart.
STRICT = 1e-12
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


SEEDS = 3


def pin_state(model, rng):
    """A random state in Pinocchio's coordinates: base position and unit
    quaternion, each joint position uniform in [-1.5, 1.5] cut to its limits
    (twinloop refuses a row beyond them; a continuous joint as cos, sin), v, a, tau standard normal. None if a joint below the root has
    nv != 1 (twinloop's URDF joints with more DoFs are compared elsewhere)."""
    q = pin.neutral(model)
    q[0:3] = rng.uniform(-1.0, 1.0, 3)
    quat = rng.normal(size=4)
    q[3:7] = quat / np.linalg.norm(quat)
    angles = {}
    for j in range(2, model.njoints):
        jm = model.joints[j]
        if jm.nv != 1:
            return None
        lo, hi = -1.5, 1.5
        if jm.nq == 1:
            lim = (model.lowerPositionLimit[jm.idx_q], model.upperPositionLimit[jm.idx_q])
            if np.isfinite(lim).all() and lim[0] < lim[1]:
                lo, hi = max(lo, lim[0]), min(hi, lim[1])
                if lo >= hi:
                    lo, hi = lim
        th = rng.uniform(lo, hi)
        angles[model.names[j]] = th
        if jm.nq == 1:
            q[jm.idx_q] = th
        else:  # continuous: (cos, sin)
            q[jm.idx_q:jm.idx_q + 2] = [np.cos(th), np.sin(th)]
    v, a, tau = (rng.normal(size=model.nv) for _ in range(3))
    return q, angles, v, a, tau


BASE_V = ["vx", "vy", "vz", "wx", "wy", "wz"]
BASE_F = ["fx", "fy", "fz", "tx", "ty", "tz"]


def rel_err(ours: np.ndarray, theirs: np.ndarray) -> float:
    """Largest difference relative to the largest entry of the reference."""
    return float(np.max(np.abs(ours - theirs)) / max(np.max(np.abs(theirs)), 1e-300))


def check(exe: str, path: str, tmp: str) -> tuple[str, str, dict]:
    """('agree' | 'refused' | 'differs' | 'skipped', detail, {quantity: relative error})."""
    # urdfdom says why it refuses a file on the process's stderr: keep its first line.
    saved = os.dup(2)
    with tempfile.TemporaryFile(mode="w+") as err:
        os.dup2(err.fileno(), 2)
        try:
            model = pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer(), mimic=False)
        except Exception:  # noqa: BLE001 -- Pinocchio itself refuses: not part of the corpus
            model = None
        finally:
            os.dup2(saved, 2)
            os.close(saved)
        err.seek(0)
        why = next((line.split("Error:", 1)[1].strip() for line in err if "Error:" in line), "")
    if model is None:
        return "skipped", f"Pinocchio refuses ({os.path.basename(path)}: {why})", {}
    info = twinloop(exe, "model", "info", "--joints", "--json", "-", path)
    if info.returncode != 0:
        return "refused", info.stderr.strip().splitlines()[0] if info.stderr.strip() else "no message", {}
    d = json.loads(info.stdout)
    dof = model.nv - 6
    if d["dof"] != dof:
        return "differs", f"dof {d['dof']} vs Pinocchio {dof}", {}
    data = model.createData()
    mass = sum(i.mass for i in model.inertias)
    errs = {"mass": abs(d["total_mass"] - mass) / max(mass, 1e-300)}
    rng = np.random.default_rng(20250611)
    states = [pin_state(model, rng) for _ in range(SEEDS)]
    if states[0] is None:
        kinds = sorted({model.joints[j].shortname() for j in range(2, model.njoints) if model.joints[j].nv != 1})
        return "skipped", f"a joint with nv != 1 ({', '.join(kinds)})", {}
    joints = [model.names[j] for j in range(2, model.njoints)]
    idx_v = {model.names[j]: model.joints[j].idx_v for j in range(2, model.njoints)}
    qcols = [f"q:base.{k}" for k in ["x", "y", "z", "qx", "qy", "qz", "qw"]] + [f"q:{n}" for n in joints]
    vcols = [f"v:base.{k}" for k in BASE_V] + [f"v:{n}" for n in joints]
    acols = [f"a:base.{k}" for k in BASE_V] + [f"a:{n}" for n in joints]
    tcols = [f"tau:base.{k}" for k in BASE_F] + [f"tau:{n}" for n in joints]
    order = list(range(6)) + [idx_v[n] for n in joints]  # our columns in Pinocchio's v
    rows = []
    want = {"com": [], "rnea": [], "aba": []}
    for q, angles, v, a, tau in states:
        qv = list(q[0:7]) + [angles[n] for n in joints]
        rows.append([0.0] + qv + list(v[order]) + list(a[order]) + list(tau[order]))
        want["com"].append(pin.centerOfMass(model, data, q).copy())
        want["rnea"].append(pin.rnea(model, data, q, v, a)[order].copy())
        want["aba"].append(pin.aba(model, data, q, v, tau)[order].copy())
    csv_in = os.path.join(tmp, "in.csv")
    with open(csv_in, "w") as f:
        f.write(",".join(["t"] + qcols + vcols + acols + tcols) + "\n")
        for r in rows:
            f.write(",".join(repr(float(x)) for x in r) + "\n")
    got = {}
    singular = None
    for what, cmd, cols in [("com", "kinematics", ["com.x", "com.y", "com.z"]),
                            ("rnea", "inverse", tcols), ("aba", "forward", acols)]:
        out = os.path.join(tmp, f"{what}.csv")
        extra = ["--frames", d["root_link"]] if cmd == "kinematics" else []
        run = twinloop(exe, "dynamics", cmd, "--robot", path, "--trajectory", csv_in, "--out", out, *extra)
        if run.returncode != 0:
            msg = run.stderr.strip().splitlines()[0] if run.stderr.strip() else "no message"
            if cmd == "forward" and "mass matrix is singular" in msg:
                singular = msg[msg.find("the mass matrix is singular"):][:90]
                continue
            return "refused", f"dynamics {cmd}: {msg}", errs
        with open(out) as f:
            header = f.readline().strip().split(",")
            table = [dict(zip(header, map(float, line.strip().split(",")))) for line in f if line.strip()]
        missing = [c for c in cols if c not in header]
        if missing:
            return "differs", f"dynamics {cmd} has no {missing[0]}", errs
        got[what] = [np.array([row[c] for c in cols]) for row in table]
    for what in ("com", "rnea"):
        errs[what] = max(rel_err(o, w) for o, w in zip(got[what], want[what]))
    # Pinocchio's mass matrix at each state: how well ABA's answer is defined.
    ratio = 1.0
    for q, _, _, _, _ in states:
        m = pin.crba(model, data, q)
        m = np.triu(m) + np.triu(m, 1).T
        e = np.linalg.eigvalsh(m)
        ratio = min(ratio, e[0] / e[-1] if e[-1] > 0 else 0.0)
    if singular is not None:
        # twinloop refuses ABA on a singular mass matrix: right if Pinocchio's is.
        if ratio > 1e-12:
            return "refused", f"dynamics forward: {singular} but Pinocchio's M has eigenvalue ratio {ratio:.1e}", errs
        errs["singular"] = ratio
    else:
        errs["aba"] = max(rel_err(o, w) for o, w in zip(got["aba"], want["aba"]))
        # ABA's normwise backward error: Pinocchio's RNEA of twinloop's
        # accelerations against the torques, |M a + b - tau| / (|M| |a| + |tau|),
        # what is left of the forward error once M's conditioning is taken out.
        back = 0.0
        for (q, _, v, _, tau), ours in zip(states, got["aba"]):
            acc = np.zeros(model.nv)
            acc[order] = ours
            m = pin.crba(model, data, q)
            m = np.triu(m) + np.triu(m, 1).T
            scale = np.linalg.norm(m, np.inf) * np.max(np.abs(acc)) + np.max(np.abs(tau))
            back = max(back, float(np.max(np.abs(pin.rnea(model, data, q, v, acc) - tau)) / scale))
        errs["aba_backward"] = back
        if errs["aba"] > STRICT and back <= STRICT:
            # The forward error is the conditioning's: report it, judge the backward one.
            errs["aba_conditioning"] = 1.0 / max(ratio, 1e-300)
            errs["aba"] = back
    judged = {k: e for k, e in errs.items() if k in ("mass", "com", "rnea", "aba")}
    worst = max(judged, key=judged.get)
    if judged[worst] > TOL:
        return "differs", f"{worst} relative error {judged[worst]:.1e}", errs
    return "agree", "", errs


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--twinloop", default=os.path.join(os.environ.get("CARGO_TARGET_DIR", "target"), "debug", "twinloop"))
    exe = ap.parse_args().twinloop
    counts = {"agree": 0, "refused": 0, "differs": 0, "skipped": 0}
    skipped: dict[str, int] = {}
    skipped_files: list[str] = []
    worst: dict[str, float] = {}
    loose = singular = conditioned = 0
    with tempfile.TemporaryDirectory() as tmp:
        for path in corpus():
            verdict, detail, errs = check(exe, path, tmp)
            counts[verdict] += 1
            judged = {k: e for k, e in errs.items() if k in ("mass", "com", "rnea", "aba")}
            for k, e in errs.items():
                if k != "singular":
                    worst[k] = max(worst.get(k, 0.0), e)
            if verdict == "agree":
                singular += "singular" in errs
                if "aba_conditioning" in errs:
                    conditioned += 1
                    print(f"ABA to its conditioning: {path}: condition number {errs['aba_conditioning']:.1e}, "
                          f"backward error {errs['aba_backward']:.1e}")
                if max(judged.values()) > STRICT:
                    loose += 1
                    print(f"agree to {TOL:.0e} only: {path}: " + ", ".join(f"{k} {e:.1e}" for k, e in errs.items()))
            if verdict == "skipped":
                why = "Pinocchio refuses" if detail.startswith("Pinocchio") else detail
                skipped_files.append(detail)
                skipped[why] = skipped.get(why, 0) + 1
            if verdict not in ("agree", "skipped"):
                print(f"{verdict}: {path}: {detail}")
    n = counts["agree"] + counts["refused"] + counts["differs"]
    print(
        f"{n} URDFs compared: {counts['agree']} agree ({100 * counts['agree'] / max(n, 1):.1f} %; "
        f"{counts['agree'] - loose} to {STRICT:.0e}, {loose} only to {TOL:.0e}), "
        f"{counts['refused']} refused, {counts['differs']} differ"
    )
    print(f"of those that agree: {singular} with a singular mass matrix (Pinocchio's too: smallest/largest "
          f"eigenvalue below 1e-12), where twinloop refuses ABA and CoM and RNEA are compared; "
          f"{conditioned} whose ABA is judged by its backward error (ill-conditioned M)")
    print("largest relative error over the compared files: " + ", ".join(f"{k} {e:.1e}" for k, e in worst.items()))
    print(f"{counts['skipped']} skipped: " + "; ".join(f"{k}: {v}" for k, v in sorted(skipped.items())))
    for f in skipped_files:
        print(f"  {f}")


if __name__ == "__main__":
    main()
