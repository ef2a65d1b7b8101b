"""A 60 s, 1 kHz recording of km20 (20 joints) for the viewer's replay benchmark:
t, q:base.* standing still, q:<joint> sinusoids, and v:<joint>, tau:<joint> columns
as `twinloop simulate` writes them (60 001 rows, 68 columns).

    python3 crates/twinloop-view/bench/make_replay.py /tmp/replay60.csv
"""
import sys
import numpy as np

JOINTS = ["l_hip_yaw", "l_hip_roll", "l_hip_pitch", "l_knee", "l_ank_pitch", "l_ank_roll",
          "r_hip_yaw", "r_hip_roll", "r_hip_pitch", "r_knee", "r_ank_pitch", "r_ank_roll",
          "l_sho_pitch", "l_sho_roll", "l_elbow", "r_sho_pitch", "r_sho_roll", "r_elbow",
          "head_pan", "head_tilt"]

t = np.arange(60001) * 1e-3
cols = {"t": t}
base = {"x": 0.0, "y": 0.0, "z": 0.3, "qx": 0.0, "qy": 0.0, "qz": 0.0, "qw": 1.0}
for k, v in base.items():
    cols["q:base." + k] = np.full_like(t, v)
for i, j in enumerate(JOINTS):
    w = 2 * np.pi * (0.2 + 0.05 * i)
    cols["q:" + j] = 0.4 * np.sin(w * t)
for i, j in enumerate(JOINTS):
    w = 2 * np.pi * (0.2 + 0.05 * i)
    cols["v:" + j] = 0.4 * w * np.cos(w * t)
for i, j in enumerate(JOINTS):
    cols["tau:" + j] = 0.5 * np.sin(2 * np.pi * 0.3 * t + i)
names = list(cols)
data = np.column_stack([cols[n] for n in names])
np.savetxt(sys.argv[1], data, delimiter=",", header=",".join(names), comments="", fmt="%.9g")
