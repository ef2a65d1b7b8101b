#!/usr/bin/env python3
"""Run the Pinocchio peer benchmark and the twinloop benchmark on the same states; print a table.

    python3 bench/pinocchio/compare.py MODEL_FILE [MODEL_FILE ...] [--states-dir DIR]
        [--count 1000] [--seed 0] [--rounds N] [--twinloop PATH | --no-twinloop] [--json OUT]

For each model: writes DIR/<stem>.csv with make_states.py (unless it exists), runs
build/bench_pinocchio and build/bench_pinocchio_native (those that were built) and
`twinloop bench dynamics --robot FILE --states CSV --json -` (--robot takes MJCF files too), then prints the
median ns per call of each and the ratio twinloop / Pinocchio. The twinloop JSON is expected to
carry an `ns_per_call` object with the same algorithm keys (fk, com, rnea, crba, aba, jacobians,
regressor); keys it lacks are shown as "-". PATH defaults to target/release/twinloop.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))
ALGOS = ["fk", "com", "rnea", "crba", "aba", "jacobians", "regressor"]


def run_json(cmd):
    print("+ " + " ".join(cmd), file=sys.stderr)
    res = subprocess.run(cmd, capture_output=True, text=True)
    if res.returncode != 0:
        print(res.stderr, file=sys.stderr)
        return None
    text = res.stdout
    start = text.find("{")
    while start != -1:  # first JSON object in the output (one line or pretty-printed)
        try:
            return json.JSONDecoder().raw_decode(text[start:])[0]
        except json.JSONDecodeError:
            start = text.find("{", start + 1)
    print(f"no JSON in output of {cmd[0]}:\n{text}", file=sys.stderr)
    return None


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("models", nargs="+")
    ap.add_argument("--states-dir", default=os.path.join(HERE, "build", "states"))
    ap.add_argument("--count", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--rounds", type=int, default=None)
    ap.add_argument("--twinloop", default=os.path.join(REPO, "target", "release", "twinloop"))
    ap.add_argument("--no-twinloop", action="store_true")
    ap.add_argument("--json", help="also write all results to this file")
    args = ap.parse_args(argv)

    os.makedirs(args.states_dir, exist_ok=True)
    peers = [(name, os.path.join(HERE, "build", name))
             for name in ("bench_pinocchio", "bench_pinocchio_native")]
    peers = [(n, p) for n, p in peers if os.path.exists(p)]
    if not peers:
        sys.exit("compare: no binary in bench/pinocchio/build: run bench/pinocchio/build.sh")

    everything = []
    for model in args.models:
        stem = os.path.splitext(os.path.basename(model))[0]
        states = os.path.join(args.states_dir, f"{stem}.csv")
        if not os.path.exists(states):
            subprocess.run([sys.executable, os.path.join(HERE, "make_states.py"), model, states,
                            "--count", str(args.count), "--seed", str(args.seed)], check=True)
        extra = ["--rounds", str(args.rounds)] if args.rounds else []
        results = {}
        for name, path in peers:
            results[name] = run_json([path, model, states] + extra)
        if not args.no_twinloop:
            if os.path.exists(args.twinloop):
                results["twinloop"] = run_json([args.twinloop, "bench", "dynamics", "--robot", model,
                                                "--states", states, "--json", "-"])
            else:
                print(f"compare: {args.twinloop} not found (cargo build --release); "
                      "twinloop column skipped", file=sys.stderr)
        everything.append({"model": model, "states": states, "results": results})

        cols = [k for k, v in results.items() if v]
        nv = next((v.get("nv") for v in results.values() if v), "?")
        print(f"\n{stem} (nv={nv}), median ns per call")
        hdr = ["algorithm"] + cols
        if "twinloop" in cols:
            hdr += [f"twinloop/{c}" for c in cols if c != "twinloop"]
        print("| " + " | ".join(hdr) + " |")
        print("|" + "---|" * len(hdr))
        for algo in ALGOS:
            vals = {c: (results[c].get("ns_per_call") or {}).get(algo) for c in cols}
            row = [algo] + [f"{vals[c]:.0f}" if vals[c] is not None else "-" for c in cols]
            if "twinloop" in cols:
                t = vals["twinloop"]
                for c in cols:
                    if c == "twinloop":
                        continue
                    row.append(f"{t / vals[c]:.2f}" if t and vals[c] else "-")
            print("| " + " | ".join(row) + " |")

    if args.json:
        with open(args.json, "w") as fh:
            json.dump(everything, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
