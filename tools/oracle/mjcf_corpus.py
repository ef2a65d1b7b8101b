#!/usr/bin/env python3
"""The wider MJCF corpus measurement: every *.xml that the installed dm_control
(suite, locomotion, manipulation and third-party assets, test assets),
gymnasium (MuJoCo assets) and pybullet_data ship, through MuJoCo and twinloop.

Run from the repository root:

    pip install mujoco dm_control gymnasium pybullet
    python3 tools/oracle/mjcf_corpus.py [--markdown]

Each file is classified:

- `MuJoCo refuses`: MuJoCo's compiler does not load it (XML schemas, fragments
  meant to be included, files whose meshes or includes are elsewhere, old
  formats). Not part of what twinloop must load.
- `no body`: MuJoCo loads it but it has no body (assets, arenas, templates):
  nothing to compare; twinloop refuses it ("no <body> in <worldbody>").
- `agrees`: twinloop loads it and agrees with MuJoCo's compiled model: per-body
  mass, CoM and inertia (`body_mass`, `body_ipos`, `body_inertia`,
  `body_iquat`), and with the root fixed the mass matrix (`mj_fullM`) and bias
  forces (`qfrc_bias`) at three seeded random states, to 1e-9 relative (with a
  free root also as a floating base). `agrees to 1e-7`: the same to 1e-7, for
  bodies weighed from meshes, whose principal axes MuJoCo finds only to ~1e-8.
- `refused`: twinloop refuses it, naming the element (shown).
- `differs`: twinloop loads it with other numbers (the first difference shown).

The comparison is crates/twinloop-dynamics/tests/mjcf_mujoco.rs's (its ignored
test `installed_mjcf_corpus`, run through cargo with the references this script
writes with make_reference.py's `reference()`), so the measurement and the
committed test check the same things. Not a test: the files are not committed.
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import subprocess
import sys
import tempfile

import mujoco

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(REPO, "crates", "twinloop-description", "tests", "data", "mjcf"))
from make_reference import reference  # noqa: E402


def roots() -> dict[str, str]:
    out = {}
    try:
        import dm_control

        out["dm_control"] = os.path.dirname(dm_control.__file__)
    except ImportError:
        print("dm_control is not installed: left out")
    try:
        import gymnasium

        out["gymnasium"] = os.path.join(os.path.dirname(gymnasium.__file__), "envs", "mujoco", "assets")
    except ImportError:
        print("gymnasium is not installed: left out")
    try:
        import pybullet_data

        out["pybullet_data"] = pybullet_data.getDataPath()
    except ImportError:
        print("pybullet is not installed: pybullet_data left out")
    return out


roots_seen: dict[str, str] = {}


def corpus() -> list[tuple[str, str]]:
    files = []
    roots_seen.update(roots())
    for package, root in roots_seen.items():
        for f in sorted(glob.glob(os.path.join(root, "**", "*.xml"), recursive=True)):
            files.append((f"{package}/{os.path.relpath(f, root)}", f))
    return files


def has_mesh_mass(m) -> bool:
    """Whether a mesh geom counts for a body's inertia (MuJoCo's axes: 1e-7)."""
    return any(int(t) == int(mujoco.mjtGeom.mjGEOM_MESH) for t in m.geom_type)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--markdown", action="store_true", help="print the table for docs/mjcf.md")
    args = ap.parse_args()
    rows = {}
    with tempfile.TemporaryDirectory() as tmp:
        manifest = []
        cwd = os.getcwd()
        os.chdir(tmp)  # MuJoCo writes MUJOCO_LOG.TXT where it runs
        for i, (name, path) in enumerate(corpus()):
            try:
                m = mujoco.MjModel.from_xml_path(path)
            except Exception as e:  # noqa: BLE001 -- MuJoCo's refusal is the verdict
                why = str(e).strip().splitlines()[0]
                for package, root in roots_seen.items():
                    why = why.replace(root, package)
                rows[name] = ("MuJoCo refuses", why[:110])
                continue
            if m.nbody == 1:
                rows[name] = ("no body", "")
                continue
            ref = os.path.join(tmp, f"{i}.json")
            with open(ref, "w") as f:
                json.dump(reference(m), f)
            manifest.append({"name": name, "xml": path, "reference": ref})
            rows[name] = ("?", "mesh" if has_mesh_mass(m) else "")
        os.chdir(cwd)
        with open(os.path.join(tmp, "manifest.json"), "w") as f:
            json.dump(manifest, f)
        run = subprocess.run(
            ["cargo", "test", "--profile", "ci", "-q", "-p", "twinloop-dynamics", "--test", "mjcf_mujoco",
             "--", "--ignored", "--exact", "installed_mjcf_corpus"],
            cwd=REPO, env=os.environ | {"TWINLOOP_MJCF_CORPUS": tmp}, capture_output=True, text=True)
        if run.returncode != 0:
            sys.exit(f"cargo test failed:\n{run.stdout}\n{run.stderr}")
        with open(os.path.join(tmp, "results.json")) as f:
            results = json.load(f)
    worst = {"agrees": 0.0, "agrees to 1e-7": 0.0}
    for r in results:
        v = r["verdict"]
        if v in worst:
            worst[v] = max(worst[v], r["worst"])
            props = [n for n in r.get("notes", []) if n.startswith("<body ")]
            detail = f"left out: {', '.join(props)}" if props else ""
            if v == "agrees to 1e-7":
                detail = ("mesh bodies; " + detail).rstrip("; ")
        elif v == "refused":
            detail = r["detail"].split(": ", 1)[-1]
            detail = detail[detail.find("<"):] if "<" in detail else detail
        else:
            detail = r["detail"]
        rows[r["name"]] = (v, detail[:160])
    counts: dict[str, int] = {}
    for v, _ in rows.values():
        counts[v] = counts.get(v, 0) + 1
    humanoids = [n for n in rows if "humanoid" in os.path.basename(n).lower()]
    compiled = sum(counts.get(k, 0) for k in ("agrees", "agrees to 1e-7", "refused", "differs"))
    agree = counts.get("agrees", 0) + counts.get("agrees to 1e-7", 0)
    if args.markdown:
        # The files that agree outright in one row; every other file in its own.
        plain = sorted(n for n, (v, d) in rows.items() if v == "agrees" and not d)
        nobody = sorted(n for n, (v, _) in rows.items() if v == "no body")
        print("| verdict | files | detail |\n|---|---|---|")
        print(f"| agrees ({len(plain)}) | {', '.join(f'`{n}`' for n in plain)} | |")
        for name in sorted(rows):
            v, d = rows[name]
            if name not in plain and v != "no body":
                print(f"| {v} | `{name}` | {d.replace('|', '/')} |")
        print(f"| no body ({len(nobody)}) | {', '.join(f'`{n}`' for n in nobody)} | |")
    else:
        for name in sorted(rows):
            v, d = rows[name]
            print(f"{v:16} {name}  {d}")
    print(f"\n{len(rows)} files: " + ", ".join(f"{counts[k]} {k}" for k in sorted(counts)))
    print(f"of the {compiled} that MuJoCo compiles into a model with bodies: {agree} load and agree "
          f"({100 * agree / max(compiled, 1):.1f} %); largest relative error {worst['agrees']:.1e} "
          f"(1e-9 files), {worst['agrees to 1e-7']:.1e} (mesh files)")
    hum_ok = [n for n in humanoids if rows[n][0].startswith("agrees")]
    print(f"humanoid files: {len(hum_ok)} of {len(humanoids)} agree; the others: "
          + "; ".join(f"{n} ({rows[n][0]})" for n in humanoids if n not in hum_ok))


if __name__ == "__main__":
    main()
