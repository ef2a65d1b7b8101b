#!/usr/bin/env python3
"""MuJoCo's compiled numbers for the MJCF corpus under this folder.

For every MJCF in dm_control's suite and gymnasium's MuJoCo assets (as pip
installs them), this copies the file (and the files it includes) into
`dm_control/` or `gymnasium/` here and writes `reference/<package>/<model>.json`:

- per body (MuJoCo's order, world excluded): name, body_mass, body_ipos,
  body_inertia, body_iquat;
- three seeded random states with the root fixed: qpos and qvel of the joints
  that twinloop models (a free joint on the root body is held at the identity
  pose with zero velocity and left out), the joint-space mass matrix
  (`mj_fullM`, same rows), the bias forces (`qfrc_bias`) and every body's
  world pose (`xpos`, `xquat`).

`cargo test` reads only the JSON. Rerun with `python3 make_reference.py`
(needs `pip install mujoco dm_control gymnasium`); the MuJoCo version is
recorded in each file.
"""
import glob
import json
import os
import shutil

import dm_control
import gymnasium
import mujoco
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
SEEDS = [1, 2, 3]
# dm_control's dog needs 20 MB of STL bone meshes: too large to commit here.
SKIP = {"dog.xml"}


def sources():
    dm = os.path.join(os.path.dirname(dm_control.__file__), "suite")
    gym = os.path.join(os.path.dirname(gymnasium.__file__), "envs", "mujoco", "assets")
    for f in sorted(glob.glob(os.path.join(dm, "*.xml"))):
        yield "dm_control", dm, f
    for f in sorted(glob.glob(os.path.join(gym, "*.xml"))):
        yield "gymnasium", gym, f


def copy_tree(package, src_dir, path):
    """The MJCF and its include files (dm_control's common/), as shipped."""
    out = os.path.join(HERE, package)
    os.makedirs(out, exist_ok=True)
    shutil.copy(path, out)
    common = os.path.join(src_dir, "common")
    if os.path.isdir(common):
        os.makedirs(os.path.join(out, "common"), exist_ok=True)
        for f in glob.glob(os.path.join(common, "*.xml")):
            shutil.copy(f, os.path.join(out, "common"))
    return os.path.join(out, os.path.basename(path))


def root_free_dofs(m):
    """Dofs of a free joint on a top-level body that is the only one: held fixed."""
    top = [b for b in range(1, m.nbody) if m.body_parentid[b] == 0]
    if len(top) == 1 and m.body_jntnum[top[0]] >= 1:
        j = m.body_jntadr[top[0]]
        if int(m.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_FREE):
            return j, m.jnt_qposadr[j], m.jnt_dofadr[j]
    return None


def state(m, seed, free):
    rng = np.random.default_rng(seed)
    d = mujoco.MjData(m)
    d.qpos[:] = m.qpos0
    keep_q, keep_v = [], []
    for j in range(m.njnt):
        qa, va = m.jnt_qposadr[j], m.jnt_dofadr[j]
        t = int(m.jnt_type[j])
        if free is not None and j == free[0]:
            d.qpos[qa:qa + 7] = [0, 0, 0, 1, 0, 0, 0]
            continue
        if t in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)):
            d.qpos[qa] = rng.uniform(-1.0, 1.0)
            d.qvel[va] = rng.uniform(-1.0, 1.0)
            keep_q.append(qa)
            keep_v.append(va)
        else:
            nq = 7 if t == int(mujoco.mjtJoint.mjJNT_FREE) else 4
            nv = 6 if t == int(mujoco.mjtJoint.mjJNT_FREE) else 3
            qr = rng.normal(size=4)
            d.qpos[qa + nq - 4:qa + nq] = qr / np.linalg.norm(qr)
            d.qvel[va:va + nv] = rng.uniform(-1.0, 1.0, nv)
            keep_q.extend(range(qa, qa + nq))
            keep_v.extend(range(va, va + nv))
    mujoco.mj_forward(m, d)
    full = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, full)
    return {
        "qpos": d.qpos[keep_q].tolist(),
        "qvel": d.qvel[keep_v].tolist(),
        "mass_matrix": full[np.ix_(keep_v, keep_v)].tolist(),
        "bias": d.qfrc_bias[keep_v].tolist(),
        "xpos": d.xpos[1:].tolist(),
        "xquat": d.xquat[1:].tolist(),
    }


def reference(m):
    free = root_free_dofs(m)
    bodies = []
    for b in range(1, m.nbody):
        bodies.append({
            "name": mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b),
            "mass": float(m.body_mass[b]),
            "ipos": m.body_ipos[b].tolist(),
            "inertia": m.body_inertia[b].tolist(),
            "iquat": m.body_iquat[b].tolist(),
        })
    return {
        "mujoco": mujoco.__version__,
        "root_free": free is not None,
        "gravity": m.opt.gravity.tolist(),
        "gravity_disabled": bool(m.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_GRAVITY),
        "nv": int(m.nv),
        "bodies": bodies,
        "states": [state(m, s, free) for s in SEEDS],
    }


def main():
    for package, src_dir, path in sources():
        name = os.path.basename(path)
        if name in SKIP:
            continue
        try:
            m = mujoco.MjModel.from_xml_path(path)
        except Exception as e:  # noqa: BLE001 -- MuJoCo refuses it: not in the corpus
            print(f"{package}/{name}: MuJoCo does not load it: {e}")
            continue
        copy_tree(package, src_dir, path)
        out = os.path.join(HERE, "reference", package)
        os.makedirs(out, exist_ok=True)
        with open(os.path.join(out, name.replace(".xml", ".json")), "w") as f:
            json.dump(reference(m), f, separators=(",", ":"))
            f.write("\n")
        print(f"{package}/{name}: {m.nbody - 1} bodies, nv {m.nv}")


if __name__ == "__main__":
    main()
