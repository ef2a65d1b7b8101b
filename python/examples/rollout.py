"""A batch of simulated rollouts on all cores (the shape of mujoco.rollout).

    python3 python/examples/rollout.py
"""

import pathlib
import time

import numpy as np

import twinloop as tl

repo = pathlib.Path(__file__).resolve().parents[2]
sim = tl.Simulator(repo / "models/op3/mjcf/op3.xml", {"dt": 1e-3, "servo": "auto"})
q0 = sim.q  # standing on the ground
n, steps = 32, 1000
rng = np.random.default_rng(1)
# Each rollout moves the knees by its own amount over 1 s.
knee = [i for i, name in enumerate(sim.joint_names) if "knee" in name]
goals = np.tile(q0[7:], (n, steps, 1))
bend = np.linspace(0, 1, steps)[None, :] * rng.uniform(0.0, 0.6, n)[:, None]
for k in knee:
    goals[:, :, k] += bend

t0 = time.perf_counter()
states = sim.rollout(q0, goals)  # (n, steps, nq + nv)
elapsed = time.perf_counter() - t0
print(f"{n} rollouts x {steps} steps in {elapsed:.2f} s ({n * steps / elapsed:.0f} steps/s)")
print("final base height (m) per rollout:", np.round(states[:, -1, 2], 4))
