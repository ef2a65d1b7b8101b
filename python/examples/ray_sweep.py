"""A Ray sweep: the tip-over of 1000 random hardware changes, batched into Ray tasks.

    python3 python/examples/ray_sweep.py [--address ray://head:10001]
"""

import argparse
import time

import numpy as np

import twinloop as tl
import twinloop.distributed as td

ap = argparse.ArgumentParser()
ap.add_argument("--address", default=None, help="a Ray cluster (default: a local Ray)")
ap.add_argument("--jobs", type=int, default=1000)
a = ap.parse_args()

prior = tl.load("builtin:km20")
changes = tl.random_changes(prior, a.jobs, seed=1, mass_range=(0.05, 0.5))
t0 = time.perf_counter()
sweep = td.tipover_sweep(prior, changes, batch_size=50, address=a.address)  # arrays, one row per change
print(f"{len(sweep)} tip-overs in {time.perf_counter() - t0:.1f} s")
angles = sweep.static_deg  # (jobs, 4), deg
print("fall angles (deg), forward/backward/left/right: min", angles.min(0).round(2), "max", angles.max(0).round(2))
