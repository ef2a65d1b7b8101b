#!/usr/bin/env python3
"""MuJoCo's step time on the same robot the twinloop simulator runs, for BENCHMARKS.md.

    python3 bench/mujoco/bench_sim.py [--model models/op3/mjcf/op3.xml] [--dt 0.002]
        [--steps 2000] [--rounds 11] [--json]

The Menagerie OP3 references STL meshes that are not in this repository; the script
drops every mesh geom and mesh asset, which leaves the robot's explicit <inertial>s
(so the dynamics are unchanged) and its foot boxes, the collision geometry twinloop
also uses. A floor plane is added, the robot is put upright with its feet on it, the
position actuators hold the neutral pose, it settles for 0.5 s, then rounds of
--steps steps are timed with mujoco.rollout (the stepping loop runs in C) and the
median microseconds per mj_step is printed.
"""
import argparse
import json
import os
import statistics
import sys
import time
import xml.etree.ElementTree as ET

import mujoco
import numpy as np
from mujoco import rollout

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def stripped_xml(path):
    tree = ET.parse(path)
    root = tree.getroot()
    for parent in list(root.iter()):
        for child in list(parent):
            if child.tag == "mesh":
                parent.remove(child)
            elif child.tag == "geom" and (child.get("mesh") is not None or child.get("type") == "mesh"):
                parent.remove(child)
    # The default class makes every geom a mesh; make the default a sphere instead.
    for d in root.iter("default"):
        for g in d.findall("geom"):
            if g.get("type") == "mesh":
                g.set("type", "sphere")
                g.set("size", "0.01")
    compiler = root.find("compiler")
    if compiler is not None and "meshdir" in compiler.attrib:
        del compiler.attrib["meshdir"]
    world = root.find("worldbody")
    floor = ET.Element("geom", {"name": "floor", "type": "plane", "size": "0 0 0.05"})
    world.insert(0, floor)
    return ET.tostring(root, encoding="unicode")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--model", default=os.path.join(ROOT, "models/op3/mjcf/op3.xml"))
    ap.add_argument("--dt", type=float, default=0.002)
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--rounds", type=int, default=11)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    model = mujoco.MjModel.from_xml_string(stripped_xml(args.model))
    model.opt.timestep = args.dt
    data = mujoco.MjData(model)
    mujoco.mj_resetData(model, data)
    # Upright, lowest foot point on the floor.
    data.qpos[:] = model.qpos0
    data.qpos[2] = 0.0
    mujoco.mj_forward(model, data)
    lowest = min(data.geom_xpos[g][2] - model.geom_size[g][2] for g in range(model.ngeom)
                 if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX)
    data.qpos[2] = -lowest
    data.ctrl[:] = 0.0
    for _ in range(int(0.5 / args.dt)):
        mujoco.mj_step(model, data)
    state_size = mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    state = np.empty(state_size)
    mujoco.mj_getState(model, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    ctrl = np.zeros((1, args.steps, model.nu))
    samples = []
    for _ in range(args.rounds):
        t = time.perf_counter()
        rollout.rollout(model, data, state[None, :], ctrl)
        samples.append((time.perf_counter() - t) * 1e6 / args.steps)
    us = statistics.median(samples)
    out = {"robot": os.path.relpath(args.model, ROOT), "dt": args.dt, "nv": int(model.nv),
           "ncon_at_rest": int(data.ncon), "us_per_step": us, "steps_per_second": 1e6 / us,
           "mujoco_version": mujoco.__version__}
    print(json.dumps(out, indent=2) if args.json else
          f"MuJoCo {mujoco.__version__}: {us:.2f} us per step ({1e6 / us:.0f} steps/s), nv = {model.nv}, "
          f"{data.ncon} contacts at rest, dt = {args.dt} s")


if __name__ == "__main__":
    sys.exit(main())
