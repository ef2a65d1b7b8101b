#!/usr/bin/env python3
"""Reference numbers for twinloop-ident's Butterworth design and zero-phase filter.

Writes crates/twinloop-ident/tests/data/butterworth.json: for each case, SciPy's
butter(order, cutoff, fs=sample) coefficients and filtfilt (default padding) of a
deterministic test signal. The Rust test compares against these; it needs no Python.

    pip install scipy numpy
    python3 tools/oracle/butterworth_reference.py
"""
import json
import math
import pathlib

import numpy as np
import scipy
from scipy import signal

CASES = [
    # order, cutoff Hz, sample Hz, samples
    (2, 10.0, 150.0, 300),
    (4, 10.0, 150.0, 300),
    (4, 10.0, 1000.0, 500),
    (2, 6.0, 100.0, 40),
    (3, 20.0, 200.0, 64),
]


def test_signal(fs, n):
    out = []
    for k in range(n):
        t = k / fs
        x = math.sin(2 * math.pi * 1.3 * t) + 0.3 * math.sin(2 * math.pi * 25.0 * t)
        x += 0.5 if t > 0.3 * n / fs else 0.0
        x += 0.01 * (((k * 7919) % 101) - 50) / 50.0
        out.append(x)
    return out


def main():
    cases = []
    for order, fc, fs, n in CASES:
        b, a = signal.butter(order, fc, btype="low", fs=fs)
        x = test_signal(fs, n)
        y = signal.filtfilt(b, a, np.array(x))
        cases.append(
            {
                "order": order,
                "cutoff_hz": fc,
                "sample_hz": fs,
                "b": list(map(float, b)),
                "a": list(map(float, a)),
                "x": x,
                "filtfilt": list(map(float, y)),
            }
        )
    out = {
        "schema": "twinloop-butterworth-reference/1",
        "generator": "tools/oracle/butterworth_reference.py",
        "scipy_version": scipy.__version__,
        "numpy_version": np.__version__,
        "signal": "sin(2 pi 1.3 t) + 0.3 sin(2 pi 25 t) + 0.5 [t > 0.3 T] + 0.01 ((7919 k mod 101) - 50) / 50",
        "cases": cases,
    }
    path = pathlib.Path(__file__).resolve().parents[2] / "crates/twinloop-ident/tests/data/butterworth.json"
    path.write_text(json.dumps(out, indent=1) + "\n")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
