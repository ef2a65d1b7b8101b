#!/usr/bin/env python3
"""Black-box identification, side by side: numpy/scipy versus twinloop on the same data.

Run from the repository root after `cargo build --release -p twinloop-cli`:

    pip install numpy scipy
    python3 bench/sysid/bench.py [--data FILE.csv] [--arx-runs 5] [--pem-runs 1] [--json OUT.json]

The data default to the synthetic record of tools/oracle/sysid_reference.py (1000 samples,
10 inputs u1..u10, 6 outputs y1..y6: the size of seed 003's data set).

ARX (na = nb = 24, nk = 1, MATLAB's structure and rows, the seed's initial model) in Python,
timed four ways:
  per-output loops   what a transcription of MATLAB's arx does: for every output its own
                     regressor, built row by row in Python, and its own numpy.linalg.lstsq
                     (MATLAB estimates each output row separately; SIPPY does the same)
  shared, loops      one regressor built row by row, one lstsq for all six outputs
  shared, vectorised one regressor built with numpy slicing, one lstsq: the fastest numpy way
  lstsq alone        numpy.linalg.lstsq on a prebuilt regressor (LAPACK gelsd)
twinloop: the library's estimation time (regressor, blocked Householder QR, solve; reported
by the CLI as timing_seconds.estimation) and the whole CLI process (CSV parsing, estimation and
the full evaluation: FIT, Hankel singular values of the 144-state realisation, frequency
response, residual tests).

PEM of a 6th-order state-space model (innovations form, D = 0) in Python: scipy's
least_squares (MINPACK Levenberg-Marquardt, finite-difference Jacobian) on the one-step
prediction errors over the full parameterisation (A, B, C, K: 168 parameters), started from
twinloop's own subspace estimate so both searches start at the same model. twinloop: the CLI
`identify ss --method pem`, whose estimation time includes computing that subspace estimate.

The Python side fits the data as they are, so twinloop runs with --no-detrend (the CLI removes
the means by default).

Medians over the runs and the ratios python / twinloop are printed; --json writes them.
numpy's lstsq runs LAPACK through OpenBLAS with one thread per CPU; on a loaded machine those
threads fight the other work, so also try OPENBLAS_NUM_THREADS=1 (twinloop is single-threaded).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np
import scipy
import scipy.optimize

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
DEFAULT_DATA = os.path.join(REPO, "crates", "twinloop-sysid", "tests", "data", "synthetic_est.csv")
DEFAULT_BIN = os.path.join(REPO, "target", "release", "twinloop")


def load(path):
    with open(path) as f:
        header = f.readline().strip().split(",")
    table = np.loadtxt(path, delimiter=",", skiprows=1)
    ui = [i for i, c in enumerate(header) if c.startswith("u")]
    yi = [i for i, c in enumerate(header) if c.startswith("y")]
    return table[:, ui], table[:, yi]


# ---------------------------------------------------------------- ARX in Python
def regressor_rows(u, y, na, nb, nk, outputs=None):
    """Row by row, as MATLAB's definition reads."""
    n = u.shape[0]
    k0 = max(na, nb + nk - 1)
    rows, targets = [], []
    for k in range(k0, n):
        row = []
        for i in range(1, na + 1):
            row.extend(-y[k - i])
        for j in range(nb):
            row.extend(u[k - nk - j])
        rows.append(row)
        targets.append(y[k] if outputs is None else y[k, outputs])
    return np.array(rows), np.array(targets)


def regressor_vectorised(u, y, na, nb, nk):
    n = u.shape[0]
    k0 = max(na, nb + nk - 1)
    blocks = [-y[k0 - i:n - i] for i in range(1, na + 1)]
    blocks += [u[k0 - nk - j:n - nk - j] for j in range(nb)]
    return np.hstack(blocks), y[k0:]


def arx_per_output(u, y, na, nb, nk):
    thetas = []
    for o in range(y.shape[1]):
        phi, t = regressor_rows(u, y, na, nb, nk, outputs=o)
        thetas.append(np.linalg.lstsq(phi, t, rcond=None)[0])
    return np.column_stack(thetas)


def arx_shared_loops(u, y, na, nb, nk):
    phi, t = regressor_rows(u, y, na, nb, nk)
    return np.linalg.lstsq(phi, t, rcond=None)[0]


def arx_vectorised(u, y, na, nb, nk):
    phi, t = regressor_vectorised(u, y, na, nb, nk)
    return np.linalg.lstsq(phi, t, rcond=None)[0]


# ---------------------------------------------------------------- PEM in Python
class Pem:
    def __init__(self, u, y, n):
        self.u, self.y, self.n = u, y, n
        self.nu, self.ny = u.shape[1], y.shape[1]
        self.calls = 0

    def pack(self, a, b, c, k):
        return np.concatenate([a.ravel(), b.ravel(), c.ravel(), k.ravel()])

    def unpack(self, th):
        n, nu, ny = self.n, self.nu, self.ny
        o = 0
        a = th[o:o + n * n].reshape(n, n)
        o += n * n
        b = th[o:o + n * nu].reshape(n, nu)
        o += n * nu
        c = th[o:o + ny * n].reshape(ny, n)
        o += ny * n
        k = th[o:o + n * ny].reshape(n, ny)
        return a, b, c, k

    def residuals(self, th):
        self.calls += 1
        a, b, c, k = self.unpack(th)
        x = np.zeros(self.n)
        e = np.empty_like(self.y)
        for t in range(self.y.shape[0]):
            et = self.y[t] - c @ x
            e[t] = et
            x = a @ x + b @ self.u[t] + k @ et
            if not np.all(np.isfinite(x)):
                e[t:] = 1e10
                break
        return e.ravel()

    def cost(self, th):
        r = self.residuals(th)
        return float(r @ r / self.y.shape[0])


def twinloop(binary, args):
    t0 = time.perf_counter()
    p = subprocess.run([binary] + args, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        sys.exit(f"twinloop failed ({p.returncode}): {p.stderr}")
    return wall


def median_time(fn, runs):
    times, out = [], None
    for _ in range(runs):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", default=DEFAULT_DATA)
    ap.add_argument("--twinloop", default=DEFAULT_BIN)
    ap.add_argument("--arx-runs", type=int, default=5)
    ap.add_argument("--pem-runs", type=int, default=1)
    ap.add_argument("--twinloop-runs", type=int, default=5)
    ap.add_argument("--na", type=int, default=24)
    ap.add_argument("--nb", type=int, default=24)
    ap.add_argument("--nk", type=int, default=1)
    ap.add_argument("--order", type=int, default=6)
    ap.add_argument("--skip-python-pem", action="store_true", help="the scipy PEM takes a minute or more")
    ap.add_argument("--json", help="write the results here")
    args = ap.parse_args()
    if not os.path.exists(args.twinloop):
        sys.exit(f"{args.twinloop} not found: cargo build --release -p twinloop-cli")

    u, y = load(args.data)
    na, nb, nk = args.na, args.nb, args.nk
    print(f"data: {args.data}: {u.shape[0]} samples, {u.shape[1]} inputs, {y.shape[1]} outputs")
    print(f"numpy {np.__version__}, scipy {scipy.__version__}, python {sys.version.split()[0]}, "
          f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs, "
          f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}")
    results = {"data": os.path.relpath(args.data, REPO), "samples": int(u.shape[0]), "arx": {}, "pem": {},
               "load_average": os.getloadavg()[0],
               "openblas_threads": os.environ.get("OPENBLAS_NUM_THREADS", "unset")}

    # ARX, Python.
    py = {}
    py["per-output loops"], th_a = median_time(lambda: arx_per_output(u, y, na, nb, nk), args.arx_runs)
    py["shared, loops"], th_b = median_time(lambda: arx_shared_loops(u, y, na, nb, nk), args.arx_runs)
    py["shared, vectorised"], th_c = median_time(lambda: arx_vectorised(u, y, na, nb, nk), args.arx_runs)
    phi, tgt = regressor_vectorised(u, y, na, nb, nk)
    py["lstsq alone"], _ = median_time(lambda: np.linalg.lstsq(phi, tgt, rcond=None), args.arx_runs)
    assert np.allclose(th_a, th_c, atol=1e-9) and np.allclose(th_b, th_c, atol=1e-9)

    # ARX, twinloop.
    tmp = tempfile.mkdtemp(prefix="sysid-bench-")
    out = os.path.join(tmp, "arx.json")
    lib, wall = [], []
    for _ in range(args.twinloop_runs):
        wall.append(twinloop(args.twinloop, ["identify", "arx", "--data", args.data, "--inputs", "u*", "--outputs", "y*",
                                             "--no-detrend", "--na", str(na), "--nb", str(nb), "--nk", str(nk), "--json", out]))
        with open(out) as f:
            res = json.load(f)
        lib.append(res["timing_seconds"]["estimation"])
    ours = np.vstack([np.array(m).T for m in res["A"]] + [np.array(m).T for m in res["B"]])
    agree = float(np.abs(ours - th_c).max())
    tl_lib, tl_wall = statistics.median(lib), statistics.median(wall)
    print(f"\nARX na={na} nb={nb} nk={nk} ({phi.shape[0]} x {phi.shape[1]} regressor, {y.shape[1]} outputs); "
          f"max |twinloop - numpy| coefficient: {agree:.1e}")
    print(f"  {'python':<22}{'median s':>10}   {'/ twinloop library':>19}{'/ twinloop CLI':>16}")
    for k, v in py.items():
        print(f"  {k:<22}{v:>10.4f}   {v / tl_lib:>18.1f}x{v / tl_wall:>15.1f}x")
    print(f"  twinloop library      {tl_lib:>10.4f}   (estimation: regressor, blocked QR, solve)")
    print(f"  twinloop CLI          {tl_wall:>10.4f}   (process: CSV, estimation, full evaluation)")
    results["arx"] = {"orders": [na, nb, nk], "python_median_s": py, "twinloop_library_median_s": tl_lib,
                      "twinloop_cli_median_s": tl_wall, "max_coefficient_difference": agree,
                      "runs": {"python": args.arx_runs, "twinloop": args.twinloop_runs}}

    # PEM: both start from twinloop's subspace estimate.
    init = os.path.join(tmp, "n4sid.json")
    twinloop(args.twinloop, ["identify", "ss", "--data", args.data, "--inputs", "u*", "--outputs", "y*",
                             "--no-detrend", "--order", str(args.order), "--method", "n4sid", "--json", init])
    with open(init) as f:
        m0 = json.load(f)
    out = os.path.join(tmp, "pem.json")
    lib, wall = [], []
    for _ in range(args.twinloop_runs):
        wall.append(twinloop(args.twinloop, ["identify", "ss", "--data", args.data, "--inputs", "u*", "--outputs", "y*",
                                             "--no-detrend", "--order", str(args.order), "--method", "pem", "--json", out]))
        with open(out) as f:
            res = json.load(f)
        lib.append(res["timing_seconds"]["estimation"])
    tl_lib, tl_wall = statistics.median(lib), statistics.median(wall)
    tl_cost = res["pem"]["final_cost"]
    pem = Pem(u, y, args.order)
    th0 = pem.pack(*(np.array(m0[k]) for k in ("A", "B", "C", "K")))
    print(f"\nPEM, state-space order {args.order} ({th0.size} parameters in Python, "
          f"{res['pem']['free_parameters']} free in twinloop); start cost {pem.cost(th0):.6f}")
    results["pem"] = {"order": args.order, "start_cost": pem.cost(th0), "twinloop_library_median_s": tl_lib,
                      "twinloop_cli_median_s": tl_wall, "twinloop_final_cost": tl_cost,
                      "twinloop_iterations": res["pem"]["iterations"]}
    if not args.skip_python_pem:
        def run_scipy():
            pem.calls = 0
            # Trial steps that make the predictor diverge are answered with large errors.
            with np.errstate(over="ignore", invalid="ignore"):
                return scipy.optimize.least_squares(pem.residuals, th0, method="lm")
        t_py, sol = median_time(run_scipy, args.pem_runs)
        calls = pem.calls
        py_cost = pem.cost(sol.x)
        print(f"  scipy least_squares (lm) {t_py:>9.2f} s   cost {py_cost:.6f}   "
              f"({calls} predictor runs, finite-difference Jacobian)")
        print(f"  twinloop library         {tl_lib:>9.3f} s   cost {tl_cost:.6f}   "
              f"({res['pem']['iterations']} iterations; includes the subspace estimate)")
        print(f"  twinloop CLI             {tl_wall:>9.3f} s   (process, with the full evaluation)")
        print(f"  ratio scipy / twinloop: {t_py / tl_lib:.0f}x (library), {t_py / tl_wall:.0f}x (CLI)")
        results["pem"].update({"scipy_median_s": t_py, "scipy_final_cost": py_cost, "scipy_predictor_runs": calls,
                               "runs": {"python": args.pem_runs, "twinloop": args.twinloop_runs}})
    else:
        print(f"  twinloop library {tl_lib:.3f} s, CLI {tl_wall:.3f} s, cost {tl_cost:.6f} (scipy skipped)")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=1)
            f.write("\n")


if __name__ == "__main__":
    main()
