#!/usr/bin/env python3
"""MuJoCo's compiled masses for mesh inertia="shell" and inertia="convex".

Run from the repository root (needs `pip install mujoco numpy`):

    python3 tools/oracle/mesh_inertia_reference.py

Writes crates/twinloop-description/tests/data/mjcf/mesh_inertia/mesh_inertia.xml:
bodies weighed from the corpus's torus STL and lumpy OBJ (../generated/meshes)
counted as a shell (mass on the surface) or as their convex hull, scaled, placed
and rotated, alone and mixed with a primitive; and reference.json with MuJoCo's
body_mass, body_ipos, body_inertia and body_iquat per body (body frame).
Deterministic (numpy default_rng).
"""

import json
import os

import mujoco
import numpy as np

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
OUT = os.path.join(REPO, "crates", "twinloop-description", "tests", "data", "mjcf", "mesh_inertia")
SEED = 20261125


def fmt(x):
    return " ".join(f"{v:.6f}" for v in np.atleast_1d(x))


def model(rng) -> str:
    assets = []
    for mesh, ext in [("torus", "stl"), ("blob", "obj")]:
        for how in ["shell", "convex"]:
            assets.append(
                f'    <mesh name="{mesh}_{how}" file="{mesh}.{ext}" inertia="{how}" '
                f'scale="{fmt(rng.uniform(0.5, 2.0, 3))}"/>'
            )
    bodies = []
    names = ["torus_shell", "torus_convex", "blob_shell", "blob_convex"]
    for k, mesh in enumerate(names):
        how = "mass" if k % 2 else "density"
        amount = f'{rng.uniform(0.1, 2.0):.6f}' if how == "mass" else f'{rng.uniform(500, 3000):.3f}'
        bodies.append(
            f'    <body name="{mesh}" pos="{fmt(rng.uniform(-1, 1, 3))}">\n'
            f'      <joint name="{mesh}_j" axis="0 0 1"/>\n'
            f'      <geom type="mesh" mesh="{mesh}" pos="{fmt(rng.uniform(-0.1, 0.1, 3))}" '
            f'euler="{fmt(rng.uniform(-1, 1, 3))}" {how}="{amount}"/>\n'
            f"    </body>"
        )
    bodies.append(
        '    <body name="mixed" pos="0 0 0.5">\n'
        '      <joint name="mixed_j" axis="1 0 0"/>\n'
        f'      <geom type="mesh" mesh="torus_convex" pos="{fmt(rng.uniform(-0.1, 0.1, 3))}" euler="{fmt(rng.uniform(-1, 1, 3))}"/>\n'
        f'      <geom type="mesh" mesh="blob_shell" pos="{fmt(rng.uniform(-0.1, 0.1, 3))}" density="900"/>\n'
        f'      <geom type="box" size="0.05 0.02 0.03" pos="{fmt(rng.uniform(-0.1, 0.1, 3))}"/>\n'
        "    </body>"
    )
    return "\n".join(
        [
            '<mujoco model="mesh_inertia">',
            '  <compiler angle="radian" meshdir="../generated/meshes"/>',
            "  <asset>",
            *assets,
            "  </asset>",
            "  <worldbody>",
            *bodies,
            "  </worldbody>",
            "</mujoco>",
            "",
        ]
    )


def main():
    os.makedirs(OUT, exist_ok=True)
    path = os.path.join(OUT, "mesh_inertia.xml")
    with open(path, "w") as f:
        f.write(model(np.random.default_rng(SEED)))
    m = mujoco.MjModel.from_xml_path(path)
    bodies = [
        {
            "name": mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b),
            "mass": float(m.body_mass[b]),
            "ipos": m.body_ipos[b].tolist(),
            "inertia": m.body_inertia[b].tolist(),
            "iquat": m.body_iquat[b].tolist(),
        }
        for b in range(1, m.nbody)
    ]
    with open(os.path.join(OUT, "reference.json"), "w") as f:
        json.dump({"mujoco": mujoco.__version__, "bodies": bodies}, f, indent=1)
    for b in bodies:
        print(b["name"], b["mass"])


if __name__ == "__main__":
    main()
