"""Write the example trajectories of examples/ (run from the repository root:
python3 examples/make_examples.py). Standard library only.

km20_goals.csv: joint goals for `twinloop simulate --robot builtin:km20 --trajectory`:
  a 2 s slow squat and back (knees, hip and ankle pitches together, so the feet stay
  flat and the trunk upright) with the arms swinging; any subset of q: columns works.
km20_swing.csv: a floating-base state for `twinloop dynamics kinematics|inverse|forward`
  on builtin:km20: q, v and a of the same squat, analytic (v and a are the exact
  derivatives of q), the base held at rest; tau:* = 0 (forward dynamics then gives the
  accelerations of the unpowered robot).
"""

import math

JOINTS = [
    "l_hip_yaw", "l_hip_roll", "l_hip_pitch", "l_knee", "l_ank_pitch", "l_ank_roll",
    "r_hip_yaw", "r_hip_roll", "r_hip_pitch", "r_knee", "r_ank_pitch", "r_ank_roll",
    "l_sho_pitch", "l_sho_roll", "l_elbow", "r_sho_pitch", "r_sho_roll", "r_elbow",
    "head_pan", "head_tilt",
]
BASE_Q = ["x", "y", "z", "qx", "qy", "qz", "qw"]
BASE_V = ["vx", "vy", "vz", "wx", "wy", "wz"]
BASE_TAU = ["fx", "fy", "fz", "tx", "ty", "tz"]
PERIOD = 2.0  # s, one squat


def squat(t):
    """Joint angle, velocity and acceleration per joint at time t (rad, rad/s, rad/s^2):
    the knee bends by 0.4 (1 - cos) / 2, the hip and ankle pitches share it."""
    w = 2 * math.pi / PERIOD
    s, ds, dds = 0.2 * (1 - math.cos(w * t)), 0.2 * w * math.sin(w * t), 0.2 * w * w * math.cos(w * t)
    arm, darm, ddarm = 0.3 * math.sin(w * t), 0.3 * w * math.cos(w * t), -0.3 * w * w * math.sin(w * t)
    gain = {"hip_pitch": -1.0, "knee": 2.0, "ank_pitch": -1.0}
    out = {}
    for j in JOINTS:
        side_part = j[2:]
        if side_part in gain:
            g = gain[side_part]
            out[j] = (g * s, g * ds, g * dds)
        elif side_part == "sho_pitch":
            g = 1.0 if j[0] == "l" else -1.0
            out[j] = (g * arm, g * darm, g * ddarm)
        else:
            out[j] = (0.0, 0.0, 0.0)
    return out


def fmt(x):
    return repr(round(x, 12) + 0.0)


def main():
    times = [k * 0.05 for k in range(int(PERIOD / 0.05) + 1)]
    with open("examples/km20_goals.csv", "w") as f:
        f.write(",".join(["t"] + [f"q:{j}" for j in JOINTS]) + "\n")
        for t in times:
            m = squat(t)
            f.write(",".join([fmt(t)] + [fmt(m[j][0]) for j in JOINTS]) + "\n")
    header = (["t"] + [f"q:base.{c}" for c in BASE_Q] + [f"q:{j}" for j in JOINTS]
              + [f"v:base.{c}" for c in BASE_V] + [f"v:{j}" for j in JOINTS]
              + [f"a:base.{c}" for c in BASE_V] + [f"a:{j}" for j in JOINTS]
              + [f"tau:base.{c}" for c in BASE_TAU] + [f"tau:{j}" for j in JOINTS])
    with open("examples/km20_swing.csv", "w") as f:
        f.write(",".join(header) + "\n")
        for t in times:
            m = squat(t)
            row = [t, 0.0, 0.0, 0.3, 0.0, 0.0, 0.0, 1.0] + [m[j][0] for j in JOINTS]
            row += [0.0] * 6 + [m[j][1] for j in JOINTS]
            row += [0.0] * 6 + [m[j][2] for j in JOINTS]
            row += [0.0] * (6 + len(JOINTS))
            f.write(",".join(fmt(x) for x in row) + "\n")


if __name__ == "__main__":
    main()
