"""The tip-over adaptation: a change of hardware (a battery on the torso) seen
through the tip-over experiment, the model adapted to it with `adapt`, and static
identification explaining the same change from force-plate poses.

    python3 python/examples/tipover_adaptation.py
"""

import numpy as np

import twinloop as tl

prior = tl.load("builtin:km20")
battery = (0.2, "torso", (0.05, 0.0, 0.0))  # kg, link, m in the link frame

# 1. The simulated tip-over experiment (seeds 000 and 001) of the robot with the battery:
#    four fall angles, and the CoM from them.
tip = tl.tipover(prior, ramp=2.0, slow_ramp=0.2, add_mass=[battery])
print("fall angles (deg):", [round(tip[d]["measured_deg"], 2) for d in ("forward", "backward", "left", "right")])
print("CoM, true      ", np.round(tip["com"]["true"], 4))
print("CoM, exact     ", np.round(tip["com"]["exact_method"], 4), f"(off by {tip['com']['exact_error'] * 1e3:.1f} mm)")
print("CoM, seed      ", np.round(tip["com"]["seed_method"], 4), f"(off by {tip['com']['seed_error'] * 1e3:.1f} mm)")

# 2. Adapt the prior to the experiment (seed 000 III, V.B), the robot weighed on a scale:
#    the added mass and where it must sit to move the CoM where the tips say.
report, adapted = tl.adapt(prior, tip, total_mass=prior.total_mass + battery[0])
added = report["added"]
print(f"adapt: {added['mass']:.3f} kg added at {np.round(added['position'], 3)} m "
      f"(on {added['host']}); adapted CoM {np.round(report['adapted_com'], 4)}")
print(f"adapted model: {adapted.total_mass:.3f} kg (prior {prior.total_mass:.3f} kg)")

# 3. Static identification (seed 004) of the changed robot from force-plate poses.
truth = prior.with_point_mass(battery[1], battery[0], battery[2])
poses = tl.static_poses(truth, count=60, cop_noise=5e-4, seed=3)
fit = tl.identify_static(prior, poses["q"], poses["cop"], truth.total_mass, category=poses["category"])
torso = next(link for link in fit["result"]["links"] if link["name"] == "torso")
print(f"torso mass: prior {torso['prior_mass']:.3f} kg, identified {torso['mass']:.3f} kg "
      f"(true {torso['prior_mass'] + battery[0]:.3f} kg)")
