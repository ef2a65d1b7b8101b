#!/usr/bin/env python3
"""MuJoCo's compiled numbers for the robot MJCFs under models/ (the Menagerie humanoids
the repository ships, and G1 and H1 as Unitree ship them).

For each robot MJCF in models/*/mjcf/ (scene files only include them), this
writes crates/twinloop-dynamics/tests/data/mujoco_models/<name>.json in the
format of crates/twinloop-description/tests/data/mjcf/make_reference.py (whose
`reference()` it calls): per body MuJoCo's `body_mass`, `body_ipos`,
`body_inertia`, `body_iquat`; at three seeded states with the free root held at
the identity, `mj_fullM` and `qfrc_bias` (also with the root free) and every
body's world pose; each joint's actuator force limit (`force_limits`).

The mesh files these MJCFs name are not in the repository (the Menagerie and
Unitree asset folders are 17-22 MB each), and MuJoCo refuses a model whose mesh
file is missing. So each model is compiled with its mesh assets and mesh geoms
removed. That cannot change a body's mass, CoM or inertia when every body has
an explicit `<inertial>` and the compiler does not say `inertiafromgeom="true"`
(MuJoCo then ignores geoms for inertia); the script checks both, and checks
that the stripped model's `body_mass` and `body_ipos` are the `<inertial>`
`mass` and `pos` written in the file. Where mesh files of the same robot are
available it also compiles the model with them and requires every number
written (masses, inertias, mass matrices, bias forces) to be identical:

- G1 (both MJCFs): the decimated meshes committed in models/unitree_g1/
  meshes_decimated/ (same file names), and Unitree's full meshes in
  shared/models/unitree_g1/meshes/ when that folder exists;
- H1 (both MJCFs): Unitree's meshes in shared/models/unitree_h1/meshes/
  h1_description/meshes/ when that folder exists (file names matched without
  regard to case: the Menagerie file writes `pelvis.stl`, Unitree ships
  `pelvis.STL`);
- the Menagerie humanoids (Cassie, Apollo, Berkeley Humanoid, T1, N1, Adam Lite,
  ToddlerBot 2xc and 2xm, Atlas, BXI Elf2, LimX Oli and Luna, Open Duck Mini v2):
  their `assets/` folders in a Menagerie checkout given as `--menagerie DIR`
  (DIR/<robot>/assets, the folder names under models/ being Menagerie's), when
  every mesh file the model names is there;
- OP3 and TALOS: no mesh files are available (see their SOURCE.md).

Texture files are not in the repository either: they are dropped with the meshes
(a texture has no mass), and from the file compiled with meshes.

A body with no `<inertial>` is accepted only when it has no geom (Apollo's empty static
`world_link`, Open Duck Mini v2's free root `base`): MuJoCo compiles it massless, and the
script checks that.

Which mesh sets were compiled and found equal is recorded in each JSON
(`meshes`). Run from anywhere:

    pip install mujoco==4.0.0 numpy
    python3 tools/oracle/robot_mjcf_reference.py [--shared /work/shared/models] [--menagerie DIR] [ROBOT ...]

ROBOT (a folder name under models/) limits the run to those robots.
"""
import argparse
import copy
import glob
import json
import os
import shutil
import sys
import tempfile
import xml.etree.ElementTree as ET

import mujoco
import numpy as np

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(REPO, "crates", "twinloop-description", "tests", "data", "mjcf"))
from make_reference import reference  # noqa: E402

OUT = os.path.join(REPO, "crates", "twinloop-dynamics", "tests", "data", "mujoco_models")

# Mesh folders of the same robot: (description, path relative to the repo or to --shared).
MESH_SETS = {
    "unitree_g1": [("decimated meshes committed in models/unitree_g1/meshes_decimated", "repo",
                    "models/unitree_g1/meshes_decimated"),
                   ("Unitree's meshes, shared/models/unitree_g1/meshes", "shared", "unitree_g1/meshes")],
    "unitree_h1": [("Unitree's meshes, shared/models/unitree_h1/meshes/h1_description/meshes", "shared",
                    "unitree_h1/meshes/h1_description/meshes")],
}
MENAGERIE = ["agility_cassie", "apptronik_apollo", "berkeley_humanoid", "booster_t1", "fourier_n1",
             "pndbotics_adam_lite", "toddlerbot_2xc", "toddlerbot_2xm", "atlas", "bxi_elf2",
             "limx_oli", "limx_luna", "open_duck_mini_v2"]
for _robot in MENAGERIE:
    MESH_SETS[_robot] = [(f"Menagerie's meshes, {_robot}/assets", "menagerie", f"{_robot}/assets")]


def robot_files():
    files = sorted(glob.glob(os.path.join(REPO, "models", "*", "mjcf", "*.xml")))
    return [f for f in files if os.path.basename(f) != "scene.xml"]


def name_of(path):
    robot = os.path.basename(os.path.dirname(os.path.dirname(path)))
    return f"{robot}_{os.path.splitext(os.path.basename(path))[0]}"


def strip_textures(root):
    """Drop texture files (not in the repository; a texture weighs nothing)."""
    for asset in root.iter("asset"):
        for tex in list(asset.findall("texture")):
            if "file" in tex.attrib:
                asset.remove(tex)
                for mat in asset.findall("material"):
                    if mat.get("texture") == tex.get("name"):
                        del mat.attrib["texture"]


def strip_meshes(text):
    """The MJCF without its mesh assets, the geoms that use them (and the contact pairs
    that name those geoms), and texture files."""
    root = ET.fromstring(text)
    strip_textures(root)
    for asset in root.iter("asset"):
        for mesh in list(asset.findall("mesh")):
            asset.remove(mesh)
    removed = 0
    names = set()
    for parent in root.find("worldbody").iter():
        for geom in list(parent.findall("geom")):
            if "mesh" in geom.attrib or geom.get("type") == "mesh":
                parent.remove(geom)
                removed += 1
                names.add(geom.get("name"))
    # A contact <pair> naming a removed geom (ToddlerBot's mesh soles) would not
    # compile; a pair has no mass, so it goes with its geom.
    for contact in root.iter("contact"):
        for pair in list(contact.findall("pair")):
            if pair.get("geom1") in names or pair.get("geom2") in names:
                contact.remove(pair)
    # A default `<geom type="mesh">` would make a primitive geom without a type a
    # mesh geom; no geom is left that relies on it, but drop it all the same.
    for default in root.iter("default"):
        for geom in default.findall("geom"):
            if geom.get("type") == "mesh":
                del geom.attrib["type"]
    return ET.tostring(root, encoding="unicode"), removed


def check_explicit_inertials(path, text, m):
    """Every body has an <inertial>, geoms are not asked to override it, and the
    compiled masses and CoMs are the file's: removing geoms changed nothing."""
    root = ET.fromstring(text)
    for comp in root.iter("compiler"):
        assert comp.get("inertiafromgeom", "auto") != "true", f"{path}: inertiafromgeom=true"
    bodies = list(root.find("worldbody").iter("body"))
    assert len(bodies) == m.nbody - 1, f"{path}: {len(bodies)} bodies vs {m.nbody - 1}"
    for b in bodies:
        name = b.get("name")
        inertial = b.find("inertial")
        i = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, name)
        assert i > 0, f"{path}: body {name}"
        if inertial is None:
            # Only a body without geoms may go without: nothing to weigh (Apollo's empty
            # static world_link, Open Duck Mini's free root holding only a joint and a site).
            assert b.find("geom") is None, f"{path}: body {name} has no <inertial>"
            assert m.body_mass[i] == 0.0, f"{path}: {name} mass {m.body_mass[i]}"
            continue
        mass = float(inertial.get("mass"))
        assert m.body_mass[i] == mass, f"{path}: {name} mass {m.body_mass[i]} vs {mass}"
        pos = np.array([float(x) for x in inertial.get("pos").split()])
        assert np.allclose(m.body_ipos[i], pos, rtol=0, atol=1e-15), f"{path}: {name} ipos"
    return len(bodies)


def mesh_dir(source, names):
    """A folder holding each mesh file the model names (matched without regard to
    case), or None when one is missing."""
    present = {f.lower(): os.path.join(source, f) for f in os.listdir(source)}
    tmp = tempfile.mkdtemp(prefix="twinloop_meshes_")
    for f in sorted(set(names)):  # Cassie's left and right meshes share files
        src = present.get(os.path.basename(f).lower())
        if src is None:
            shutil.rmtree(tmp)
            return None
        os.makedirs(os.path.dirname(os.path.join(tmp, f)), exist_ok=True)
        os.symlink(src, os.path.join(tmp, f))
    return tmp


def with_meshes(text, meshes):
    """Compile the original file with its meshdir pointed at `meshes`."""
    root = ET.fromstring(text)
    strip_textures(root)
    spec = mujoco.MjSpec.from_string(ET.tostring(root, encoding="unicode"))
    spec.meshdir = meshes
    return spec.compile()


def force_limits(m):
    """Each joint's actuator force limit as MuJoCo applies it: `qfrc_actuator` with every
    control at 1e6, where a position or velocity actuator (an affine bias) has its bias
    and its control range taken away, so that what is left is the clamp of its
    `forcerange` and the joint's `actuatorfrcrange` (kp times a control within its
    range at one pose would be a pose's force, not a limit). A motor keeps its
    control range: gear times the largest control is its limit."""
    m = copy.deepcopy(m)
    for a in range(m.nu):
        if m.actuator_biastype[a] != mujoco.mjtBias.mjBIAS_NONE:
            m.actuator_biasprm[a, :] = 0.0
            m.actuator_ctrllimited[a] = 0
    d = mujoco.MjData(m)
    d.ctrl[:] = 1e6
    mujoco.mj_forward(m, d)
    return d.qfrc_actuator.tolist()


def summary(path, m):
    """The summary.json entry of a Menagerie folder added in issue 30, from MuJoCo's
    compiled model (the fields crates/twinloop-description/tests/mjcf_models.rs reads,
    as the shared collection's summaries have them): bodies (the world left out),
    joints by type, the inertials' total mass, hinges MuJoCo limits (with `range`
    given in the file or its default classes, `autolimits`), and the empty static
    bodies (no joint, no geom, no mass) MuJoCo welds to the world."""
    kinds = {0: "free", 1: "ball", 2: "slide", 3: "hinge"}
    by_type = {}
    for t in m.jnt_type:
        by_type[kinds[int(t)]] = by_type.get(kinds[int(t)], 0) + 1
    hinge = m.jnt_type == mujoco.mjtJoint.mjJNT_HINGE
    names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, i) for i in range(m.nbody)]
    empty = [names[i] for i in range(1, m.nbody)
             if m.body_jntnum[i] == 0 and m.body_geomnum[i] == 0 and m.body_mass[i] == 0
             and m.body_parentid[i] == 0]
    return {
        "format": "MJCF",
        "model": os.path.basename(path),
        "source": "tools/oracle/robot_mjcf_reference.py (MuJoCo %s, mesh geoms removed)" % mujoco.__version__,
        "n_bodies": int(m.nbody - 1),
        "joints_by_type": by_type,
        "total_mass_kg_from_inertial": float(m.body_mass.sum()),
        "joints_with_range_attr": int((m.jnt_limited.astype(bool) & hinge).sum()),
        "empty_static_bodies": empty,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shared", default=os.path.join(os.path.dirname(REPO), "shared", "models"),
                    help="the shared model collection (for the full Unitree meshes), if present")
    ap.add_argument("--menagerie", default=None,
                    help="a MuJoCo Menagerie checkout, for the humanoids' own meshes")
    ap.add_argument("robots", nargs="*", help="folder names under models/ (default: all)")
    args = ap.parse_args()
    os.makedirs(OUT, exist_ok=True)
    for path in robot_files():
        name = name_of(path)
        robot = os.path.basename(os.path.dirname(os.path.dirname(path)))
        if args.robots and robot not in args.robots:
            continue
        text = open(path).read()
        stripped, removed = strip_meshes(text)
        m = mujoco.MjModel.from_xml_string(stripped)
        nbodies = check_explicit_inertials(path, text, m)
        ref = reference(m)
        mesh_files = [el.get("file") for el in ET.fromstring(text).iter("mesh") if el.get("file")]
        compiled = []
        for what, where, rel in MESH_SETS.get(robot, []):
            base = {"repo": REPO, "shared": args.shared, "menagerie": args.menagerie}[where]
            source = os.path.join(base, rel) if base else ""
            if not os.path.isdir(source):
                print(f"{name}: {what}: not here, skipped")
                continue
            tmp = mesh_dir(source, mesh_files)
            if tmp is None:
                print(f"{name}: {what}: a mesh file is missing, skipped")
                continue
            try:
                full = with_meshes(text, tmp)
            finally:
                shutil.rmtree(tmp)
            assert full.nmesh == len(mesh_files) and full.nbody == m.nbody
            assert full.ngeom == m.ngeom + removed, f"{name}: mesh geoms"
            theirs = reference(full)
            assert theirs == ref, f"{name}: the numbers with {what} differ from the stripped model's"
            compiled.append(what)
        ref["actuator_force_limit"] = force_limits(m)
        ref["source_file"] = os.path.relpath(path, REPO)
        ref["meshes"] = {
            "mesh_assets_in_file": len(mesh_files),
            "mesh_geoms_removed_to_compile": removed,
            "every_body_has_inertial": all(b.find("inertial") is not None
                                           for b in ET.fromstring(text).find("worldbody").iter("body")),
            "compiled_with_meshes_and_identical": compiled,
        }
        if robot in MENAGERIE:
            summary_path = os.path.join(REPO, "models", robot, "summary.json")
            key = os.path.relpath(path, os.path.join(REPO, "models", robot))
            entries = json.load(open(summary_path)) if os.path.exists(summary_path) else {}
            entries[key] = summary(path, m)
            with open(summary_path, "w") as f:
                json.dump(entries, f, indent=1, sort_keys=True)
                f.write("\n")
        with open(os.path.join(OUT, f"{name}.json"), "w") as f:
            json.dump(ref, f, separators=(",", ":"))
            f.write("\n")
        print(f"{name}: {nbodies} bodies, nv {m.nv}, total mass {m.body_mass.sum():.6f} kg, "
              f"{removed} mesh geoms removed; identical with meshes: {compiled or 'none available'}")


if __name__ == "__main__":
    main()
