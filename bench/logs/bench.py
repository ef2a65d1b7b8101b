#!/usr/bin/env python3
"""Log reading speed (issue 31): an hour of 1 kHz sensor_msgs/JointState for 20 joints
(3.6 M messages, zstd chunks) read by twinloop into a table, and by the reference Python
reader (read_python.py), on the same file.

    pip install mcap==1.6.0 mcap-ros2-support==0.6.0
    python3 bench/logs/bench.py [--seconds 3600] [--file /tmp/joint_states_1h.mcap] [--profile ci]

Builds crates/twinloop-logs/examples/logs_bench.rs (release profile, as shipped; `ci`:
the same optimisation without fat LTO, quicker to build beside the tests),
writes the file with it unless it exists, reads it with twinloop three times (median
of the wall time of `read_log`, which includes building the table) and once with
Python, and prints the table row of BENCHMARKS.md.
"""
import argparse
import os
import pathlib
import statistics
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]


def run(cmd):
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout.split()
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=3600.0)
    ap.add_argument("--file", default="/tmp/joint_states_1h.mcap")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--profile", default="release")
    a = ap.parse_args()
    subprocess.run(["cargo", "build", "--profile", a.profile, "-p", "twinloop-logs", "--example", "logs_bench"],
                   cwd=ROOT, check=True)
    exe = ROOT / "target" / a.profile / "examples/logs_bench"
    if not os.path.exists(a.file):
        subprocess.run([str(exe), "write", str(a.seconds), a.file], check=True)
    size = os.path.getsize(a.file) / 1e6
    times = []
    for _ in range(a.rounds):
        rows, cols, s = run([str(exe), "read", a.file])
        times.append(float(s))
        print(f"twinloop: {rows} rows x {cols} columns in {s} s", file=sys.stderr)
    n, py = run([sys.executable, str(ROOT / "bench/logs/read_python.py"), a.file])
    print(f"python: {n} messages in {py} s", file=sys.stderr)
    tw = statistics.median(times)
    print(f"| {int(n):,} JointState, 20 joints ({size:.0f} MB) | {tw:.2f} s | {float(py):.1f} s | "
          f"**{float(py) / tw:.0f}x** |")


if __name__ == "__main__":
    main()
