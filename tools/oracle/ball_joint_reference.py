#!/usr/bin/env python3
"""Reference numbers for spherical (ball) joints, from Pinocchio and MuJoCo.

Run from the repository root:

    python3 tools/oracle/ball_joint_reference.py

Writes crates/twinloop-dynamics/tests/data/ball/<name>.xml (random MJCF trees
mixing ball, hinge and slide joints, several per body, with explicit inertials,
rotated bodies, joint anchors and armature) and <name>.json with, per seeded
random state:

* Pinocchio 4 (`buildModelFromMJCF`; a ball joint is JointModelSpherical, q a
  unit quaternion stored x, y, z, w, v the angular velocity in the child frame):
  rnea, the full mass matrix (crba, symmetrised), nonlinear effects, aba, the
  CoM and its Jacobian, every body's world-frame Jacobian (`getFrameJacobian`
  of its BODY frame, WORLD), `integrate(q, v dt)` and `difference(q, q2)`.
* MuJoCo (models without a free root, whose free-joint velocity convention
  differs): `mj_fullM` and `qfrc_bias`. MuJoCo stores a ball's quaternion as
  w, x, y, z; the JSON's `q` is Pinocchio's order (also twinloop's).

The script checks its own numbers before writing (tolerance 1e-9 relative):
Pinocchio's mass matrix and bias forces against MuJoCo's, M a + nle == rnea,
and rnea(q, v, aba(q, v, tau)) == tau. Deterministic (numpy default_rng).
Needs `pip install pin mujoco numpy`.
"""

from __future__ import annotations

import json
import os

import mujoco
import numpy as np
import pinocchio as pin

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
OUT_DIR = os.path.join(REPO, "crates", "twinloop-dynamics", "tests", "data", "ball")
SEED = 20261125
MODELS = 8
FREE_ROOT = {6, 7}
STATES = 3
DT = 0.05
TOL = 1e-9


def unit_quat(rng) -> np.ndarray:
    g = rng.normal(size=4)
    return g / np.linalg.norm(g)


def fmt(x) -> str:
    return " ".join(f"{float(v):.17g}" for v in np.atleast_1d(x))


def rotation_wxyz(q) -> np.ndarray:
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def inertial(rng) -> str:
    """An <inertial> with a full, physical inertia tensor (moments in [0.05, 0.1])."""
    moments = rng.uniform(0.05, 0.1, size=3)
    r = rotation_wxyz(unit_quat(rng))
    i = r @ np.diag(moments) @ r.T
    full = [i[0, 0], i[1, 1], i[2, 2], i[0, 1], i[0, 2], i[1, 2]]
    return (
        f'<inertial pos="{fmt(rng.uniform(-0.1, 0.1, 3))}" mass="{rng.uniform(0.5, 3.0):.17g}" '
        f'fullinertia="{fmt(full)}"/>'
    )


def joints(rng, body: int, first_ball: bool) -> list[str]:
    out = []
    n = int(rng.integers(1, 4))
    dofs = 0
    for k in range(n):
        kind = "ball" if (first_ball and k == 0) else rng.choice(["ball", "hinge", "slide"], p=[0.4, 0.4, 0.2])
        if any('"ball"' in j for j in out):
            kind = "slide"  # MuJoCo refuses a rotation after a ball in one body
        dofs += 3 if kind == "ball" else 1
        if dofs > 6:  # MuJoCo's limit per body
            break
        attrs = [f'name="b{body}_j{k}"', f'type="{kind}"']
        if kind != "slide":
            attrs.append(f'pos="{fmt(rng.uniform(-0.1, 0.1, 3))}"')
        if kind != "ball":
            axis = rng.normal(size=3) if rng.uniform() < 0.5 else np.eye(3)[rng.integers(3)]
            attrs.append(f'axis="{fmt(axis / np.linalg.norm(axis))}"')
        if rng.uniform() < 0.5:
            attrs.append(f'armature="{rng.uniform(0.0, 0.05):.17g}"')
        out.append(f"<joint {' '.join(attrs)}/>")
    return out


def make_mjcf(rng, free_root: bool) -> str:
    nbodies = int(rng.integers(3, 7))
    parents = [-1] + [int(rng.integers(0, b)) for b in range(1, nbodies)]
    children: dict[int, list[int]] = {b: [] for b in range(-1, nbodies)}
    for b, p in enumerate(parents):
        children[p].append(b)

    def body(b: int, depth: int) -> list[str]:
        pad = "  " * depth
        pos = fmt(rng.uniform(-0.3, 0.3, 3))
        quat = fmt(unit_quat(rng))
        if b == 0 and free_root:
            # Pinocchio's MJCF reader turns a free body's pos into a joint placement
            # that MuJoCo (and twinloop) treat as qpos0 only: keep it at the origin.
            pos, quat = "0 0 0", "1 0 0 0"
        lines = [f'{pad}<body name="body{b}" pos="{pos}" quat="{quat}">']
        if b == 0 and free_root:
            lines.append(f'{pad}  <freejoint name="root"/>')
        else:
            lines += [f"{pad}  {j}" for j in joints(rng, b, b == 0)]
        lines.append(f"{pad}  {inertial(rng)}")
        for c in children[b]:
            lines += body(c, depth + 1)
        lines.append(f"{pad}</body>")
        return lines

    lines = ['<mujoco model="ball">', '  <compiler angle="radian"/>', "  <worldbody>"]
    lines += body(0, 2)
    lines += ["  </worldbody>", "</mujoco>", ""]
    return "\n".join(lines)


def pin_order(model) -> list[dict]:
    """Per Pinocchio joint (universe excluded): name, type, idx_q, nq, idx_v, nv;
    composite joints (several MJCF joints in one body) are expanded."""
    out = []
    for j in range(1, model.njoints):
        jm = model.joints[j]
        out.append(
            {
                "name": model.names[j],
                "type": jm.shortname(),
                "idx_q": jm.idx_q,
                "nq": jm.nq,
                "idx_v": jm.idx_v,
                "nv": jm.nv,
            }
        )
    return out


def mujoco_qpos(mj, q_pin: np.ndarray) -> np.ndarray:
    """Pinocchio's q (ball x, y, z, w) in MuJoCo's order (ball w, x, y, z).
    Both walk the joints in the same order (checked by the caller)."""
    qpos = q_pin.copy()
    for j in range(mj.njnt):
        if mj.jnt_type[j] == mujoco.mjtJoint.mjJNT_BALL:
            a = mj.jnt_qposadr[j]
            qpos[a : a + 4] = np.r_[q_pin[a + 3], q_pin[a : a + 3]]
    return qpos


def random_q(mj, model, rng) -> np.ndarray:
    q = np.zeros(model.nq)
    for j in range(mj.njnt):
        a = mj.jnt_qposadr[j]
        t = mj.jnt_type[j]
        if t == mujoco.mjtJoint.mjJNT_FREE:
            q[a : a + 3] = rng.uniform(-1, 1, 3)
            q[a + 3 : a + 7] = unit_quat(rng)
        elif t == mujoco.mjtJoint.mjJNT_BALL:
            q[a : a + 4] = unit_quat(rng)
        else:
            q[a] = rng.uniform(-1.5, 1.5)
    return q


def check(what: str, ours, theirs) -> float:
    ours, theirs = np.asarray(ours), np.asarray(theirs)
    err = np.abs(ours - theirs).max() if ours.size else 0.0
    scale = max(1.0, np.abs(theirs).max() if theirs.size else 0.0)
    if err > TOL * scale:
        raise SystemExit(f"self-check failed: {what}: error {err:e}")
    return float(err)


def state(model, data, mj, mjd, rng, free_root: bool) -> tuple[dict, float]:
    q = random_q(mj, model, rng)
    v, a, tau = (rng.normal(size=model.nv) for _ in range(3))
    worst = 0.0
    out = {"q": q.tolist(), "v": v.tolist(), "a": a.tolist(), "tau": tau.tolist()}
    out["rnea"] = pin.rnea(model, data, q, v, a).tolist()
    m = pin.crba(model, data, q)
    m = np.triu(m) + np.triu(m, 1).T
    out["mass_matrix"] = m.tolist()
    nle = pin.nonLinearEffects(model, data, q, v)
    out["nle"] = nle.tolist()
    ddq = pin.aba(model, data, q, v, tau)
    out["aba"] = ddq.tolist()
    worst = max(worst, check("M a + nle == rnea", m @ a + nle, out["rnea"]))
    worst = max(worst, check("rnea(aba) == tau", pin.rnea(model, data, q, v, ddq), tau))
    out["com"] = pin.centerOfMass(model, data, q).tolist()
    out["com_jacobian"] = pin.jacobianCenterOfMass(model, data, q).tolist()
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    out["body_jacobians"] = {
        f.name: pin.getFrameJacobian(model, data, k, pin.ReferenceFrame.WORLD).tolist()
        for k, f in enumerate(model.frames)
        if f.type == pin.FrameType.BODY and f.name.startswith("body")
    }
    out["integrate_dt"] = DT
    out["integrate"] = pin.integrate(model, q, v * DT).tolist()
    q2 = random_q(mj, model, rng)
    out["q2"] = q2.tolist()
    out["difference"] = pin.difference(model, q, q2).tolist()
    if not free_root:
        mjd.qpos[:] = mujoco_qpos(mj, q)
        mjd.qvel[:] = v
        mujoco.mj_forward(mj, mjd)
        full = np.zeros((mj.nv, mj.nv))
        mujoco.mj_fullM(mj, mjd, full)
        out["mujoco_mass_matrix"] = full.tolist()
        out["mujoco_bias"] = mjd.qfrc_bias.tolist()
        worst = max(worst, check("Pinocchio M == MuJoCo M", m, full))
        worst = max(worst, check("Pinocchio nle == MuJoCo bias", nle, mjd.qfrc_bias))
    return out, worst


def dof_names(mj) -> list[str]:
    """twinloop's velocity names in MuJoCo's dof order: a ball joint `j` gives
    j.wx, j.wy, j.wz; the free root is left to the caller."""
    out = []
    for j in range(mj.njnt):
        name = mujoco.mj_id2name(mj, mujoco.mjtObj.mjOBJ_JOINT, j)
        t = mj.jnt_type[j]
        if t == mujoco.mjtJoint.mjJNT_FREE:
            out += ["base.vx", "base.vy", "base.vz", "base.wx", "base.wy", "base.wz"]
        elif t == mujoco.mjtJoint.mjJNT_BALL:
            out += [f"{name}.wx", f"{name}.wy", f"{name}.wz"]
        else:
            out.append(name)
    return out


def main() -> None:
    os.makedirs(OUT_DIR, exist_ok=True)
    rng = np.random.default_rng(SEED)
    worst = 0.0
    for k in range(MODELS):
        free_root = k in FREE_ROOT
        name = f"ball_{k}"
        xml = make_mjcf(rng, free_root)
        path = os.path.join(OUT_DIR, f"{name}.xml")
        with open(path, "w") as f:
            f.write(xml)
        mj = mujoco.MjModel.from_xml_path(path)
        mjd = mujoco.MjData(mj)
        model = pin.buildModelFromMJCF(path)
        data = model.createData()
        if model.nq != mj.nq or model.nv != mj.nv:
            raise SystemExit(f"{name}: Pinocchio and MuJoCo sizes differ")
        states = []
        for _ in range(STATES):
            s, w = state(model, data, mj, mjd, rng, free_root)
            states.append(s)
            worst = max(worst, w)
        ref = {
            "schema": "twinloop-ball-reference/1",
            "pinocchio": pin.__version__,
            "mujoco": mujoco.__version__,
            "free_root": free_root,
            "nq": model.nq,
            "nv": model.nv,
            "v_names": dof_names(mj),
            "pinocchio_joints": pin_order(model),
            "states": states,
        }
        with open(os.path.join(OUT_DIR, f"{name}.json"), "w") as f:
            json.dump(ref, f)
        print(f"{name}: nq {model.nq} nv {model.nv} free_root {free_root}")
    print(f"largest self-check error {worst:.1e}")


if __name__ == "__main__":
    main()
