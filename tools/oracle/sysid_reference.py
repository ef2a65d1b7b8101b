#!/usr/bin/env python3
"""Reference data for the twinloop-sysid tests (black-box identification, seed 003).

Run from the repository root:

    pip install numpy scipy control slycot
    python3 tools/oracle/sysid_reference.py [--out-dir DIR]

It draws a known random stable MIMO system in innovations form

    x(k+1) = A x(k) + B u(k) + K e(k),   y(k) = C x(k) + e(k)

(6 states, 10 inputs, 6 outputs, no feedthrough, as the seed's final model),
simulates two independent records of 1000 samples (estimation and
validation) with white Gaussian inputs and white Gaussian innovations, and
writes

    crates/twinloop-sysid/tests/data/synthetic_est.csv
    crates/twinloop-sysid/tests/data/synthetic_val.csv
    crates/twinloop-sysid/tests/data/reference.json

The JSON holds the numbers the Rust tests compare against, each computed
here by an independent implementation:

* the true system and its noise level;
* Hankel singular values of the true system from slycot AB09AD (discrete)
  and both Gramians from python-control `gram` (slycot SB03MD);
* a discrete Lyapunov equation of order 30 with eigenvalues near the unit
  circle, solved by slycot SB03MD (scipy's direct Kronecker solution is
  recorded beside it: the equation is ill-conditioned, the two differ by
  about 1e-8 relative while both have residuals near 1e-12);
* MIMO ARX coefficients for several (na, nb, nk), from numpy.linalg.lstsq
  on a regressor built here row by row with MATLAB's `arx` structure
  y(k) + A1 y(k-1) + ... + Ana y(k-na) = B1 u(k-nk) + ... + Bnb u(k-nk-nb+1) + e(k)
  over the rows k = max(na, nb+nk-1) .. N-1, plus ARX simulation and
  k-step predictions for one order;
* the true system's one-step prediction errors, prediction cost, simulated
  and predicted outputs' FIT (MATLAB `compare` definition and the seed's
  eq 10), and residual correlations;
* singular values of the true system's frequency response at given
  frequencies, its DC gain;
* a balanced truncation to 4 states by slycot AB09AD (python-control's
  `balred` and `hsvd` handle continuous time only) and its frequency response;
* chi-square quantiles and tail probabilities from scipy.stats.

Everything is seeded, so reruns write identical files.
"""

from __future__ import annotations

import argparse
import json
import os

import control
import numpy as np
import scipy.linalg
import scipy.stats
import slycot

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
OUT_DIR = os.path.join(REPO, "crates", "twinloop-sysid", "tests", "data")

SEED = 20240603
N_STATES, N_INPUTS, N_OUTPUTS, N_SAMPLES = 6, 10, 6, 1000
SAMPLE_TIME = 0.01
NOISE_STD = 0.5
ARX_ORDERS = [(2, 2, 1), (3, 2, 0), (1, 4, 2), (24, 24, 1)]
FREQS = [0.1, 1.0, 5.0, 20.0, 60.0, 150.0, 300.0]  # rad/s, below Nyquist (314.16)


def random_system(rng):
    """A stable (A, B, C, K) with poles of radius 0.6 .. 0.95, well-conditioned basis."""
    n = N_STATES
    blocks = []
    for _ in range(n // 2):
        r = rng.uniform(0.6, 0.95)
        th = rng.uniform(0.1, 2.5)
        blocks.append(r * np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]]))
    a_modal = scipy.linalg.block_diag(*blocks)
    q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    s = np.diag(rng.uniform(0.7, 1.4, n))
    t = q @ s
    a = t @ a_modal @ np.linalg.inv(t)
    b = rng.standard_normal((n, N_INPUTS)) * 0.5
    c = rng.standard_normal((N_OUTPUTS, n))
    while True:
        k = rng.standard_normal((n, N_OUTPUTS)) * 0.15
        if max(abs(np.linalg.eigvals(a - k @ c))) < 0.9:
            break
    return a, b, c, np.zeros((N_OUTPUTS, N_INPUTS)), k


def simulate_innovations(a, b, c, d, k, u, e):
    n = a.shape[0]
    x = np.zeros(n)
    y = np.zeros((u.shape[0], c.shape[0]))
    for t in range(u.shape[0]):
        y[t] = c @ x + d @ u[t] + e[t]
        x = a @ x + b @ u[t] + k @ e[t]
    return y


def one_step_errors(a, b, c, d, k, u, y):
    """Prediction errors of the Kalman predictor started at x = 0."""
    x = np.zeros(a.shape[0])
    err = np.zeros_like(y)
    for t in range(u.shape[0]):
        err[t] = y[t] - c @ x - d @ u[t]
        x = a @ x + b @ u[t] + k @ err[t]
    return err


def simulate(a, b, c, d, u):
    x = np.zeros(a.shape[0])
    y = np.zeros((u.shape[0], c.shape[0]))
    for t in range(u.shape[0]):
        y[t] = c @ x + d @ u[t]
        x = a @ x + b @ u[t]
    return y


def predict_h(a, b, c, d, k, u, y, h):
    """yhat(t | t-h): Kalman predictor up to t-h+1, then h-1 free simulation steps."""
    n = a.shape[0]
    xs = np.zeros((u.shape[0] + 1, n))  # xs[t] = x(t | t-1)
    x = np.zeros(n)
    for t in range(u.shape[0]):
        xs[t] = x
        e = y[t] - c @ x - d @ u[t]
        x = a @ x + b @ u[t] + k @ e
    out = np.zeros_like(y)
    for t in range(u.shape[0]):
        s = t - h + 1  # x(s | s-1) is the last state that used measured data
        if s < 0:
            xx = np.zeros(n)
            s = 0
        else:
            xx = xs[s].copy()
        for tau in range(s, t):
            xx = a @ xx + b @ u[tau]
        out[t] = c @ xx + d @ u[t]
    return out


def fit_percent(y, yhat):
    return [
        float(100.0 * (1.0 - np.linalg.norm(y[:, i] - yhat[:, i]) / np.linalg.norm(y[:, i] - y[:, i].mean())))
        for i in range(y.shape[1])
    ]


def seed_eq10(y, yhat):
    return [float(100.0 * np.linalg.norm(y[:, i] - yhat[:, i]) / np.linalg.norm(y[:, i])) for i in range(y.shape[1])]


def arx_regressor(u, y, na, nb, nk):
    """MATLAB arx rows: phi(k) = [-y(k-1) .. -y(k-na), u(k-nk) .. u(k-nk-nb+1)], k = k0 .. N-1."""
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
        targets.append(y[k])
    return np.array(rows), np.array(targets), k0


def arx_fit(u, y, na, nb, nk):
    phi, tgt, k0 = arx_regressor(u, y, na, nb, nk)
    theta, *_ = np.linalg.lstsq(phi, tgt, rcond=None)
    ny, nu = y.shape[1], u.shape[1]
    a = [theta[i * ny:(i + 1) * ny, :].T for i in range(na)]
    b = [theta[na * ny + j * nu:na * ny + (j + 1) * nu, :].T for j in range(nb)]
    resid = tgt - phi @ theta
    return a, b, k0, resid, phi.shape


def arx_simulate(a, b, nk, u, ny):
    n = u.shape[0]
    y = np.zeros((n, ny))
    for k in range(n):
        acc = np.zeros(ny)
        for i, ai in enumerate(a, start=1):
            if k - i >= 0:
                acc -= ai @ y[k - i]
        for j, bj in enumerate(b):
            if k - nk - j >= 0:
                acc += bj @ u[k - nk - j]
        y[k] = acc
    return y


def arx_predict(a, b, nk, u, y, h):
    """yhat(t | t-h): measured y up to t-h, predicted after, zero before the record."""
    n, ny = y.shape
    out = np.zeros_like(y)
    for t in range(n):
        pred = {}
        for s in range(t - h + 1, t + 1):
            if s < 0:
                continue
            acc = np.zeros(ny)
            for i, ai in enumerate(a, start=1):
                r = s - i
                if r < 0:
                    continue
                acc -= ai @ (y[r] if r <= t - h else pred[r])
            for j, bj in enumerate(b):
                if s - nk - j >= 0:
                    acc += bj @ u[s - nk - j]
            pred[s] = acc
        out[t] = pred[t]
    return out


def correlation(x, z, maxlag):
    """Normalised sample cross-correlation of the mean-removed sequences,
    r(tau) = sum_t x(t+tau) z(t) / sqrt(sum x^2 sum z^2), tau = -M..M."""
    x = x - x.mean()
    z = z - z.mean()
    n = len(x)
    den = np.sqrt(np.dot(x, x) * np.dot(z, z))
    out = []
    for tau in range(-maxlag, maxlag + 1):
        if tau >= 0:
            s = np.dot(x[tau:], z[:n - tau])
        else:
            s = np.dot(x[:n + tau], z[-tau:])
        out.append(float(s / den))
    return out


def sigma(a, b, c, d, w, ts):
    z = np.exp(1j * w * ts)
    g = c @ np.linalg.solve(z * np.eye(a.shape[0]) - a, b) + d
    return np.linalg.svd(g, compute_uv=False).tolist()


def mat(m):
    return np.asarray(m).tolist()


def write_csv(path, u, y):
    with open(path, "w") as f:
        cols = ["t"] + [f"u{i + 1}" for i in range(u.shape[1])] + [f"y{i + 1}" for i in range(y.shape[1])]
        f.write(",".join(cols) + "\n")
        for k in range(u.shape[0]):
            vals = [k * SAMPLE_TIME] + list(u[k]) + list(y[k])
            f.write(",".join(repr(float(v)) for v in vals) + "\n")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out-dir", default=OUT_DIR)
    args = ap.parse_args()
    os.makedirs(args.out_dir, exist_ok=True)
    rng = np.random.default_rng(SEED)

    a, b, c, d, k = random_system(rng)
    records = {}
    for name in ["est", "val"]:
        u = rng.standard_normal((N_SAMPLES, N_INPUTS))
        e = rng.standard_normal((N_SAMPLES, N_OUTPUTS)) * NOISE_STD
        y = simulate_innovations(a, b, c, d, k, u, e)
        records[name] = (u, y, e)
        write_csv(os.path.join(args.out_dir, f"synthetic_{name}.csv"), u, y)
        # What the CSV holds is what the tests read: use the rounded-tripped values.
    ref = {
        "generator": "tools/oracle/sysid_reference.py",
        "versions": {
            "numpy": np.__version__,
            "scipy": scipy.__version__,
            "control": control.__version__,
            "slycot": slycot.__version__,
        },
        "seed": SEED,
        "sample_time": SAMPLE_TIME,
        "noise_std": NOISE_STD,
        "system": {"A": mat(a), "B": mat(b), "C": mat(c), "D": mat(d), "K": mat(k)},
        "poles_abs": sorted(abs(np.linalg.eigvals(a)).tolist(), reverse=True),
        "predictor_poles_abs": sorted(abs(np.linalg.eigvals(a - k @ c)).tolist(), reverse=True),
    }

    # Gramians from python-control (slycot SB03MD, dico 'D'); Hankel singular values
    # from slycot AB09AD (discrete square-root balance & truncate), checked against
    # sqrt(eig(Wc Wo)). python-control's own hsvd/balred are continuous-time only.
    sys = control.ss(a, b, c, d, SAMPLE_TIME)
    wc, wo = control.gram(sys, "c"), control.gram(sys, "o")
    ref["gram_c"] = mat(wc)
    ref["gram_o"] = mat(wo)
    _, _, _, _, hsv = slycot.ab09ad("D", "B", "N", N_STATES, N_INPUTS, N_OUTPUTS, a, b, c, nr=N_STATES, tol=0.0)
    hsv_eig = np.sort(np.sqrt(np.linalg.eigvals(wc @ wo).real))[::-1]
    assert np.allclose(hsv, hsv_eig, rtol=1e-10), (hsv, hsv_eig)
    ref["hsv"] = sorted(np.asarray(hsv).tolist(), reverse=True)

    # A harder Lyapunov equation: order 30, complex pairs near the unit circle, a real pole.
    n2 = 30
    blocks = []
    for i in range(14):
        r = 0.5 + 0.49 * (i + 1) / 14
        th = rng.uniform(0.05, 3.0)
        blocks.append(r * np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]]))
    blocks += [np.array([[0.97]]), np.array([[-0.3]])]
    a2m = scipy.linalg.block_diag(*blocks)
    t2 = rng.standard_normal((n2, n2)) + 3 * np.eye(n2)
    a2 = t2 @ a2m @ np.linalg.inv(t2)
    g2 = rng.standard_normal((n2, 3))
    q2 = g2 @ g2.T
    # slycot SB03MD (Bartels-Stewart): A X A^T - X = scale * (-Q).
    x2, scale, _, _, _ = slycot.sb03md(n2, -q2, a2.copy(), np.zeros((n2, n2)), "D", job="X", fact="N", trana="T")
    x2 = x2 / scale
    x2s = scipy.linalg.solve_discrete_lyapunov(a2, q2, method="direct")
    res = np.abs(a2 @ x2 @ a2.T - x2 + q2).max() / np.abs(x2).max()
    ref["lyapunov"] = {"A": mat(a2), "Q": mat(q2), "X": mat(x2), "relative_residual": float(res),
                       "scipy_direct_relative_difference": float(np.abs(x2s - x2).max() / np.abs(x2).max())}

    # ARX by numpy least squares on the estimation record.
    u, y, e = records["est"]
    ref["arx"] = []
    for na, nb, nk in ARX_ORDERS:
        aa, bb, k0, resid, shape = arx_fit(u, y, na, nb, nk)
        case = {"na": na, "nb": nb, "nk": nk, "first_row": k0, "regressor_shape": list(shape),
                "A": [mat(m) for m in aa], "B": [mat(m) for m in bb],
                "residual_rms": float(np.sqrt(np.mean(resid ** 2)))}
        if (na, nb, nk) == (2, 2, 1):
            uv, yv, _ = records["val"]
            case["val_simulation_first_50"] = mat(arx_simulate(aa, bb, nk, uv, N_OUTPUTS)[:50])
            case["val_prediction_1_first_50"] = mat(arx_predict(aa, bb, nk, uv, yv, 1)[:50])
            case["val_prediction_3_first_50"] = mat(arx_predict(aa, bb, nk, uv, yv, 3)[:50])
            case["val_fit_simulation"] = fit_percent(yv, arx_simulate(aa, bb, nk, uv, N_OUTPUTS))
            case["val_fit_prediction_1"] = fit_percent(yv, arx_predict(aa, bb, nk, uv, yv, 1))
        if (na, nb, nk) == (3, 2, 0):
            uv, yv, _ = records["val"]
            case["val_prediction_2_first_50"] = mat(arx_predict(aa, bb, nk, uv, yv, 2)[:50])
            case["val_simulation_first_50"] = mat(arx_simulate(aa, bb, nk, uv, N_OUTPUTS)[:50])
        ref["arx"].append(case)

    # The true system's predictions and errors on both records.
    ref["true_model"] = {}
    for name, (u, y, e) in records.items():
        err = one_step_errors(a, b, c, d, k, u, y)
        ysim = simulate(a, b, c, d, u)
        yp1 = y - err
        yp5 = predict_h(a, b, c, d, k, u, y, 5)
        ref["true_model"][name] = {
            "prediction_cost": float(np.sum(err ** 2) / N_SAMPLES),
            "innovation_cost": float(np.sum(e ** 2) / N_SAMPLES),
            "fit_simulation": fit_percent(y, ysim),
            "fit_prediction_1": fit_percent(y, yp1),
            "fit_prediction_5": fit_percent(y, yp5),
            "eq10_simulation": seed_eq10(y, ysim),
            "eq10_prediction_1": seed_eq10(y, yp1),
            "simulation_first_50": mat(ysim[:50]),
            "prediction_5_first_50": mat(yp5[:50]),
            "residual_autocorr_y1": correlation(err[:, 0], err[:, 0], 25),
            "residual_crosscorr_y2_y5": correlation(err[:, 1], err[:, 4], 25),
            "residual_input_crosscorr_y3_u7": correlation(err[:, 2], u[:, 6], 25),
        }

    # Frequency response singular values.
    ref["frequency_response"] = {
        "omega": FREQS,
        "sigma": [sigma(a, b, c, d, w, SAMPLE_TIME) for w in FREQS],
        "dc_sigma_max": float(np.linalg.svd(c @ np.linalg.solve(np.eye(N_STATES) - a, b) + d, compute_uv=False)[0]),
    }

    # Balanced truncation to 4 states (slycot AB09AD, discrete, square-root B & T).
    nr, ar, br, cr, _ = slycot.ab09ad("D", "B", "N", N_STATES, N_INPUTS, N_OUTPUTS, a, b, c, nr=4, tol=0.0)
    assert nr == 4
    red = control.ss(ar, br, cr, d, SAMPLE_TIME)
    wcr, wor = control.gram(red, "c"), control.gram(red, "o")
    ref["balred4"] = {
        "A": mat(ar), "B": mat(br), "C": mat(cr),
        "sigma": [sigma(ar, br, cr, d, w, SAMPLE_TIME) for w in FREQS],
        "hsv": sorted(np.sqrt(np.linalg.eigvals(wcr @ wor).real).tolist(), reverse=True),
    }

    # Chi-square quantiles (99 %) and tail probabilities.
    dofs = [1, 2, 5, 25, 26, 50, 100, 260]
    ref["chi2"] = {
        "dof": dofs,
        "q99": [float(scipy.stats.chi2.ppf(0.99, k)) for k in dofs],
        "sf_at_dof": [float(scipy.stats.chi2.sf(k, k)) for k in dofs],
        "sf_at_2dof": [float(scipy.stats.chi2.sf(2 * k, k)) for k in dofs],
    }

    with open(os.path.join(args.out_dir, "reference.json"), "w") as f:
        json.dump(ref, f, indent=1)
        f.write("\n")
    print("wrote", args.out_dir)
    print("true HSV:", np.round(ref["hsv"], 4))
    print("true FIT sim (val):", np.round(ref["true_model"]["val"]["fit_simulation"], 1))
    print("true FIT pred (val):", np.round(ref["true_model"]["val"]["fit_prediction_1"], 1))
    print("true cost est/val:", ref["true_model"]["est"]["prediction_cost"], ref["true_model"]["val"]["prediction_cost"])


if __name__ == "__main__":
    main()
