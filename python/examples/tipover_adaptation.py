"""The tip-over adaptation: a change of hardware (a battery on the torso) seen
through the tip-over experiment, and the static identification that explains it.

    python3 python/examples/tipover_adaptation.py
"""

import twinloop as tl

prior = tl.load("builtin:km20")
battery = (0.2, "torso", (0.05, 0.0, 0.0))  # kg, link, m in the link frame

# 1. The simulated tip-over experiment (seeds 000 and 001): CoM from the tip angles.
r = tl.tipover(prior, ramp=2.0, slow_ramp=0.2, add_mass=[battery])
print("CoM, true      ", r["com"]["true"])
print("CoM, exact     ", r["com"]["exact_method"], f"(off by {r['com']['exact_error'] * 1e3:.1f} mm)")
print("CoM, seed      ", r["com"]["seed_method"], f"(off by {r['com']['seed_error'] * 1e3:.1f} mm)")

# 2. Static identification (seed 004) of the changed robot from force-plate poses.
truth = prior.with_point_mass(battery[1], battery[0], battery[2])
poses = tl.static_poses(truth, count=60, cop_noise=5e-4, seed=3)
fit = tl.identify_static(prior, poses["q"], poses["cop"], truth.total_mass, category=poses["category"])
torso = next(link for link in fit["result"]["links"] if link["name"] == "torso")
print(f"torso mass: prior {torso['prior_mass']:.3f} kg, identified {torso['mass']:.3f} kg "
      f"(true {torso['prior_mass'] + battery[0]:.3f} kg)")
