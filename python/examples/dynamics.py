"""Pinocchio-style dynamics: the same calls, the same conventions.

    python3 python/examples/dynamics.py [robot.urdf]
"""

import pathlib
import sys

import numpy as np

import twinloop as tl

repo = pathlib.Path(__file__).resolve().parents[2]
path = sys.argv[1] if len(sys.argv) > 1 else repo / "models/unitree_g1/g1_29dof_rev_1_0.nomesh.urdf"

desc = tl.load(path)  # a URDF, an MJCF, or "builtin:km20"
print(desc, "-", len(desc.findings), "lint findings")
model = tl.Model.from_description(desc)  # free-flyer base, as pin.JointModelFreeFlyer()
data = tl.Data(model)

rng = np.random.default_rng(0)
q = model.neutral()
q[7:] = rng.uniform(-0.5, 0.5, len(model.joint_names))
v, a = rng.normal(size=model.nv), rng.normal(size=model.nv)

tau = tl.rnea(model, data, q, v, a)  # N m; a read-only view of data.tau
M = tl.crba(model, data, q).copy()  # copy: data.M changes with the next crba
nle = tl.nonlinear_effects(model, data, q, v).copy()
print("|M a + nle - rnea| =", np.abs(M @ a + nle - tl.rnea(model, data, q, v, a)).max())
ddq = tl.aba(model, data, q, v, tau)
print("|aba(rnea(a)) - a| =", np.abs(ddq - a).max())
com = tl.center_of_mass(model, data, q)
print("CoM (m):", com, " total mass (kg):", model.total_mass)
J = tl.frame_jacobian(model, data, q, model.frame_names[-1], tl.LOCAL_WORLD_ALIGNED)
print("Jacobian of", model.frame_names[-1], J.shape)

# 1000 states in one call, the GIL released, on every core.
Q = np.tile(q, (1000, 1))
Q[:, 7:] += rng.normal(scale=0.1, size=(1000, len(model.joint_names)))
TAU = tl.rnea_batch(model, Q, np.zeros((1000, model.nv)), np.zeros((1000, model.nv)))
print("gravity torques of 1000 poses:", TAU.shape)
