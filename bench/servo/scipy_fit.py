#!/usr/bin/env python3
"""The peer of `twinloop identify servo`: the same m1 servo model (docs/servo-models.md)
replayed against the same `experiment servo` logs and fitted with SciPy's
least_squares (Levenberg-Marquardt, 3-point finite-difference Jacobian, log-parameters,
the same residual weights), in plain Python loops (the model is a time-stepping
simulation with clamps: numpy cannot vectorise it).

Usage: scipy_fit.py LOAD.toml LOG.csv [LOG.csv ...]
Prints the fitted parameters, the held-out RMS error (last 25 % of each log) and the
wall time, as JSON on the last line.
"""
import json
import math
import sys
import time
import tomllib

import numpy as np
from scipy.optimize import least_squares

MAX_STEP = 5e-4
GRAVITY = 9.81
CURRENT_SD = 0.02
# name: (family, resolution rad, pwm max, current unit or None, stall torque, stall current, rpm, voltage, ratio)
TYPES = {
    "RX-28": ("rx", math.radians(300 / 1024), 1023.0, None, 3.7, 1.9, 85.0, 18.5, 193.0),
    "RX-64": ("rx", math.radians(300 / 1024), 1023.0, None, 5.3, 2.6, 64.0, 18.5, 200.0),
    "MX-64(2.0)": ("pid", 2 * math.pi / 4096, 885.0, 0.00336, 6.0, 4.1, 63.0, 12.0, 200.0),
    "XM430-W350": ("pid", 2 * math.pi / 4096, 885.0, 0.00269, 4.1, 2.3, 46.0, 12.0, 353.5),
}


def rround(x):
    """Rust's f64::round: half away from zero (Python's round is half to even)."""
    return math.copysign(math.floor(abs(x) + 0.5), x)


def rx_slope(raw):
    v = min(max(int(raw), 2), 255)
    return float(min(1 << (v.bit_length() - 1), 128))


def datasheet(name):
    _, _, _, _, stall, amps, rpm, volts, ratio = TYPES[name]
    kt, r = stall / amps, volts / amps
    fc = 0.025 * stall
    w0 = rpm * 2 * math.pi / 60
    b = max((kt / r * (volts - kt * w0) - fc) / w0, 0.0)
    return {"kt": kt, "resistance": r, "armature": 0.012 * (ratio / 200) ** 2, "friction_base": fc, "friction_viscous": b}


def read_log(path):
    with open(path) as f:
        first = f.readline()
    servo = first.split(":", 1)[1].split()[0]
    # The first line is the log's comment naming the servo; the header follows.
    data = np.genfromtxt(path, delimiter=",", names=True, skip_header=1)
    return servo, data


def replay(p, volts, load, servo, log, lo, hi):
    """Positions and currents of the model over rows lo..hi (the Rust replay)."""
    family, res, pwm_max, _, *_ = TYPES[servo]
    kt, r, arm, fc = p[:4]
    b = p[4] if len(p) > 4 else 0.0
    m, l, ja = load
    inertia = arm + ja + m * l * l
    t, goal, t_goal = log["t"], log["goal"], log["t_goal"]
    fw = [log[c] for c in (("compliance_slope", "compliance_margin", "punch") if family == "rx" else ("p_gain", "i_gain", "d_gain"))]
    q, v = float(log["q"][lo]), float(log["v"][lo])
    g = float(goal[lo])
    regs = [float(c[lo]) for c in fw]
    integral, prev = 0.0, 0.0
    out_q, out_i = [q], [float("nan")]
    current = 0.0
    emf = kt * kt / r
    damping = emf + b
    h_scale = None

    def step(dt):
        nonlocal q, v, integral, prev, current
        e = rround(g / res) - rround(q / res)
        if family == "rx":
            slope, margin, punch = rx_slope(regs[0]), regs[1], regs[2] / 1023.0
            beyond = abs(e) - margin
            duty = 0.0 if beyond <= 0 else math.copysign(min(max(beyond / max(slope, 1.0), punch), 1.0), e)
        else:
            integral += e
            de = e - prev
            prev = e
            duty = (regs[0] / 128 * e + regs[1] / 65536 * integral + regs[2] / 16 * de) / pwm_max
            duty = min(max(duty, -1.0), 1.0)
        drive = kt / r * duty * volts
        h = inertia + dt * damping
        free = (inertia * v + dt * (drive - m * GRAVITY * l * math.sin(q))) / h
        stop = free * h / dt
        fr = min(max(stop, -fc), fc)
        v = free - dt * fr / h
        q += dt * v
        current = (duty * volts - kt * v) / r

    def advance(span):
        if span <= 0:
            return
        n = max(math.ceil(span / MAX_STEP), 1)
        for _ in range(n):
            step(span / n)

    for i in range(lo + 1, hi):
        sw = min(max(t_goal[i], t[i - 1]), t[i])
        advance(sw - t[i - 1])
        g = float(goal[i])
        regs = [float(c[i]) for c in fw]
        advance(t[i] - sw)
        out_q.append(q)
        out_i.append(current)
    return np.array(out_q), np.array(out_i)


def main():
    load_file, logs = sys.argv[1], sys.argv[2:]
    with open(load_file, "rb") as f:
        ld = tomllib.load(f)
    load = (ld["mass"], ld["length"], ld["arm_inertia"])
    data = [read_log(p) for p in logs]
    servo = data[0][0]
    res, unit = TYPES[servo][1], TYPES[servo][3]
    volts = float(np.mean(np.concatenate([d["voltage"] for _, d in data])))
    names = ["kt", "resistance", "armature", "friction_base", "friction_viscous"]
    if unit is None:
        # Positions alone: viscous friction held at 0, as twinloop does.
        names = names[:4]
    start = datasheet(servo)
    x0 = np.log([max(start[n], 1e-6) for n in names])
    splits = [round(len(d) * 0.75) for _, d in data]
    sd_q = res / math.sqrt(12)

    def residuals(x):
        p = np.exp(x)
        out = []
        for (_, d), s in zip(data, splits):
            q, i = replay(p, volts, load, servo, d, 0, s)
            out.append((q - d["q"][:s]) / sd_q)
            if unit is not None:
                ri = (i - d["current"][:s]) / CURRENT_SD
                ri[0] = 0.0
                out.append(ri)
        return np.concatenate(out)

    t0 = time.perf_counter()
    sol = least_squares(residuals, x0, method="lm", jac="3-point")
    took = time.perf_counter() - t0
    p = np.exp(sol.x)
    sq, n = 0.0, 0
    for (_, d), s in zip(data, splits):
        q, _ = replay(p, volts, load, servo, d, s - 1, len(d))
        e = q[1:] - d["q"][s:]
        sq += float(np.sum(e * e))
        n += len(e)
    result = {
        "servo": servo,
        "params": dict(zip(names, p.tolist())),
        "heldout_rms_mrad": 1e3 * math.sqrt(sq / max(n, 1)),
        "seconds": took,
        "evaluations": int(sol.nfev),
        "rows": int(sum(len(d) for _, d in data)),
    }
    print(json.dumps(result))


if __name__ == "__main__":
    main()
