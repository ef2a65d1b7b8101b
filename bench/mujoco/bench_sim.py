#!/usr/bin/env python3
"""MuJoCo's step time and tip-over on the same robot the twinloop simulator runs, for
BENCHMARKS.md.

    python3 bench/mujoco/bench_sim.py [--model models/op3/mjcf/op3.xml] [--dt 0.002]
        [--steps 2000] [--rounds 11] [--json] [--tipover]

The Menagerie OP3 references STL meshes that are not in this repository; the script
drops the mesh assets and every geom that is a mesh (its own `mesh` or `type`), and
nothing else: the classes keep every attribute their authors gave them (the default
class's solref=".004 1" included; only its `type="mesh"` goes, so a class geom without
a type is MuJoCo's default sphere). What remains is the robot's explicit <inertial>s
(so the dynamics are unchanged) and its foot boxes, the collision geometry twinloop
also uses. A floor plane is added, the robot is put upright with its feet on it, the
position actuators hold the neutral pose, it settles for 0.5 s, then rounds of
--steps steps are timed with mujoco.rollout (the stepping loop runs in C) and the
median microseconds per mj_step is printed.

--tipover adds fidelity beside speed: seed 000's forward tip-over as twinloop's
`experiment tipover` runs it (ankle pitches ramped at 0.5 deg/s, then again from half a
degree before that tip at --slow-ramp deg/s; the onset is the last moment the soles'
tilt grew no faster than 1.5 times the ankles over 0.1 s before it passed 5 deg), with
the static tipping angle of the posture at the onset (the ankles turned further, every
other joint as measured, until the CoM's ground projection reaches the soles' front
edge) beside the measured one.
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
    """The model as shipped, less its meshes (see the module notes)."""
    tree = ET.parse(path)
    root = tree.getroot()
    world = root.find("worldbody")
    # Mesh assets go; so do the geoms that are meshes. The class tree stays whole.
    for asset in root.iter("asset"):
        for m in asset.findall("mesh"):
            asset.remove(m)
    for parent in list(world.iter()):
        for child in list(parent):
            if child.tag == "geom" and (child.get("mesh") is not None or child.get("type") == "mesh"):
                parent.remove(child)
    for d in root.iter("default"):
        for m in d.findall("mesh"):
            d.remove(m)
        for g in d.findall("geom"):
            if g.get("type") == "mesh":
                del g.attrib["type"]
    compiler = root.find("compiler")
    if compiler is not None and "meshdir" in compiler.attrib:
        del compiler.attrib["meshdir"]
    floor = ET.Element("geom", {"name": "floor", "type": "plane", "size": "0 0 0.05"})
    world.insert(0, floor)
    return ET.tostring(root, encoding="unicode")


def stand(model, data, settle_s):
    """Upright with the lowest foot point on the floor, servos at the neutral pose,
    settled for settle_s."""
    mujoco.mj_resetData(model, data)
    data.qpos[:] = model.qpos0
    data.qpos[2] = 0.0
    mujoco.mj_forward(model, data)
    lowest = min(data.geom_xpos[g][2] - model.geom_size[g][2] for g in range(model.ngeom)
                 if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX)
    data.qpos[2] = -lowest
    data.ctrl[:] = 0.0
    for _ in range(int(settle_s / model.opt.timestep)):
        mujoco.mj_step(model, data)


class Trajectory:
    """Joint goals over time from a CSV (`t`, `q:<joint>` in rad; twinloop's
    `--trajectory` format) as position-actuator controls, linearly interpolated as
    twinloop interpolates them; joints without a column hold 0 (the standing goal)."""

    def __init__(self, model, path):
        with open(path) as f:
            header = f.readline().strip().split(",")
        table = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
        self.t = table[:, header.index("t")]
        self.nu = model.nu
        self.cols = []
        for a in range(model.nu):
            name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, model.actuator_trnid[a, 0])
            if f"q:{name}" in header:
                self.cols.append((a, table[:, header.index(f"q:{name}")]))

    def ctrl(self, times):
        out = np.zeros((len(times), self.nu))
        for a, q in self.cols:
            out[:, a] = np.interp(times, self.t, q)
        return out


def pitch_of(xmat):
    """Forward pitch (rad) of a body's x axis from its world rotation matrix."""
    r = np.asarray(xmat).reshape(3, 3)
    return float(np.arctan2(-r[2, 0], r[0, 0]))


class Ankles:
    """The ankle pitch joints and actuators, each with the sign that leans forward."""

    def __init__(self, model):
        self.joints = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, n)
                       for n in ("l_ank_pitch", "r_ank_pitch")]
        self.qadr = [model.jnt_qposadr[j] for j in self.joints]
        self.acts = [int(np.where(model.actuator_trnid[:, 0] == j)[0][0]) for j in self.joints]
        self.foot = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "l_ank_roll_link")
        self.feet = [self.foot, mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "r_ank_roll_link")]
        data = mujoco.MjData(model)
        self.sign = []
        # The forward sign of each ankle: the one that moves the CoM forward over its foot
        # (the two ankle axes point opposite ways).
        for k in range(2):
            base = self.com_ahead(model, data, model.qpos0.copy(), self.feet[k])
            q = model.qpos0.copy()
            q[self.qadr[k]] += 0.01
            self.sign.append(1.0 if self.com_ahead(model, data, q, self.feet[k]) > base else -1.0)

    def com_ahead(self, model, data, qpos, foot=None):
        """How far the CoM is ahead of the soles' front edge (m, in the frame of `foot`,
        default the left one, the feet flat): positive once it has passed it."""
        foot = self.foot if foot is None else foot
        data.qpos[:] = qpos
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        p, r = data.xpos[foot], data.xmat[foot].reshape(3, 3)
        com = r.T @ (data.subtree_com[0] - p)
        front = -np.inf
        for g in range(model.ngeom):
            if model.geom_bodyid[g] in self.feet and model.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX:
                gp = r.T @ (data.geom_xpos[g] - p)
                front = max(front, gp[0] + model.geom_size[g][0])
        return com[0] - front

    def static_angle(self, model, qpos):
        """The ankle lean (deg) at which the CoM of posture qpos reaches the front edge,
        the ankles turned further from their angles in qpos (bisection)."""
        data = mujoco.MjData(model)

        def ahead(extra_deg):
            q = qpos.copy()
            for k in range(2):
                q[self.qadr[k]] += self.sign[k] * np.radians(extra_deg)
            return self.com_ahead(model, data, q)

        lo, hi = -20.0, 45.0
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if ahead(mid) < 0 else (lo, mid)
        return self.measured_deg(qpos) + 0.5 * (lo + hi)

    def measured_deg(self, qpos):
        return float(np.degrees(np.mean([self.sign[k] * qpos[self.qadr[k]] for k in range(2)])))


def tip_forward(model, ankles, ramp, slow_from=None, slow_ramp=None, fall_deg=5.0, ratio=1.5, window=0.1):
    """One forward tip-over run; (commanded deg, measured deg, qpos) at the onset."""
    data = mujoco.MjData(model)
    stand(model, data, 1.0)
    dt = model.opt.timestep
    cmd, hist = 0.0, []
    while cmd < 45.0:
        rate = ramp if slow_from is None or cmd < slow_from else slow_ramp
        cmd += rate * dt
        for k in range(2):
            data.ctrl[ankles.acts[k]] = ankles.sign[k] * np.radians(cmd)
        mujoco.mj_step(model, data)
        excess = np.degrees(pitch_of(data.xmat[ankles.foot]))
        hist.append((cmd, ankles.measured_deg(data.qpos), data.time, excess, data.qpos.copy()))
        if excess > fall_deg:
            break
    t = np.array([h[2] for h in hist])
    for k in range(len(hist) - 1, 0, -1):
        j = int(np.searchsorted(t, t[k] - window + 1e-9, side="right")) - 1
        if j < 0:
            break
        if hist[k][3] - hist[j][3] <= ratio * max(hist[k][1] - hist[j][1], 0.0):
            return hist[k][0], hist[k][1], hist[k][4]
    raise RuntimeError("no onset found")


def tipover(model, ramp=0.5, slow_ramp=0.05):
    """twinloop's protocol: a run at `ramp`, then one slowing to `slow_ramp` half a
    degree before the first tip; the second run's onset against its static angle."""
    ankles = Ankles(model)
    first, _, _ = tip_forward(model, ankles, ramp)
    cmd, measured, q = tip_forward(model, ankles, ramp, first - 0.5, slow_ramp)
    static = ankles.static_angle(model, q)
    return {"commanded_deg": cmd, "measured_deg": measured, "static_deg": static,
            "early_deg": static - measured, "slow_ramp_deg_per_s": slow_ramp}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--model", default=os.path.join(ROOT, "models/op3/mjcf/op3.xml"))
    ap.add_argument("--dt", type=float, default=0.002)
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--rounds", type=int, default=11)
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--trajectory", help="joint goals CSV the timed steps follow (the walking case)")
    ap.add_argument("--tipover", action="store_true", help="also the forward tip-over (model's own timestep)")
    ap.add_argument("--slow-ramp", type=float, default=0.05, help="deg/s of the tip-over's final approach")
    args = ap.parse_args()
    model = mujoco.MjModel.from_xml_string(stripped_xml(args.model))
    tip = tipover(model, slow_ramp=args.slow_ramp) if args.tipover else None
    model.opt.timestep = args.dt
    data = mujoco.MjData(model)
    stand(model, data, 0.5)
    state_size = mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    state = np.empty(state_size)
    mujoco.mj_getState(model, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    goals = Trajectory(model, args.trajectory) if args.trajectory else None
    ctrl = np.zeros((1, args.steps, model.nu))
    samples = []
    for r in range(args.rounds):
        if goals is not None:
            # The walk's clock starts at the first timed step; each round goes on from
            # the last one's state, as twinloop's rounds do.
            ctrl[0] = goals.ctrl(np.arange(r * args.steps, (r + 1) * args.steps) * args.dt)
        t = time.perf_counter()
        states, _ = rollout.rollout(model, data, state[None, :], ctrl)
        samples.append((time.perf_counter() - t) * 1e6 / args.steps)
        if goals is not None:
            state = states[0, -1].copy()
    us = statistics.median(samples)
    out = {"robot": os.path.relpath(args.model, ROOT), "dt": args.dt, "nv": int(model.nv),
           "ncon_at_rest": int(data.ncon), "us_per_step": us, "steps_per_second": 1e6 / us,
           "mujoco_version": mujoco.__version__}
    if tip is not None:
        out["tipover_forward"] = tip
    print(json.dumps(out, indent=2) if args.json else
          f"MuJoCo {mujoco.__version__}: {us:.2f} us per step ({1e6 / us:.0f} steps/s), nv = {model.nv}, "
          f"{data.ncon} contacts at rest, dt = {args.dt} s"
          + ("" if tip is None else
             f"\nforward tip-over: measured {tip['measured_deg']:.3f} deg (commanded {tip['commanded_deg']:.3f}), "
             f"static {tip['static_deg']:.3f} deg: {tip['early_deg']:.3f} deg early"))


if __name__ == "__main__":
    sys.exit(main())
