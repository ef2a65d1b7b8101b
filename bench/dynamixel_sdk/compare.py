#!/usr/bin/env python3
"""Side-by-side markdown tables of `twinloop bench link --json FILE` and bench_sdk.py --json runs:
per case, the median over runs of each run's median."""

import argparse
import json
import statistics


def load(paths):
    runs = [json.load(open(p))["cases"] for p in paths]
    names = [c["name"] for c in runs[0]]
    out = {}
    for name in names:
        cs = [c for run in runs for c in run if c["name"] == name]
        us = statistics.median(c["median_us"] for c in cs)
        cpu = [c["cpu_us"] for c in cs if c.get("cpu_us") is not None]
        out[name] = {"median_us": us, "per_second": 1e6 / us, "wire_us": cs[0].get("wire_us"),
                     "cpu_us": statistics.median(cpu) if cpu else None,
                     "best_us": min(c["median_us"] for c in cs),
                     "runs": [round(c["median_us"], 1) for c in cs]}
    return names, out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--ours", nargs="+", required=True)
    ap.add_argument("--sdk", nargs="+", required=True)
    a = ap.parse_args()
    names, ours = load(a.ours)
    _, sdk = load(a.sdk)
    print(f"{len(a.ours)} runs each; per-run medians in brackets\n")
    print("| software per transaction (replies replayed from memory) | twinloop (us) | SDK (us) | SDK / twinloop |")
    print("|---|---|---|---|")
    for n in names:
        if n in sdk and n.startswith("replay:"):
            o, s = ours[n], sdk[n]
            print(f"| {n[8:]} | {o['median_us']:.2f} | {s['median_us']:.1f} | {s['median_us'] / o['median_us']:.0f}x |")
    print()
    print("| over the pty, same served robot | twinloop wall (us) | SDK wall (us) | wall ratio | best-run ratio | twinloop CPU (us) | SDK CPU (us) | CPU ratio |")
    print("|---|---|---|---|---|---|---|---|")
    for n in names:
        if n in sdk and n.startswith("pty:"):
            o, s = ours[n], sdk[n]
            print(f"| {n[5:]} | {o['median_us']:.1f} {o['runs']} | {s['median_us']:.1f} {s['runs']} | "
                  f"{s['median_us'] / o['median_us']:.1f}x | {s['best_us']:.1f} / {o['best_us']:.1f} = {s['best_us'] / o['best_us']:.1f}x | "
                  f"{o['cpu_us']:.1f} | {s['cpu_us']:.1f} | "
                  f"{s['cpu_us'] / o['cpu_us']:.1f}x |")
    print()
    print("| software cost of one control cycle (no wire) | median (us) | wire time at 1 Mbps (us) | overhead / wire |")
    print("|---|---|---|---|")
    for n in names:
        o = ours[n]
        if o["wire_us"]:
            print(f"| {n[10:]} | {o['median_us']:.2f} | {o['wire_us']:.0f} | {100 * o['median_us'] / o['wire_us']:.3f} % |")


if __name__ == "__main__":
    main()
