#!/usr/bin/env python3
"""twinloop vs Pinocchio, same model, same states, same machine, same run.

    python3 bench/compare_dynamics.py [--count 500] [--rounds 3] [--out BENCHMARKS.table.md]

For each model: writes a states CSV (bench/pinocchio/make_states.py), runs the
Pinocchio C++ bench (bench/pinocchio/build/, built by bench/pinocchio/build.sh) and
`twinloop bench dynamics` on that file, alternating them --rounds times so machine
load hits both alike, and prints the median ns per call and the ratio
twinloop / Pinocchio per algorithm as a Markdown table.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MODELS = [
    ("OP3", "models/op3/robotis_op3.nomesh.urdf"),
    ("G1", "models/unitree_g1/g1_29dof_rev_1_0.nomesh.urdf"),
    ("H1", "models/unitree_h1/h1.nomesh.urdf"),
    ("TALOS (MJCF)", "models/talos/mjcf/talos.xml"),
]
ALGOS = ["fk", "com", "rnea", "crba", "aba", "jacobians", "regressor"]


def run_json(cmd):
    out = subprocess.run(cmd, check=True, capture_output=True, text=True, cwd=ROOT).stdout
    return json.loads(out)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--count", type=int, default=500)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--pinocchio", default=os.path.join(ROOT, "bench/pinocchio/build/bench_pinocchio"))
    ap.add_argument("--twinloop", default=os.path.join(ROOT, "target/release/twinloop"))
    ap.add_argument("--out")
    args = ap.parse_args()
    lines = []
    head = "| model | nv | " + " | ".join(ALGOS) + " |"
    lines.append(head)
    lines.append("|" + "---|" * (len(ALGOS) + 2))
    with tempfile.TemporaryDirectory() as tmp:
        for label, path in MODELS:
            states = os.path.join(tmp, "states.csv")
            subprocess.run([sys.executable, "bench/pinocchio/make_states.py", path, states, "--count", str(args.count)],
                           check=True, capture_output=True, cwd=ROOT)
            ours, theirs = {a: [] for a in ALGOS}, {a: [] for a in ALGOS}
            nv = None
            for _ in range(args.rounds):
                p = run_json([args.pinocchio, path, states])
                t = run_json([args.twinloop, "bench", "dynamics", "--urdf", path, "--states", states, "--json"])
                nv = t["nv"]
                for a in ALGOS:
                    theirs[a].append(p["ns_per_call"][a])
                    ours[a].append(t["ns_per_call"][a])
            cells = []
            for a in ALGOS:
                o, p = statistics.median(ours[a]), statistics.median(theirs[a])
                cells.append(f"{o:.0f} / {p:.0f} = **{o / p:.2f}**")
            lines.append(f"| {label} | {nv} | " + " | ".join(cells) + " |")
            print(lines[-1], file=sys.stderr)
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out:
        with open(args.out, "w") as f:
            f.write(text)


if __name__ == "__main__":
    main()
