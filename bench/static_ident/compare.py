#!/usr/bin/env python3
"""Static identification speed: twinloop beside a Python implementation of the same
fit (Pinocchio link placements + scipy.optimize.least_squares,
tools/oracle/static_ident_reference.py), on the same pose files, in one run.

For each robot: the virtual force plate makes 172 poses of the truth (1 mm CoP
noise, 0.1 degree joint noise), then both implementations identify every link with
mass from the prior, repeating the fit (regressor from the poses + constrained
solve) --rounds times; the median is reported, and the two answers are compared.

    cargo build --release -p twinloop-cli
    pip install pin scipy numpy
    python3 bench/static_ident/compare.py [--rounds 20] [--json out.json]

Python runs with OPENBLAS_NUM_THREADS=1: on a small, shared machine OpenBLAS's
threads make scipy's SVDs 30x slower, so single-threaded is Python's best case.
"""
import argparse
import json
import math
import os
import pathlib
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

ROOT = pathlib.Path(__file__).resolve().parents[2]
TWINLOOP = ROOT / "target/release/twinloop"
ORACLE = ROOT / "tools/oracle/static_ident_reference.py"


def coman_truth(path):
    """COMAN with 10 kg the prior does not know of (as in the recovery test)."""
    t = ET.parse(ROOT / "models/coman/coman.urdf")
    extra = {
        "DWYTorso": (4.0, [0.02, 0.0, 0.05]),
        "Waist": (2.0, [-0.02, 0.0, 0.01]),
        "RThighUpLeg": (1.0, [0.0, -0.01, -0.02]),
        "RThighLowLeg": (1.0, [0.01, 0.0, -0.03]),
        "LThighUpLeg": (1.0, [0.0, 0.01, -0.02]),
        "LThighLowLeg": (1.0, [0.01, 0.0, -0.03]),
    }
    for link in t.getroot().findall("link"):
        if link.get("name") in extra:
            dm, dc = extra[link.get("name")]
            i = link.find("inertial")
            m = float(i.find("mass").get("value"))
            o = i.find("origin")
            c = [float(x) for x in o.get("xyz").split()]
            c2 = [(m * c[k] + dm * (c[k] + dc[k])) / (m + dm) for k in range(3)]
            o.set("xyz", " ".join(repr(x) for x in c2))
            i.find("mass").set("value", repr(m + dm))
    t.write(path)


def total_mass(urdf):
    root = ET.parse(urdf).getroot()
    return sum(float(i.find("mass").get("value")) for i in root.iter("inertial"))


def run(cmd, env=None):
    out = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if out.returncode != 0:
        sys.exit(f"failed: {' '.join(map(str, cmd))}\n{out.stderr}")
    return out.stdout


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=20)
    ap.add_argument("--json")
    args = ap.parse_args()
    if not TWINLOOP.exists():
        sys.exit("build first: cargo build --release -p twinloop-cli")
    tmp = pathlib.Path(tempfile.mkdtemp(prefix="twinloop-bench-static-"))
    coman_truth(tmp / "coman_truth.urdf")
    cases = [
        ("Unitree H1 (19 joints)", ROOT / "models/unitree_h1/h1.urdf", ROOT / "models/unitree_h1/variants/h1_2025-06_a3b70ca.urdf"),
        ("COMAN + 10 kg (29 joints)", tmp / "coman_truth.urdf", ROOT / "models/coman/coman.urdf"),
    ]
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    rows = []
    for name, truth, prior in cases:
        poses = tmp / (truth.stem + "_poses.csv")
        run([TWINLOOP, "experiment", "static-poses", "--robot", truth, "--count", "172", "--cop-noise", "0.001",
             "--joint-noise", str(math.radians(0.1)), "--seed", "3", "--out", poses])
        m = total_mass(truth)
        out_json = tmp / (truth.stem + "_twinloop.json")
        run([TWINLOOP, "identify", "static", "--robot", prior, "--poses", poses, "--total-mass", repr(m),
             "--suggest", "0", "--time", str(args.rounds), "--json", out_json])
        tw = json.loads(out_json.read_text())
        ref_json = tmp / (truth.stem + "_python.json")
        py_out = run([sys.executable, ORACLE, "--urdf", prior, "--poses", poses, "--total-mass", repr(m),
                      "--bench", str(args.rounds), "--out", ref_json], env=env)
        py_time = json.loads(py_out.splitlines()[0])["fit_seconds_median"]
        ref = json.loads(ref_json.read_text())
        dm = max(abs(a["mass"] - b["mass"]) for a, b in zip(ref["links"], tw["result"]["links"]))
        dc = max(abs(p - q) for a, b in zip(ref["links"], tw["result"]["links"]) for p, q in zip(a["com"], b["com"]))
        t = tw["fit_seconds_median"]
        rows.append({
            "robot": name, "links": len(ref["links"]), "unknowns": 4 * len(ref["links"]), "poses": 172,
            "twinloop_ms": t * 1e3, "python_ms": py_time * 1e3, "ratio": t / py_time,
            "max_mass_difference_kg": dm, "max_com_difference_m": dc,
            "gcom_before_mm": tw["result"]["before"]["mean"] * 1e3, "gcom_after_mm": tw["result"]["after"]["mean"] * 1e3,
        })
    print("| robot | links (unknowns) | twinloop fit ms | Pinocchio + scipy ms | ratio | largest difference (mass, CoM) |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['robot']} | {r['links']} ({r['unknowns']}) | {r['twinloop_ms']:.3f} | {r['python_ms']:.1f} | "
              f"**{r['ratio']:.4f}** | {r['max_mass_difference_kg']:.1e} kg, {r['max_com_difference_m']:.1e} m |")
    if args.json:
        pathlib.Path(args.json).write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main()
