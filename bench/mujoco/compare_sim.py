#!/usr/bin/env python3
"""twinloop's simulator vs MuJoCo on the same robot, alternating runs so machine load
hits both alike; prints the median us per step of each and the ratio.

    python3 bench/mujoco/compare_sim.py [--model models/op3/mjcf/op3.xml] [--dt 0.002] [--runs 5]
        [--walk] [--twinloop target/ci/twinloop [--twinloop other/twinloop ...]]

--twinloop given more than once: each binary runs in every round, in turn with MuJoCo
(before and after a change under the same load); each gets its median and ratio.

--walk: the walking case, both following the joint goals of walk_trajectory.py (OP3
stepping in place, each foot leaving the floor and landing once per cycle), written
to a temporary CSV first; without it, standing.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--model", default="models/op3/mjcf/op3.xml")
    ap.add_argument("--dt", type=float, default=0.002)
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--twinloop", action="append",
                    help="twinloop binary (repeatable; default target/release/twinloop)")
    ap.add_argument("--walk", action="store_true", help="the walking case (walk_trajectory.py's goals)")
    args = ap.parse_args()
    binaries = args.twinloop or [os.path.join(ROOT, "target/release/twinloop")]
    extra = []
    if args.walk:
        walk = os.path.join(tempfile.mkdtemp(prefix="twinloop-walk-"), "op3_walk.csv")
        subprocess.run([sys.executable, os.path.join(ROOT, "bench/mujoco/walk_trajectory.py"), "--out", walk],
                       check=True, cwd=ROOT)
        extra = ["--trajectory", walk]
    ours, theirs = [[] for _ in binaries], []
    for _ in range(args.runs):
        m = subprocess.run([sys.executable, os.path.join(ROOT, "bench/mujoco/bench_sim.py"), "--model", args.model,
                            "--dt", str(args.dt), "--json"] + extra, check=True, capture_output=True, text=True,
                           cwd=ROOT)
        theirs.append(json.loads(m.stdout)["us_per_step"])
        for b, times in zip(binaries, ours):
            t = subprocess.run([b, "bench", "sim", "--robot", args.model, "--dt", str(args.dt), "--json", "-"]
                               + extra, check=True, capture_output=True, text=True, cwd=ROOT)
            times.append(json.loads(t.stdout)["us_per_step"])
    p = statistics.median(theirs)
    case = "walking" if args.walk else "standing"
    for b, times in zip(binaries, ours):
        o = statistics.median(times)
        print(f"{args.model} {case} dt={args.dt}: twinloop ({b}) {o:.2f} us/step, MuJoCo {p:.2f} us/step, "
              f"twinloop steps/s = {p / o:.2f} x MuJoCo's (runs: {args.runs})")


if __name__ == "__main__":
    main()
