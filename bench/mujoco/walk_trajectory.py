#!/usr/bin/env python3
"""The walking case of `compare_sim.py`: OP3 stepping in place, as joint goals over time
in the CSV `twinloop simulate --trajectory` and `twinloop bench sim --trajectory` read
(`t`, then `q:<joint>` in rad), which `bench_sim.py --trajectory` feeds MuJoCo's position
actuators as the same goals (linear interpolation between rows, as twinloop's).

    python3 bench/mujoco/walk_trajectory.py --out op3_walk.csv

The legs crouch in the first second (hip, knee and ankle pitch at -a, 2a, a: the sole
stays parallel to the trunk), then the trunk sways sideways (hip and ankle rolls
together, the soles stay flat) and the leg away from the CoM shortens by a further
crouch of its own, so each foot leaves the floor and lands again once per cycle.
Signs follow the joint axes of models/op3/mjcf/op3.xml (left hip pitch about +y, right
about -y, and so on). Open loop: nothing balances it, which is why the sway is slow.
"""
import argparse
import math
import os

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
JOINTS = ["l_hip_roll", "l_hip_pitch", "l_knee", "l_ank_pitch", "l_ank_roll",
          "r_hip_roll", "r_hip_pitch", "r_knee", "r_ank_pitch", "r_ank_roll"]


def goals(t, crouch, sway, lift, period, ramp):
    """Joint goals (rad) at time t, in the order of JOINTS."""
    w = min(t / ramp, 1.0)
    walk = max(0.0, min((t - ramp) / ramp, 1.0))  # the sway fades in over a second
    phase = 2.0 * math.pi * max(t - ramp, 0.0) / period
    roll = walk * sway * math.sin(phase)
    # The leg away from the CoM lifts: left while the sway is to the right, and back.
    lift_l = walk * lift * max(0.0, -math.sin(phase)) ** 2
    lift_r = walk * lift * max(0.0, math.sin(phase)) ** 2
    a_l, a_r = w * crouch + lift_l, w * crouch + lift_r
    return [roll, -a_l, 2.0 * a_l, a_l, roll,
            roll, a_r, -2.0 * a_r, -a_r, roll]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", required=True)
    ap.add_argument("--duration", type=float, default=60.0, help="s")
    ap.add_argument("--rate", type=float, default=100.0, help="rows per second")
    ap.add_argument("--crouch", type=float, default=0.35, help="rad of hip pitch")
    ap.add_argument("--sway", type=float, default=0.17, help="rad of hip and ankle roll")
    ap.add_argument("--lift", type=float, default=0.3, help="rad of extra hip pitch")
    ap.add_argument("--period", type=float, default=2.0, help="s per step cycle")
    args = ap.parse_args()
    n = int(round(args.duration * args.rate))
    with open(args.out, "w") as f:
        f.write("t," + ",".join(f"q:{j}" for j in JOINTS) + "\n")
        for k in range(n + 1):
            t = k / args.rate
            g = goals(t, args.crouch, args.sway, args.lift, args.period, 1.0)
            f.write(f"{t:.4f}," + ",".join(f"{x:.6f}" for x in g) + "\n")


if __name__ == "__main__":
    main()
