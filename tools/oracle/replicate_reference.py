#!/usr/bin/env python3
"""MuJoCo's expansion of <replicate>, as reference numbers for twinloop.

Run from the repository root (needs `pip install mujoco numpy`):

    python3 tools/oracle/replicate_reference.py

Writes crates/twinloop-dynamics/tests/data/replicate/replicate.xml: nested
<replicate>s (offsets and rotations, `sep`, a count of 10 for two-digit
suffixes) at the top level and inside a body, around bodies with hinge and ball
joints, geoms and sites; and replicate.json with MuJoCo 4's body names, body
masses, joint dof names (twinloop's velocity names) and, at two seeded states,
the joint-space mass matrix (`mj_fullM`) and bias forces (`qfrc_bias`), with q in
twinloop's order (a ball's quaternion x, y, z, w). Deterministic.
"""

import json
import os

import mujoco
import numpy as np

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
OUT = os.path.join(REPO, "crates", "twinloop-dynamics", "tests", "data", "replicate")

XML = """<mujoco model="replicate">
  <worldbody>
    <replicate count="2" sep="-" offset="0.5 0 0" euler="0 0 30">
      <replicate count="3" offset="0 0.2 0.1" euler="10 0 0">
        <body name="leg" pos="0.1 0 0">
          <joint name="hip" axis="0 1 0"/>
          <geom name="thigh" type="capsule" fromto="0 0 0 0 0 -0.3" size="0.04"/>
          <site name="knee_site" pos="0 0 -0.3"/>
          <body name="shin" pos="0 0 -0.3">
            <joint name="knee" type="ball"/>
            <geom type="box" size="0.03 0.04 0.12" pos="0 0 -0.12" mass="0.7"/>
          </body>
        </body>
      </replicate>
    </replicate>
    <body name="arm" pos="0 0 1" euler="0 20 0">
      <joint name="shoulder" axis="1 0 0"/>
      <geom type="sphere" size="0.06"/>
      <replicate count="10" sep="_" offset="0.05 0 0" euler="0 0 36">
        <body name="finger" pos="0.1 0 0">
          <joint name="finger_j" axis="0 0 1"/>
          <geom name="nail" type="box" size="0.01 0.02 0.005" pos="0.02 0 0"/>
        </body>
      </replicate>
    </body>
  </worldbody>
</mujoco>
"""


def dof_names(m):
    out = []
    for j in range(m.njnt):
        name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j)
        if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_BALL:
            out += [f"{name}.wx", f"{name}.wy", f"{name}.wz"]
        else:
            out.append(name)
    return out


def main():
    os.makedirs(OUT, exist_ok=True)
    path = os.path.join(OUT, "replicate.xml")
    with open(path, "w") as f:
        f.write(XML)
    m = mujoco.MjModel.from_xml_path(path)
    d = mujoco.MjData(m)
    rng = np.random.default_rng(20261125)
    states = []
    for _ in range(2):
        q = np.zeros(m.nq)  # twinloop order
        qpos = np.zeros(m.nq)
        for j in range(m.njnt):
            a = m.jnt_qposadr[j]
            if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_BALL:
                g = rng.normal(size=4)
                g /= np.linalg.norm(g)
                q[a : a + 4] = g
                qpos[a : a + 4] = [g[3], g[0], g[1], g[2]]
            else:
                q[a] = qpos[a] = rng.uniform(-1.5, 1.5)
        v = rng.normal(size=m.nv)
        d.qpos[:] = qpos
        d.qvel[:] = v
        mujoco.mj_forward(m, d)
        full = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, full)
        states.append(
            {"q": q.tolist(), "v": v.tolist(), "mass_matrix": full.tolist(), "bias": d.qfrc_bias.tolist()}
        )
    ref = {
        "mujoco": mujoco.__version__,
        "bodies": [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b) for b in range(1, m.nbody)],
        "body_mass": m.body_mass[1:].tolist(),
        "sites": [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_SITE, s) for s in range(m.nsite)],
        "v_names": dof_names(m),
        "states": states,
    }
    with open(os.path.join(OUT, "replicate.json"), "w") as f:
        json.dump(ref, f)
    print(m.nbody - 1, "bodies", m.nv, "dofs")


if __name__ == "__main__":
    main()
