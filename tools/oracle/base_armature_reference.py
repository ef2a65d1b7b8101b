#!/usr/bin/env python3
"""MuJoCo's numbers for a floating base with armature on its free joint (issue 30: BXI
Elf2's `<default><joint armature="0.01">` reaches its `<joint type="free">`).

Run from the repository root:

    python3 tools/oracle/base_armature_reference.py

Writes crates/twinloop-dynamics/tests/data/base_armature/free_armature.xml (a free
body, rotated inertial, with two hinges below it; the default class gives every
joint, the free one included, an armature) and free_armature.json with, per seeded
random state (base turned and moving), MuJoCo's `mj_fullM`, `qfrc_bias`, and for a
random `qfrc_applied` the accelerations `qacc` of `mj_forward`.

MuJoCo's free-joint velocity is (world-frame linear velocity of the body origin,
body-frame angular velocity); twinloop's (Pinocchio's) base velocity has both in
the base frame. The JSON keeps MuJoCo's own coordinates (qpos with w, x, y, z) and
the test converts them (crates/twinloop-dynamics/tests/base_armature.rs), so the
conversion itself is under test. The script checks `M qacc + qfrc_bias ==
qfrc_applied` (no passive forces or constraints: damping and frictionloss zero)
before writing. Deterministic (numpy default_rng). Needs `pip install mujoco numpy`.
"""

from __future__ import annotations

import json
import os

import mujoco
import numpy as np

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
OUT_DIR = os.path.join(REPO, "crates", "twinloop-dynamics", "tests", "data", "base_armature")
SEED = 20261207
STATES = 3

XML = """<mujoco model="free_armature">
  <!-- Written by tools/oracle/base_armature_reference.py: the default class's
       armature reaches the free joint, as in BXI Elf2 (MuJoCo Menagerie). -->
  <default>
    <joint armature="0.25"/>
  </default>
  <worldbody>
    <body name="base" pos="0 0 1">
      <joint name="root" type="free"/>
      <inertial pos="0.05 -0.02 0.1" quat="0.9 0.2 -0.3 0.1" mass="3.5" diaginertia="0.04 0.03 0.02"/>
      <body name="arm" pos="0.1 0.05 0.2" euler="0.3 -0.2 0.5">
        <joint name="shoulder" axis="0 1 0" armature="0.02"/>
        <inertial pos="0 0 -0.15" mass="0.8" diaginertia="0.006 0.005 0.001"/>
        <body name="forearm" pos="0 0 -0.3">
          <joint name="elbow" axis="1 0 0"/>
          <inertial pos="0.01 0 -0.1" quat="0.8 0 0.6 0" mass="0.5" diaginertia="0.003 0.0025 0.001"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def main() -> None:
    os.makedirs(OUT_DIR, exist_ok=True)
    m = mujoco.MjModel.from_xml_string(XML)
    assert m.nv == 8 and list(m.dof_armature[:6]) == [0.25] * 6
    d = mujoco.MjData(m)
    rng = np.random.default_rng(SEED)
    states = []
    for _ in range(STATES):
        quat = rng.normal(size=4)
        d.qpos[:] = np.concatenate([rng.normal(size=3), quat / np.linalg.norm(quat), rng.uniform(-1.5, 1.5, 2)])
        d.qvel[:] = rng.normal(size=m.nv)
        d.qfrc_applied[:] = rng.normal(size=m.nv) * 5.0
        mujoco.mj_forward(m, d)
        full = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, full)
        residual = full @ d.qacc + d.qfrc_bias - d.qfrc_applied
        assert np.abs(residual).max() < 1e-9 * max(1.0, np.abs(d.qfrc_applied).max()), residual
        states.append({
            "qpos": d.qpos.tolist(),
            "qvel": d.qvel.tolist(),
            "qfrc_applied": d.qfrc_applied.tolist(),
            "qacc": d.qacc.tolist(),
            "mass_matrix": full.tolist(),
            "bias": d.qfrc_bias.tolist(),
        })
    with open(os.path.join(OUT_DIR, "free_armature.xml"), "w") as f:
        f.write(XML)
    ref = {
        "mujoco": mujoco.__version__,
        "gravity": m.opt.gravity.tolist(),
        "base_armature": float(m.dof_armature[0]),
        "states": states,
    }
    with open(os.path.join(OUT_DIR, "free_armature.json"), "w") as f:
        json.dump(ref, f, indent=1)
        f.write("\n")
    print(f"wrote {OUT_DIR}/free_armature.xml and .json (MuJoCo {mujoco.__version__}, {STATES} states)")


if __name__ == "__main__":
    main()
