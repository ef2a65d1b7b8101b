#!/usr/bin/env python3
"""Run `twinloop demo` over many hidden changes and tabulate what the bus path finds.

Each run serves a km20 with a hidden change on a pty and adapts it over the bus
exactly as the README's first command does; this collects, per run, the change, the
adapted CoM's and the part's distance from the truth, and the four fall angles
(measured over the bus, adapted and true models at the robot's onsets). The table
in docs/adaptation.md comes from it.

    python3 tools/adaptation/demo_sweep.py --seeds 1-12 [--tell-where] [--scenarios a,c,d,e,f]
        [--twinloop target/release/twinloop] [--out sweep.json] [--keep DIR] [--check] [--goal-counts dithered|staircase]
        [--protocol-passes N]

With --check each demo also measures the adapted model's simulation over the bus by
the same protocol (`demo --check`), and the table gives it minus the robot's angles.
"""
import argparse, json, os, statistics, subprocess, sys, tempfile, time


def seeds(spec):
    out = []
    for part in spec.split(","):
        if "-" in part:
            a, b = part.split("-")
            out += range(int(a), int(b) + 1)
        elif part:
            out.append(int(part))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", default="1-12")
    ap.add_argument("--scenarios", default="")
    ap.add_argument("--tell-where", action="store_true")
    ap.add_argument("--twinloop", default="target/release/twinloop")
    ap.add_argument("--out", default=None)
    ap.add_argument("--keep", default=None, help="keep each run's files in DIR/<job>")
    ap.add_argument("--check", action="store_true", help="demo --check: the adapted simulation over the bus")
    ap.add_argument("--goal-counts", choices=["dithered", "staircase"],
                    help="demo --goal-counts (the demo's default when not given)")
    ap.add_argument("--protocol-passes", type=int, default=None,
                    help="demo --protocol-passes N (the demo's default when not given)")
    a = ap.parse_args()
    jobs = [["--seed", str(s)] for s in seeds(a.seeds)]
    jobs += [["--scenario", c] for c in a.scenarios.split(",") if c]
    rows = []
    for job in jobs:
        with tempfile.TemporaryDirectory() as tmp:
            d = tmp
            if a.keep:
                d = os.path.join(a.keep, "-".join(x.lstrip("-") for x in job))
                os.makedirs(d, exist_ok=True)
            cmd = [a.twinloop, "demo", *job, "--out", d, "--json", os.path.join(d, "demo.json")]
            if a.tell_where and job[0] == "--seed":
                cmd.append("--tell-where")
            if a.check:
                cmd.append("--check")
            if a.goal_counts:
                cmd += ["--goal-counts", a.goal_counts]
            if a.protocol_passes is not None:
                cmd += ["--protocol-passes", str(a.protocol_passes)]
            load = os.getloadavg()[0]
            t0 = time.time()
            p = subprocess.run(cmd, capture_output=True, text=True)
            if p.returncode != 0:
                print(" ".join(job), "FAILED:", p.stderr.strip().splitlines()[-1:], flush=True)
                rows.append({"job": " ".join(job), "failed": p.stderr.strip()})
                continue
            r = json.load(open(os.path.join(d, "demo.json")))
        mass = sum(c["mass"] for c in r["truth"])
        links = "+".join(c["link"] for c in r["truth"])
        dm = [r["adapted_model_deg"][k] - r["measured_deg"][k] for k in range(4)]
        dt = [r["true_model_deg"][k] - r["measured_deg"][k] for k in range(4)]
        sim = r.get("adapted_simulation_deg")
        ds = None if sim is None else [sim[k] - r["measured_deg"][k] for k in range(4)]
        # The protocol on the true model in lockstep: the robot's reading less the bus's noise.
        tp = r.get("true_protocol_deg")
        dp = None if tp is None else [tp[k] - r["measured_deg"][k] for k in range(4)]
        # Pass 1 of the protocol's correction fits with zero bias (the sideways offset
        # already weighted as once the bias is off: `adapt --protocol-passes 0` is the
        # plain adaptation itself): the same measurement, for a paired comparison.
        cal = r.get("calibration")
        plain = None
        if cal and cal["passes"] and cal["passes"][0]["adapted_com"]:
            c = cal["passes"][0]["adapted_com"]
            plain = 1e3 * sum((c[i] - r["true_com"][i]) ** 2 for i in range(3)) ** 0.5
        row = {
            "job": " ".join(job), "mass": mass, "links": links,
            "com_error_mm": 1e3 * r["com_error"], "plain_com_error_mm": plain,
            "position_error_mm": None if r["position_error"] is None else 1e3 * r["position_error"],
            "found_host": (r.get("found") or {}).get("host"),
            "adapted_minus_measured_deg": dm, "true_minus_measured_deg": dt,
            "simulated_minus_measured_deg": ds, "true_protocol_minus_measured_deg": dp,
            "wall_s": time.time() - t0, "load": load,
        }
        rows.append(row)
        pe = row["position_error_mm"]
        print(f"{row['job']:>14} {mass:.3f} kg {links:<18} CoM {row['com_error_mm']:5.2f} mm "
              f"part {'-' if pe is None else f'{pe:5.1f}'} mm  adapted-measured "
              + " ".join(f"{x:+.2f}" for x in dm) + "  true-measured "
              + " ".join(f"{x:+.2f}" for x in dt)
              + ("" if ds is None else "  simulated-measured " + " ".join(f"{x:+.2f}" for x in ds))
              + ("" if dp is None else "  truth's protocol-measured " + " ".join(f"{x:+.2f}" for x in dp))
              + ("" if plain is None else f"  (plain {plain:.2f} mm)")
              + f"  {row['wall_s']:.0f} s load {load:.1f}", flush=True)
    ok = [r for r in rows if "failed" not in r]
    if ok:
        ce = [r["com_error_mm"] for r in ok]
        print(f"CoM error: median {statistics.median(ce):.2f} mm, max {max(ce):.2f} mm, "
              f"{sum(c < 3 for c in ce)} of {len(ce)} within 3 mm")
        pl = [r["plain_com_error_mm"] for r in ok if r["plain_com_error_mm"] is not None]
        if pl:
            print(f"the same runs adapted without the protocol's bias: median {statistics.median(pl):.2f} mm, "
                  f"max {max(pl):.2f} mm, {sum(c < 3 for c in pl)} of {len(pl)} within 3 mm")
        worst = [max(abs(x) for x in r["adapted_minus_measured_deg"]) for r in ok]
        print(f"adapted model vs measured, worst direction: median {statistics.median(worst):.2f} deg, "
              f"max {max(worst):.2f} deg, {sum(w < 0.3 for w in worst)} of {len(worst)} within 0.3 deg")
        checked = [r for r in ok if r["simulated_minus_measured_deg"] is not None]
        if checked:
            ws = [max(abs(x) for x in r["simulated_minus_measured_deg"]) for r in checked]
            print(f"adapted simulation (over the bus) vs measured, worst direction: median "
                  f"{statistics.median(ws):.2f} deg, max {max(ws):.2f} deg, "
                  f"{sum(w <= 0.3 for w in ws)} of {len(ws)} within 0.3 deg")
        noise = [abs(x) for r in ok if r["true_protocol_minus_measured_deg"] for x in r["true_protocol_minus_measured_deg"]]
        if noise:
            print(f"the robot's reading vs the protocol on the true model (the bus's noise), per direction: median "
                  f"{statistics.median(noise):.3f} deg, max {max(noise):.2f} deg, "
                  f"{sum(x <= 0.1 for x in noise)} of {len(noise)} within 0.1 deg")
        big = [r for r in ok if r["mass"] >= 0.3 and r["position_error_mm"] is not None]
        if big:
            pe = [r["position_error_mm"] for r in big]
            print(f"parts of 0.3 kg and above: position error median {statistics.median(pe):.1f} mm, "
                  f"max {max(pe):.1f} mm, {sum(p < 20 for p in pe)} of {len(pe)} within 2 cm")
    if a.out:
        json.dump(rows, open(a.out, "w"), indent=1)
    sys.exit(0 if len(ok) == len(rows) else 1)


if __name__ == "__main__":
    main()
