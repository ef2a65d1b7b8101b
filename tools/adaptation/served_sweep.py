#!/usr/bin/env python3
"""The adaptation loop as a user runs it on a robot served in its own process.

For each run: draw a hidden change (0.1-0.5 kg at a random point inside a random
link's collision outline, read from the URDF `twinloop model export` writes, with
numpy's generator, not twinloop's), serve the changed robot on a pty with
`twinloop serve --robot builtin:R --add-mass ... --catch-falls --realtime-factor 4`,
measure it with `twinloop experiment tipover --port P --map builtin:R --yes
--realtime-factor 4 --json tip.json`, adapt with `twinloop adapt --robot builtin:R
--tipover tip.json --total-mass KG --out adapted.urdf`, and compare the adapted CoM
with the truth: the changed robot's CoM from `twinloop experiment tipover --robot
builtin:R --add-mass ...` (the simulator's study reports the model's CoM in the same
standing frame). The table in docs/adaptation.md comes from it.

    python3 tools/adaptation/served_sweep.py --robot op3 --seeds 1-10 \
        [--twinloop target/ci/twinloop] [--keep DIR] [--out sweep.json] [--jobs 2] \
        [--stage all|tipover|adapt]

`--stage tipover` measures only (each run's `row.json` in --keep's folder);
`--stage adapt` adapts the kept measurements again (a changed `adapt` on the same
robot's tips, without serving it again).
"""
import argparse, json, os, random, statistics, subprocess, sys, tempfile, time
import xml.etree.ElementTree as ET
from concurrent.futures import ThreadPoolExecutor


def seeds(spec):
    out = []
    for part in spec.split(","):
        if "-" in part:
            a, b = part.split("-")
            out += range(int(a), int(b) + 1)
        elif part:
            out.append(int(part))
    return out


def rot(rpy):
    import math
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return [[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr]]


def outlines(urdf):
    """Per link, its primitive collision shapes (kind, dims, xyz, rpy), or its
    inertia box when it has none."""
    out = {}
    for link in ET.parse(urdf).getroot().iter("link"):
        shapes = []
        for c in link.findall("collision"):
            o = c.find("origin")
            xyz = [float(v) for v in (o.get("xyz", "0 0 0") if o is not None else "0 0 0").split()]
            rpy = [float(v) for v in (o.get("rpy", "0 0 0") if o is not None else "0 0 0").split()]
            g = c.find("geometry")
            for kind in ("box", "cylinder", "sphere"):
                e = g.find(kind)
                if e is not None:
                    shapes.append((kind, e.attrib, xyz, rpy))
        if not shapes:
            shapes = inertia_box(link)
        if shapes:
            out[link.get("name")] = shapes
    return out


def inertia_box(link):
    """A link without primitive collision shapes (OP3's are meshes, which the
    repository does not ship): the box of uniform density with its mass and inertia,
    centred on its CoM along its principal axes, as its outline."""
    import numpy as np
    i = link.find("inertial")
    if i is None:
        return []
    m = float(i.find("mass").get("value"))
    if m < 0.01:
        return []
    a = i.find("inertia").attrib
    I = np.array([[float(a["ixx"]), float(a["ixy"]), float(a["ixz"])],
                  [float(a["ixy"]), float(a["iyy"]), float(a["iyz"])],
                  [float(a["ixz"]), float(a["iyz"]), float(a["izz"])]])
    o = i.find("origin")
    xyz = [float(v) for v in (o.get("xyz", "0 0 0") if o is not None else "0 0 0").split()]
    rpy = [float(v) for v in (o.get("rpy", "0 0 0") if o is not None else "0 0 0").split()]
    R0 = np.array(rot(rpy))
    w, V = np.linalg.eigh(R0 @ I @ R0.T)
    # Box side along principal axis k: I_j + I_l - I_k = m d_k^2 / 6.
    d = [np.sqrt(max(6.0 * (w.sum() - 2.0 * w[k]) / m, 0.0)) for k in range(3)]
    if min(d) <= 0.0:
        return []
    import math
    # The principal frame's roll-pitch-yaw (V's columns are the axes; a proper rotation).
    if np.linalg.det(V) < 0:
        V[:, 2] *= -1
    pitch = -math.asin(max(-1.0, min(1.0, V[2, 0])))
    roll = math.atan2(V[2, 1], V[2, 2])
    yaw = math.atan2(V[1, 0], V[0, 0])
    return [("box", {"size": " ".join(f"{v:.6f}" for v in d)}, xyz, [roll, pitch, yaw])]


def draw(rng, shapes_by_link):
    link = rng.choice(sorted(shapes_by_link))
    kind, a, xyz, rpy = rng.choice(shapes_by_link[link])
    if kind == "box":
        s = [float(v) for v in a["size"].split()]
        local = [rng.uniform(-0.5 * v, 0.5 * v) for v in s]
    elif kind == "sphere":
        r = float(a["radius"])
        while True:
            local = [rng.uniform(-r, r) for _ in range(3)]
            if sum(v * v for v in local) <= r * r:
                break
    else:
        r, h = float(a["radius"]), float(a["length"])
        while True:
            x, y = rng.uniform(-r, r), rng.uniform(-r, r)
            if x * x + y * y <= r * r:
                break
        local = [x, y, rng.uniform(-0.5 * h, 0.5 * h)]
    R = rot(rpy)
    p = [xyz[i] + sum(R[i][j] * local[j] for j in range(3)) for i in range(3)]
    return link, round(rng.uniform(0.1, 0.5), 3), [round(v, 4) for v in p]


def run(tw, robot, seed, shapes, prior_mass, keep, stage="all"):
    rng = random.Random(seed * 7919 + sum(map(ord, robot)))
    link, mass, xyz = draw(rng, shapes)
    add = f"{mass}@{link}:{xyz[0]},{xyz[1]},{xyz[2]}"
    d = os.path.join(keep, f"{robot}-{seed}") if keep else tempfile.mkdtemp()
    os.makedirs(d, exist_ok=True)
    row = {"robot": robot, "seed": seed, "add_mass": add, "load": os.getloadavg()[0]}
    if stage == "adapt":
        # Adapt a kept measurement again (a changed `adapt`, the same robot's tips).
        row.update(json.load(open(f"{d}/row.json")))
        if "failed" in row:
            return row
        return adapt(tw, d, row, prior_mass + mass)
    truth = subprocess.run([tw, "experiment", "tipover", "--robot", f"builtin:{robot}",
                            f"--add-mass={add}", "--json", f"{d}/truth.json"],
                           capture_output=True, text=True)
    if truth.returncode != 0:
        row["failed"] = "truth: " + truth.stderr.strip()[-300:]
        return row
    pty = f"{d}/pty"
    if os.path.lexists(pty):
        os.remove(pty)
    serve = subprocess.Popen([tw, "serve", "--robot", f"builtin:{robot}", "--map", f"builtin:{robot}",
                              "--link", pty, f"--add-mass={add}", "--catch-falls",
                              "--realtime-factor", "4"],
                             stdout=open(f"{d}/serve.log", "w"), stderr=subprocess.STDOUT,
                             # Its own session, as in a terminal of its own: the kernel
                             # shares the processor between sessions first.
                             start_new_session=True)
    for _ in range(100):
        if os.path.exists(pty):
            break
        time.sleep(0.1)
    t0 = time.time()
    tip = subprocess.run([tw, "experiment", "tipover", "--port", pty, "--map", f"builtin:{robot}",
                          "--yes", "--realtime-factor", "4", "--json", f"{d}/tip.json",
                          "--record", f"{d}/rec.csv"], capture_output=True, text=True)
    row["tipover_s"] = time.time() - t0
    serve.terminate()
    serve.wait()
    open(f"{d}/tip.out", "w").write(tip.stdout + tip.stderr)
    if tip.returncode != 0:
        row["failed"] = f"tipover exit {tip.returncode}: " + tip.stderr.strip()[-300:]
    json.dump(row, open(f"{d}/row.json", "w"))
    if "failed" in row or stage == "tipover":
        return row
    return adapt(tw, d, row, prior_mass + mass)


def adapt(tw, d, row, total):
    true_com = json.load(open(f"{d}/truth.json"))["com"]["true"]
    row["load_adapt"] = os.getloadavg()[0]
    for f in ("adapt.json", "adapted.urdf"):
        if os.path.exists(f"{d}/{f}"):
            os.remove(f"{d}/{f}")
    t0 = time.time()
    with open(f"{d}/adapt.out", "w") as out:
        ad = subprocess.Popen([tw, "adapt", "--robot", f"builtin:{row['robot']}", "--tipover", f"{d}/tip.json",
                               "--total-mass", f"{total:.6f}", "--out", f"{d}/adapted.urdf",
                               "--json", f"{d}/adapt.json"], stdout=out, stderr=subprocess.STDOUT)
        # wait4: this child's own CPU time (the threads' pool runs several at once).
        _, status, usage = os.wait4(ad.pid, 0)
    row["adapt_s"] = time.time() - t0
    row["adapt_cpu_s"] = usage.ru_utime + usage.ru_stime
    row["adapt_exit"] = os.waitstatus_to_exitcode(status)
    if not os.path.exists(f"{d}/adapt.json"):
        row["failed"] = f"adapt exit {row['adapt_exit']}: " + open(f"{d}/adapt.out").read().strip()[-300:]
        return row
    a = json.load(open(f"{d}/adapt.json"))
    com = a.get("adapted_com") or a.get("measured_com")
    row["com_error_mm"] = 1e3 * sum((com[i] - true_com[i]) ** 2 for i in range(3)) ** 0.5
    row["measured_deg"] = a["measured_deg"]
    res = a.get("com_resolution")
    if res:
        # What the encoders cannot tell apart (every angle within its resolution).
        row["com_resolution_mm"] = [1e3 * v for v in res["axes_m"]]
        row["com_resolution_worst_mm"] = 1e3 * res["worst_m"]
        # Its shares: the angles' alone and the fitted floor's (when the floor was fitted).
        if res.get("angles"):
            row["com_resolution_angles_worst_mm"] = 1e3 * res["angles"]["worst_m"]
        if res.get("floor"):
            f = res["floor"]
            row["com_resolution_floor_worst_mm"] = 1e3 * f["share"]["worst_m"]
            row["floor_reading"] = f["reading"]
            row["floor_sink_mm"] = 1e3 * f["sink_m"]
            row["floor_resolution_mm"] = 1e3 * f["resolution_m"]
    row["angle_resolution_deg"] = a.get("angle_resolution_deg")
    row["place"] = (a.get("added") or {}).get("host")
    row["failed_checks"] = [c["name"] for c in a.get("checks", []) if not c.get("passed", True)]
    row["floor"] = next((n for n in a.get("notes", []) if "floor sinking" in n), None)
    return row


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--robot", required=True)
    ap.add_argument("--seeds", default="1-10")
    ap.add_argument("--twinloop", default="target/ci/twinloop")
    ap.add_argument("--keep", default=None)
    ap.add_argument("--out", default=None)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--stage", choices=["all", "tipover", "adapt"], default="all",
                    help="tipover: measure only (keeps row.json); adapt: adapt --keep's measurements again")
    a = ap.parse_args()
    tw = os.path.abspath(a.twinloop)
    with tempfile.TemporaryDirectory() as tmp:
        urdf = os.path.join(tmp, "prior.urdf")
        subprocess.run([tw, "model", "export", f"builtin:{a.robot}", "--out", urdf], check=True,
                       capture_output=True)
        shapes = outlines(urdf)
    info = json.loads(subprocess.run([tw, "model", "info", f"builtin:{a.robot}", "--json", "-"],
                                     capture_output=True, text=True, check=True).stdout)
    prior_mass = info["total_mass"]
    rows = []
    with ThreadPoolExecutor(a.jobs) as pool:
        for row in pool.map(lambda s: run(tw, a.robot, s, shapes, prior_mass, a.keep, a.stage), seeds(a.seeds)):
            rows.append(row)
            if "failed" in row:
                print(f"{a.robot} seed {row['seed']} {row['add_mass']}: FAILED {row['failed']}", flush=True)
                continue
            if "com_error_mm" not in row:
                print(f"{a.robot} seed {row['seed']:>2} {row['add_mass']:<40} tipover "
                      f"{row['tipover_s']:.0f} s load {row['load']:.1f}", flush=True)
                continue
            print(f"{a.robot} seed {row['seed']:>2} {row['add_mass']:<40} CoM {row['com_error_mm']:5.2f} mm "
                  f"(resolution {row.get('com_resolution_worst_mm', float('nan')):.2f} mm) "
                  f"adapt exit {row['adapt_exit']} {','.join(row['failed_checks'])} "
                  f"tipover {row['tipover_s']:.0f} s adapt {row['adapt_s']:.0f} s load {row['load']:.1f}",
                  flush=True)
    ok = [r for r in rows if "com_error_mm" in r]
    ce = [r["com_error_mm"] for r in ok]
    if ce:
        print(f"{a.robot}: {len(ok)} of {len(rows)} tip-overs completed; CoM error median "
              f"{statistics.median(ce):.2f} mm, max {max(ce):.2f} mm, {sum(c < 3 for c in ce)} of "
              f"{len(rows)} within 3 mm; {sum(r['adapt_exit'] == 0 for r in ok)} adapted models written")
    if a.out:
        json.dump(rows, open(a.out, "w"), indent=1)


if __name__ == "__main__":
    main()
