#!/usr/bin/env python3
"""MuJoCo's compiled numbers for the MJCF corpus under this folder.

For every MJCF in dm_control's suite and gymnasium's MuJoCo assets (as pip
installs them), this copies the file (and the files it includes) into
`dm_control/` or `gymnasium/` here and writes `reference/<package>/<model>.json`:

- per body (MuJoCo's order, world excluded): name, body_mass, body_ipos,
  body_inertia, body_iquat;
- three seeded random states with the root fixed: qpos and qvel of the joints
  that twinloop models (a free joint on the root body is held at the identity
  pose with zero velocity and left out; a ball joint's quaternion is written
  x, y, z, w, twinloop's order, where MuJoCo's qpos has w first), the joint-space mass matrix
  (`mj_fullM`, same rows), the bias forces (`qfrc_bias`) and every body's
  world pose (`xpos`, `xquat`); with a free root, also the mass matrix and bias
  forces with the root's six dofs first (`floating_mass_matrix`,
  `floating_bias`).

When every top-level body is free-floating (dm_control's quadruped and dog with
their ball), the robot is the one with the most bodies (the first on a tie) and
the others are props, which twinloop leaves out (as it leaves out free trees
beside a larger robot held by the world): `"props"` names their top-level
bodies, their bodies are written with `"left_out": true` and their dofs are held at MuJoCo's qpos0 and left out of the
states. MuJoCo's mass matrix is block diagonal over separate trees and their bias
forces are independent (they interact only through contact), so the robot's rows
and columns are the robot's dynamics whatever the prop does; `state` checks that
the cross blocks are exactly zero.

dm_control's `dog.xml` needs 20 MB of STL bones: its reference is written (with
`"installed": "suite/dog.xml"` and the dm_control version) but the file is not
copied; the Rust test loads it from the installed package (TWINLOOP_DM_CONTROL).

`cargo test` reads only the JSON. Rerun with `python3 make_reference.py`
(needs `pip install mujoco dm_control gymnasium`); the MuJoCo version is
recorded in each file.
"""
import glob
import json
import os
import shutil

import mujoco
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
SEEDS = [1, 2, 3]
# dm_control's dog needs 20 MB of STL bone meshes: too large to commit here, so
# it is compared from the installed package (reference written, file not copied).
INSTALLED_ONLY = {"dog.xml"}


def sources():
    # Imported here so that other scripts can use reference() without them
    # (tools/oracle/robot_mjcf_reference.py).
    import dm_control
    import gymnasium

    dm = os.path.join(os.path.dirname(dm_control.__file__), "suite")
    gym = os.path.join(os.path.dirname(gymnasium.__file__), "envs", "mujoco", "assets")
    for f in sorted(glob.glob(os.path.join(dm, "*.xml"))):
        yield "dm_control", dm, f
    for f in sorted(glob.glob(os.path.join(gym, "*.xml"))):
        yield "gymnasium", gym, f


def copy_tree(package, src_dir, path):
    """The MJCF and its include files (dm_control's common/), as shipped."""
    out = os.path.join(HERE, package)
    os.makedirs(out, exist_ok=True)
    shutil.copy(path, out)
    common = os.path.join(src_dir, "common")
    if os.path.isdir(common):
        os.makedirs(os.path.join(out, "common"), exist_ok=True)
        for f in glob.glob(os.path.join(common, "*.xml")):
            shutil.copy(f, os.path.join(out, "common"))
    return os.path.join(out, os.path.basename(path))


def is_free(m, b):
    return m.body_jntnum[b] == 1 and int(m.jnt_type[m.body_jntadr[b]]) == int(mujoco.mjtJoint.mjJNT_FREE)


def is_empty(m, b):
    """No mass and no joint anywhere in the subtree of body b: nothing to the dynamics."""
    sub = [c for c in range(1, m.nbody) if m.body_rootid[c] == b]
    return all(m.body_mass[c] == 0 and m.body_jntnum[c] == 0 for c in sub)


def props(m):
    """Top-level trees twinloop leaves out (the reader's rule): when every top-level
    body is free, all but the robot (the one with the most bodies, the first on a
    tie); when some are not free and they have more bodies together than the
    largest free tree, every free tree. Returns the set of the props' body ids
    (whole subtrees)."""
    top = [b for b in range(1, m.nbody) if m.body_parentid[b] == 0]
    free = [b for b in top if is_free(m, b)]
    # An empty static body beside a free robot (Apollo's world_link): left out.
    empty = {b for b in top if not is_free(m, b) and is_empty(m, b)} if free else set()
    fixed = [b for b in top if not is_free(m, b) and b not in empty]
    top = [b for b in top if b not in empty]
    if len(top) < 2 or not free:
        return empty
    size = {b: sum(1 for c in range(1, m.nbody) if m.body_rootid[c] == b) for b in top}
    largest = free[0]
    for b in free:
        if size[b] > size[largest]:
            largest = b
    if not fixed:
        robot = {largest}
    elif sum(size[b] for b in fixed) > size[largest]:
        robot = set(fixed)
    else:
        return empty
    return {c for c in range(1, m.nbody) if m.body_rootid[c] not in robot} | empty


def root_free_dofs(m, left_out):
    """Dofs of a free joint on the robot's only top-level body: held fixed."""
    top = [b for b in range(1, m.nbody) if m.body_parentid[b] == 0 and b not in left_out]
    if len(top) == 1 and is_free(m, top[0]):
        j = m.body_jntadr[top[0]]
        return j, m.jnt_qposadr[j], m.jnt_dofadr[j]
    return None


def state(m, seed, free, left_out):
    rng = np.random.default_rng(seed)
    d = mujoco.MjData(m)
    d.qpos[:] = m.qpos0
    keep_q, keep_v = [], []
    for j in range(m.njnt):
        qa, va = m.jnt_qposadr[j], m.jnt_dofadr[j]
        t = int(m.jnt_type[j])
        if m.jnt_bodyid[j] in left_out:
            continue  # a prop: held at qpos0, at rest, left out
        if free is not None and j == free[0]:
            d.qpos[qa:qa + 7] = [0, 0, 0, 1, 0, 0, 0]
            continue
        if t in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)):
            d.qpos[qa] = rng.uniform(-1.0, 1.0)
            d.qvel[va] = rng.uniform(-1.0, 1.0)
            keep_q.append(qa)
            keep_v.append(va)
        else:
            nq = 7 if t == int(mujoco.mjtJoint.mjJNT_FREE) else 4
            nv = 6 if t == int(mujoco.mjtJoint.mjJNT_FREE) else 3
            qr = rng.normal(size=4)
            d.qpos[qa + nq - 4:qa + nq] = qr / np.linalg.norm(qr)
            d.qvel[va:va + nv] = rng.uniform(-1.0, 1.0, nv)
            # The quaternion x, y, z, w (twinloop's q; MuJoCo's qpos has w first).
            keep_q.extend(list(range(qa, qa + nq - 4)) + [qa + nq - 3, qa + nq - 2, qa + nq - 1, qa + nq - 4])
            keep_v.extend(range(va, va + nv))
    mujoco.mj_forward(m, d)
    full = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, full)
    if left_out:
        robot = [v for v in range(m.nv) if m.dof_bodyid[v] not in left_out]
        prop = [v for v in range(m.nv) if m.dof_bodyid[v] in left_out]
        assert not full[np.ix_(robot, prop)].any(), "a prop coupled to the robot"
    floating = {}
    if free is not None:
        # The root free too, at the identity pose and at rest: its dofs first.
        dofs = list(range(free[2], free[2] + 6)) + keep_v
        floating = {
            "floating_mass_matrix": full[np.ix_(dofs, dofs)].tolist(),
            "floating_bias": d.qfrc_bias[dofs].tolist(),
        }
    return floating | {
        "qpos": d.qpos[keep_q].tolist(),
        "qvel": d.qvel[keep_v].tolist(),
        "mass_matrix": full[np.ix_(keep_v, keep_v)].tolist(),
        "bias": d.qfrc_bias[keep_v].tolist(),
        # Springs about springref and damping (frictionloss is a constraint, not here).
        "passive": d.qfrc_passive[keep_v].tolist(),
        "xpos": d.xpos[1:].tolist(),
        "xquat": d.xquat[1:].tolist(),
    }


def reference(m):
    left_out = props(m)
    free = root_free_dofs(m, left_out)
    bodies = []
    for b in range(1, m.nbody):
        bodies.append({
            "name": mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b),
            "mass": float(m.body_mass[b]),
            "ipos": m.body_ipos[b].tolist(),
            "inertia": m.body_inertia[b].tolist(),
            "iquat": m.body_iquat[b].tolist(),
        } | ({"left_out": True} if b in left_out else {}))
    tops = [b for b in sorted(left_out) if m.body_parentid[b] == 0]
    name = lambda b: mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b)  # noqa: E731
    empty = [name(b) for b in tops if not is_free(m, b) and is_empty(m, b)]
    props_ = [name(b) for b in tops if name(b) not in empty]
    named = ({"props": props_} if props_ else {}) | ({"empty_static": empty} if empty else {})
    return named | {
        "mujoco": mujoco.__version__,
        "root_free": free is not None,
        "gravity": m.opt.gravity.tolist(),
        "gravity_disabled": bool(m.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_GRAVITY),
        "nv": int(m.nv),
        "bodies": bodies,
        "states": [state(m, s, free, left_out) for s in SEEDS],
    } | saturation(m)


def saturation(m):
    """With actuators: the joint forces of every control at a huge value, which MuJoCo
    clamps to ctrlrange (times the gear) and forcerange when those are limited."""
    if m.nu == 0:
        return {}
    d = mujoco.MjData(m)
    d.ctrl[:] = 1e6
    mujoco.mj_forward(m, d)
    return {"saturated_actuator_force": d.qfrc_actuator.tolist()}


def fmt(v):
    return " ".join(repr(round(float(x), 6)) for x in v)


def random_orientation(rng):
    """One of MJCF's orientation forms, sometimes exactly at pitch +-90 deg."""
    k = rng.integers(6)
    if k == 0:
        return f'quat="{fmt(rng.normal(size=4))}"'
    if k == 1:
        return f'axisangle="{fmt(rng.normal(size=3))} {round(float(rng.uniform(-3, 3)), 4)}"'
    if k == 2:
        return f'euler="{fmt(rng.uniform(-1.5, 1.5, 3))}"'
    if k == 3:
        return f'xyaxes="{fmt(rng.normal(size=6))}"'
    if k == 4:
        return f'zaxis="{fmt(rng.normal(size=3))}"'
    return 'quat="0.7071067811865476 0 0.7071067811865476 0"'  # pitch +90 deg


def random_geom(rng, group_hi):
    kind = ["sphere", "capsule", "cylinder", "box", "ellipsoid"][rng.integers(5)]
    n = {"sphere": 1, "capsule": 2, "cylinder": 2, "box": 3, "ellipsoid": 3}[kind]
    attrs = [f'type="{kind}"']
    if kind in ("capsule", "cylinder", "box", "ellipsoid") and rng.random() < 0.3:
        a, b = rng.uniform(-0.2, 0.2, 3), rng.uniform(-0.2, 0.2, 3)
        size = rng.uniform(0.02, 0.1, n - 1 if kind != "capsule" and kind != "cylinder" else 1)
        attrs += [f'size="{fmt(size)}"', f'fromto="{fmt(a)} {fmt(b)}"']
    else:
        attrs += [f'size="{fmt(rng.uniform(0.02, 0.15, n))}"', f'pos="{fmt(rng.uniform(-0.2, 0.2, 3))}"']
        if rng.random() < 0.7:
            attrs.append(random_orientation(rng))
    if rng.random() < 0.3:
        attrs.append(f'mass="{round(float(rng.uniform(0.1, 3)), 4)}"')
    elif rng.random() < 0.5:
        attrs.append(f'density="{round(float(rng.uniform(100, 3000)), 2)}"')
    if rng.random() < 0.2:
        attrs.append('shellinertia="true"')
    attrs.append(f'group="{rng.integers(0, group_hi + 1)}"')
    return "<geom " + " ".join(attrs) + "/>"


def open_frame(rng, frames, lines, indent):
    """Sometimes a <frame> (placed, maybe with a childclass) around what follows."""
    if not frames or rng.random() < 0.5:
        return indent, False
    cls = ' childclass="heavy"' if rng.random() < 0.3 else ""
    lines.append(f'{indent}<frame pos="{fmt(rng.uniform(-0.2, 0.2, 3))}" {random_orientation(rng)}{cls}>')
    return indent + "  ", True


def close_frame(opened, lines, indent):
    if opened:
        lines.append(f"{indent[:-2]}</frame>")


def random_joint(rng, name, j, degrees, balls, indent, seen):
    """A hinge or slide (or, in the ball trees, a ball) joint, maybe anchored,
    with a ref and armature. A ball joint has no axis and no ref. `seen` is the
    body's (dofs, ball so far): MuJoCo takes at most 6 dofs in a body and no
    rotation after a ball, so after a ball only slides follow."""
    dofs, ball = seen
    if balls and not ball and dofs <= 3 and rng.random() < 0.4:
        seen[:] = [dofs + 3, True]
        extra = f' pos="{fmt(rng.uniform(-0.1, 0.1, 3))}"' if rng.random() < 0.6 else ""
        extra += f' armature="{round(float(rng.uniform(0, 0.1)), 4)}"' if rng.random() < 0.3 else ""
        return f'{indent}  <joint name="{name}_j{j}" type="ball"{extra}/>'
    kind = "hinge" if rng.random() < 0.7 else "slide"
    if ball:
        kind = "slide"
    seen[0] = dofs + 1
    ref = rng.uniform(-40, 40) if degrees and kind == "hinge" else rng.uniform(-0.7, 0.7)
    extra = f' pos="{fmt(rng.uniform(-0.1, 0.1, 3))}"' if rng.random() < 0.6 else ""
    extra += f' ref="{round(float(ref), 4)}"' if rng.random() < 0.5 else ""
    extra += f' armature="{round(float(rng.uniform(0, 0.1)), 4)}"' if rng.random() < 0.3 else ""
    return f'{indent}  <joint name="{name}_j{j}" type="{kind}" axis="{fmt(rng.normal(size=3))}"{extra}/>'


def random_body(rng, depth, counter, degrees, group_hi, lines, indent, frames=False, balls=False,
                explicit=0.25):
    counter[0] += 1
    name = f"b{counter[0]}"
    cls = ' childclass="heavy"' if rng.random() < 0.2 else ""
    indent, framed = open_frame(rng, frames, lines, indent)
    lines.append(f'{indent}<body name="{name}" pos="{fmt(rng.uniform(-0.3, 0.3, 3))}" '
                 f'{random_orientation(rng)}{cls}>')
    seen = [0, False]
    for j in range(rng.integers(0, 4)):
        lines.append(random_joint(rng, name, j, degrees, balls, indent, seen))
    if rng.random() < explicit:
        if rng.random() < 0.5:
            inertia = f'diaginertia="{fmt(rng.uniform(0.01, 0.02, 3))}" {random_orientation(rng)}'
        else:
            d = rng.uniform(0.02, 0.03, 3)
            inertia = f'fullinertia="{fmt(d)} {fmt(rng.uniform(-0.002, 0.002, 3))}"'
        lines.append(f'{indent}  <inertial pos="{fmt(rng.uniform(-0.1, 0.1, 3))}" '
                     f'mass="{round(float(rng.uniform(0.5, 2)), 4)}" {inertia}/>')
    # At least one geom in group 0 so that every body has mass.
    lines.append(f'{indent}  ' + random_geom(rng, 0))
    inner, opened = open_frame(rng, frames, lines, indent + "  ")
    for _ in range(rng.integers(0, 3)):
        lines.append(f'{inner}' + random_geom(rng, group_hi))
    if frames:
        lines.append(f'{inner}<site name="{name}_s" pos="{fmt(rng.uniform(-0.1, 0.1, 3))}"/>')
    close_frame(opened, lines, inner)
    if depth < 3:
        for _ in range(rng.integers(0, 3)):
            random_body(rng, depth + 1, counter, degrees, group_hi, lines, indent + "  ", frames, balls,
                        explicit)
    lines.append(f"{indent}</body>")
    close_frame(framed, lines, indent)


def generated_model(seed, frames=False, balls=False, nogeom=False):
    """A random tree exercising the compiler: geoms of every primitive type,
    several joints per body with anchors and refs (with `balls`, ball joints
    among them), rotated roots, defaults and childclass, include, and the
    compiler's mass options. With `nogeom` (and balls), `inertiafromgeom="false"`:
    geoms never weigh, and most bodies get an <inertial> (MuJoCo refuses a
    massless moving leaf), so a body without one is massless."""
    rng = np.random.default_rng(1000 + seed + (5000 if frames else 0) + (9000 if balls else 0)
                                + (4000 if nogeom else 0))
    degrees = rng.random() < 0.5
    group_hi = int(rng.integers(0, 5))
    comp = [f'angle="{"degree" if degrees else "radian"}"']
    if rng.random() < 0.5:
        fromgeom = ["true", "auto"][rng.integers(2)]
        if not nogeom:
            comp.append(f'inertiafromgeom="{fromgeom}"')
    if nogeom:
        comp.append('inertiafromgeom="false"')
    if rng.random() < 0.3:
        comp.append(f'inertiagrouprange="0 {rng.integers(0, 4)}"')
    if rng.random() < 0.3:
        comp.append(f'settotalmass="{round(float(rng.uniform(1, 30)), 3)}"')
    if rng.random() < 0.3:
        comp.append(f'boundmass="{round(float(rng.uniform(0.1, 2)), 3)}"')
    if rng.random() < 0.3:
        comp.append(f'boundinertia="{round(float(rng.uniform(0.001, 0.05)), 4)}"')
    if rng.random() < 0.3:
        comp.append('balanceinertia="true"')
    if rng.random() < 0.3:
        comp.append(f'eulerseq="{["zyx", "XYZ", "xzy"][rng.integers(3)]}"')
    defaults = ['<default>',
                f'  <joint armature="{round(float(rng.uniform(0, 0.05)), 4)}" damping="0.1"/>',
                f'  <geom density="{round(float(rng.uniform(300, 1500)), 1)}"/>',
                '  <default class="heavy">',
                '    <geom density="5000"/>',
                '    <joint armature="0.2"/>',
                '  </default>',
                '</default>']
    prefix = "nogeom" if nogeom else "ball" if balls else "framed" if frames else "generated"
    lines = [f'<mujoco model="{prefix}_{seed}">', f'  <compiler {" ".join(comp)}/>']
    include = None
    if rng.random() < 0.4:
        include = [f'<mujoco>'] + ["  " + d for d in defaults] + ['</mujoco>']
        lines.append(f'  <include file="{prefix}_{seed}_defaults.xml"/>')
    else:
        lines += ["  " + d for d in defaults]
    if rng.random() < 0.3:
        lines.append(f'  <option gravity="{fmt(rng.normal(size=3) * 5)}"/>')
    elif rng.random() < 0.2:
        lines.append('  <option><flag gravity="disable"/></option>')
    lines.append("  <worldbody>")
    lines.append('    <geom type="plane" size="5 5 0.1"/>')
    counter = [0]
    for _ in range(1 + (rng.random() < 0.3)):
        random_body(rng, 0, counter, degrees, group_hi, lines, "    ", frames, balls, 0.8 if nogeom else 0.25)
    lines.append("  </worldbody>")
    lines.append("</mujoco>")
    return "\n".join(lines) + "\n", include


GENERATED = 24
FRAMED = 6
BALLS = 6
# Seeds (of the first 60) whose inertiafromgeom="false" tree MuJoCo loads and has a massless
# body: most others leave a moving leaf massless, which MuJoCo refuses.
NOGEOM_SEEDS = [17, 26, 30, 49]
MESH_MODELS = 6
SHELL_MESH_MODELS = 4


def torus(R=0.1, r=0.04, n=16, m=8):
    """A closed torus: not star-shaped, so MuJoCo's legacy volume differs from the exact one."""
    v = []
    for i in range(n):
        for j in range(m):
            a, b = 2 * np.pi * i / n, 2 * np.pi * j / m
            v.append([(R + r * np.cos(b)) * np.cos(a), (R + r * np.cos(b)) * np.sin(a), r * np.sin(b)])
    f = []
    for i in range(n):
        for j in range(m):
            p, q = i * m + j, ((i + 1) % n) * m + j
            p2, q2 = i * m + (j + 1) % m, ((i + 1) % n) * m + (j + 1) % m
            f += [[p, q, q2], [p, q2, p2]]
    return np.array(v), np.array(f)


def blob(rng, n=10, m=7):
    """A closed, lumpy, star-shaped surface (a deformed UV sphere, poles capped)."""
    v = [[0, 0, 0.08]]
    for j in range(1, m):
        for i in range(n):
            a, b = 2 * np.pi * i / n, np.pi * j / m
            rad = 0.08 * (1 + 0.3 * rng.random())
            v.append([rad * np.sin(b) * np.cos(a) * 1.3, rad * np.sin(b) * np.sin(a), rad * np.cos(b)])
    v.append([0, 0, -0.08])
    ring = lambda j, i: 1 + (j - 1) * n + i % n
    f = [[0, ring(1, i), ring(1, i + 1)] for i in range(n)]
    for j in range(1, m - 1):
        for i in range(n):
            f += [[ring(j, i), ring(j + 1, i), ring(j + 1, i + 1)], [ring(j, i), ring(j + 1, i + 1), ring(j, i + 1)]]
    last = len(v) - 1
    f += [[last, ring(m - 1, i + 1), ring(m - 1, i)] for i in range(n)]
    return np.array(v), np.array(f)


def write_stl(path, v, f):
    import struct
    with open(path, "wb") as out:
        out.write(b"twinloop test mesh".ljust(80, b" "))
        out.write(struct.pack("<I", len(f)))
        for t in f:
            out.write(struct.pack("<3f", 0, 0, 0))
            for k in t:
                out.write(struct.pack("<3f", *v[k]))
            out.write(struct.pack("<H", 0))


def write_obj(path, v, f):
    with open(path, "w") as out:
        for p in v:
            out.write(f"v {p[0]:.6f} {p[1]:.6f} {p[2]:.6f}\n")
        for t in f:
            out.write(f"f {t[0] + 1} {t[1] + 1} {t[2] + 1}\n")


def mesh_model(seed, out, shell=False):
    """Bodies whose mass comes from mesh geoms (STL and OBJ, scaled, legacy or
    exact inertia, mass or density) beside primitive geoms. With `shell`
    (`mesh_shell_*`), the meshes' inertia is "shell" (mass on the surface) or
    "convex" (the convex hull's), scaled or not."""
    rng = np.random.default_rng(2000 + seed + (1000 if shell else 0))
    name = f"mesh_shell_{seed}" if shell else f"mesh_{seed}"
    lines = [f'<mujoco model="{name}">',
             '  <compiler angle="radian" meshdir="meshes"/>',
             '  <asset>']
    if shell:
        lines += [f'    <mesh name="torus" file="torus.stl" inertia="shell" scale="{fmt(rng.uniform(0.5, 2, 3))}"/>',
                  '    <mesh name="torus_exact" file="torus.stl" inertia="convex"/>',
                  f'    <mesh name="blob" file="blob.obj" inertia="convex" scale="{fmt(rng.uniform(0.5, 2, 3))}"/>',
                  '    <mesh name="blob_exact" file="blob.obj" inertia="shell"/>']
    else:
        lines += [f'    <mesh name="torus" file="torus.stl" scale="{fmt(rng.uniform(0.5, 2, 3))}"/>',
                  '    <mesh name="torus_exact" file="torus.stl" inertia="exact"/>',
                  f'    <mesh name="blob" file="blob.obj" scale="{fmt(rng.uniform(0.5, 2, 3))}"/>',
                  '    <mesh name="blob_exact" file="blob.obj" inertia="exact"/>']
    lines += ['  </asset>',
              '  <worldbody>']
    indent = "    "
    for b in range(3):
        lines.append(f'{indent}<body name="m{b}" pos="{fmt(rng.uniform(-0.2, 0.2, 3))}" {random_orientation(rng)}>')
        lines.append(f'{indent}  <joint name="m{b}_j" axis="{fmt(rng.normal(size=3))}" pos="{fmt(rng.uniform(-0.1, 0.1, 3))}"/>')
        for _ in range(1 + rng.integers(2)):
            mesh = ["torus", "torus_exact", "blob", "blob_exact"][rng.integers(4)]
            extra = f' mass="{round(float(rng.uniform(0.1, 2)), 4)}"' if rng.random() < 0.4 else ""
            lines.append(f'{indent}  <geom type="mesh" mesh="{mesh}" pos="{fmt(rng.uniform(-0.1, 0.1, 3))}" '
                         f'{random_orientation(rng)}{extra}/>')
        if rng.random() < 0.5:
            lines.append(f'{indent}  ' + random_geom(rng, 0))
        indent += "  "
    for b in range(3):
        indent = indent[:-2]
        lines.append(f"{indent}</body>")
    lines += ["  </worldbody>", "</mujoco>"]
    path = os.path.join(out, f"{name}.xml")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    return path


def write_generated():
    out = os.path.join(HERE, "generated")
    os.makedirs(out, exist_ok=True)
    for f in glob.glob(os.path.join(out, "*.xml")):
        os.remove(f)
    families = [(False, False, False, range(GENERATED)), (True, False, False, range(FRAMED)),
                (False, True, False, range(BALLS)), (False, True, True, NOGEOM_SEEDS)]
    for frames, balls, nogeom, seeds in families:
        prefix = "nogeom" if nogeom else "ball" if balls else "framed" if frames else "generated"
        for seed in seeds:
            text, include = generated_model(seed, frames, balls, nogeom)
            path = os.path.join(out, f"{prefix}_{seed}.xml")
            with open(path, "w") as f:
                f.write(text)
            if include:
                with open(os.path.join(out, f"{prefix}_{seed}_defaults.xml"), "w") as f:
                    f.write("\n".join(include) + "\n")
            yield "generated", out, path
    meshes = os.path.join(out, "meshes")
    os.makedirs(meshes, exist_ok=True)
    write_stl(os.path.join(meshes, "torus.stl"), *torus())
    write_obj(os.path.join(meshes, "blob.obj"), *blob(np.random.default_rng(7)))
    for seed in range(MESH_MODELS):
        yield "generated", out, mesh_model(seed, out)
    for seed in range(SHELL_MESH_MODELS):
        yield "generated", out, mesh_model(seed, out, shell=True)


def dm_control_version():
    from importlib.metadata import version
    return version("dm_control")


def main():
    import sys

    # --generated-only: rewrite the generated trees and their references alone
    # (no dm_control or gymnasium needed; the copied corpus is left as it is).
    # --edges-only: the hand-written edge cases of issue 30 (edges/*.xml) alone.
    if "--edges-only" in sys.argv[1:]:
        edges = os.path.join(HERE, "edges")
        todo = [("edges", edges, f) for f in sorted(glob.glob(os.path.join(edges, "*.xml")))]
    else:
        packages = [] if "--generated-only" in sys.argv[1:] else list(sources())
        todo = packages + list(write_generated())
    for package, src_dir, path in todo:
        name = os.path.basename(path)
        try:
            m = mujoco.MjModel.from_xml_path(path)
        except Exception as e:  # noqa: BLE001 -- MuJoCo refuses it: not in the corpus
            print(f"{package}/{name}: MuJoCo does not load it: {e}")
            continue
        refd = reference(m)
        if name in INSTALLED_ONLY:
            import dm_control
            refd["installed"] = os.path.relpath(path, os.path.dirname(dm_control.__file__))
            refd["dm_control"] = dm_control_version()
        elif package not in ("generated", "edges"):
            copy_tree(package, src_dir, path)
        out = os.path.join(HERE, "reference", package)
        os.makedirs(out, exist_ok=True)
        with open(os.path.join(out, name.replace(".xml", ".json")), "w") as f:
            json.dump(refd, f, separators=(",", ":"))
            f.write("\n")
        print(f"{package}/{name}: {m.nbody - 1} bodies, nv {m.nv}")


if __name__ == "__main__":
    main()
