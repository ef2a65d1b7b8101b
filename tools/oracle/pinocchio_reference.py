#!/usr/bin/env python3
"""Pinocchio reference data for twinloop-dynamics tests.

Run from the repository root:

    python3 tools/oracle/pinocchio_reference.py [--only NAME ...] [--out-dir DIR]

For every model listed in MODELS this loads the robot description with
Pinocchio, draws STATES_PER_MODEL seeded random states and writes
crates/twinloop-dynamics/tests/data/pinocchio/<name>.json holding the model
structure (joints, body frames, dynamic parameters) and, per state, the
results of the kinematics and dynamics algorithms. The JSON schema is
described in tools/oracle/README.md.

Conventions (all recorded in each JSON file as well):

* Floating base: a pinocchio.JointModelFreeFlyer() root joint (named
  "root_joint") is added, unless the file already has a floating root
  (COMAN's URDF `floating` joint below link `world`, the MJCF `freejoint`s);
  then the file is loaded as is. `floating_base.mode` says which.
* URDF mimic joints are loaded with mimic disabled: every mimic joint is an
  independent degree of freedom.
* Armature, rotor inertia, damping and friction of the model are set to zero
  before computing (the MJCF parser fills armature/damping/friction from the
  file; they never enter the algorithms below except armature and rotor
  inertia, which are zeroed so that M(q) is the rigid-body mass matrix).
* Gravity (0, 0, -9.81) in the world frame.
* Random states, drawn with numpy.random.default_rng(seed) where
  seed = [BASE_SEED, crc32(name), state_index]:
    1. base position uniform in [-1, 1]^3,
    2. base orientation: 4 standard normal numbers normalised to a unit
       quaternion, stored in Pinocchio order (x, y, z, w),
    3. one angle per non-root joint, in Pinocchio joint order, uniform in
       [-1.5, 1.5] rad (limits ignored); continuous URDF joints
       (JointModelRUB*, nq = 2) store (cos angle, sin angle),
    4. v, 5. a, 6. tau: nv standard normal numbers each.
* Results are computed with the default Pinocchio conventions; the few
  that matter (free-flyer velocity in the base frame, Jacobian row order,
  dynamic parameter order, static regressor normalisation) are written in
  the JSON and the README.

The script checks its own output: regressor @ parameters == rnea,
M a + nle == rnea, rnea(q, v, aba(q, v, tau)) == tau and
static_regressor @ (m, mc) == com, and aborts if any check fails.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import zlib

import numpy as np
import pinocchio as pin

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
OUT_DIR = os.path.join(REPO, "crates", "twinloop-dynamics", "tests", "data", "pinocchio")

SCHEMA = "twinloop-pinocchio-reference/1"
BASE_SEED = 20250611
STATES_PER_MODEL = 3
MAX_JACOBIAN_FRAMES = 8
GRAVITY = [0.0, 0.0, -9.81]
CHECK_TOL = 1e-9

# name -> (format, path relative to the repository root)
MODELS = {
    "op3": ("urdf", "models/op3/robotis_op3.nomesh.urdf"),
    "g1": ("urdf", "models/unitree_g1/g1_29dof_rev_1_0.nomesh.urdf"),
    "h1": ("urdf", "models/unitree_h1/h1.nomesh.urdf"),
    "coman": ("urdf", "models/coman/coman.nomesh.urdf"),
    "nao": ("urdf", "models/nao/nao_V50.nomesh.urdf"),
    "icub": ("urdf", "models/icub/iCubGazeboV2_5.nomesh.urdf"),
    "op3_mjcf": ("mjcf", "models/op3/mjcf/op3.xml"),
    "talos_mjcf": ("mjcf", "models/talos/mjcf/talos.xml"),
}

REFERENCE_FRAMES = {
    "LOCAL": pin.ReferenceFrame.LOCAL,
    "WORLD": pin.ReferenceFrame.WORLD,
    "LOCAL_WORLD_ALIGNED": pin.ReferenceFrame.LOCAL_WORLD_ALIGNED,
}

FIXED_AXES = {"X": [1.0, 0.0, 0.0], "Y": [0.0, 1.0, 0.0], "Z": [0.0, 0.0, 1.0]}


# --------------------------------------------------------------------------
# loading


def _urdf_has_floating_root(path: str) -> bool:
    """True when a joint of type floating hangs below the URDF root link."""
    import xml.etree.ElementTree as ET

    root = ET.parse(path).getroot()
    joints = root.findall("joint")
    child_links = {j.find("child").get("link") for j in joints}
    roots = [l.get("name") for l in root.findall("link") if l.get("name") not in child_links]
    return any(
        j.get("type") == "floating" and j.find("parent").get("link") in roots for j in joints
    )


def load_model(fmt: str, path: str):
    """Returns (model, floating_base info dict, mimic note)."""
    if fmt == "urdf":
        if _urdf_has_floating_root(path):
            model = pin.buildModelFromUrdf(path, mimic=False)
            mode = "file_floating_root"
            note = (
                "the URDF has its own `floating` joint below its root link; loaded without an "
                "added root joint (Pinocchio maps it to JointModelFreeFlyer; the root link is a "
                "BODY frame attached to the universe)"
            )
        else:
            model = pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer(), mimic=False)
            mode = "added_freeflyer"
            note = "pinocchio.JointModelFreeFlyer() added as root joint (default name root_joint)"
        mimic = "disabled (buildModelFromUrdf(..., mimic=False)): mimic joints are independent joints"
    elif fmt == "mjcf":
        model = pin.buildModelFromMJCF(path)
        if model.njoints < 2 or model.joints[1].shortname() != "JointModelFreeFlyer":
            raise RuntimeError(f"{path}: MJCF without a freejoint root is not handled")
        mode = "file_floating_root"
        note = (
            "the MJCF root body has a freejoint; loaded as is (Pinocchio maps it to "
            "JointModelFreeFlyer with identity placement: the body's pos/quat is not kept, "
            "as in MuJoCo where it only sets qpos0)"
        )
        mimic = "not applicable (MJCF)"
    else:
        raise ValueError(fmt)
    root = 1
    assert model.joints[root].shortname() == "JointModelFreeFlyer"
    floating = {"mode": mode, "joint_name": model.names[root], "joint_index": root, "note": note}
    return model, floating, mimic


def zero_actuation_fields(model) -> dict:
    """Zero armature, rotor inertia, damping and friction; return what was nonzero."""
    before = {}
    for field in ("armature", "rotorInertia", "damping", "friction"):
        arr = np.array(getattr(model, field), dtype=float)
        before[field] = {
            "nonzero_entries": int(np.count_nonzero(arr)),
            "max_abs": float(np.max(np.abs(arr))) if arr.size else 0.0,
        }
        setattr(model, field, np.zeros_like(arr))
    return before


# --------------------------------------------------------------------------
# helpers


def mat(x) -> list:
    return np.asarray(x, dtype=float).tolist()


def se3(m) -> dict:
    return {"translation": mat(m.translation), "rotation": mat(m.rotation)}


def joint_axis(jm):
    """Axis of 1-DoF revolute/prismatic joints, else None."""
    sn = jm.shortname()
    for prefix in ("JointModelRUB", "JointModelR", "JointModelP"):
        if sn.startswith(prefix) and sn[len(prefix):] in FIXED_AXES:
            return FIXED_AXES[sn[len(prefix):]]
    if sn in ("JointModelRevoluteUnaligned", "JointModelPrismaticUnaligned",
              "JointModelRevoluteUnboundedUnaligned"):
        return mat(jm.extract().axis)
    return None


def frame_parent_body(model, fid):
    """Index of the nearest BODY frame strictly above frame fid, or None."""
    f = model.frames[fid].parentFrame
    while True:
        if model.frames[f].type == pin.FrameType.BODY and f != fid:
            return f
        if f == 0:
            return None
        f = model.frames[f].parentFrame


def frame_depth(model, fid):
    d = 0
    while fid != 0:
        fid = model.frames[fid].parentFrame
        d += 1
    return d


def choose_jacobian_frames(model, root):
    """Up to MAX_JACOBIAN_FRAMES leaf BODY frames covering as many joints as possible.

    Leaf = BODY frame that no other BODY frame hangs below. Among leaves with
    the same parent joint only the one deepest in the frame tree (then lowest
    frame index) is kept. Greedy choice: repeatedly take the leaf whose
    support path (joints from the root to its parent joint) contains the most
    joints not covered by the leaves already chosen; ties go to the leaf with
    more joints on its support path, then deeper in the frame tree, then the
    lowest frame index. This picks the deepest limb ends first (feet, hands,
    fingertips, head) and frames on the base last.
    """
    body_ids = [i for i, f in enumerate(model.frames) if f.type == pin.FrameType.BODY]
    has_child = set()
    for i in body_ids:
        p = frame_parent_body(model, i)
        if p is not None:
            has_child.add(p)
    leaves = [i for i in body_ids if i not in has_child and model.frames[i].parentJoint != 0]
    leaves.sort(key=lambda i: (-frame_depth(model, i), i))
    best_per_joint = {}
    for i in leaves:
        best_per_joint.setdefault(model.frames[i].parentJoint, i)
    candidates = list(best_per_joint.values())
    covered, chosen = set(), []
    while candidates and len(chosen) < MAX_JACOBIAN_FRAMES:
        def key(i):
            sup = set(model.supports[model.frames[i].parentJoint]) - {0}
            return (-len(sup - covered), -len(sup), -frame_depth(model, i), i)
        best = min(candidates, key=key)
        candidates.remove(best)
        chosen.append(best)
        covered |= set(model.supports[model.frames[best].parentJoint]) - {0}
    return chosen


def random_state(model, root, rng):
    q = np.zeros(model.nq)
    iq = model.joints[root].idx_q
    q[iq:iq + 3] = rng.uniform(-1.0, 1.0, 3)
    quat = rng.standard_normal(4)
    q[iq + 3:iq + 7] = quat / np.linalg.norm(quat)
    others = [j for j in range(1, model.njoints) if j != root]
    angles = rng.uniform(-1.5, 1.5, len(others))
    for j, th in zip(others, angles):
        jm = model.joints[j]
        if jm.nq == 1 and jm.nv == 1:
            q[jm.idx_q] = th
        elif jm.nq == 2 and jm.nv == 1:  # continuous joint: (cos, sin)
            q[jm.idx_q] = np.cos(th)
            q[jm.idx_q + 1] = np.sin(th)
        else:
            raise RuntimeError(f"joint {model.names[j]} of type {jm.shortname()} not handled")
    v = rng.standard_normal(model.nv)
    a = rng.standard_normal(model.nv)
    tau = rng.standard_normal(model.nv)
    return q, v, a, tau


def check(label, got, want, tol=CHECK_TOL):
    got, want = np.asarray(got), np.asarray(want)
    err = float(np.max(np.abs(got - want))) if got.size else 0.0
    scale = max(1.0, float(np.max(np.abs(want))) if want.size else 1.0)
    if not err <= tol * scale:
        raise AssertionError(f"{label}: max abs error {err:.3e} > {tol:.0e} * {scale:.3g}")
    return err


# --------------------------------------------------------------------------
# generation


def generate(name: str, fmt: str, rel_path: str) -> dict:
    path = os.path.join(REPO, rel_path)
    model, floating, mimic = load_model(fmt, path)
    actuation_before = zero_actuation_fields(model)
    model.gravity = pin.Motion(np.array(GRAVITY), np.zeros(3))
    data = model.createData()
    root = floating["joint_index"]

    params = np.concatenate(
        [model.inertias[j].toDynamicParameters() for j in range(1, model.njoints)]
    )
    total_mass = float(sum(model.inertias[j].mass for j in range(1, model.njoints)))

    joints = []
    for j in range(1, model.njoints):
        jm = model.joints[j]
        joints.append({
            "index": j,
            "name": model.names[j],
            "type": jm.shortname(),
            "idx_q": int(jm.idx_q),
            "idx_v": int(jm.idx_v),
            "nq": int(jm.nq),
            "nv": int(jm.nv),
            "parent": int(model.parents[j]),
            "parent_name": model.names[model.parents[j]],
            "axis": joint_axis(jm),
            "placement": se3(model.jointPlacements[j]),
            "dynamic_parameters": mat(model.inertias[j].toDynamicParameters()),
        })

    body_ids = [i for i, f in enumerate(model.frames) if f.type == pin.FrameType.BODY]
    names = [model.frames[i].name for i in body_ids]
    if len(set(names)) != len(names):
        raise RuntimeError(f"{name}: duplicate BODY frame names")
    body_frames = []
    for i in body_ids:
        f = model.frames[i]
        pb = frame_parent_body(model, i)
        body_frames.append({
            "name": f.name,
            "parent_joint": model.names[f.parentJoint],
            "parent_joint_index": int(f.parentJoint),
            "parent_body": model.frames[pb].name if pb is not None else None,
            "placement": se3(f.placement),
        })

    jac_ids = choose_jacobian_frames(model, root)
    seed_base = [BASE_SEED, zlib.crc32(name.encode())]

    states = []
    max_err = {}
    for k in range(STATES_PER_MODEL):
        rng = np.random.default_rng(seed_base + [k])
        q, v, a, tau = random_state(model, root, rng)

        pin.forwardKinematics(model, data, q)
        pin.updateFramePlacements(model, data)
        placements = {model.frames[i].name: se3(data.oMf[i]) for i in body_ids}

        com = pin.centerOfMass(model, data, q).copy()
        jcom = pin.jacobianCenterOfMass(model, data, q).copy()

        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        frame_jac = {}
        for i in jac_ids:
            frame_jac[model.frames[i].name] = {
                key: mat(pin.getFrameJacobian(model, data, i, rf))
                for key, rf in REFERENCE_FRAMES.items()
            }

        tau_rnea = pin.rnea(model, data, q, v, a).copy()
        nle = pin.nonLinearEffects(model, data, q, v).copy()
        grav = pin.computeGeneralizedGravity(model, data, q).copy()
        M = pin.crba(model, data, q).copy()
        M = np.triu(M) + np.triu(M, 1).T
        ddq = pin.aba(model, data, q, v, tau).copy()
        reg = pin.computeJointTorqueRegressor(model, data, q, v, a).copy()
        sreg = pin.computeStaticRegressor(model, data, q).copy()

        # self-consistency checks
        e = max_err.setdefault
        e("regressor_vs_rnea", 0.0)
        max_err["regressor_vs_rnea"] = max(max_err["regressor_vs_rnea"],
                                           check(f"{name}[{k}] regressor@params vs rnea", reg @ params, tau_rnea))
        e("mass_matrix_vs_rnea", 0.0)
        max_err["mass_matrix_vs_rnea"] = max(max_err["mass_matrix_vs_rnea"],
                                             check(f"{name}[{k}] M a + nle vs rnea", M @ a + nle, tau_rnea))
        e("rnea_of_aba_vs_tau", 0.0)
        max_err["rnea_of_aba_vs_tau"] = max(max_err["rnea_of_aba_vs_tau"],
                                            check(f"{name}[{k}] rnea(aba) vs tau", pin.rnea(model, data, q, v, ddq), tau, 1e-8))
        static_params = params.reshape(-1, 10)[:, :4].reshape(-1)
        e("static_regressor_vs_com", 0.0)
        max_err["static_regressor_vs_com"] = max(max_err["static_regressor_vs_com"],
                                                 check(f"{name}[{k}] static regressor vs com", sreg @ static_params, com))
        check(f"{name}[{k}] gravity vs rnea(q,0,0)", grav, pin.rnea(model, data, q, 0 * v, 0 * v))
        assert np.all(np.isfinite(M)) and np.all(np.isfinite(ddq))

        states.append({
            "index": k,
            "seed": seed_base + [k],
            "q": mat(q),
            "v": mat(v),
            "a": mat(a),
            "tau": mat(tau),
            "body_placements": placements,
            "com": mat(com),
            "com_jacobian": mat(jcom),
            "frame_jacobians": frame_jac,
            "rnea": mat(tau_rnea),
            "nle": mat(nle),
            "gravity_torque": mat(grav),
            "mass_matrix": mat(M),
            "aba": mat(ddq),
            "joint_torque_regressor": mat(reg),
            "static_regressor": mat(sreg),
        })

    return {
        "schema": SCHEMA,
        "generator": "tools/oracle/pinocchio_reference.py",
        "pinocchio_version": pin.__version__,
        "numpy_version": np.__version__,
        "name": name,
        "source_file": rel_path,
        "format": fmt,
        "floating_base": floating,
        "mimic": mimic,
        "zeroed_before_computing": {
            "fields": ["armature", "rotorInertia", "damping", "friction"],
            "as_loaded": actuation_before,
        },
        "gravity": GRAVITY,
        "conventions": {
            "quaternion_order": "x, y, z, w",
            "free_flyer_q": "base position in world, then unit quaternion (x,y,z,w) rotating base to world",
            "free_flyer_v": "linear velocity of the base origin, then angular velocity, both in the base frame",
            "free_flyer_tau": "force then torque, in the base frame",
            "continuous_joints": "JointModelRUB* joints have nq=2 storing (cos angle, sin angle), nv=1",
            "rotation": "3x3 matrix as 3 rows (row-major)",
            "jacobian_rows": "linear (3) then angular (3)",
            "dynamic_parameters": "m, mc_x, mc_y, mc_z, Ixx, Ixy, Iyy, Ixz, Iyz, Izz; c and I about the joint frame origin, in the joint frame (I = I_C + m S(c)^T S(c))",
            "joint_torque_regressor": "nv x 10*njoints; columns 10*(i-1)..10*i-1 belong to joints[i-1] (Pinocchio joint index i)",
            "static_regressor": "3 x 4*njoints; com = static_regressor @ concat over joints of (m, mc_x, mc_y, mc_z); entries already divided by total_mass",
            "mass_matrix": "crba symmetrised (Pinocchio fills only the upper triangle)",
        },
        "seeding": {
            "rng": "numpy.random.default_rng(seed) with seed = [base_seed, crc32(name), state_index]",
            "base_seed": BASE_SEED,
            "crc32_name": zlib.crc32(name.encode()),
        },
        "nq": int(model.nq),
        "nv": int(model.nv),
        "njoints": int(model.njoints - 1),
        "total_mass": total_mass,
        "joints": joints,
        "body_frames": body_frames,
        "jacobian_frames": [model.frames[i].name for i in jac_ids],
        "self_check_max_abs_error": max_err,
        "states": states,
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", nargs="*", help="model names to generate (default: all)")
    ap.add_argument("--out-dir", default=OUT_DIR)
    args = ap.parse_args(argv)
    names = args.only or list(MODELS)
    os.makedirs(args.out_dir, exist_ok=True)
    failed = []
    for name in names:
        fmt, rel = MODELS[name]
        try:
            doc = generate(name, fmt, rel)
        except AssertionError:
            raise
        except Exception as exc:  # parser failure: report and skip
            print(f"{name}: SKIPPED ({type(exc).__name__}: {exc})", file=sys.stderr)
            failed.append(name)
            continue
        out = os.path.join(args.out_dir, f"{name}.json")
        with open(out, "w") as fh:
            json.dump(doc, fh, separators=(",", ":"))
            fh.write("\n")
        size = os.path.getsize(out)
        print(f"{name}: nq={doc['nq']} nv={doc['nv']} joints={doc['njoints']} "
              f"bodies={len(doc['body_frames'])} jac={doc['jacobian_frames']} "
              f"root={doc['floating_base']['mode']}:{doc['floating_base']['joint_name']} "
              f"{size / 1e6:.2f} MB")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
