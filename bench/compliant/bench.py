#!/usr/bin/env python3
"""Compact compliant model (seed 002, eq 14-17): rollout and fit, Python versus twinloop.

Run from the repository root after `cargo build --release -p twinloop-cli`:

    pip install numpy scipy          # numba optional: pip install numba
    python3 bench/compliant/bench.py [--rounds 11] [--json OUT.json]

Data: the seed's gait (sl 0.03 m, Tss 0.5 s, Tdb 0.2 s, 40 steps: 30.2 s at 1 kHz, 30 201
samples) from `twinloop gait zmp`, and the compact model's own response with Table 1
corrections (`twinloop compliant simulate --table1`), for COMAN's x-z stiffness with the
pelvis free (the entries below, from `twinloop compliant stiffness`).

Python, on the same CSV and the same RK4 (reference linearly interpolated inside each
sample interval, phase of the interval's first sample):
  rollout, Python loop   the RK4 loop in plain Python floats (faster than numpy arrays for a
                         4-element state)
  rollout, numba         the same loop compiled by numba.njit (if numba is installed)
  fit, scipy            scipy.optimize.least_squares(method="lm"): MINPACK's
                         Levenberg-Marquardt with a finite-difference Jacobian on the
                         residuals (numba rollout), from all ones
twinloop: `twinloop identify compliant --timing-rounds N` times its rollout, its sensitivity
rollout and its whole LM fit in-process and reports medians.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

try:
    import numba
except ImportError:  # the bench runs without it
    numba = None

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
TWINLOOP = os.path.join(ROOT, "target", "release", "twinloop")

MODEL = dict(
    m=32.053860196, g=9.81,
    Kxx=440.91346363174296, Kxz=-2173.515375145169, Kzx=-2173.515375145169, Kzz=60061.10789312922,
    Dxx=14.527209046033501, Dxz=-3.3326729999481515, Dzx=-3.3326729999481515, Dzz=667.4461329201686,
)
TABLE1 = [0.9827, 1.0357, 1.0560, 1.1335, 0.9792, 0.9561, 1.0072, 1.1053]


def rollout_py(t, xr, zr, ds, x0, z0, p, plant):
    """RK4 of seed 002 eq 14-17 in plain Python; returns x, z lists."""
    m, g, kxx, kxz, kzx, kzz, dxx, dxz, dzx, dzz = plant
    a1, b1, g1, e1, a2, b2, g2, e2, eta1, eta2 = p

    def f(s0, s1, s2, s3, r0, r1, d):
        ex, ez = s0 - r0, s1 - r1
        fx = -a1 * kxx * ex - b1 * kxz * ez - g1 * dxx * s2 - e1 * dxz * s3
        fz = -a2 * kzx * ex - b2 * kzz * ez - g2 * dzx * s2 - e2 * dzz * s3
        if d:
            return s2, s3, eta1 * fx / m, -g + eta2 * fz / m
        return s2, s3, fx / m, -g + fz / m

    n = len(t)
    xs, zs = [x0] * n, [z0] * n
    s0, s1, s2, s3 = x0, z0, 0.0, 0.0
    for i in range(1, n):
        h = t[i] - t[i - 1]
        d = ds[i - 1]
        xa, za, xb, zb = xr[i - 1], zr[i - 1], xr[i], zr[i]
        xm, zm = 0.5 * (xa + xb), 0.5 * (za + zb)
        k1 = f(s0, s1, s2, s3, xa, za, d)
        k2 = f(s0 + 0.5 * h * k1[0], s1 + 0.5 * h * k1[1], s2 + 0.5 * h * k1[2], s3 + 0.5 * h * k1[3], xm, zm, d)
        k3 = f(s0 + 0.5 * h * k2[0], s1 + 0.5 * h * k2[1], s2 + 0.5 * h * k2[2], s3 + 0.5 * h * k2[3], xm, zm, d)
        k4 = f(s0 + h * k3[0], s1 + h * k3[1], s2 + h * k3[2], s3 + h * k3[3], xb, zb, d)
        s0 += h / 6.0 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
        s1 += h / 6.0 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
        s2 += h / 6.0 * (k1[2] + 2 * k2[2] + 2 * k3[2] + k4[2])
        s3 += h / 6.0 * (k1[3] + 2 * k2[3] + 2 * k3[3] + k4[3])
        xs[i], zs[i] = s0, s1
    return xs, zs


def _deriv(s0, s1, s2, s3, r0, r1, d, p, pl):
    ex, ez = s0 - r0, s1 - r1
    fx = -p[0] * pl[2] * ex - p[1] * pl[3] * ez - p[2] * pl[6] * s2 - p[3] * pl[7] * s3
    fz = -p[4] * pl[4] * ex - p[5] * pl[5] * ez - p[6] * pl[8] * s2 - p[7] * pl[9] * s3
    if d:
        return s2, s3, p[8] * fx / pl[0], -pl[1] + p[9] * fz / pl[0]
    return s2, s3, fx / pl[0], -pl[1] + fz / pl[0]


def _rollout_nb(t, xr, zr, ds, x0, z0, p, pl, xs, zs):
    n = t.shape[0]
    s0, s1, s2, s3 = x0, z0, 0.0, 0.0
    xs[0], zs[0] = x0, z0
    for i in range(1, n):
        h = t[i] - t[i - 1]
        d = ds[i - 1]
        xa, za, xb, zb = xr[i - 1], zr[i - 1], xr[i], zr[i]
        xm, zm = 0.5 * (xa + xb), 0.5 * (za + zb)
        k1 = _deriv(s0, s1, s2, s3, xa, za, d, p, pl)
        k2 = _deriv(s0 + 0.5 * h * k1[0], s1 + 0.5 * h * k1[1], s2 + 0.5 * h * k1[2], s3 + 0.5 * h * k1[3], xm, zm, d, p, pl)
        k3 = _deriv(s0 + 0.5 * h * k2[0], s1 + 0.5 * h * k2[1], s2 + 0.5 * h * k2[2], s3 + 0.5 * h * k2[3], xm, zm, d, p, pl)
        k4 = _deriv(s0 + h * k3[0], s1 + h * k3[1], s2 + h * k3[2], s3 + h * k3[3], xb, zb, d, p, pl)
        s0 += h / 6.0 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
        s1 += h / 6.0 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
        s2 += h / 6.0 * (k1[2] + 2 * k2[2] + 2 * k3[2] + k4[2])
        s3 += h / 6.0 * (k1[3] + 2 * k2[3] + 2 * k3[3] + k4[3])
        xs[i], zs[i] = s0, s1


if numba is not None:
    _deriv = numba.njit(_deriv)
    _rollout_nb = numba.njit(_rollout_nb)


def median_time(rounds, fn):
    times = []
    for _ in range(rounds):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{r.stderr}")
    return r.stdout


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=11)
    ap.add_argument("--json", help="write the results here")
    ap.add_argument("--held", action="store_true",
                    help="the x-z block of K_C (pelvis held) instead of the stiffness under forces alone")
    args = ap.parse_args()
    if not os.path.exists(TWINLOOP):
        sys.exit("build first: cargo build --release -p twinloop-cli")
    if args.held:
        MODEL.update(Kxx=57188.06530958703, Kxz=217399.9125848724, Kzx=217399.9125848724, Kzz=916201.4610526043)
    work = tempfile.mkdtemp(prefix="bench-compliant-")
    model = os.path.join(work, "PLANT.toml")
    with open(model, "w") as fh:
        fh.write("".join(f"{k} = {v!r}\n" for k, v in MODEL.items()))
    ref, walk = os.path.join(work, "ref.csv"), os.path.join(work, "walk.csv")
    run([TWINLOOP, "gait", "zmp", "--footsteps", "40", "--out", ref])
    run([TWINLOOP, "compliant", "simulate", "--reference", ref, "--plant", model, "--table1", "--out", walk])
    d = np.genfromtxt(walk, delimiter=",", names=True)
    t, xr, zr, xm, zm = (np.ascontiguousarray(d[k]) for k in ("t", "xr", "zr", "x", "z"))
    ds = np.ascontiguousarray(d["phase"] == 1.0)
    n = len(t)
    plant = [MODEL[k] for k in ("m", "g", "Kxx", "Kxz", "Kzx", "Kzz", "Dxx", "Dxz", "Dzx", "Dzz")]
    truth = TABLE1 + [1.0, 1.0]
    res = {"samples": n, "rounds": args.rounds}

    # twinloop, in-process medians
    out_json = os.path.join(work, "fit.json")
    run([TWINLOOP, "identify", "compliant", "--data", walk, "--plant", model, "--timing-rounds", str(args.rounds), "--json", out_json])
    tl = json.load(open(out_json))
    res["twinloop"] = dict(tl["timing"], evaluations=tl["evaluations"], iterations=tl["iterations"],
                           mse_after=tl["mse_after"],
                           max_param_error=max(abs(tl["params"][k] - v) for k, v in zip(
                               ["alpha1", "beta1", "gamma1", "epsilon1", "alpha2", "beta2", "gamma2", "epsilon2"], TABLE1)))

    # Python loop rollout (fewer rounds: it is slow)
    tl_list = (t.tolist(), xr.tolist(), zr.tolist(), ds.tolist())
    py_rounds = max(3, args.rounds // 3)
    res["python_loop_rollout"] = median_time(py_rounds, lambda: rollout_py(*tl_list, xm[0], zm[0], truth, plant))
    xs, zs = rollout_py(*tl_list, xm[0], zm[0], truth, plant)
    res["python_loop_max_deviation_from_twinloop"] = float(max(np.max(np.abs(np.array(xs) - xm)), np.max(np.abs(np.array(zs) - zm))))

    if numba is not None:
        p_arr, pl_arr = np.array(truth), np.array(plant)
        xs, zs = np.zeros(n), np.zeros(n)
        _rollout_nb(t, xr, zr, ds, xm[0], zm[0], p_arr, pl_arr, xs, zs)  # compile
        res["numba_rollout"] = median_time(args.rounds, lambda: _rollout_nb(t, xr, zr, ds, xm[0], zm[0], p_arr, pl_arr, xs, zs))
        res["numba_max_deviation_from_twinloop"] = float(max(np.max(np.abs(xs - xm)), np.max(np.abs(zs - zm))))
        res["numba_version"] = numba.__version__

        from scipy.optimize import least_squares

        calls = [0]

        def residuals(p8):
            calls[0] += 1
            p = np.concatenate([p8, [1.0, 1.0]])
            _rollout_nb(t, xr, zr, ds, xm[0], zm[0], p, pl_arr, xs, zs)
            return np.concatenate([xs - xm, zs - zm])

        fits = []
        for _ in range(max(3, args.rounds // 3)):
            calls[0] = 0
            t0 = time.perf_counter()
            sol = least_squares(residuals, np.ones(8), method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=5000)
            fits.append((time.perf_counter() - t0, sol, calls[0]))
        secs = statistics.median(f[0] for f in fits)
        sol = fits[0][1]
        # scipy's nfev leaves out the finite-difference calls: count every rollout
        res["scipy_lm_fit"] = dict(seconds=secs, nfev=fits[0][2], mse_after=float(np.mean(sol.fun ** 2)),
                                   max_param_error=float(np.max(np.abs(sol.x - np.array(TABLE1)))),
                                   status=int(sol.status))

    r = res
    res["plant"] = "pelvis held" if args.held else "pelvis free"
    print(f"{n} samples (30.2 s at 1 kHz), {res['plant']}, medians of {args.rounds} rounds")
    print(f"rollout: twinloop {r['twinloop']['rollout'] * 1e3:.3f} ms "
          f"({r['twinloop']['rollout_per_1000_samples'] * 1e6:.1f} us per 1000 samples), "
          f"Python loop {r['python_loop_rollout'] * 1e3:.1f} ms"
          + (f", numba {r['numba_rollout'] * 1e3:.3f} ms" if "numba_rollout" in r else ""))
    print(f"sensitivity rollout (twinloop, all 10 directions): {r['twinloop']['sensitivity_rollout'] * 1e3:.3f} ms")
    print(f"LM fit: twinloop {r['twinloop']['fit'] * 1e3:.1f} ms ({r['twinloop']['evaluations']} evaluations, "
          f"max parameter error {r['twinloop']['max_param_error']:.1e})"
          + (f"; scipy lm + numba {r['scipy_lm_fit']['seconds'] * 1e3:.1f} ms ({r['scipy_lm_fit']['nfev']} evaluations, "
             f"max parameter error {r['scipy_lm_fit']['max_param_error']:.1e})" if "scipy_lm_fit" in r else ""))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(res, fh, indent=2)


if __name__ == "__main__":
    main()
