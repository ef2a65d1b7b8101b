"""Every URDF twinloop writes loads in other tools with the same robot (issue 30, item 5).

`Description.to_urdf()` is the writer behind `twinloop model export`, `adapt --out` and
`identify static --out` (one function, `twinloop_description::urdf::to_string`). For each
robot the repository ships (URDF and MJCF, Menagerie's among them), the builtin robots and
the MJCF edge cases (crates/twinloop-description/tests/data/mjcf/edges), the written
URDF must load in Pinocchio, yourdfpy and urdf_parser_py (urdfdom's `check_urdf` rules:
every `<limit>` with effort and velocity, no `type="spherical"`), and Pinocchio must see
twinloop's robot: the same total mass, the same CoM and mass matrix at the neutral pose
(floating base), and the same joint tree, a ball joint being three revolute joints
`<ball>_x`, `<ball>_y`, `<ball>_z`.
"""

import math
import subprocess
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import twinloop as tl
from conftest import MODELS, REPO, oracle
from test_cli_parity import cli

EDGES = REPO / "crates" / "twinloop-description" / "tests" / "data" / "mjcf" / "edges"
ROBOTS = (
    sorted(MODELS.glob("*/*.nomesh.urdf"))
    + sorted(MODELS.glob("*/mjcf/*.xml"))
    + sorted(EDGES.glob("*.xml"))
    + ["builtin:km20", "builtin:lab17"]
)
TOL = 1e-9


def close(what, ours, theirs):
    ours, theirs = np.asarray(ours, dtype=float), np.asarray(theirs, dtype=float)
    assert ours.shape == theirs.shape, f"{what}: shape {ours.shape} vs {theirs.shape}"
    err = np.abs(ours - theirs) / np.maximum(1.0, np.abs(theirs))
    assert err.max(initial=0.0) <= TOL, f"{what}: max relative error {err.max():.3e}"


def expected_tree(desc, model):
    """Movable joint -> its nearest movable ancestor joint ("" at the base), balls as x, y, z."""
    joints = {j["child"]: j for j in desc.joints}
    kind = {j["name"]: j["type"] for j in desc.joints}
    tree = {}
    for name in model.joint_names:
        j = next(x for x in desc.joints if x["name"] == name)
        link, parent = j["parent"], ""
        while link in joints:
            up = joints[link]
            if up["type"] not in ("fixed", "floating"):
                parent = up["name"] + ("_z" if up["type"] == "spherical" else "")
                break
            link = up["parent"]
        if kind[name] == "spherical":
            tree.update({name + "_x": parent, name + "_y": name + "_x", name + "_z": name + "_y"})
        else:
            tree[name] = parent
    return tree


def v_index(desc, model):
    """twinloop's v index of each joint name Pinocchio will have (balls as x, y, z)."""
    kind = {j["name"]: j["type"] for j in desc.joints}
    out, k = {}, 6
    for name in model.joint_names:
        if kind[name] == "spherical":
            out.update({name + "_x": k, name + "_y": k + 1, name + "_z": k + 2})
            k += 3
        else:
            out[name] = k
            k += 1
    return out


def check_other_readers(desc, path, text):
    """yourdfpy's strict validation passes, but for a `<limit>` without lower/upper on a
    joint the description gives none (Sigmaban's: the URDF spec makes them optional,
    yourdfpy's strict handler does not); urdf_parser_py reads it."""
    yourdfpy = oracle("yourdfpy")
    urdf_parser_py = oracle("urdf_parser_py.urdf")
    robot = yourdfpy.URDF.load(str(path), load_meshes=False, build_scene_graph=False,
                               load_collision_meshes=False)
    unbounded = any(j["type"] == "revolute" and j["lower"] is None for j in desc.joints)
    found = []
    robot.validate(validation_fn=lambda errors: found.extend(errors) or True)
    found = [e for e in found if not (unbounded and ("attribute 'upper'" in str(e) or "attribute 'lower'" in str(e)))]
    assert not found, f"{path.name}: yourdfpy finds it invalid: {found[:3]}"
    urdf_parser_py.URDF.from_xml_string(text.encode())


def check_against_pinocchio(pin, spec, desc, path):
    root = ET.parse(path).getroot()
    assert not any(j.get("type") == "spherical" for j in root.iter("joint"))
    for lim in root.iter("limit"):
        assert lim.get("effort") is not None and lim.get("velocity") is not None
    has_floating = any(j.get("type") == "floating" for j in root.iter("joint"))
    pm = pin.buildModelFromUrdf(str(path)) if has_floating else \
        pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
    pd = pm.createData()
    m = tl.Model.from_description(desc)
    d = tl.Data(m)
    close(f"{spec} total mass", pin.computeTotalMass(pm), m.total_mass)
    qp = pin.neutral(pm)
    q = m.neutral()
    close(f"{spec} CoM", pin.centerOfMass(pm, pd, qp), tl.center_of_mass(m, d, q))
    names = list(pm.names)[2:]  # universe, then the floating base
    parents = {pm.names[j]: pm.names[pm.parents[j]] for j in range(2, pm.njoints)}
    parents = {k: ("" if v == pm.names[1] else v) for k, v in parents.items()}
    assert parents == expected_tree(desc, m), spec
    # The mass matrix at the neutral pose, Pinocchio's armature being 0 in URDF.
    vi = v_index(desc, m)
    arm = {j["name"]: j["armature"] for j in desc.joints}
    cols = list(range(6)) + [vi[n] for n in names]
    ours = np.triu(tl.crba(m, d, q))
    ours = ours + np.triu(ours, 1).T
    theirs = np.triu(pin.crba(pm, pd, qp))
    theirs = theirs + np.triu(theirs, 1).T
    for n in names:
        k = pm.joints[pm.getJointId(n)].idx_v
        theirs[k, k] += arm[n] if n in arm else arm[n[:-2]]  # a ball's x, y, z
    # An MJCF free joint's armature (BXI Elf2's), which the URDF says only in a comment.
    theirs[range(6), range(6)] += desc.base_armature
    if desc.base_armature:
        assert "<!-- the floating base's armature" in path.read_text(), spec
    close(f"{spec} mass matrix", ours[np.ix_(cols, cols)], theirs)
    return len(names)


@pytest.mark.parametrize("spec", ROBOTS, ids=lambda p: str(p).split("/models/")[-1].split("/edges/")[-1])
def test_written_urdf_loads_in_pinocchio_with_the_same_robot(spec, tmp_path):
    pin = oracle("pinocchio")
    desc = tl.load(spec)
    text = desc.to_urdf()
    path = tmp_path / "written.urdf"
    path.write_text(text)
    check_other_readers(desc, path, text)
    check_against_pinocchio(pin, str(spec), desc, path)


def test_ball_joint_written_as_three_revolute_joints(tmp_path):
    desc = tl.load(EDGES / "ball_joints.xml")
    back = tl.Description.from_urdf(desc.to_urdf())
    hips = {j["name"]: j for j in back.joints if j["name"].startswith("left_hip")}
    assert set(hips) == {"left_hip_x", "left_hip_y", "left_hip_z"}
    assert [hips[f"left_hip_{a}"]["axis"] for a in "xyz"] == [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
    assert all(h["type"] == "revolute" and h["lower"] == -math.pi and h["upper"] == math.pi
               for h in hips.values())
    # What the description does not give reads back as not given.
    assert all(h["effort"] is None and h["velocity"] is None for h in hips.values())


def test_model_export_writes_what_pinocchio_loads(tmp_path):
    """The command itself, on a Menagerie humanoid whose joints have no effort or velocity."""
    pin = oracle("pinocchio")
    out = tmp_path / "h1.urdf"
    src = MODELS / "unitree_h1" / "mjcf" / "h1_menagerie.xml"
    subprocess.run([cli(), "model", "export", str(src), "--out", str(out)], check=True,
                   capture_output=True, timeout=120)
    assert check_against_pinocchio(pin, "h1 export", tl.load(src), out) == 19
